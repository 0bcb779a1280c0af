//! `sim.world`: the simulator as a module, standing where a real robot's driver would.

use std::time::Duration;

use petrel_actors::types::Path2;
use petrel_actors::{
    AgentView, CheckProblem, Context, FilePath, Image, Input, LaserScan, Module, Output, Point2,
    Ports, Pose2, QueueWriter, Range, Schedule, Twist2, Unrecoverable,
};
use tokio::time::Instant;

mod config;
mod sim;

use self::sim::Sim;
use super::world_body::{
    bodies_problem, check_bodies, start_pose, start_problem, BodyIo, BodyNames,
};
use super::world_tracks::Tracks;
use super::{check_params, param_error};
use crate::sim::error::{non_negative, positive};
use crate::sim::resume::WorldState;
use crate::sim::{load_world, World, WorldMap};

/// Core names of the robot's parameters that `sim.world` exposes under other property paths;
/// `World::add_robot` checks the config and names the core parameter.
const ROBOT_PARAMS: &[(&str, &str)] = &[
    ("rays", "laser/rays"),
    ("range_max", "laser/range_max"),
    ("range_noise_std", "laser/noise_std"),
    ("rate_hz", "laser/rate_hz"),
    ("trans_std", "odom_noise[0]"),
    ("rot_std", "odom_noise[1]"),
    ("rot_per_trans_std", "odom_noise[2]"),
];

/// Side of the square around each victim that the simulator makes solid, metres (inside
/// the camera's victim cylinder, [`crate::sim::camera::VICTIM_RADIUS`]).
const VICTIM_BODY: f64 = 0.3;

/// The world's walls with its victims filled in: victims are bodies on the floor, so a robot
/// must drive around them, and its laser sees them as small obstacles (the camera sees who
/// they are).
fn with_victims(mut grid: crate::sim::grid::Grid, victims: &[Point2]) -> crate::sim::grid::Grid {
    let r = VICTIM_BODY / 2.0;
    for v in victims {
        grid.fill_rect(v.0.x - r, v.0.y - r, v.0.x + r, v.0.y + r);
    }
    grid
}

/// `sim.world`: loads a world file and simulates robots in it.
///
/// With `params/bodies` empty the module is the one robot (its own `in/controlSpeed`,
/// `out/odometry`, ...). Otherwise it hosts one robot per `sim.body` module named there, on
/// those modules' ports, all of the same make (this module's robot parameters): they see
/// each other in lasers and cameras and collide with each other. A body per module keeps
/// every robot's ports at the paths a single robot has, so another agent links to
/// `sim/robot_2/out/laserScan` as it would to its own simulator or driver.
pub struct SimWorld {
    world_file: Input<FilePath>,
    start: Input<Vec<f64>>,
    bodies: Input<BodyNames>,
    png: Input<String>,
    seed: Input<i64>,
    dt: Input<f64>,
    time_scale: Input<f64>,
    deterministic: Input<bool>,
    command_timeout: Input<f64>,
    radius: Input<f64>,
    drive: Input<String>,
    max_speed: Input<f64>,
    max_lateral_speed: Input<f64>,
    max_turn: Input<f64>,
    max_accel: Input<f64>,
    max_turn_accel: Input<f64>,
    odom_noise: Input<Vec<f64>>,
    laser_enabled: Input<bool>,
    laser_rays: Input<i64>,
    laser_fov_deg: Input<f64>,
    laser_range_max: Input<f64>,
    laser_noise: Input<f64>,
    laser_rate: Input<f64>,
    laser_mount: Input<Pose2>,
    camera_enabled: Input<bool>,
    camera_exposure: Input<f64>,
    camera_gain: Input<f64>,
    camera_rate: Input<f64>,
    camera_fov_deg: Input<f64>,
    // The robot's own ports: declared here, written through the same feeds as a sim.body's
    // (world_body.rs), so one step serves one robot or many.
    _command: Input<Twist2>,
    _odometry: QueueWriter<Pose2>,
    _scans: QueueWriter<LaserScan>,
    _images: QueueWriter<Image>,
    pose: Output<Pose2>,
    _speed: Output<Twist2>,
    _collisions: Output<i64>,
    sim_time: Output<f64>,
    world_goals: Output<Path2>,
    world_victims: Output<Path2>,
    _vibration: Output<f64>,
    dark_areas: Output<Vec<f64>>,
    rough_areas: Output<Vec<f64>>,
    saved_world: Output<WorldState>,
    saved_tracks: Output<Tracks>,
    sim: Option<Sim>,
}

impl SimWorld {
    fn load_map(&self) -> Result<WorldMap, Unrecoverable> {
        let file = self.world_file.get();
        if file.is_empty() {
            let expected =
                "params/world is empty; expected the path of a world file (`.txt` or `.yaml`)";
            return Err(Unrecoverable(expected.into()));
        }
        load_world(file.as_path()).map_err(|e| Unrecoverable(e.to_string()))
    }
}

impl Module for SimWorld {
    const TYPE: &'static str = "sim.world";
    const DESCRIPTION: &'static str =
        "Simulates robots (kinematics, odometry, laser, camera, collisions) in a world file: itself, or the sim.body modules it names.";

    fn declare(ports: &mut Ports) -> Self {
        let module = SimWorld {
            world_file: ports.param("params/world", FilePath::default(), "world file: `.txt` ASCII grid or `.yaml` map_server map (relative to the config file)"),
            start: ports.param("params/start", Vec::new(), "start pose `[x, y, heading_deg]`; empty = the world file's `R` marker"),
            png: ports.param("params/png", String::new(), "a picture (path relative to the working directory, as sim.recorder's) written when the run stops: the world, its victims, every robot's trajectory in its own colour, a cross where one whose agent left the team stopped (empty = none)"),
            bodies: ports.param("params/bodies", BodyNames::default(), "names of the sim.body modules (of this agent) whose robots this world hosts; empty = this module is the one robot"),
            seed: ports.param("params/seed", 1, "seed of every noise source"),
            dt: ports.param_in("params/dt", 0.01, Range::new(1e-4, 1.0), "simulated seconds per step"),
            time_scale: ports.param_in("params/time_scale", 1.0, Range::new(0.01, 1000.0), "simulated seconds per wall second: steps run every dt / time_scale"),
            deterministic: ports.param("params/deterministic", true, "true: every step advances exactly dt (a slow host slows simulated time down); false: follow the wall clock"),
            command_timeout: ports.param_in("params/command_timeout_s", 0.5, Range::new(0.0, 3600.0), "stop the robot when in/controlSpeed is not rewritten for this many simulated seconds (0 = never)"),
            radius: ports.param_in("params/radius", 0.2, Range::new(0.01, 5.0), "robot footprint radius, m"),
            drive: ports.param_one_of("params/drive", "differential", &["differential", "holonomic"], "differential or holonomic"),
            max_speed: ports.param_in("params/max_speed", 0.7, Range::new(0.01, 20.0), "largest |forward speed|, m/s"),
            max_lateral_speed: ports.param_in("params/max_lateral_speed", 0.5, Range::new(0.01, 20.0), "largest |sideways speed| (holonomic), m/s"),
            max_turn: ports.param_in("params/max_turn", 2.0, Range::new(0.01, 20.0), "largest |turn rate|, rad/s"),
            max_accel: ports.param_in("params/max_accel", 1.5, Range::new(0.01, 100.0), "largest linear acceleration, m/s²"),
            max_turn_accel: ports.param_in("params/max_turn_accel", 4.0, Range::new(0.01, 100.0), "largest turn acceleration, rad/s²"),
            odom_noise: ports.param("params/odom_noise", Vec::new(), "odometry noise `[trans_std, rot_std, rot_per_trans_std]`; empty = exact odometry"),
            laser_enabled: ports.param("params/laser/enabled", true, "whether the robot has a laser"),
            laser_rays: ports.param_in("params/laser/rays", 181, Range::new(1.0, 10000.0), "rays per scan"),
            laser_fov_deg: ports.param_in("params/laser/fov_deg", 180.0, Range::new(1.0, 360.0), "field of view, degrees"),
            laser_range_max: ports.param_in("params/laser/range_max", 8.0, Range::new(0.1, 100.0), "maximum range, m"),
            laser_noise: ports.param_in("params/laser/noise_std", 0.0, Range::new(0.0, 10.0), "Gaussian range noise, m"),
            laser_rate: ports.param_in("params/laser/rate_hz", 20.0, Range::new(0.0, 1000.0), "scans per simulated second (0 = every step)"),
            laser_mount: ports.param("params/laser/mount", Pose2::default(), "laser pose in the robot frame"),
            camera_enabled: ports.param("params/camera/enabled", false, "whether the robot has a camera (out/image)"),
            camera_exposure: ports.param_in("params/camera/exposure_ms", 10.0, Range::new(0.01, 200.0), "exposure time, ms (0..200]: longer is brighter and less noisy, and blurs more when moving; read at every frame"),
            camera_gain: ports.param_in("params/camera/gain", 1.0, Range::new(1.0, 16.0), "sensor gain [1, 16]: brighter, noise amplified alike; read at every frame"),
            camera_rate: ports.param_in("params/camera/rate_hz", 10.0, Range::new(0.1, 100.0), "frames per simulated second"),
            camera_fov_deg: ports.param_in("params/camera/fov_deg", 60.0, Range::new(1.0, 179.0), "horizontal field of view, degrees (0, 180)"),
            _command: ports.input("in/controlSpeed", Twist2::default(), "velocity command (clamped to the limits)"),
            _odometry: ports.queue_out("out/odometry", 256, "odometric pose at every step (item stamp = push time; simulated time is out/simTime)"),
            _scans: ports.queue_out("out/laserScan", 16, "laser scans, in the laser frame"),
            _images: ports.queue_out("out/image", 4, "camera frames, 160 x 120 mono8 (shared, never copied)"),
            pose: ports.output("out/pose", Pose2::default(), "ground-truth pose (for evaluation: a real robot has none)"),
            _speed: ports.output("out/actualSpeed", Twist2::default(), "actual speed over the last step"),
            _collisions: ports.output("out/collisions", 0, "collision events so far, written when it changes"),
            sim_time: ports.output("out/simTime", 0.0, "simulated time, s"),
            world_goals: ports.output("out/worldGoals", Path2::default(), "goal markers `1`..`9` of an ASCII world file, in order"),
            world_victims: ports.output("out/worldVictims", Path2::default(), "victims of the world file (ground truth, for evaluation)"),
            _vibration: ports.output("out/vibration", 0.0, "vibration of the base, 0..1 (an IMU would measure it): high on rough floor even when slow"),
            dark_areas: ports.output("out/darkAreas", Vec::new(), "dark areas of the world file `[x0, y0, x1, y1, ...]` (for drawing)"),
            rough_areas: ports.output("out/roughAreas", Vec::new(), "rough floor of the world file `[x0, y0, x1, y1, ...]` (for drawing)"),
            saved_world: ports.state("state/world", WorldState::default(), "time and robots' motion, kept when stopped for a restart or a move: the next instance goes on from them (once)"),
            saved_tracks: ports.state("state/tracks", Tracks::default(), "trajectories and departures for the picture, kept likewise"),
            sim: None,
        };
        // Read only by `init`: a running agent refuses new values for these.
        ports.read_at_start(&["params/world", "params/start", "params/seed", "params/dt"]);
        module
    }

    fn schedule(&self) -> Schedule {
        let period = self.sim.as_ref().map_or(0.01, |s| s.dt) / self.time_scale.value();
        Schedule::every(Duration::from_secs_f64(period))
    }

    /// The world file, the bodies it names, and where the robot of a single-robot world
    /// starts (bodies are placed from their own modules' values: a body started in a wall is
    /// found when the world places it, at init).
    fn check(&self, agent: &AgentView) -> Vec<CheckProblem> {
        let bodies = self.bodies.get();
        if let Some(problem) = bodies_problem(&bodies.0, |name| agent.module_type(name)) {
            return vec![CheckProblem::new("params/bodies", problem)];
        }
        let map = match self.load_map() {
            Ok(map) => map,
            Err(e) => return vec![CheckProblem::new("params/world", e.0)],
        };
        let start = self.start.get();
        if let Some(problem) = start_problem(&start) {
            return vec![CheckProblem::new("params/start", problem)];
        }
        // Other parameters are refused by their ranges, or here (the drive, the noise).
        let config = match self.robot_config() {
            Ok(config) => config,
            Err(e) => return vec![super::check_problem(&e)],
        };
        if !self.bodies.get().0.is_empty() {
            return Vec::new();
        }
        let file = self.world_file.get();
        let placed = start_pose(&start, &map.starts, 0, &file, None)
            .map_err(|e| CheckProblem::new("params/start", format!("{e:#}")))
            .and_then(|pose| {
                let mut world = World::new(with_victims(map.grid, &map.features.victims), 0);
                world
                    .add_robot(config, pose)
                    .map_err(|e| CheckProblem::new(&format!("params/{}", e.param), e.message))
            });
        placed.err().into_iter().collect()
    }

    async fn init(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let file = self.world_file.get();
        // A file that does not parse will not parse after a restart either.
        let map = self.load_map()?;
        let bodies = self.bodies.get().0.clone();
        // A config naming the wrong modules will not name better ones after a restart.
        check_bodies(ctx.blackboard(), &bodies)
            .await
            .map_err(|e| Unrecoverable(format!("{e:#}")))?;
        let own = [ctx.module().to_string()];
        let names: &[String] = if bodies.is_empty() { &own } else { &bodies };
        let dt = self.dt.value();
        let scale = self.time_scale.value();
        check_params(positive, &[("dt", dt), ("time_scale", scale)])?;
        let timeout = self.command_timeout.value();
        check_params(non_negative, &[("command_timeout_s", timeout)])?;
        let config = self.robot_config()?;
        let seed = self.seed.value() as u64;
        self.camera_config()?;
        let rate = self.camera_rate.value();
        check_params(positive, &[("camera/rate_hz", rate)])?;
        let mut world = World::new(with_victims(map.grid, &map.features.victims), seed);
        let mut ios = Vec::with_capacity(names.len());
        for (rank, name) in names.iter().enumerate() {
            let is_own = bodies.is_empty();
            let start = match is_own {
                true => self.start.get(),
                false => {
                    ctx.blackboard()
                        .get(&format!("{name}/params/start"))
                        .await?
                }
            };
            let start = start_pose(&start, &map.starts, rank, &file, (!is_own).then_some(name))?;
            // A start pose that overlaps will overlap again after a restart.
            let id = world.add_robot(config.clone(), start).map_err(|e| {
                let e = param_error(e, ROBOT_PARAMS);
                Unrecoverable(match is_own {
                    true => e.to_string(),
                    false => format!("placing body `{name}`: {e}"),
                })
            })?;
            ios.push(BodyIo::bind(ctx.blackboard(), name, id, seed).await?);
            tracing::info!(module = ctx.module(), body = %name, ?start, "robot placed");
        }
        self.world_goals.set(
            map.goals
                .iter()
                .map(|g| g.position())
                .collect::<Vec<_>>()
                .into(),
        );
        self.world_victims.set(map.features.victims.clone().into());
        let flat = |rects: &[crate::sim::Rect]| {
            rects
                .iter()
                .flat_map(|r| [r.x0, r.y0, r.x1, r.y1])
                .collect::<Vec<f64>>()
        };
        self.dark_areas.set(flat(&map.features.dark));
        self.rough_areas.set(flat(&map.features.rough));
        if bodies.is_empty() {
            self.pose.set(world.pose(0).unwrap_or_default());
        }
        tracing::info!(module = ctx.module(), world = %file, robots = ios.len(), "world loaded");
        super::png_folder(&self.png.get())?;
        let members = ctx.blackboard().any_handle("_team/members").await.ok();
        // An instance started again after a restart or a move goes on where the last one
        // stopped, not with every robot back at its start at time 0. The memory is used once:
        // an instance that failed left none, and starts over.
        let saved = self.saved_world.get();
        if saved.time > 0.0 {
            match world.restore(&saved) {
                Ok(()) => tracing::info!(module = ctx.module(), t = saved.time, "world resumed"),
                Err(e) => tracing::warn!(module = ctx.module(), "world not resumed: {e}"),
            }
            self.saved_world.set(WorldState::default());
        }
        let tracks = match self.saved_tracks.get() {
            saved if saved.is_of(names) => (*saved).clone(),
            _ => Tracks::new(names),
        };
        self.saved_tracks.set(Tracks::default());
        self.sim = Some(Sim {
            tracks,
            members: members.map(|h| (h, u64::MAX)),
            world,
            bodies: ios,
            dt,
            owed: 0.0,
            last_wake: ctx.now(),
            features: map.features,
        });
        Ok(())
    }

    async fn cleanup(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        // The picture is of the whole run: drawn when it ends, not at a restart or a move,
        // where the next instance goes on from the world and tracks kept here.
        match (ctx.restarting(), &self.sim) {
            (true, Some(sim)) => {
                self.saved_world.set(sim.world.state());
                self.saved_tracks.set(sim.tracks.clone());
                Ok(())
            }
            (true, None) => Ok(()),
            (false, _) => self.picture(),
        }
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let camera = match self.camera_enabled.value() {
            true => Some((self.camera_config()?, self.camera_rate.value())),
            false => None,
        };
        let deterministic = self.deterministic.value();
        let (scale, timeout) = (self.time_scale.value(), self.command_timeout.value());
        let sim = super::initialized(&mut self.sim);
        let steps = sim.steps_due(ctx.now(), deterministic, scale);
        sim.note_departures();
        sim.take_commands(timeout)?;
        let multi_robot = !self.bodies.get().0.is_empty();
        for k in 0..steps {
            // Catching up with the wall clock: each simulation step reaches the modules that
            // read it before the next, stamped later than what they wrote meanwhile, as if
            // the steps had come on time (a localizer or mapper pairing a scan with its
            // step's odometry or pose goes by these stamps).
            let stamp = match k {
                0 => ctx.now(),
                _ => {
                    ctx.settle_agent().await;
                    Instant::now()
                }
            };
            sim.step(stamp, camera.as_ref())?;
            if multi_robot {
                // The world's own clock, for tools and evaluators of a multi-robot world.
                self.sim_time.set(sim.world.time());
            }
        }
        Ok(())
    }
}

impl SimWorld {
    /// Writes `params/png` and says which colour is whose (the end of a run, or a restart).
    fn picture(&self) -> anyhow::Result<()> {
        let (Some(sim), png) = (self.sim.as_ref(), self.png.get()) else {
            return Ok(());
        };
        if png.is_empty() {
            return Ok(());
        }
        sim.tracks
            .save(
                std::path::Path::new(png.as_str()),
                sim.world.grid(),
                &sim.features,
            )
            .map_err(|e| anyhow::anyhow!("cannot write params/png `{png}`: {e}"))?;
        petrel_actors::outln!("robots' trajectories {png}\n{}", sim.tracks.legend());
        Ok(())
    }
}
