//! `nav.obstacle_avoidance`: laser + local target → velocity command.

use petrel_actors::{
    Context, Input, LaserScan, Module, Output, Ports, Pose2, QueueReader, Range, Schedule, Twist2,
};

use super::param_error;
use crate::nav::{Avoidance, AvoidanceParams};

/// `nav.obstacle_avoidance`: wraps [`Avoidance`].
///
/// `params/maxSpeed` and `params/maxTurn` keep these exact names: context rules lower them at
/// run time (rough terrain), and every parameter is re-read at each scan.
pub struct ObstacleAvoidance {
    scans: QueueReader<LaserScan>,
    target: Input<Pose2>,
    max_speed: Input<f64>,
    max_turn: Input<f64>,
    robot_radius: Input<f64>,
    safety_margin: Input<f64>,
    brake_time: Input<f64>,
    lookahead_time: Input<f64>,
    turn_in_place_bearing: Input<f64>,
    stop_distance: Input<f64>,
    clearance_weight: Input<f64>,
    laser_mount: Input<Pose2>,
    command: Output<Twist2>,
    nearest: Output<f64>,
    /// The core and the parameters it was built with.
    core: Option<(Avoidance, AvoidanceParams)>,
}

/// Core parameter names that differ from the property names.
const RENAMES: &[(&str, &str)] = &[("max_speed", "maxSpeed"), ("max_turn", "maxTurn")];

impl Module for ObstacleAvoidance {
    const TYPE: &'static str = "nav.obstacle_avoidance";
    const DESCRIPTION: &'static str =
        "Steers toward in/localTargetPose without hitting what the laser sees.";

    fn declare(ports: &mut Ports) -> Self {
        ObstacleAvoidance {
            scans: ports.queue_in("in/laserScan", "laser scans (each one produces a command)"),
            target: ports.input(
                "in/localTargetPose",
                Pose2::default(),
                "where to go, robot frame (identity = stop)",
            ),
            max_speed: ports.param_in(
                "params/maxSpeed",
                0.5,
                Range::new(0.01, 20.0),
                "largest forward speed commanded, m/s",
            ),
            max_turn: ports.param_in(
                "params/maxTurn",
                1.5,
                Range::new(0.01, 20.0),
                "largest turn rate commanded, rad/s",
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
                "distance kept from laser points, m",
            ),
            brake_time: ports.param_in(
                "params/brake_time",
                1.0,
                Range::new(0.01, 60.0),
                "free distance required per m/s of speed, s",
            ),
            lookahead_time: ports.param_in(
                "params/lookahead_time",
                1.0,
                Range::new(0.05, 60.0),
                "how far ahead arcs are scored, s",
            ),
            turn_in_place_bearing: ports.param_in(
                "params/turn_in_place_bearing",
                0.8,
                Range::new(0.01, std::f64::consts::PI),
                "bearing beyond which the robot turns in place, rad",
            ),
            stop_distance: ports.param_in(
                "params/stop_distance",
                0.05,
                Range::new(0.0, 10.0),
                "distance to the target under which the robot stops, m",
            ),
            clearance_weight: ports.param_in(
                "params/clearance_weight",
                0.3,
                Range::new(0.0, 100.0),
                "weight of free space in the score",
            ),
            laser_mount: ports.param(
                "params/laser_mount",
                Pose2::default(),
                "laser pose in the robot frame",
            ),
            command: ports.output("out/controlSpeed", Twist2::default(), "velocity command"),
            nearest: ports.output(
                "out/nearest",
                f64::INFINITY,
                "range of the closest laser return, m (what `crowded` rules read)",
            ),
            core: None,
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::new().on_items(&self.scans)
    }

    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let params = self.params();
        let core = Avoidance::new(params.clone()).map_err(|e| param_error(e, RENAMES))?;
        self.core = Some((core, params));
        Ok(())
    }

    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let Some(scan) = self.scans.drain().pop() else {
            return Ok(());
        };
        let params = self.params();
        let (core, built_with) = super::initialized(&mut self.core);
        if *built_with != params {
            match Avoidance::new(params.clone()) {
                Ok(fresh) => (*core, *built_with) = (fresh, params),
                Err(e) => {
                    // Stop before failing: the last command must not keep the robot driving.
                    self.command.set(Twist2::default());
                    return Err(param_error(e, RENAMES));
                }
            }
        }
        self.command.set(core.step(&scan, self.target.value()));
        let nearest = scan
            .value
            .ranges
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        self.nearest.set(nearest);
        Ok(())
    }
}

impl ObstacleAvoidance {
    fn params(&self) -> AvoidanceParams {
        AvoidanceParams {
            max_speed: self.max_speed.value(),
            max_turn: self.max_turn.value(),
            robot_radius: self.robot_radius.value(),
            safety_margin: self.safety_margin.value(),
            brake_time: self.brake_time.value(),
            lookahead_time: self.lookahead_time.value(),
            turn_in_place_bearing: self.turn_in_place_bearing.value(),
            stop_distance: self.stop_distance.value(),
            clearance_weight: self.clearance_weight.value(),
            laser_mount: self.laser_mount.value(),
        }
    }
}
