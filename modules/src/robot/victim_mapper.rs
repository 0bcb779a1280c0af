//! `vision.victim_mapper`: detections + estimated pose in, victims in the map frame out.

use anyhow::anyhow;
use petrel_actors::team::Message;
use petrel_actors::types::Path2;
use petrel_actors::{Context, Input, Module, Output, Ports, Pose2, QueueWriter, Schedule};

use super::count;
use crate::vision::{Detections, VictimMap, VictimMapParams};

/// `vision.victim_mapper`: wraps [`VictimMap`].
pub struct VictimMapper {
    detections: Input<Detections>,
    robot: Input<Pose2>,
    merge_radius: Input<f64>,
    confirm_hits: Input<i64>,
    min_confidence: Input<f64>,
    max_range: Input<f64>,
    report_to: Input<String>,
    victims: Output<Path2>,
    found: Output<i64>,
    outbox: QueueWriter<Message>,
    core: Option<VictimMap>,
}

impl Module for VictimMapper {
    const TYPE: &'static str = "vision.victim_mapper";
    const DESCRIPTION: &'static str =
        "Turns repeated victim detections and the robot pose into de-duplicated victim positions in the map frame.";

    fn declare(ports: &mut Ports) -> Self {
        VictimMapper {
            detections: ports.input(
                "in/detections",
                Detections::default(),
                "detections of the latest frame",
            ),
            robot: ports.input(
                "in/robotPose",
                Pose2::default(),
                "estimated robot pose (camera at its centre, looking ahead)",
            ),
            merge_radius: ports.param(
                "params/merge_radius",
                1.5,
                "sightings this close are one victim, m",
            ),
            confirm_hits: ports.param("params/confirm_hits", 3, "sightings that confirm a victim"),
            min_confidence: ports.param(
                "params/min_confidence",
                0.1,
                "weaker detections are ignored, 0..1",
            ),
            max_range: ports.param("params/max_range", 5.0, "farther detections are ignored, m"),
            report_to: ports.param(
                "params/report_to",
                String::new(),
                "`agent/module` told of each victim confirmed (a team's vision.team_victims); empty = nobody",
            ),
            outbox: ports.queue_out(
                "out/outbox",
                64,
                "victims confirmed, as messages to params/report_to",
            ),
            victims: ports.output(
                "out/victims",
                Path2::default(),
                "confirmed victims, map frame, in the order found",
            ),
            found: ports.output("out/found", 0, "confirmed victims"),
            core: None,
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.detections)
    }

    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let params = VictimMapParams {
            merge_radius: self.merge_radius.value(),
            confirm_hits: count("confirm_hits", self.confirm_hits.value())? as u32,
            min_confidence: self.min_confidence.value(),
            max_range: self.max_range.value(),
        };
        params
            .validate()
            .map_err(|e| anyhow!("invalid parameter {e}"))?;
        self.core = Some(VictimMap::new(params));
        Ok(())
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let core = self
            .core
            .as_mut()
            .expect("stepping only after a successful init");
        let pose = self.robot.value();
        let mut confirmed = false;
        for d in &self.detections.get().0 {
            if let Some(p) = core.add(pose, d) {
                confirmed = true;
                println!(
                    "[{}] victim {} confirmed at ({:.2}, {:.2})",
                    ctx.module(),
                    self.found.value() + 1,
                    p.0.x,
                    p.0.y
                );
                self.found.set(self.found.value() + 1);
                let to = self.report_to.get();
                if !to.is_empty() {
                    // `x y` in metres: what vision.team_victims reads.
                    let body = format!("{} {}", p.0.x, p.0.y);
                    let (to, from) = ((*to).clone(), String::new());
                    self.outbox.push(Message { to, from, body });
                }
            }
        }
        // Positions keep improving with every sighting; publish them when a victim is added
        // or every time a confirmed one was seen again.
        let now = core.confirmed();
        if confirmed || (!now.is_empty() && !self.detections.get().0.is_empty()) {
            self.victims.set(now.into());
        }
        Ok(())
    }
}
