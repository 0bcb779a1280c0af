//! Where the robot was when a measurement was taken: the estimated poses in the order they were
//! written, looked up by a measurement's stamp.
//!
//! A camera frame reaches the modules that place what it shows some time after it was taken:
//! the detector has to get to it and process it. A robot turning at 1.5 rad/s turns 6° in 70 ms,
//! which puts a sighting 3 m away 0.3 m off and counts as searched floor the camera never
//! looked at. So results computed from a frame keep the frame's stamp
//! ([`Output::set_at`](petrel_actors::Output::set_at)), and their readers place them from the
//! pose of that time, by the rule the mapper pairs a scan with its pose: the first pose written
//! at or after the stamp (the estimate from the same simulation step, not the one before).

use std::collections::VecDeque;

use petrel_actors::Pose2;
use tokio::time::Instant;

/// Poses kept by default: at the simulator's default 50 odometry updates per simulated
/// second and 4x real time, two seconds of wall time, far more than a frame waits.
pub const DEFAULT_CAPACITY: usize = 400;

/// The latest poses with their write stamps, oldest first.
#[derive(Clone, Debug)]
pub struct PoseHistory {
    poses: VecDeque<(Instant, Pose2)>,
    capacity: usize,
}

impl Default for PoseHistory {
    fn default() -> Self {
        PoseHistory::new(DEFAULT_CAPACITY)
    }
}

impl PoseHistory {
    /// An empty history keeping the latest `capacity` poses (at least one).
    pub fn new(capacity: usize) -> Self {
        PoseHistory {
            poses: VecDeque::new(),
            capacity: capacity.max(1),
        }
    }

    /// Adds a pose written at `written`, forgetting the oldest beyond the capacity. Stamps come
    /// in write order; one earlier than the latest (another writer's clock) is taken as the
    /// latest's, so lookups stay well defined.
    pub fn record(&mut self, written: Instant, pose: Pose2) {
        let written = self.poses.back().map_or(written, |&(t, _)| written.max(t));
        if self.poses.len() == self.capacity {
            self.poses.pop_front();
        }
        self.poses.push_back((written, pose));
    }

    /// The pose for a measurement stamped `stamp`: the first one written at or after it; the
    /// latest when none was yet (the estimate for that moment is still being computed: the
    /// latest is the nearest); `None` before any pose.
    pub fn at(&self, stamp: Instant) -> Option<Pose2> {
        let first_after = self.poses.partition_point(|&(t, _)| t < stamp);
        self.poses
            .get(first_after)
            .or(self.poses.back())
            .map(|&(_, pose)| pose)
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;

    fn ms(base: Instant, ms: u64) -> Instant {
        base + Duration::from_millis(ms)
    }

    #[test]
    fn a_stamp_gets_the_first_pose_written_at_or_after_it() {
        let t0 = Instant::now();
        let mut history = PoseHistory::new(10);
        assert_eq!(history.at(t0), None);
        for (i, t) in [10, 20, 30].into_iter().enumerate() {
            history.record(ms(t0, t), Pose2::new(i as f64, 0.0, 0.0));
        }
        // Before the first: the first. Between two: the later. Equal: that one.
        assert_eq!(history.at(ms(t0, 0)), Some(Pose2::new(0.0, 0.0, 0.0)));
        assert_eq!(history.at(ms(t0, 15)), Some(Pose2::new(1.0, 0.0, 0.0)));
        assert_eq!(history.at(ms(t0, 20)), Some(Pose2::new(1.0, 0.0, 0.0)));
        assert_eq!(history.at(ms(t0, 30)), Some(Pose2::new(2.0, 0.0, 0.0)));
        // After the latest (its estimate not written yet): the latest.
        assert_eq!(history.at(ms(t0, 99)), Some(Pose2::new(2.0, 0.0, 0.0)));
    }

    #[test]
    fn poses_written_at_one_instant_are_found_in_write_order() {
        // On a paused test clock every write of a wake-up bears the same stamp.
        let t0 = Instant::now();
        let mut history = PoseHistory::new(10);
        history.record(t0, Pose2::new(1.0, 0.0, 0.0));
        history.record(t0, Pose2::new(2.0, 0.0, 0.0));
        assert_eq!(history.at(t0), Some(Pose2::new(1.0, 0.0, 0.0)));
    }

    #[test]
    fn the_oldest_poses_go_beyond_the_capacity_and_a_stamp_never_goes_back() {
        let t0 = Instant::now();
        let mut history = PoseHistory::new(2);
        for t in [10, 20, 30] {
            history.record(ms(t0, t), Pose2::new(t as f64, 0.0, 0.0));
        }
        // The pose of 10 ms is gone: the oldest kept stands in for it.
        assert_eq!(history.at(ms(t0, 5)), Some(Pose2::new(20.0, 0.0, 0.0)));
        // A stamp earlier than the latest is recorded as the latest's.
        history.record(ms(t0, 25), Pose2::new(25.0, 0.0, 0.0));
        assert_eq!(history.at(ms(t0, 26)), Some(Pose2::new(30.0, 0.0, 0.0)));
        assert_eq!(history.at(ms(t0, 31)), Some(Pose2::new(25.0, 0.0, 0.0)));
    }
}
