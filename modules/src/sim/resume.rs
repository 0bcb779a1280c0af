//! What a simulated world needs to go on where it was: its time and each robot's motion.
//!
//! `sim.world` keeps it in `state/world` when it is stopped for a restart (or a move off its
//! agent's thread), so the new instance does not put every robot back at its start at time 0.
//! The noise streams start again from the seed: a resumed run is not bit-identical to one that
//! never stopped.

use petrel_actors::{Pose2, Twist2};
use serde::{Deserialize, Serialize};

use super::World;

/// A world's time and robots, to resume it ([`World::restore`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WorldState {
    /// Simulated time, seconds.
    pub time: f64,
    /// Each robot's motion, by id.
    pub robots: Vec<RobotState>,
}

/// One robot's motion state.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobotState {
    /// True pose.
    pub pose: Pose2,
    /// Odometric pose (drifts from the true one with odometry noise).
    pub odom: Pose2,
    /// Actual speed.
    pub speed: Twist2,
    /// Collisions so far.
    pub collisions: u64,
}

impl World {
    /// The time and every robot's motion.
    pub fn state(&self) -> WorldState {
        WorldState {
            time: self.time,
            robots: self
                .robots
                .iter()
                .map(|r| RobotState {
                    pose: r.pose,
                    odom: r.odom,
                    speed: r.speed,
                    collisions: r.collisions,
                })
                .collect(),
        }
    }

    /// Goes on from `state` (a world with the same robots, just built); an error if the robot
    /// count differs.
    pub fn restore(&mut self, state: &WorldState) -> Result<(), String> {
        if state.robots.len() != self.robots.len() {
            return Err(format!(
                "the saved world has {} robots, this one {}",
                state.robots.len(),
                self.robots.len()
            ));
        }
        self.time = state.time;
        for (robot, s) in self.robots.iter_mut().zip(&state.robots) {
            robot.pose = s.pose;
            robot.odom = s.odom;
            robot.speed = s.speed;
            robot.collisions = s.collisions;
            robot.next_scan = None;
        }
        Ok(())
    }
}

impl petrel_actors::PropertyType for WorldState {
    const TYPE_NAME: &'static str = "sim.world_state";
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{Grid, RobotConfig};

    fn world() -> World {
        let mut w = World::new(Grid::new(40, 40, 0.1, 0.0, 0.0).unwrap(), 7);
        w.add_robot(RobotConfig::default(), Pose2::new(1.0, 1.0, 0.0))
            .unwrap();
        w.add_robot(RobotConfig::default(), Pose2::new(2.0, 3.0, 1.0))
            .unwrap();
        w
    }

    #[test]
    fn a_restored_world_goes_on_from_the_saved_time_and_poses() {
        let mut w = world();
        w.set_command(0, Twist2::new(0.3, 0.2)).unwrap();
        for _ in 0..50 {
            w.step(0.02).unwrap();
        }
        let saved = w.state();
        assert!((saved.time - 1.0).abs() < 1e-9);
        // Through RON's dynamic values, as a snapshot reads it.
        let saved: WorldState = crate::test_support::through_ron_values(&saved);
        let mut fresh = world();
        fresh.restore(&saved).unwrap();
        assert_eq!(fresh.state(), saved);
        assert!(
            (fresh.pose(0).unwrap().x() - 1.0).abs() > 0.2,
            "it had moved"
        );
        let out = fresh.step(0.02).unwrap();
        assert!((out[0].odometry.stamp - 1.02).abs() < 1e-9);
        let mut one = World::new(Grid::new(40, 40, 0.1, 0.0, 0.0).unwrap(), 7);
        one.add_robot(RobotConfig::default(), Pose2::new(1.0, 1.0, 0.0))
            .unwrap();
        assert!(one
            .restore(&saved)
            .unwrap_err()
            .contains("2 robots, this one 1"));
    }
}
