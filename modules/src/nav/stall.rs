//! Robots that hold a frontier but do not move (pure).
//!
//! A robot can be wedged between a box and a wall, or keep failing to follow its path, while
//! its explorer still believes in its target: it gives the target up only when its time runs
//! out, and the team's search hands it the next frontier nearby, so one stuck robot can hold
//! the last frontier while the others stand idle. A robot that holds a claim and has not moved
//! `min_move` metres for `stall_s` seconds is *stalled*: the coordinator takes its frontier
//! back, never gives that frontier to it again (another robot takes it over), and leaves the
//! robot out of the allocation for another `stall_s` (it may get free meanwhile, and then gets
//! other frontiers). A robot without a claim is waiting, not stalled.

use std::collections::BTreeMap;

use petrel_actors::Point2;

/// Watches each robot's progress while it holds a frontier.
#[derive(Clone, Debug)]
pub struct StallWatch {
    stall_s: f64,
    min_move: f64,
    robots: BTreeMap<String, Track>,
}

#[derive(Clone, Debug)]
struct Track {
    /// Where the robot was when it last made progress (or got its claim).
    anchor: Point2,
    /// When that was.
    since: f64,
    /// Left out of the allocation until then.
    benched_until: f64,
    /// The frontiers it stalled on.
    avoid: Vec<Point2>,
}

impl StallWatch {
    /// A robot holding a claim that moves less than `min_move` metres in `stall_s` seconds
    /// is stalled; `stall_s` of 0 turns the watch off.
    pub fn new(stall_s: f64, min_move: f64) -> Self {
        StallWatch {
            stall_s,
            min_move,
            robots: BTreeMap::new(),
        }
    }

    /// Records `robot` at `at` at time `t`, holding `claim`; returns the claim when the robot
    /// has just stalled on it (it is benched from now for `stall_s`, and avoids the claim).
    pub fn observe(
        &mut self,
        robot: &str,
        at: Point2,
        claim: Option<Point2>,
        t: f64,
    ) -> Option<Point2> {
        let track = self.robots.entry(robot.to_string()).or_insert(Track {
            anchor: at,
            since: t,
            benched_until: f64::NEG_INFINITY,
            avoid: Vec::new(),
        });
        let moved = (at.0 - track.anchor.0).norm() >= self.min_move;
        let Some(claim) = claim.filter(|_| !moved) else {
            track.anchor = at;
            track.since = t;
            return None;
        };
        if self.stall_s > 0.0 && t - track.since >= self.stall_s {
            track.anchor = at;
            track.since = t;
            track.benched_until = t + self.stall_s;
            track.avoid.push(claim);
            return Some(claim);
        }
        None
    }

    /// Whether `robot` stalled on a frontier within `radius` of `target`.
    pub fn avoids(&self, robot: &str, target: Point2, radius: f64) -> bool {
        self.robots.get(robot).is_some_and(|track| {
            track
                .avoid
                .iter()
                .any(|p| (p.0 - target.0).norm() <= radius)
        })
    }

    /// Whether `robot` is left out of the allocation at `t`.
    pub fn benched(&self, robot: &str, t: f64) -> bool {
        self.robots
            .get(robot)
            .is_some_and(|track| t < track.benched_until)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_robot_holding_a_claim_without_moving_stalls_and_is_benched_for_a_while() {
        let mut watch = StallWatch::new(20.0, 0.3);
        let here = Point2::new(3.4, 11.5);
        let claim = Some(Point2::new(6.5, 8.0));
        assert_eq!(watch.observe("r3", here, claim, 100.0), None);
        // Jitter in place is not progress.
        assert_eq!(
            watch.observe("r3", Point2::new(3.5, 11.4), claim, 110.0),
            None
        );
        assert_eq!(watch.observe("r3", here, claim, 119.9), None);
        assert_eq!(watch.observe("r3", here, claim, 120.0), claim);
        assert!(watch.benched("r3", 120.0) && watch.benched("r3", 139.9));
        assert!(!watch.benched("r3", 140.0));
        // It never gets that frontier again; others may.
        assert!(watch.avoids("r3", Point2::new(6.9, 8.0), 0.5));
        assert!(!watch.avoids("r3", Point2::new(7.6, 8.0), 0.5));
        assert!(!watch.avoids("r1", Point2::new(6.5, 8.0), 0.5));
        // Once, not on every step after.
        assert_eq!(watch.observe("r3", here, claim, 121.0), None);
        assert!(!watch.benched("r1", 120.0));
    }

    #[test]
    fn moving_or_waiting_without_a_claim_is_no_stall() {
        let mut watch = StallWatch::new(20.0, 0.3);
        for k in 0..10 {
            let t = 10.0 * k as f64;
            let driving = Point2::new(0.5 * k as f64, 0.0);
            let claim = Some(Point2::new(9.0, 0.0));
            assert_eq!(
                watch.observe("r1", driving, claim, t),
                None,
                "driving at {t}"
            );
            assert_eq!(
                watch.observe("r2", Point2::new(1.0, 1.0), None, t),
                None,
                "idle at {t}"
            );
        }
        // The wait does not count once a claim comes.
        let claim = Some(Point2::new(2.0, 1.0));
        let idle = Point2::new(1.0, 1.0);
        assert_eq!(watch.observe("r2", idle, claim, 100.0), None);
        assert_eq!(watch.observe("r2", idle, claim, 120.0), claim);
        let mut off = StallWatch::new(0.0, 0.3);
        assert_eq!(off.observe("r1", idle, claim, 0.0), None);
        assert_eq!(off.observe("r1", idle, claim, 1e6), None);
    }
}
