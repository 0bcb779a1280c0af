//! `vision.victim_mapper`: detections + estimated pose in, victims in the map frame out, and
//! the one a mission handles now (its target, report and dismiss).

use anyhow::anyhow;
use petrel_actors::team::Message;
use petrel_actors::types::Path2;
use petrel_actors::{Context, Input, Module, Output, Ports, Pose2, QueueWriter, Range, Schedule};

use super::count;
use super::pose_trail::PoseTrail;
use crate::vision::{Detections, VictimMap, VictimMapParams};

/// `targetDistance` when there is no target: farther than any map.
const NO_TARGET_DISTANCE: f64 = 1e6;

/// `vision.victim_mapper`: wraps [`VictimMap`].
pub struct VictimMapper {
    detections: Input<Detections>,
    robot: Input<Pose2>,
    report: Input<bool>,
    dismiss: Input<bool>,
    merge_radius: Input<f64>,
    confirm_hits: Input<i64>,
    min_confidence: Input<f64>,
    max_range: Input<f64>,
    confirm_range: Input<f64>,
    standoff: Input<f64>,
    view_frames: Input<i64>,
    victims: Output<Path2>,
    found: Output<i64>,
    seen: Output<Path2>,
    pending: Output<i64>,
    target: Output<Pose2>,
    target_distance: Output<f64>,
    target_in_view: Output<bool>,
    report_done: Output<bool>,
    dismiss_done: Output<bool>,
    dismissed: Output<i64>,
    report_to: Input<String>,
    report_move: Input<f64>,
    outbox: QueueWriter<Message>,
    saved: Output<MapperMemory>,
    /// The detections version last added (a step may be for a command only).
    frame_version: Option<u64>,
    /// The poses since the frames began, to place a sighting from where the camera was when
    /// it took the frame.
    poses: PoseTrail,
    core: Option<VictimMap>,
}

/// What a restarted `vision.victim_mapper` goes on from (`state/map`).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MapperMemory {
    /// Candidates, seen and reported victims.
    pub map: VictimMap,
    /// The `in/detections` version last added: a new instance must not add it again.
    pub frame_version: Option<u64>,
}

impl petrel_actors::PropertyType for MapperMemory {
    const TYPE_NAME: &'static str = "vision.victim_mapper_memory";
}

impl Module for VictimMapper {
    const TYPE: &'static str = "vision.victim_mapper";
    const DESCRIPTION: &'static str =
        "Turns repeated victim detections and the robot pose into de-duplicated victim positions in the map frame; a mission reports or dismisses them one at a time.";

    fn declare(ports: &mut Ports) -> Self {
        let module = VictimMapper {
            detections: ports.input("in/detections", Detections::default(), "detections of the latest frame"),
            robot: ports.input("in/robotPose", Pose2::default(), "estimated robot pose (camera at its centre, looking ahead); a frame's sightings are placed from the first pose written at or after its stamp (in/detections' write time: the detector stamps it with the frame's)"),
            report: ports.input("in/report", false, "while true: the target is reported (joins out/victims), then out/reportDone is true"),
            dismiss: ports.input("in/dismiss", false, "while true: the target is dismissed (not a victim), then out/dismissDone is true"),
            merge_radius: ports.param_in("params/merge_radius", 1.5, Range::new(0.01, 100.0), "sightings this close are one victim, m"),
            confirm_hits: ports.param_in("params/confirm_hits", 3, Range::new(1.0, 1000.0), "sightings that make a seen victim"),
            min_confidence: ports.param_in("params/min_confidence", 0.7, Range::new(0.0, 1.0), "weaker detections are ignored, 0..1"),
            max_range: ports.param_in("params/max_range", 5.0, Range::new(0.1, 100.0), "farther detections are ignored, m"),
            confirm_range: ports.param_in("params/confirm_range", 5.0, Range::new(0.1, 100.0), "a victim is seen only once one of its sightings was this close (a far victim's range can be metres short), m"),
            standoff: ports.param_in("params/standoff", 1.0, Range::new(0.01, 20.0), "distance of the approach pose from the target, m"),
            view_frames: ports.param_in("params/view_frames", 3, Range::new(1.0, 1000.0), "the target is in view while one of the last this many frames saw it"),
            victims: ports.output("out/victims", Path2::default(), "reported victims (the found list), map frame, in report order"),
            found: ports.output("out/found", 0, "reported victims"),
            seen: ports.output("out/seen", Path2::default(), "seen victims, reported or pending, map frame"),
            pending: ports.output("out/pending", 0, "seen victims neither reported nor dismissed"),
            target: ports.output("out/target", Pose2::default(), "approach pose of the target (the pending victim handled now): standoff away, facing it"),
            target_distance: ports.output("out/targetDistance", NO_TARGET_DISTANCE, "robot to target, m (1e6 when none)"),
            target_in_view: ports.output("out/targetInView", false, "the target is in the camera's view"),
            report_done: ports.output("out/reportDone", false, "in/report was carried out (false again when in/report is)"),
            dismiss_done: ports.output("out/dismissDone", false, "in/dismiss was carried out (false again when in/dismiss is)"),
            dismissed: ports.output("out/dismissed", 0, "candidates dismissed so far"),
            report_to: ports.param("params/report_to", String::new(), "`agent/module` told of each victim seen (a team's vision.team_victims); empty = nobody"),
            report_move: ports.param_in("params/report_move", 0.3, Range::new(0.01, 100.0), "a victim told to params/report_to is told again when its estimate moved this far, m"),
            outbox: ports.queue_out("out/outbox", 64, "victims seen, as messages to params/report_to (`x y id`; the same id again: a better estimate)"),
            saved: ports.state("state/map", MapperMemory::default(), "candidates, seen and reported victims: a restarted module goes on from them"),
            frame_version: None,
            poses: PoseTrail::default(),
            core: None,
        };
        // Read only by `init`: a running agent refuses new values for these.
        ports.read_at_start(&[
            "params/merge_radius",
            "params/confirm_hits",
            "params/min_confidence",
            "params/max_range",
            "params/confirm_range",
            "params/standoff",
            "params/view_frames",
        ]);
        module
    }

    fn schedule(&self) -> Schedule {
        // Every pose, not only the one current at a frame: a frame reaches this module after
        // the robot has moved on.
        Schedule::new()
            .on_change(&self.detections)
            .on_change(&self.report)
            .on_change(&self.dismiss)
            .on_change(&self.robot)
    }

    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let params = VictimMapParams {
            merge_radius: self.merge_radius.value(),
            confirm_hits: count("confirm_hits", self.confirm_hits.value())? as u32,
            min_confidence: self.min_confidence.value(),
            max_range: self.max_range.value(),
            confirm_range: self.confirm_range.value(),
            standoff: self.standoff.value(),
            view_frames: count("view_frames", self.view_frames.value())? as u32,
        };
        params
            .validate()
            .map_err(|e| anyhow!("invalid parameter {e}"))?;
        let saved = self.saved.get();
        self.frame_version = saved.frame_version;
        self.core = Some(match saved.map.is_empty() {
            true => VictimMap::new(params),
            false => VictimMap::resume(params, &saved.map),
        });
        Ok(())
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let core = super::initialized(&mut self.core);
        self.poses.follow(&self.robot);
        let pose = self.robot.value();
        let frame = self.detections.read();
        let new_frame = self.frame_version != Some(frame.version);
        let commands = self.report.value() != self.report_done.value()
            || self.dismiss.value() != self.dismiss_done.value();
        // A pose alone changes nothing else: what follows runs at frames and commands.
        if !(new_frame || commands || ctx.cause().first()) {
            return Ok(());
        }
        if new_frame {
            self.frame_version = Some(frame.version);
            core.next_frame();
            // Before the localizer's first estimate the pose reads (0, 0, 0): a sighting placed
            // from there lands metres from its victim (seen at start in the rescue team).
            let (placed, pose) = match self.poses.at(frame.written) {
                None => (&[][..], pose),
                Some(taken_from) => (&frame.value.0[..], taken_from),
            };
            let age_ms = ctx
                .now()
                .saturating_duration_since(frame.written)
                .as_millis() as u64;
            for d in placed {
                // Why a victim was, or was not, confirmed: each sighting, the pose it is placed
                // from and how old its frame was by then.
                tracing::debug!(
                    age_ms,
                    x = pose.x(),
                    y = pose.y(),
                    theta = pose.theta(),
                    bearing = d.bearing,
                    range = d.range,
                    confidence = d.confidence,
                    "sighting"
                );
                if let Some(p) = core.add(pose, d) {
                    petrel_actors::outln!(
                        "[{}] victim seen at ({:.2}, {:.2})",
                        ctx.module(),
                        p.0.x,
                        p.0.y
                    );
                }
            }
            let to = self.report_to.get();
            if !to.is_empty() {
                // `x y id`, metres: what vision.team_victims reads; a later message with the
                // same id revises the estimate (it improves as the robot comes closer).
                for (id, p) in core.news(self.report_move.value()) {
                    let body = format!("{} {} {id}", p.0.x, p.0.y);
                    let (to, from) = ((*to).clone(), String::new());
                    self.outbox.push(Message { to, from, body });
                }
            }
        }
        // Commands: carried out once per request, acknowledged until the request is withdrawn.
        if self.report.value() != self.report_done.value() {
            if self.report.value() {
                if let Some(p) = core.report() {
                    petrel_actors::outln!(
                        "[{}] victim {} reported at ({:.2}, {:.2})",
                        ctx.module(),
                        self.found.value() + 1,
                        p.0.x,
                        p.0.y
                    );
                }
            }
            self.report_done.set(self.report.value());
        }
        if self.dismiss.value() != self.dismiss_done.value() {
            if self.dismiss.value() {
                if let Some(p) = core.dismiss() {
                    petrel_actors::outln!(
                        "[{}] not a victim: candidate at ({:.2}, {:.2}) dismissed",
                        ctx.module(),
                        p.0.x,
                        p.0.y
                    );
                    self.dismissed.set(self.dismissed.value() + 1);
                }
            }
            self.dismiss_done.set(self.dismiss.value());
        }
        let reported = core.reported();
        if reported.len() as i64 != self.found.value()
            || reported.as_slice() != self.victims.get().points()
        {
            self.found.set(reported.len() as i64);
            self.victims.set(reported.into());
        }
        let seen = core.seen();
        if seen.as_slice() != self.seen.get().points() {
            self.seen.set(seen.into());
        }
        self.pending.set_if_changed(core.pending() as i64);
        let target = core.target(pose.position());
        let distance = target.map_or(NO_TARGET_DISTANCE, |t| {
            (t.position.0 - pose.position().0).norm()
        });
        self.target_distance.set_if_changed(distance);
        self.target_in_view
            .set_if_changed(target.is_some_and(|t| t.in_view));
        if let Some(t) = target {
            // The approach pose moves as sightings refine the position: tell the planner only
            // of moves that matter, so it does not replan at every frame.
            let old = self.target.value();
            if (old.position().0 - t.approach.position().0).norm() > 0.15 || old == Pose2::default()
            {
                self.target.set(t.approach);
            }
        }
        let saved = self.saved.get();
        if saved.map != *core || saved.frame_version != self.frame_version {
            self.saved.set(MapperMemory {
                map: core.clone(),
                frame_version: self.frame_version,
            });
        }
        Ok(())
    }
}
