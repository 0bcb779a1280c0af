//! `nav.localizer`: odometry in, estimated pose out, with the simulated localization error.

use anyhow::bail;
use petrel_actors::{
    Context, Input, Module, Output, Ports, Pose2, QueueReader, QueueWriter, Schedule,
};

use super::param_error;
use crate::nav::{Localizer, LocalizerParams};
use crate::sim::Odometry;

/// `nav.localizer`: wraps [`Localizer`].
pub struct LocalizerModule {
    odometry: QueueReader<Pose2>,
    sim_time: Input<f64>,
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
    core: Option<Localizer>,
}

impl Module for LocalizerModule {
    const TYPE: &'static str = "nav.localizer";
    const DESCRIPTION: &'static str =
        "Estimates the robot pose from odometry, with configurable drift and lost episodes.";

    fn declare(ports: &mut Ports) -> Self {
        LocalizerModule {
            odometry: ports.queue_in("in/odometry", "odometric poses"),
            sim_time: ports.input(
                "in/simTime",
                0.0,
                "current (simulated) time, s: times the drift and lost episodes",
            ),
            drift_per_meter: ports.param(
                "params/drift_per_meter",
                0.0,
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
            lost_drift_speed: ports.param(
                "params/lost_drift_speed",
                0.3,
                "position error growth while lost, m/s",
            ),
            lost_heading_rate: ports.param(
                "params/lost_heading_rate",
                0.1,
                "heading error growth while lost, rad/s",
            ),
            recovery_time: ports.param(
                "params/recovery_time",
                2.0,
                "time constant of error decay outside episodes, s (0 = never recovers)",
            ),
            quality_scale: ports.param(
                "params/quality_scale",
                0.3,
                "position error at which quality is 1/e, m",
            ),
            heading_quality_scale: ports.param(
                "params/heading_quality_scale",
                0.3,
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
                "localization quality, 0 (lost) .. 1 (perfect)",
            ),
            lost: ports.output("out/lost", false, "inside a lost episode"),
            core: None,
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::new().on_items(&self.odometry)
    }

    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
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
        self.core = Some(Localizer::new(params).map_err(|e| param_error(e, &[]))?);
        Ok(())
    }

    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let core = self
            .core
            .as_mut()
            .expect("stepping only after a successful init");
        // Items carry no simulated time; a batch is at most a few steps old, so all of it is
        // stamped with the current time (drift depends on distance, not on these stamps).
        let stamp = self.sim_time.value();
        let mut last = None;
        for item in self.odometry.drain() {
            let out = core.step(Odometry {
                stamp,
                pose: *item.value,
            });
            self.estimates.push(out.pose);
            last = Some(out);
        }
        if let Some(out) = last {
            self.estimate.set(out.pose);
            self.quality.set(out.quality);
            if out.lost != self.lost.value() {
                self.lost.set(out.lost);
            }
        }
        Ok(())
    }
}
