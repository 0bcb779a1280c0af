//! `sim.recorder`: watches a run; at the end prints a summary and draws map + trajectory.

use std::path::Path;

use petrel_actors::types::Path2;
use petrel_actors::{
    Context, Input, Module, OccupancyGrid, Output, Point2, Ports, Pose2, Schedule,
};

use crate::sim::render::{save_png, RenderLayers};

/// `sim.recorder`: trajectory, distance, and the end-of-run summary and PNG.
pub struct Recorder {
    pose: Input<Pose2>,
    estimate: Input<Pose2>,
    map: Input<OccupancyGrid>,
    path: Input<Path2>,
    goals: Input<Path2>,
    reached: Input<i64>,
    collisions: Input<i64>,
    sim_time: Input<f64>,
    png: Input<String>,
    sample_m: Input<f64>,
    robot_radius: Input<f64>,
    distance: Output<f64>,
    pose_error: Output<f64>,
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
            collisions: ports.input("in/collisions", 0, "collision count"),
            sim_time: ports.input("in/simTime", 0.0, "simulated time, s"),
            png: ports.param(
                "params/png",
                String::new(),
                "PNG file written at the end (empty = none)",
            ),
            sample_m: ports.param(
                "params/sample_m",
                0.05,
                "spacing of recorded trajectory points, m",
            ),
            robot_radius: ports.param("params/robot_radius", 0.2, "robot radius drawn, m"),
            distance: ports.output("out/distance", 0.0, "distance travelled, m"),
            pose_error: ports.output(
                "out/poseError",
                0.0,
                "distance between in/pose and in/estimatedPose, m (0 while unlinked)",
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
        let p = self.pose.get().position();
        let estimate = self.estimate.read();
        if estimate.version > 0 && !ctx.cause().first() {
            let e = (estimate.value.position().0 - p.0).norm();
            let (sum, n, max) = self.error_stats;
            self.error_stats = (sum + e, n + 1, max.max(e));
            self.pose_error.set(e);
        }
        match self.last {
            // The first pose read may be an unlinked default; the first real one is the start.
            None if ctx.cause().first() => return Ok(()),
            None => self.trajectory.push(p),
            Some(last) => {
                let d = (p.0 - last.0).norm();
                self.distance.set(self.distance.value() + d);
                let sampled = self
                    .trajectory
                    .last()
                    .map_or(f64::INFINITY, |q| (p.0 - q.0).norm());
                if sampled >= self.sample_m.value() {
                    self.trajectory.push(p);
                }
            }
        }
        self.last = Some(p);
        Ok(())
    }

    async fn cleanup(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        if let Some(p) = self.last {
            self.trajectory.push(p);
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
        println!("\n── mission summary ─────────────────────────");
        if !goals.is_empty() {
            println!(
                "goals reached    {} / {}",
                self.reached.value(),
                goals.len()
            );
        }
        println!("path length      {:.1} m", self.distance.value());
        println!("collisions       {}", self.collisions.value());
        if let (sum, n @ 1.., max) = self.error_stats {
            println!(
                "pose error       mean {:.3} m, max {max:.3} m (estimate vs truth)",
                sum / n as f64
            );
        }
        println!("sim time         {sim:.1} s");
        println!(
            "wall time        {wall:.1} s ({:.1}x real time)",
            sim / wall.max(1e-9)
        );
        let png = self.png.get();
        if !png.is_empty() {
            let path = self.path.get();
            let layers = RenderLayers {
                trajectory: &self.trajectory,
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
            };
            save_png(Path::new(png.as_str()), &self.map.get(), &layers)
                .map_err(|e| anyhow::anyhow!("cannot write params/png `{png}`: {e}"))?;
            println!("map + trajectory {png}");
        }
        Ok(())
    }
}
