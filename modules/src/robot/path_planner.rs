//! `nav.path_planner`: global A* path to the target on the current map, and the local target.

use std::sync::Arc;

use petrel_actors::types::Path2;
use petrel_actors::{
    AgentView, CheckProblem, Context, Input, Module, OccupancyGrid, Output, Ports, Pose2, Range,
    Schedule,
};

use super::param_error;
use crate::nav::{CostParams, Planner, PlannerParams};

/// `nav.path_planner`: wraps [`Planner`].
pub struct PathPlanner {
    target: Input<Pose2>,
    robot: Input<Pose2>,
    map: Input<OccupancyGrid>,
    robot_radius: Input<f64>,
    safety_margin: Input<f64>,
    preferred_clearance: Input<f64>,
    clearance_weight: Input<f64>,
    unknown_is_free: Input<bool>,
    occupied_threshold: Input<i64>,
    goal_tolerance: Input<f64>,
    lookahead: Input<f64>,
    max_deviation: Input<f64>,
    face_goal: Input<bool>,
    heading_tolerance: Input<f64>,
    path: Output<Path2>,
    local_target: Output<Pose2>,
    arrived: Output<bool>,
    failed: Output<bool>,
    replans: Output<i64>,
    core: Option<Planner>,
}

impl PathPlanner {
    fn params(&self) -> PlannerParams {
        PlannerParams {
            cost: CostParams {
                robot_radius: self.robot_radius.value(),
                safety_margin: self.safety_margin.value(),
                preferred_clearance: self.preferred_clearance.value(),
                clearance_weight: self.clearance_weight.value(),
                unknown_is_free: self.unknown_is_free.value(),
                // Within i8: the parameter's range is 1..=100.
                occupied_threshold: self.occupied_threshold.value() as i8,
            },
            goal_tolerance: self.goal_tolerance.value(),
            lookahead: self.lookahead.value(),
            max_deviation: self.max_deviation.value(),
            heading_tolerance: self.heading_tolerance(),
        }
    }

    /// What `params/face_goal` and `params/heading_tolerance` ask of the core.
    fn heading_tolerance(&self) -> Option<f64> {
        self.face_goal
            .value()
            .then(|| self.heading_tolerance.value())
    }
}

impl Module for PathPlanner {
    const TYPE: &'static str = "nav.path_planner";
    const DESCRIPTION: &'static str =
        "Plans a path to in/targetPose on in/map and publishes the local target to follow.";

    fn declare(ports: &mut Ports) -> Self {
        PathPlanner {
            target: ports.input(
                "in/targetPose",
                Pose2::default(),
                "goal in the world frame (the planner idles until it is first written)",
            ),
            robot: ports.input(
                "in/robotPose",
                Pose2::default(),
                "robot pose in the world frame",
            ),
            map: ports.input(
                "in/map",
                OccupancyGrid::default(),
                "occupancy grid to plan on",
            ),
            robot_radius: ports.param_in(
                "params/robot_radius",
                0.2,
                Range::new(0.01, 5.0),
                "robot radius, m",
            ),
            safety_margin: ports.param_in(
                "params/safety_margin",
                0.05,
                Range::new(0.0, 5.0),
                "clearance kept beyond the radius, m",
            ),
            preferred_clearance: ports.param_in(
                "params/preferred_clearance",
                0.6,
                Range::new(0.0, 20.0),
                "clearance below which cells cost more, m",
            ),
            clearance_weight: ports.param_in(
                "params/clearance_weight",
                3.0,
                Range::new(0.0, 1000.0),
                "extra cost factor near obstacles",
            ),
            unknown_is_free: ports.param(
                "params/unknown_is_free",
                true,
                "plan through unknown cells",
            ),
            occupied_threshold: ports.param_in(
                "params/occupied_threshold",
                50,
                Range::new(1.0, 100.0),
                "occupancy percent from which a cell is an obstacle",
            ),
            goal_tolerance: ports.param_in(
                "params/goal_tolerance",
                0.25,
                Range::new(0.01, 100.0),
                "distance at which the target counts as reached, m",
            ),
            lookahead: ports.param_in(
                "params/lookahead",
                0.8,
                Range::new(0.05, 100.0),
                "distance along the path to the local target, m",
            ),
            max_deviation: ports.param_in(
                "params/max_deviation",
                0.6,
                Range::new(0.05, 100.0),
                "distance from the path that triggers a replan, m",
            ),
            face_goal: ports.param(
                "params/face_goal",
                false,
                "at the target's position, also turn to its heading before arriving (a robot sent to look at something); read every step",
            ),
            heading_tolerance: ports.param_in(
                "params/heading_tolerance",
                0.15,
                Range::new(0.01, std::f64::consts::PI),
                "with params/face_goal: how closely the robot faces the target's heading, rad",
            ),
            path: ports.output(
                "out/path",
                Path2::default(),
                "current global path (world frame)",
            ),
            local_target: ports.output(
                "out/localTargetPose",
                Pose2::default(),
                "where to head next, robot frame (identity = stay)",
            ),
            arrived: ports.output("out/arrived", false, "the robot is at the target"),
            failed: ports.output(
                "out/failed",
                false,
                "no path to the target on the current map",
            ),
            replans: ports.output("out/replans", 0, "A* searches so far"),
            core: None,
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::new()
            .on_change(&self.robot)
            .on_change(&self.target)
            .on_change(&self.map)
    }

    /// Parameters that are valid alone but not together (a preferred clearance inside the
    /// robot's own margin): `petrel check` says so before anything runs.
    fn check(&self, _agent: &AgentView) -> Vec<CheckProblem> {
        match Planner::new(self.params()) {
            Ok(_) => Vec::new(),
            Err(e) => vec![CheckProblem::new(&format!("params/{}", e.param), e.message)],
        }
    }

    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        self.core = Some(Planner::new(self.params()).map_err(|e| param_error(e, &[]))?);
        Ok(())
    }

    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let heading_tolerance = self.heading_tolerance();
        let core = super::initialized(&mut self.core);
        core.set_heading_tolerance(heading_tolerance)
            .map_err(|e| param_error(e, &[]))?;
        let target = self.target.read();
        if target.version == 0 {
            return Ok(()); // no target yet: the outputs already say "stay"
        }
        let out = core.step(&self.map.get(), self.robot.value(), *target.value);
        if !Arc::ptr_eq(&out.path, &self.path.get().0) {
            self.path.set(Path2(out.path.clone()));
        }
        self.local_target.set(out.local_target);
        // Flags are written only when they change so that their watchers wake for news.
        self.arrived.set_if_changed(out.arrived);
        self.failed.set_if_changed(out.failed);
        if out.replanned {
            self.replans.set(core.replans() as i64);
        }
        Ok(())
    }
}
