//! The poses an `in/robotPose` input was written with, for modules that place a measurement
//! taken earlier (a camera frame the detector got to later) from the pose of its time.

use petrel_actors::{Input, Pose2};
use tokio::time::Instant;

use crate::nav::PoseHistory;

/// A [`PoseHistory`] fed from one input; its module must be woken by the input's changes.
#[derive(Default)]
pub(super) struct PoseTrail {
    history: PoseHistory,
    /// The input's version last recorded (0, the declared default, is no estimate yet).
    seen: u64,
}

impl PoseTrail {
    /// Records the input's pose if it was written since the last call.
    pub fn follow(&mut self, input: &Input<Pose2>) {
        // The version alone, read without a lock: most wake-ups of a frame bring no pose.
        if input.version() == self.seen {
            return;
        }
        let sample = input.read();
        self.seen = sample.version;
        self.history.record(sample.written, *sample.value);
    }

    /// The pose for a measurement stamped `stamp` ([`PoseHistory::at`]); `None` before the
    /// first estimate.
    pub fn at(&self, stamp: Instant) -> Option<Pose2> {
        self.history.at(stamp)
    }
}
