//! `nav.searched`: the floor the camera has searched for victims, frame by frame.

use petrel_actors::{
    AgentView, CheckProblem, Context, Input, Module, OccupancyGrid, Output, Ports, Pose2, Range,
    Schedule,
};

use super::pose_trail::PoseTrail;
use super::{count, param_error};
use crate::nav::{SearchParams, SearchedMap};

/// `nav.searched`: wraps [`SearchedMap`].
pub struct SearchedModule {
    frames: Input<i64>,
    map: Input<OccupancyGrid>,
    robot: Input<Pose2>,
    brightness: Input<f64>,
    fov_deg: Input<f64>,
    victim_radius: Input<f64>,
    min_range: Input<f64>,
    max_range: Input<f64>,
    edge_range: Input<f64>,
    min_views: Input<i64>,
    min_brightness: Input<f64>,
    max_brightness: Input<f64>,
    max_turn_deg: Input<f64>,
    searched: Output<OccupancyGrid>,
    area: Output<f64>,
    counted: Output<i64>,
    skipped: Output<i64>,
    /// The frame count last looked at: a step without a new frame (the first) looks at nothing.
    last_frame: i64,
    /// The pose the frame before was taken from: how far the robot turned between frames.
    last_pose: Option<Pose2>,
    /// The poses since the frames began, to look from where the camera was when it took one.
    poses: PoseTrail,
    core: Option<SearchedMap>,
}

impl Module for SearchedModule {
    const TYPE: &'static str = "nav.searched";
    const DESCRIPTION: &'static str =
        "Marks the map cells the camera looked at well enough to see a victim (in range, in view, not hidden, image not too dark or bright, robot not turning fast), for an explorer that searches.";

    fn declare(ports: &mut Ports) -> Self {
        let module = SearchedModule {
            frames: ports.input("in/frames", 0, "frames the detector processed (link to its out/frames): each new value is one frame looked at"),
            map: ports.input("in/map", OccupancyGrid::default(), "the navigation map (walls and unknown space hide what lies behind them)"),
            robot: ports.input("in/robotPose", Pose2::default(), "estimated robot pose (camera at its centre, looking ahead); the floor of a frame is searched from the first pose written at or after its stamp (in/frames' write time: the detector stamps it with the frame's)"),
            brightness: ports.input("in/brightness", 0.5, "mean grey level of the frame, 0..1 (link to the detector's out/brightness)"),
            fov_deg: ports.param_in("params/fov_deg", 60.0, Range::new(1.0, 179.0), "the camera's horizontal field of view, degrees"),
            victim_radius: ports.param_in("params/victim_radius", 0.25, Range::new(0.0, 5.0), "radius of a victim, m: a cell counts only where a victim standing anywhere on it would be whole in view (the detector leaves one cut by the image's border); 0: where all of the cell is in the field of view"),
            min_range: ports.param_in("params/min_range", 1.0, Range::new(0.0, 20.0), "floor less than this far ahead of the camera, along its heading, is not searched (a victim's foot leaves the image), m"),
            max_range: ports.param_in("params/max_range", 3.5, Range::new(0.1, 50.0), "farther floor is not searched (a victim is too small to resolve), m"),
            edge_range: ports.param_in("params/edge_range", 3.0, Range::new(0.0, 50.0), "floor beside unknown space is searched only from this near, m (the laser reaches about as far as the camera: the far edge of a scan is not searched yet); more than min_range (max_range or more: no difference)"),
            min_views: ports.param_in("params/min_views", 3, Range::new(1.0, 255.0), "frames a cell must be in view in to be searched"),
            min_brightness: ports.param_in("params/min_brightness", 0.1, Range::new(0.0, 1.0), "darker frames search nothing (too little contrast left to detect), 0..1"),
            max_brightness: ports.param_in("params/max_brightness", 0.95, Range::new(0.0, 1.0), "brighter frames search nothing (saturated), 0..1"),
            max_turn_deg: ports.param_in("params/max_turn_deg", 6.0, Range::new(0.0, 180.0), "frames taken after the robot turned more than this since the frame before search nothing (the turn smears a victim's pattern: the detector finds one in 1 frame of 5 turning 6° a frame at 10 Hz), degrees; 180: no limit"),
            searched: ports.output("out/searched", OccupancyGrid::default(), "the navigation map's cells: 0 searched, -1 not (written when it grows)"),
            area: ports.output("out/area", 0.0, "searched area, m²"),
            counted: ports.output("out/frames", 0, "frames that searched (bright enough, taken without a fast turn)"),
            skipped: ports.output("out/skipped", 0, "frames too dark, too bright or too smeared by a turn to search anything"),
            last_frame: 0,
            last_pose: None,
            poses: PoseTrail::default(),
            core: None,
        };
        // Read only by `init`: a running agent refuses new values for these.
        ports.read_at_start(&[
            "params/fov_deg",
            "params/victim_radius",
            "params/min_range",
            "params/max_range",
            "params/edge_range",
            "params/min_views",
        ]);
        module
    }

    fn schedule(&self) -> Schedule {
        // Every pose, not only the one current at a frame: a frame reaches this module after
        // the robot has moved on.
        Schedule::new()
            .on_change(&self.frames)
            .on_change(&self.robot)
    }

    fn check(&self, _agent: &AgentView) -> Vec<CheckProblem> {
        super::check_built(self.build_core())
    }

    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        self.core = Some(self.build_core()?);
        Ok(())
    }

    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let core = super::initialized(&mut self.core);
        self.poses.follow(&self.robot);
        let frame = self.frames.read();
        if *frame.value == self.last_frame {
            return Ok(());
        }
        self.last_frame = *frame.value;
        // Before the localizer's first estimate the pose reads (0, 0, 0): not where it looked.
        let looked_from = self.poses.at(frame.written);
        // The turn since the frame before, whatever becomes of either frame.
        let turned = looked_from.and_then(|pose| {
            let before = self.last_pose.replace(pose)?;
            Some(crate::nav::heading_change(&before, &pose))
        });
        let brightness = self.brightness.value();
        // A frame too dark (or washed out) holds too little contrast for a victim's pattern,
        // and a turn smears it over the exposure: looking through such a frame searched nothing.
        let exposed =
            (self.min_brightness.value()..=self.max_brightness.value()).contains(&brightness);
        let smeared = turned.is_some_and(|deg| deg > self.max_turn_deg.value());
        if !exposed || smeared {
            self.skipped.set(self.skipped.value() + 1);
            return Ok(());
        }
        let Some(looked_from) = looked_from else {
            return Ok(());
        };
        self.counted.set(self.counted.value() + 1);
        if core.look(looked_from, &self.map.get()) > 0 {
            self.searched.set(core.grid());
            self.area.set(core.area());
        }
        Ok(())
    }
}

impl SearchedModule {
    /// The core its parameters make, or an error naming the parameter.
    fn build_core(&self) -> anyhow::Result<SearchedMap> {
        let (lo, hi) = (self.min_brightness.value(), self.max_brightness.value());
        if lo >= hi {
            anyhow::bail!("invalid parameter `params/min_brightness`: expected less than params/max_brightness ({hi}), got {lo}");
        }
        let min_views = count("min_views", self.min_views.value())?;
        let params = SearchParams {
            fov: self.fov_deg.value().to_radians(),
            victim_radius: self.victim_radius.value(),
            min_range: self.min_range.value(),
            max_range: self.max_range.value(),
            edge_range: self.edge_range.value(),
            min_views: u8::try_from(min_views).map_err(|_| {
                anyhow::anyhow!("invalid parameter `params/min_views`: expected 1..=255 frames, got {min_views}")
            })?,
            ..SearchParams::default()
        };
        SearchedMap::new(params).map_err(|e| param_error(e, &[("fov", "fov_deg")]))
    }
}
