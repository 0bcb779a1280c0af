//! `sim.body`: one robot of a shared `sim.world`, as its own module with its own ports.
//!
//! The module is passive: it only declares the properties a robot's driver would have
//! (`in/controlSpeed`, `out/odometry`, `out/laserScan`, `out/image`, ...), with the same
//! paths as a single-robot `sim.world`. The world module that names it in `params/bodies`
//! reads its command and writes its readings at every simulation step. So each body is one
//! `agent/module` that other agents link to exactly as to a single robot's simulator or a
//! real driver: a robot agent's config changes only in the agent and module it names.

use petrel_actors::{
    AgentView, CheckProblem, Context, Image, Input, LaserScan, Module, Output, Ports, Pose2,
    QueueWriter, Schedule, Twist2,
};

/// `sim.body`: a robot body hosted by a `sim.world` (see the module docs).
pub struct SimBody {
    _start: Input<Vec<f64>>,
    _command: Input<Twist2>,
    _odometry: QueueWriter<Pose2>,
    _scans: QueueWriter<LaserScan>,
    _images: QueueWriter<Image>,
    _pose: Output<Pose2>,
    _speed: Output<Twist2>,
    _collisions: Output<i64>,
    _sim_time: Output<f64>,
    _vibration: Output<f64>,
    _exposure: Input<f64>,
    _gain: Input<f64>,
}

impl Module for SimBody {
    const TYPE: &'static str = "sim.body";
    const DESCRIPTION: &'static str =
        "One robot body of a shared sim.world (named in its params/bodies): the robot's driver ports.";

    fn declare(ports: &mut Ports) -> Self {
        SimBody {
            _start: ports.param("params/start", Vec::new(), "start pose `[x, y, heading_deg]`; empty = the world file's `R` marker of this body's rank in the world's params/bodies"),
            _command: ports.input("in/controlSpeed", Twist2::default(), "velocity command (clamped to the world's limits)"),
            _odometry: ports.queue_out("out/odometry", 256, "odometric pose at every world step"),
            _scans: ports.queue_out("out/laserScan", 16, "laser scans, in the laser frame (other robots are seen)"),
            _images: ports.queue_out("out/image", 4, "camera frames, 160 x 120 mono8, when the world's camera is enabled (other robots are seen)"),
            _pose: ports.output("out/pose", Pose2::default(), "ground-truth pose (for evaluation)"),
            _speed: ports.output("out/actualSpeed", Twist2::default(), "actual speed over the last step"),
            _collisions: ports.output("out/collisions", 0, "collision events so far (walls and other robots), written when it changes"),
            _sim_time: ports.output("out/simTime", 0.0, "simulated time, s"),
            _vibration: ports.output("out/vibration", 0.0, "vibration of the base, 0..1"),
            // A driver's camera settings: the robot that drives this body may link them to what
            // its vision asks for (longer exposure and more gain in the dark).
            _exposure: ports.input("in/camera/exposure_ms", 0.0, "this robot's camera exposure, ms (0, 200]; 0 = the world's params/camera/exposure_ms"),
            _gain: ports.input("in/camera/gain", 0.0, "this robot's camera gain [1, 16]; 0 = the world's params/camera/gain"),
        }
    }

    /// The start pose's shape; the world checks where it lies when it places the body.
    fn check(&self, _agent: &AgentView) -> Vec<CheckProblem> {
        let start = self._start.get();
        super::world_body::start_problem(&start)
            .map(|p| CheckProblem::new("params/start", p))
            .into_iter()
            .collect()
    }

    /// Never steps: the world writes its outputs.
    fn schedule(&self) -> Schedule {
        Schedule::new()
    }

    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        Ok(())
    }
}
