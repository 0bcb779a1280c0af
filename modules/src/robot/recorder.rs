//! `sim.recorder`: watches a run; at the end prints a summary and draws map + trajectory.

use std::path::Path;

use petrel_actors::types::Path2;
use petrel_actors::{
    Context, Input, Module, OccupancyGrid, Output, Point2, Ports, Pose2, Range, Schedule,
};

use crate::sim::render::{save_png, RenderLayers};
use crate::sim::run_record::{match_victims, RunRecord};
use crate::sim::Rect;

/// Trajectory colour while no context is active.
const NO_CONTEXT: [u8; 3] = [60, 110, 230];

/// Trajectory colour of a context: fixed for the rescue robot's contexts, cycling otherwise.
fn context_colour(name: &str, index: usize) -> [u8; 3] {
    match name {
        "lost" => [220, 20, 20],
        "dark" => [130, 60, 200],
        "rough" => [150, 95, 30],
        "crowded" => [245, 150, 0],
        "victim_seen" => [20, 170, 90],
        _ => [[0, 160, 200], [200, 0, 150], [110, 110, 110]][index % 3],
    }
}

/// `sim.recorder`: trajectory, distance, and the end-of-run summary and PNG.
pub struct Recorder {
    pose: Input<Pose2>,
    estimate: Input<Pose2>,
    map: Input<OccupancyGrid>,
    path: Input<Path2>,
    goals: Input<Path2>,
    reached: Input<i64>,
    victims: Input<Path2>,
    true_victims: Input<Path2>,
    explored: Input<f64>,
    contexts: Input<String>,
    activity: Input<String>,
    progress_s: Input<f64>,
    dark: Input<Vec<f64>>,
    rough: Input<Vec<f64>>,
    searched: Input<OccupancyGrid>,
    collisions: Input<i64>,
    sim_time: Input<f64>,
    png: Input<String>,
    sample_m: Input<f64>,
    robot_radius: Input<f64>,
    distance: Output<f64>,
    pose_error: Output<f64>,
    pose_error_max: Output<f64>,
    /// The run so far, kept in `saved` (see [`SAVE_EVERY_S`]).
    record: RunRecord,
    saved: Output<RunRecord>,
    /// Simulated time of the latest save.
    saved_at: f64,
    started: Option<std::time::Instant>,
}

/// Simulated seconds between saves of the record to `state/run`: what a crash can lose (a
/// restart or a move saves it first). Not at every step: the trajectory grows all run long.
const SAVE_EVERY_S: f64 = 5.0;

impl Module for Recorder {
    const TYPE: &'static str = "sim.recorder";
    const DESCRIPTION: &'static str =
        "Records the trajectory; at the end prints a summary and writes a PNG of map and trajectory.";

    fn declare(ports: &mut Ports) -> Self {
        Recorder {
            pose: ports.input(
                "in/pose",
                Pose2::default(),
                "robot pose to record (ground truth in simulation)",
            ),
            estimate: ports.input(
                "in/estimatedPose",
                Pose2::default(),
                "estimated pose: when linked, the error to in/pose is tracked and summarized",
            ),
            map: ports.input(
                "in/map",
                OccupancyGrid::default(),
                "map to draw under the trajectory",
            ),
            path: ports.input("in/path", Path2::default(), "planned path to draw"),
            goals: ports.param(
                "params/goals",
                Path2::default(),
                "goals to draw (link it to the sequencer's params/goals)",
            ),
            reached: ports.input("in/reached", 0, "goals reached"),
            victims: ports.input("in/victims", Path2::default(), "victims found (map frame)"),
            true_victims: ports.input(
                "in/trueVictims",
                Path2::default(),
                "the world's victims (ground truth): found ones are matched to them within 1 m",
            ),
            explored: ports.input("in/explored", 0.0, "explored (known) area, m²"),
            contexts: ports.input(
                "in/contexts",
                String::new(),
                "active contexts, highest priority first (link to contexts/out/active)",
            ),
            activity: ports.input(
                "in/activity",
                String::new(),
                "what the robot is doing, for progress lines (link to a mission's out/running)",
            ),
            progress_s: ports.param_in(
                "params/progress_s",
                0.0,
                Range::new(0.0, 1e7),
                "print a progress line every this many simulated seconds (0 = none)",
            ),
            dark: ports.input(
                "in/darkAreas",
                Vec::new(),
                "dark areas to tint, `[x0, y0, x1, y1, ...]`",
            ),
            rough: ports.input(
                "in/roughAreas",
                Vec::new(),
                "rough floor to tint, `[x0, y0, x1, y1, ...]`",
            ),
            searched: ports.input("in/searched", OccupancyGrid::default(), "optional: the floor the camera searched (nav.searched's out/searched); free floor not searched is tinted"),
            collisions: ports.input("in/collisions", 0, "collision count"),
            sim_time: ports.input("in/simTime", 0.0, "simulated time, s"),
            png: ports.param(
                "params/png",
                String::new(),
                "PNG file written at the end (empty = none)",
            ),
            sample_m: ports.param_in(
                "params/sample_m",
                0.05,
                Range::new(0.001, 100.0),
                "spacing of recorded trajectory points, m",
            ),
            robot_radius: ports.param_in(
                "params/robot_radius",
                0.2,
                Range::new(0.01, 5.0),
                "robot radius drawn, m",
            ),
            distance: ports.output("out/distance", 0.0, "distance travelled, m"),
            pose_error: ports.output(
                "out/poseError",
                0.0,
                "distance between in/pose and in/estimatedPose, m (0 while unlinked)",
            ),
            pose_error_max: ports.output(
                "out/poseErrorMax",
                0.0,
                "largest out/poseError so far, m",
            ),
            record: RunRecord::default(),
            saved: ports.state("state/run", RunRecord::default(), "trajectory, contexts and pose errors so far: a restarted recorder goes on with them"),
            saved_at: f64::NEG_INFINITY,
            started: None,
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.pose)
    }

    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        super::png_folder(&self.png.get())?;
        self.started = Some(std::time::Instant::now());
        self.record = (*self.saved.get()).clone();
        Ok(())
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let t = self.sim_time.value();
        self.record.contexts.update(t, &self.contexts.get());
        let pose = self.pose.read();
        let p = pose.value.position();
        let estimate = self.estimate.read();
        if estimate.version > 0 && !ctx.cause().first() {
            let e = (estimate.value.position().0 - p.0).norm();
            self.record.error(e);
            self.pose_error.set(e);
            if e > self.pose_error_max.value() {
                self.pose_error_max.set(e);
            }
        }
        // A pose never written is the declared default, not where the robot is (a replay
        // writes the first one after the recorder's first steps): the first real one is the
        // start.
        if self.record.last.is_none() && (pose.version == 0 || ctx.cause().first()) {
            return Ok(());
        }
        let colour = self.colour();
        let d = self.record.moved(p, self.sample_m.value(), colour);
        if d > 0.0 {
            self.distance.set(self.distance.value() + d);
        }
        if self.record.progress_due(t, self.progress_s.value()) {
            self.progress(t);
        }
        if t - self.saved_at >= SAVE_EVERY_S {
            self.save(t);
        }
        Ok(())
    }

    async fn cleanup(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        // The summary is the run's, printed when it ends, not at a restart or a move: the
        // next instance goes on with the record.
        if ctx.restarting() {
            self.save(self.sim_time.value());
            return Ok(());
        }
        if let Some(p) = self.record.last {
            let colour = self.colour();
            self.record.sample(p, colour);
        }
        let wall =
            self.record.wall_before + self.started.map_or(0.0, |s| s.elapsed().as_secs_f64());
        let sim = self.sim_time.value();
        let goals: Vec<Pose2> = self
            .goals
            .get()
            .points()
            .iter()
            .map(|g| Pose2::new(g.0.x, g.0.y, 0.0))
            .collect();
        petrel_actors::outln!("\n── mission summary ─────────────────────────");
        if !goals.is_empty() {
            petrel_actors::outln!(
                "goals reached    {} / {}",
                self.reached.value(),
                goals.len()
            );
        }
        let truth = self.true_victims.get();
        if !truth.points().is_empty() {
            let found = self.victims.get();
            let matched = match_victims(truth.points(), found.points(), 1.0);
            let errors: Vec<String> = matched
                .iter()
                .flatten()
                .map(|e| format!("{e:.2}"))
                .collect();
            petrel_actors::outln!(
                "victims found    {} / {} (position errors {} m; {} false)",
                errors.len(),
                truth.points().len(),
                if errors.is_empty() {
                    "-".to_string()
                } else {
                    errors.join(", ")
                },
                found.points().len().saturating_sub(errors.len())
            );
            for (v, e) in truth.points().iter().zip(&matched) {
                if e.is_none() {
                    petrel_actors::outln!("  missed victim  ({:.2}, {:.2})", v.0.x, v.0.y);
                }
            }
        }
        let totals = self.record.contexts.totals(sim);
        if !totals.is_empty() {
            petrel_actors::outln!("contexts         (switches on, time active)");
            for (name, on, secs) in &totals {
                petrel_actors::outln!("  {name:<14} {on:>3}x  {secs:6.1} s");
            }
        }
        let explored = self.explored.value();
        if explored > 0.0 {
            petrel_actors::outln!("explored area    {explored:.0} m²");
        }
        petrel_actors::outln!("path length      {:.1} m", self.distance.value());
        petrel_actors::outln!("collisions       {}", self.collisions.value());
        if let (sum, n @ 1.., max) = self.record.errors {
            petrel_actors::outln!(
                "pose error       mean {:.3} m, max {max:.3} m (estimate vs truth)",
                sum / n as f64
            );
        }
        petrel_actors::outln!("sim time         {sim:.1} s");
        petrel_actors::outln!(
            "wall time        {wall:.1} s ({:.1}x real time)",
            sim / wall.max(1e-9)
        );
        let png = self.png.get();
        // A run that ended before any pose (a replay refused at its start) has no picture to
        // draw: an empty one would replace the last run's.
        if !png.is_empty() && self.record.last.is_none() {
            petrel_actors::outln!("no pose recorded: {} not written", png.as_str());
        } else if !png.is_empty() {
            let path = self.path.get();
            let rects = |flat: &[f64], tint: [u8; 3]| -> Vec<(Rect, [u8; 3])> {
                flat.chunks_exact(4)
                    .filter_map(|c| Rect::from_corners([c[0], c[1], c[2], c[3]]).ok())
                    .map(|r| (r, tint))
                    .collect()
            };
            let mut areas = rects(&self.dark.get(), [40, 20, 90]);
            areas.extend(rects(&self.rough.get(), [150, 95, 30]));
            let truth = self.true_victims.get();
            let found = self.victims.get();
            let matched = match_victims(truth.points(), found.points(), 1.0);
            let victims: Vec<(Point2, bool)> = truth
                .points()
                .iter()
                .zip(&matched)
                .map(|(v, m)| (*v, m.is_some()))
                .collect();
            let searched = self.searched.get();
            let layers = RenderLayers {
                trajectory: &self.record.trajectory,
                // Without contexts, the trajectory shows time instead (blue to orange).
                trajectory_colours: match totals.is_empty() {
                    true => &[],
                    false => &self.record.colours,
                },
                areas: &areas,
                searched: Some(&searched),
                victims: &victims,
                reported: found.points(),
                path: path.points(),
                goals: &goals,
                reached: self.reached.value().max(0) as usize,
                robot: self.record.last.map(|p| {
                    (
                        Pose2::new(p.0.x, p.0.y, self.pose.get().theta()),
                        self.robot_radius.value(),
                    )
                }),
                scale: None,
                tracks: &[],
            };
            save_png(Path::new(png.as_str()), &self.map.get(), &layers)
                .map_err(|e| anyhow::anyhow!("cannot write params/png `{png}`: {e}"))?;
            petrel_actors::outln!("map + trajectory {png}");
            if !totals.is_empty() {
                let legend: Vec<String> = totals
                    .iter()
                    .enumerate()
                    .map(|(i, (n, _, _))| format!("{n} {:?}", context_colour(n, i)))
                    .collect();
                petrel_actors::outln!(
                    "  trajectory colour by context: none {NO_CONTEXT:?}, {}",
                    legend.join(", ")
                );
            }
        }
        Ok(())
    }
}

impl Recorder {
    /// One progress line: simulated time, share of the map known, victims found, what the
    /// robot is doing, active contexts.
    fn progress(&self, t: f64) {
        let map = self.map.get();
        let area = map.width as f64 * map.height as f64 * map.resolution * map.resolution;
        let mut line = format!("[{}] t = {t:6.1} s", "progress");
        if area > 0.0 {
            line += &format!("  explored {:3.0} %", 100.0 * self.explored.value() / area);
        }
        let truth = self.true_victims.get().points().len();
        if truth > 0 {
            line += &format!("  victims {} / {truth}", self.victims.get().points().len());
        }
        let activity = self.activity.get();
        if !activity.is_empty() {
            line += &format!("  doing: {activity}");
        }
        let contexts = self.contexts.get();
        line += &format!(
            "  contexts: {}",
            if contexts.is_empty() {
                "-"
            } else {
                contexts.as_str()
            }
        );
        petrel_actors::outln!("{line}");
    }

    /// The colour of a trajectory point now: that of the highest-priority active context.
    fn colour(&self) -> [u8; 3] {
        let active = self.contexts.get();
        let top = active.split(',').map(str::trim).find(|s| !s.is_empty());
        top.map_or(NO_CONTEXT, |name| {
            context_colour(name, self.record.contexts.index(name).unwrap_or(0))
        })
    }

    /// Keeps the record in `state/run`, with this instance's wall time so far.
    fn save(&mut self, t: f64) {
        let mut saved = self.record.clone();
        saved.wall_before += self.started.map_or(0.0, |s| s.elapsed().as_secs_f64());
        self.saved.set(saved);
        self.saved_at = t;
    }
}
