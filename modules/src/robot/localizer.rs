//! `nav.localizer`: odometry in, estimated pose out; either odometry with a simulated error
//! ([`Localizer`]) or odometry corrected by scan matching ([`ScanLocalizer`]).

use std::collections::VecDeque;

use anyhow::bail;
use petrel_actors::{
    AgentView, CheckProblem, Context, Input, Item, LaserScan, Module, Output, Point2, Ports, Pose2,
    QueueReader, QueueWriter, Range, Schedule,
};

use super::param_error;
use crate::nav::{Localizer, LocalizerParams, ScanLocalizer, ScanMatcherParams};
use crate::sim::Odometry;

/// Scans kept waiting for the odometry of their step before being matched anyway.
const MAX_PENDING_SCANS: usize = 4;

/// The estimator chosen by `params/scan_matching`.
enum Core {
    Simulated(Localizer),
    ScanMatching(ScanLocalizer),
}

/// `nav.localizer`: wraps [`Localizer`].
pub struct LocalizerModule {
    odometry: QueueReader<Pose2>,
    scans: QueueReader<LaserScan>,
    sim_time: Input<f64>,
    scan_matching: Input<bool>,
    resolution: Input<f64>,
    size: Input<Point2>,
    origin: Input<Point2>,
    laser_mount: Input<Pose2>,
    lost_below: Input<f64>,
    drift_per_meter: Input<f64>,
    drift_direction: Input<f64>,
    lost_episodes: Input<Vec<f64>>,
    lost_drift_speed: Input<f64>,
    lost_heading_rate: Input<f64>,
    recovery_time: Input<f64>,
    quality_scale: Input<f64>,
    heading_quality_scale: Input<f64>,
    estimate: Output<Pose2>,
    estimates: QueueWriter<Pose2>,
    quality: Output<f64>,
    lost: Output<bool>,
    pending_scans: VecDeque<Item<LaserScan>>,
    /// Push time of the latest odometry sample used.
    odometry_stamp: Option<tokio::time::Instant>,
    core: Option<Core>,
}

impl LocalizerModule {
    /// The core the parameters ask for, or what is wrong with them.
    fn build_core(&self) -> anyhow::Result<Core> {
        let episodes = self.lost_episodes.get();
        if episodes.len() % 2 != 0 {
            bail!("invalid parameter `params/lost_episodes`: expected pairs `[start1, end1, ...]`, got {} numbers", episodes.len());
        }
        let recovery = self.recovery_time.value();
        let params = LocalizerParams {
            drift_per_meter: self.drift_per_meter.value(),
            drift_direction: self.drift_direction.value(),
            lost_episodes: episodes.chunks(2).map(|p| (p[0], p[1])).collect(),
            lost_drift_speed: self.lost_drift_speed.value(),
            lost_heading_rate: self.lost_heading_rate.value(),
            recovery_time: (recovery != 0.0).then_some(recovery),
            quality_scale: self.quality_scale.value(),
            heading_quality_scale: self.heading_quality_scale.value(),
        };
        if !self.scan_matching.value() {
            let core = Localizer::new(params).map_err(|e| param_error(e, &[]))?;
            return Ok(Core::Simulated(core));
        }
        if params != LocalizerParams::default() {
            bail!("`params/scan_matching` is true: the simulated error parameters (drift_per_meter, drift_direction, lost_episodes, lost_*, recovery_time, *quality_scale) do not apply; remove them");
        }
        let lost_below = self.lost_below.value();
        if !(0.0..=1.0).contains(&lost_below) {
            bail!(
                "invalid parameter `params/lost_below`: expected a number in [0, 1], got {}",
                petrel_actors::short_number(lost_below)
            );
        }
        let (res, size, origin) = (
            self.resolution.value(),
            self.size.value(),
            self.origin.value(),
        );
        let (width, height) = super::grid_cells(res, size)?;
        let matcher = ScanMatcherParams {
            width,
            height,
            resolution: res,
            origin: (origin.0.x, origin.0.y),
            laser_mount: self.laser_mount.value(),
            ..ScanMatcherParams::default()
        };
        let core = ScanLocalizer::new(matcher).map_err(|e| param_error(e, &[]))?;
        Ok(Core::ScanMatching(core))
    }
}

impl Module for LocalizerModule {
    const TYPE: &'static str = "nav.localizer";
    const DESCRIPTION: &'static str =
        "Estimates the robot pose from odometry, corrected by scan matching or with simulated drift and lost episodes.";

    fn declare(ports: &mut Ports) -> Self {
        let module = LocalizerModule {
            odometry: ports.queue_in("in/odometry", "odometric poses"),
            scans: ports.queue_in(
                "in/laserScan",
                "laser scans, matched against the map being built (with params/scan_matching)",
            ),
            scan_matching: ports.param(
                "params/scan_matching",
                false,
                "correct odometry by matching laser scans (true) or simulate drift (false)",
            ),
            resolution: ports.param_in(
                "params/resolution",
                0.05,
                Range::new(0.01, 1.0),
                "scan matching: cell size of the likelihood field, m",
            ),
            size: ports.param(
                "params/size",
                Point2::new(20.0, 20.0),
                "scan matching: extent of the field (x: width, y: height), m",
            ),
            origin: ports.param(
                "params/origin",
                Point2::new(0.0, 0.0),
                "scan matching: world position of the field's lower-left corner",
            ),
            laser_mount: ports.param(
                "params/laser_mount",
                Pose2::default(),
                "scan matching: laser pose in the robot frame",
            ),
            lost_below: ports.param_in(
                "params/lost_below",
                0.3,
                Range::new(0.0, 1.0),
                "scan matching: out/lost while the scan fit (out/quality) is below this, 0..1",
            ),
            sim_time: ports.input(
                "in/simTime",
                0.0,
                "current (simulated) time, s: times the drift and lost episodes",
            ),
            drift_per_meter: ports.param_in(
                "params/drift_per_meter",
                0.0,
                Range::new(0.0, 1.0),
                "position error added per metre travelled, m/m",
            ),
            drift_direction: ports.param(
                "params/drift_direction",
                0.0,
                "world direction of that drift, rad",
            ),
            lost_episodes: ports.param(
                "params/lost_episodes",
                Vec::new(),
                "times when localization is lost, `[start1, end1, start2, end2, ...]` in s",
            ),
            lost_drift_speed: ports.param_in(
                "params/lost_drift_speed",
                0.3,
                Range::new(0.0, 10.0),
                "position error growth while lost, m/s",
            ),
            lost_heading_rate: ports.param_in(
                "params/lost_heading_rate",
                0.1,
                Range::new(0.0, 10.0),
                "heading error growth while lost, rad/s",
            ),
            recovery_time: ports.param_in(
                "params/recovery_time",
                2.0,
                Range::new(0.0, 1e6),
                "time constant of error decay outside episodes, s (0 = never recovers)",
            ),
            quality_scale: ports.param_in(
                "params/quality_scale",
                0.3,
                Range::new(0.001, 100.0),
                "position error at which quality is 1/e, m",
            ),
            heading_quality_scale: ports.param_in(
                "params/heading_quality_scale",
                0.3,
                Range::new(0.001, 100.0),
                "heading error at which quality is 1/e, rad",
            ),
            estimate: ports.output(
                "out/estimatedPose",
                Pose2::default(),
                "latest estimated pose",
            ),
            estimates: ports.queue_out(
                "out/estimatedPoses",
                64,
                "every estimated pose, as a stream",
            ),
            quality: ports.output(
                "out/quality",
                1.0,
                "localization quality, 0 (lost) .. 1 (perfect); written when it changes",
            ),
            lost: ports.output(
                "out/lost",
                false,
                "inside a lost episode, or scan fit below params/lost_below",
            ),
            pending_scans: VecDeque::new(),
            odometry_stamp: None,
            core: None,
        };
        // Read only by `init`: a running agent refuses new values for these.
        ports.read_at_start(&[
            "params/scan_matching",
            "params/resolution",
            "params/size",
            "params/origin",
            "params/laser_mount",
            "params/drift_per_meter",
            "params/drift_direction",
            "params/lost_episodes",
            "params/lost_drift_speed",
            "params/lost_heading_rate",
            "params/recovery_time",
            "params/quality_scale",
            "params/heading_quality_scale",
        ]);
        module
    }

    fn schedule(&self) -> Schedule {
        Schedule::new()
            .on_items(&self.odometry)
            .on_items(&self.scans)
    }

    /// Parameters valid alone but not together: `petrel check` says so before anything runs.
    fn check(&self, _agent: &AgentView) -> Vec<CheckProblem> {
        super::check_built(self.build_core())
    }

    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        self.core = Some(self.build_core()?);
        Ok(())
    }

    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        match super::initialized(&mut self.core) {
            Core::Simulated(core) => {
                // Items carry no simulated time; a batch is at most a few steps old, so all of
                // it is stamped with the current time (drift depends on distance, not on
                // these stamps).
                let stamp = self.sim_time.value();
                let mut last = None;
                for item in self.odometry.drain() {
                    let out = core.step(Odometry {
                        stamp,
                        pose: *item.value,
                    });
                    self.estimates.push(out.pose);
                    last = Some((out.pose, out.quality, out.lost));
                }
                if let Some(out) = last {
                    self.publish(out);
                }
            }
            Core::ScanMatching(core) => {
                // A scan is matched at the odometry of its own simulation step (same push
                // time); one that arrives first waits for it, a few at most.
                self.pending_scans.extend(self.scans.drain());
                let mut moved = false;
                for item in self.odometry.drain() {
                    // Scans older than this sample belong to steps already integrated.
                    while self
                        .pending_scans
                        .front()
                        .is_some_and(|s| s.stamp < item.stamp)
                    {
                        let scan = self.pending_scans.pop_front().expect("peeked");
                        core.scan(&scan.value);
                    }
                    let pose = core.odometry(*item.value);
                    self.odometry_stamp = Some(item.stamp);
                    self.estimates.push(pose);
                    moved = true;
                }
                while let Some(scan) = self.pending_scans.front() {
                    let due = self.odometry_stamp.is_some_and(|t| scan.stamp <= t);
                    if !due && self.pending_scans.len() <= MAX_PENDING_SCANS {
                        break;
                    }
                    let scan = self.pending_scans.pop_front().expect("peeked");
                    core.scan(&scan.value);
                    moved = true;
                }
                if moved {
                    let quality = core.quality();
                    let out = (core.pose(), quality, quality < self.lost_below.value());
                    self.publish(out);
                }
            }
        }
        Ok(())
    }
}

impl LocalizerModule {
    fn publish(&mut self, (pose, quality, lost): (Pose2, f64, bool)) {
        self.estimate.set(pose);
        self.quality.set_if_changed(quality);
        self.lost.set_if_changed(lost);
    }
}
