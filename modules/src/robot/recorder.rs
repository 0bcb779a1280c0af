//! `sim.recorder`: watches a run; at the end prints a summary and draws map + trajectory.

use std::path::Path;

use petrel_actors::types::Path2;
use petrel_actors::{
    Context, Input, Module, OccupancyGrid, Output, Point2, Ports, Pose2, Range, Schedule,
};

use crate::sim::context_log::ContextLog;
use crate::sim::render::{save_png, RenderLayers};
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
    /// Simulated time of the last progress line.
    last_progress: f64,
    dark: Input<Vec<f64>>,
    rough: Input<Vec<f64>>,
    searched: Input<OccupancyGrid>,
    context_log: ContextLog,
    /// Colour of each trajectory point (the highest-priority active context).
    colours: Vec<[u8; 3]>,
    collisions: Input<i64>,
    sim_time: Input<f64>,
    png: Input<String>,
    sample_m: Input<f64>,
    robot_radius: Input<f64>,
    distance: Output<f64>,
    pose_error: Output<f64>,
    pose_error_max: Output<f64>,
    /// Sum, count and maximum of the localization error samples.
    error_stats: (f64, u64, f64),
    trajectory: Vec<Point2>,
    last: Option<Point2>,
    started: Option<std::time::Instant>,
}

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
            last_progress: 0.0,
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
            context_log: ContextLog::default(),
            colours: Vec::new(),
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
            error_stats: (0.0, 0, 0.0),
            trajectory: Vec::new(),
            last: None,
            started: None,
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.pose)
    }

    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let png = self.png.get();
        if let Some(dir) = Path::new(png.as_str())
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
        {
            std::fs::create_dir_all(dir).map_err(|e| {
                anyhow::anyhow!(
                    "params/png is `{png}`, but its folder {} cannot be created: {e}",
                    dir.display()
                )
            })?;
        }
        self.started = Some(std::time::Instant::now());
        Ok(())
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        self.context_log
            .update(self.sim_time.value(), &self.contexts.get());
        let p = self.pose.get().position();
        let estimate = self.estimate.read();
        if estimate.version > 0 && !ctx.cause().first() {
            let e = (estimate.value.position().0 - p.0).norm();
            let (sum, n, max) = self.error_stats;
            self.error_stats = (sum + e, n + 1, max.max(e));
            self.pose_error.set(e);
            if e > self.pose_error_max.value() {
                self.pose_error_max.set(e);
            }
        }
        match self.last {
            // The first pose read may be an unlinked default; the first real one is the start.
            None if ctx.cause().first() => return Ok(()),
            None => self.record(p),
            Some(last) => {
                let d = (p.0 - last.0).norm();
                self.distance.set(self.distance.value() + d);
                let sampled = self
                    .trajectory
                    .last()
                    .map_or(f64::INFINITY, |q| (p.0 - q.0).norm());
                if sampled >= self.sample_m.value() {
                    self.record(p);
                }
            }
        }
        self.last = Some(p);
        let t = self.sim_time.value();
        let every = self.progress_s.value();
        if every > 0.0 && t - self.last_progress >= every {
            self.last_progress = t;
            self.progress(t);
        }
        Ok(())
    }

    async fn cleanup(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if let Some(p) = self.last {
            self.record(p);
        }
        // The summary is the run's, printed when it ends, not at a restart or a move.
        if ctx.restarting() {
            return Ok(());
        }
        let wall = self.started.map_or(0.0, |s| s.elapsed().as_secs_f64());
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
        let totals = self.context_log.totals(sim);
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
        if let (sum, n @ 1.., max) = self.error_stats {
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
        if !png.is_empty() {
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
                trajectory: &self.trajectory,
                // Without contexts, the trajectory shows time instead (blue to orange).
                trajectory_colours: match totals.is_empty() {
                    true => &[],
                    false => &self.colours,
                },
                areas: &areas,
                searched: Some(&searched),
                victims: &victims,
                reported: found.points(),
                path: path.points(),
                goals: &goals,
                reached: self.reached.value().max(0) as usize,
                robot: self.last.map(|p| {
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

    /// Appends a trajectory point, coloured by the highest-priority active context.
    fn record(&mut self, p: Point2) {
        let active = self.contexts.get();
        let top = active.split(',').map(str::trim).find(|s| !s.is_empty());
        let colour = top.map_or(NO_CONTEXT, |name| {
            context_colour(name, self.context_log.index(name).unwrap_or(0))
        });
        self.trajectory.push(p);
        self.colours.push(colour);
    }
}

/// For each true victim, the distance to the found one matched to it (greedy by distance,
/// each found victim used once, within `radius`), or `None` when it was missed.
pub(crate) fn match_victims(truth: &[Point2], found: &[Point2], radius: f64) -> Vec<Option<f64>> {
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for (i, t) in truth.iter().enumerate() {
        for (j, f) in found.iter().enumerate() {
            let d = (t.0 - f.0).norm();
            if d <= radius {
                pairs.push((d, i, j));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out = vec![None; truth.len()];
    let mut used = vec![false; found.len()];
    for (d, i, j) in pairs {
        if out[i].is_none() && !used[j] {
            out[i] = Some(d);
            used[j] = true;
        }
    }
    out
}
