//! A deterministic headless mission loop: world -> localizer -> mapper -> planner ->
//! avoidance -> world, with a goal sequencer on top.
//!
//! This is the reference wiring for the module actors: each call below corresponds to one
//! module reading its input properties and publishing its outputs (`sim.world`,
//! `nav.localizer`, `nav.mapper`, `nav.path_planner`, `nav.obstacle_avoidance`,
//! `nav.goal_sequencer`).

use petrel_actors::{LaserScan, OccupancyGrid, Point2, Pose2, Twist2};

use super::avoidance::{Avoidance, AvoidanceParams};
use super::localizer::{Localizer, LocalizerParams};
use super::mapper::{Mapper, MapperParams};
use super::planner::{Planner, PlannerParams};
use super::sequencer::GoalSequencer;
use crate::sim::error::{positive, ParamError};
use crate::sim::{Grid, RobotConfig, World};

/// Parameters of a headless mission.
#[derive(Clone, Debug, PartialEq)]
pub struct MissionParams {
    /// Seed for all simulated noise (default 1).
    pub seed: u64,
    /// Simulation steps per simulated second (default 100).
    pub sim_hz: f64,
    /// Control (localize, map, plan, avoid) ticks per simulated second; must divide `sim_hz`
    /// (default 20). The laser is set to scan at this rate.
    pub control_hz: f64,
    /// Simulated time after which the mission is abandoned, s (default 600).
    pub max_sim_time: f64,
    /// Continuous planning failure after which the mission is abandoned, s (default 10).
    pub give_up_after: f64,
    /// The simulated robot.
    pub robot: RobotConfig,
    /// Simulated localization error.
    pub localizer: LocalizerParams,
    /// Mapper cell size, metres (default 0.1); the map covers the world's bounds.
    pub map_resolution: f64,
    /// Planner parameters (its robot radius should match the robot's).
    pub planner: PlannerParams,
    /// Avoidance parameters (its speeds should not exceed the robot's limits).
    pub avoidance: AvoidanceParams,
    /// Other robots that stand still all mission long (a teammate that broke down), each a
    /// body of the mission robot's radius at its pose (default none).
    pub still_robots: Vec<Pose2>,
}

impl Default for MissionParams {
    fn default() -> Self {
        MissionParams {
            seed: 1,
            sim_hz: 100.0,
            control_hz: 20.0,
            max_sim_time: 600.0,
            give_up_after: 10.0,
            robot: RobotConfig::default(),
            localizer: LocalizerParams::default(),
            map_resolution: 0.1,
            planner: PlannerParams::default(),
            avoidance: AvoidanceParams::default(),
            still_robots: Vec::new(),
        }
    }
}

/// Outcome of a headless mission.
#[derive(Clone, Debug)]
pub struct MissionSummary {
    /// Goals reached, in order.
    pub reached: usize,
    /// Goals given.
    pub goals: usize,
    /// All goals reached.
    pub done: bool,
    /// The planner reported no path for `give_up_after` seconds.
    pub gave_up: bool,
    /// Simulation steps run.
    pub steps: u64,
    /// Simulated time, s.
    pub sim_time: f64,
    /// Collision events of the robot.
    pub collisions: u64,
    /// Number of A* searches.
    pub replans: u64,
    /// Distance driven (ground truth), m.
    pub distance: f64,
    /// Smallest localization quality seen.
    pub min_quality: f64,
    /// Ground-truth positions at every control tick.
    pub trajectory: Vec<Point2>,
    /// Final ground-truth pose.
    pub final_pose: Pose2,
    /// The mapper's final map.
    pub map: OccupancyGrid,
    /// The last planned path.
    pub last_path: Vec<Point2>,
}

/// Drives one robot from `start` through `goals` in `grid`, headless and deterministic.
pub fn run_mission(
    grid: &Grid,
    start: Pose2,
    goals: &[Pose2],
    params: &MissionParams,
) -> Result<MissionSummary, ParamError> {
    positive("sim_hz", params.sim_hz)?;
    positive("control_hz", params.control_hz)?;
    positive("max_sim_time", params.max_sim_time)?;
    positive("give_up_after", params.give_up_after)?;
    let ratio = params.sim_hz / params.control_hz;
    if (ratio - ratio.round()).abs() > 1e-9 || ratio < 1.0 {
        return Err(ParamError {
            param: "control_hz".into(),
            message: format!(
                "expected a divisor of sim_hz = {}, got {}",
                params.sim_hz, params.control_hz
            ),
        });
    }
    let steps_per_tick = ratio.round() as u64;
    let dt = 1.0 / params.sim_hz;

    let mut robot = params.robot.clone();
    if let Some(laser) = robot.laser.as_mut() {
        laser.rate_hz = Some(params.control_hz);
    }
    let mut world = World::new(grid.clone(), params.seed);
    for &pose in &params.still_robots {
        let body = RobotConfig {
            radius: params.robot.radius,
            laser: None,
            ..RobotConfig::default()
        };
        world.add_robot(body, pose)?;
    }
    let id = world.add_robot(robot, start)?;
    let mut localizer = Localizer::new(params.localizer.clone())?;
    let (x0, y0, x1, y1) = grid.bounds();
    positive("map_resolution", params.map_resolution)?;
    let mut mapper = Mapper::new(MapperParams {
        width: ((x1 - x0) / params.map_resolution).ceil() as u32,
        height: ((y1 - y0) / params.map_resolution).ceil() as u32,
        resolution: params.map_resolution,
        origin: (x0, y0),
        laser_mount: params
            .robot
            .laser
            .as_ref()
            .map(|l| l.mount)
            .unwrap_or_default(),
        ..MapperParams::default()
    })?;
    let mut planner = Planner::new(params.planner.clone())?;
    let mut avoidance = Avoidance::new(params.avoidance.clone())?;
    let mut sequencer = GoalSequencer::new(goals.to_vec(), params.planner.goal_tolerance * 1.5)?;

    let mut scan = LaserScan::default();
    let (mut steps, mut distance, mut min_quality, mut failing_since) = (0u64, 0.0, 1.0f64, None);
    let mut trajectory = vec![start.position()];
    let mut last_path = Vec::new();
    let mut gave_up = false;
    let mut out = world.step(dt)?[id].clone();
    while world.time() < params.max_sim_time {
        if steps % steps_per_tick == 0 {
            // nav.localizer
            let loc = localizer.step(out.odometry);
            min_quality = min_quality.min(loc.quality);
            // nav.mapper
            if let Some(s) = &out.scan {
                mapper.update(loc.pose, s);
                scan = s.clone();
            }
            // nav.goal_sequencer (goal for this tick)
            let Some(goal) = sequencer.progress().goal else {
                break;
            };
            // nav.path_planner
            let plan = planner.step(&mapper.grid(), loc.pose, goal);
            if plan.failed {
                let since = *failing_since.get_or_insert(world.time());
                if world.time() - since > params.give_up_after {
                    gave_up = true;
                    break;
                }
            } else {
                failing_since = None;
                last_path = plan.path.to_vec();
            }
            // nav.goal_sequencer (progress)
            let progress = sequencer.step(loc.pose, plan.arrived);
            // nav.obstacle_avoidance
            let cmd = if plan.failed || plan.arrived || progress.done {
                Twist2::default()
            } else {
                avoidance.step(&scan, plan.local_target)
            };
            world.set_command(id, cmd)?;
            trajectory.push(out.ground_truth.position());
            if progress.done {
                break;
            }
        }
        let prev = out.ground_truth;
        out = world.step(dt)?[id].clone();
        distance += (out.ground_truth.0.translation.vector - prev.0.translation.vector).norm();
        steps += 1;
    }
    let progress = sequencer.progress();
    Ok(MissionSummary {
        reached: progress.reached,
        goals: progress.total,
        done: progress.done,
        gave_up,
        steps,
        sim_time: world.time(),
        collisions: out.collisions,
        replans: planner.replans(),
        distance,
        min_quality,
        trajectory,
        final_pose: out.ground_truth,
        map: mapper.grid(),
        last_path,
    })
}

#[cfg(test)]
mod tests;
