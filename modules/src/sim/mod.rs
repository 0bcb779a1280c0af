//! A deterministic 2D robot simulator: world grid, robots, lasers, collisions.
//!
//! Pure and synchronous: [`World::step`] advances simulated time by `dt` and returns, per
//! robot, odometry, a laser scan, the actual speed and the collision count. Robots are discs
//! that stop at walls and at each other and see each other in their scans. Fixed `dt` and a
//! fixed seed give bit-identical runs; mapping simulated time to wall time is the caller's job.

#![warn(missing_docs)]

pub mod camera;
pub mod context_log;
pub mod error;
pub mod features;
pub mod grid;
pub mod kinematics;
pub mod map_io;
pub mod map_yaml;
pub mod pgm;
mod pgm_ascii;
pub mod raycast;
pub mod render;
pub mod resume;
pub mod robot;
pub mod run_record;

use std::sync::Arc;

use petrel_actors::{LaserScan, Pose2, Twist2};

pub use error::{ParamError, WorldFileError};
pub use features::{Rect, WorldFeatures};
pub use grid::Grid;
pub use kinematics::{DriveKind, Limits};
pub use map_io::{load_world, parse_ascii, WorldMap};
pub use robot::{LaserConfig, OdomNoise, RobotConfig};

use robot::{Disc, Robot};

/// Index of a robot in its [`World`], in the order robots were added.
pub type RobotId = usize;

/// A pose measured at a simulated time.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Odometry {
    /// Simulated time of the measurement, seconds since the world was created.
    pub stamp: f64,
    /// Odometric pose: starts at the true start pose and integrates (noisy) motion increments,
    /// so without noise it equals the ground truth.
    pub pose: Pose2,
}

/// What one robot produces in one simulation step.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotOutput {
    /// Odometry stamped with the simulated time.
    pub odometry: Odometry,
    /// A fresh scan if the robot has a laser and a scan was due this step.
    pub scan: Option<LaserScan>,
    /// Actual speed over the step (zero after hitting a wall).
    pub speed: Twist2,
    /// Number of collision events so far (a blocked motion after an unblocked one).
    pub collisions: u64,
    /// True pose, for evaluation and rendering (a real robot does not have it).
    pub ground_truth: Pose2,
}

/// The simulated world: a ground-truth grid and the robots in it.
#[derive(Clone, Debug)]
pub struct World {
    grid: Arc<Grid>,
    robots: Vec<Robot>,
    outputs: Vec<RobotOutput>,
    time: f64,
    seed: u64,
}

impl World {
    /// An empty world over `grid`; `seed` drives every noise source.
    pub fn new(grid: Grid, seed: u64) -> Self {
        World {
            grid: Arc::new(grid),
            robots: Vec::new(),
            outputs: Vec::new(),
            time: 0.0,
            seed,
        }
    }

    /// Adds a robot at `start`; fails if the configuration is invalid or the start pose
    /// overlaps a wall.
    pub fn add_robot(&mut self, config: RobotConfig, start: Pose2) -> Result<RobotId, ParamError> {
        config.validate()?;
        let n = petrel_actors::short_number;
        let (x0, y0, x1, y1) = self.grid.bounds();
        let inside = (x0..=x1).contains(&start.x()) && (y0..=y1).contains(&start.y());
        if !inside || !start.theta().is_finite() {
            return Err(ParamError {
                param: "start".into(),
                message: format!(
                    "expected a start pose inside the world (x in {}..={}, y in {}..={}, a finite heading), got ({}, {}, {})",
                    n(x0), n(x1), n(y0), n(y1), n(start.x()), n(start.y()), n(start.theta())
                ),
            });
        }
        if self.grid.disc_collides(start.x(), start.y(), config.radius) {
            return Err(ParamError {
                param: "start".into(),
                message: format!(
                    "expected a free start pose, but a disc of radius {} at ({}, {}) overlaps a wall",
                    n(config.radius),
                    n(start.x()),
                    n(start.y())
                ),
            });
        }
        let overlaps = self.robots.iter().any(|r| {
            (r.pose.x() - start.x()).hypot(r.pose.y() - start.y()) < r.config.radius + config.radius
        });
        if overlaps {
            return Err(ParamError {
                param: "start".into(),
                message: format!(
                    "expected a free start pose, but ({}, {}) overlaps another robot",
                    n(start.x()),
                    n(start.y())
                ),
            });
        }
        let id = self.robots.len();
        // Each robot has its own stream so adding a robot does not change the others' noise.
        let rng =
            crate::seeded::seeded(self.seed ^ (id as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        self.robots.push(Robot {
            config,
            pose: start,
            odom: start,
            speed: Twist2::default(),
            command: Twist2::default(),
            collisions: 0,
            in_contact: false,
            next_scan: None,
            rng,
        });
        Ok(id)
    }

    /// Sets the velocity command robot `id` follows from the next step on (clamped to its
    /// limits); fails if there is no such robot.
    pub fn set_command(&mut self, id: RobotId, cmd: Twist2) -> Result<(), ParamError> {
        let count = self.robots.len();
        let robot = self.robots.get_mut(id).ok_or_else(|| ParamError {
            param: "robot".into(),
            message: format!("expected a robot id below {count}, got {id}"),
        })?;
        robot.command = cmd;
        Ok(())
    }

    /// Advances simulated time by `dt` seconds and returns each robot's outputs, by id.
    pub fn step(&mut self, dt: f64) -> Result<&[RobotOutput], ParamError> {
        error::positive("dt", dt)?;
        self.time += dt;
        self.outputs.clear();
        let grid = &*self.grid;
        // Robots move one after the other (in id order), each against the others' latest
        // footprints, so two robots can never end up overlapping.
        let mut discs: Vec<Disc> = self.robots.iter().map(Robot::disc).collect();
        for (i, robot) in self.robots.iter_mut().enumerate() {
            robot.advance(grid, &discs, i, dt);
            discs[i] = robot.disc();
        }
        // Scans are taken after everyone moved, from one consistent snapshot.
        for (i, robot) in self.robots.iter_mut().enumerate() {
            let scan = match robot.config.laser.clone() {
                Some(laser) if robot.next_scan.is_none_or(|t| self.time + 1e-9 >= t) => {
                    // Scans keep the phase of the first one; a scan that fell more than a
                    // period behind (large dt) restarts the phase instead of bursting.
                    robot.next_scan = laser.rate_hz.map(|rate| {
                        let next = robot.next_scan.unwrap_or(self.time) + 1.0 / rate;
                        if next <= self.time {
                            self.time + 1.0 / rate
                        } else {
                            next
                        }
                    });
                    Some(robot.scan(grid, &discs, i, &laser))
                }
                _ => None,
            };
            self.outputs.push(RobotOutput {
                odometry: Odometry {
                    stamp: self.time,
                    pose: robot.odom,
                },
                scan,
                speed: robot.speed,
                collisions: robot.collisions,
                ground_truth: robot.pose,
            });
        }
        Ok(&self.outputs)
    }

    /// Simulated time, seconds.
    pub fn time(&self) -> f64 {
        self.time
    }
    /// The ground-truth grid.
    pub fn grid(&self) -> &Arc<Grid> {
        &self.grid
    }
    /// Number of robots.
    pub fn robot_count(&self) -> usize {
        self.robots.len()
    }
    /// True pose of robot `id`.
    pub fn pose(&self, id: RobotId) -> Option<Pose2> {
        self.robots.get(id).map(|r| r.pose)
    }
    /// Footprints `(x, y, radius)` of every robot but `id`: what `id`'s camera can see.
    pub fn footprints_except(&self, id: RobotId) -> Vec<(f64, f64, f64)> {
        let others = self.robots.iter().enumerate().filter(|(i, _)| *i != id);
        others.map(|(_, r)| r.disc()).collect()
    }
    /// Configuration of robot `id`.
    pub fn config(&self, id: RobotId) -> Option<&RobotConfig> {
        self.robots.get(id).map(|r| &r.config)
    }
}

#[cfg(test)]
mod tests;
