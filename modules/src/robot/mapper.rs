//! `nav.mapper`: pose + laser scans → occupancy grid.

use std::collections::VecDeque;

use petrel_actors::{
    Context, Input, Item, LaserScan, Module, OccupancyGrid, Output, Point2, Ports, Pose2,
    QueueReader, Range, Schedule,
};

use super::param_error;
use crate::nav::{Mapper, MapperParams, PublishGate};

/// Scans kept waiting for a matching pose; beyond this the pose source is presumed silent and
/// the oldest scan is mapped with the latest pose.
const MAX_PENDING: usize = 4;

/// `nav.mapper`: wraps [`Mapper`].
pub struct MapperModule {
    scans: QueueReader<LaserScan>,
    pose: Input<Pose2>,
    resolution: Input<f64>,
    size: Input<Point2>,
    origin: Input<Point2>,
    laser_mount: Input<Pose2>,
    fov_deg: Input<f64>,
    max_range: Input<f64>,
    publish_every: Input<i64>,
    map: Output<OccupancyGrid>,
    pending: VecDeque<Item<LaserScan>>,
    core: Option<Mapper>,
    gate: PublishGate,
}

impl Module for MapperModule {
    const TYPE: &'static str = "nav.mapper";
    const DESCRIPTION: &'static str =
        "Builds an occupancy grid from laser scans taken at the estimated pose.";

    fn declare(ports: &mut Ports) -> Self {
        let module = MapperModule {
            scans: ports.queue_in("in/laserScan", "laser scans"),
            pose: ports.input(
                "in/pose",
                Pose2::default(),
                "robot pose the scans were taken from",
            ),
            resolution: ports.param_in("params/resolution", 0.1, Range::new(0.01, 1.0), "cell size, m"),
            size: ports.param(
                "params/size",
                Point2::new(20.0, 20.0),
                "extent of the map (x: width, y: height), m",
            ),
            origin: {
                let origin = ports.param(
                    "params/origin",
                    Point2::new(0.0, 0.0),
                    "world position of the map's lower-left corner",
                );
                // As a world's: beyond, the cells' positions are lost in the rounding.
                ports.accept_last(
                    |o: &Point2| crate::sim::grid::origin_problem(o.0.x, o.0.y).is_none(),
                    "`(x: .., y: ..)` in metres, each within -1e6..=1e6",
                );
                origin
            },
            laser_mount: ports.param(
                "params/laser_mount",
                Pose2::default(),
                "laser pose in the robot frame",
            ),
            fov_deg: ports.param_in(
                "params/fov_deg",
                0.0,
                Range::new(0.0, 360.0),
                "map only rays within this field of view, degrees (0 = all): with a camera's view, the map holds what the camera saw",
            ),
            max_range: ports.param_in(
                "params/max_range",
                0.0,
                Range::new(0.0, 100.0),
                "map returns only up to this range, m (0 = the laser's)",
            ),
            publish_every: ports.param_in(
                "params/publish_every_scans",
                1,
                Range::new(1.0, 100_000.0),
                "publish the map at most once per this many scans mapped (1 = whenever a scan changed it); what changed meanwhile is published with a later scan, or when the module stops",
            ),
            map: ports.output(
                "out/map",
                OccupancyGrid::default(),
                "the map (written only when it changed, at most once per params/publish_every_scans)",
            ),
            pending: VecDeque::new(),
            core: None,
            gate: PublishGate::new(1),
        };
        // Read only by `init`: a running agent refuses new values for these.
        ports.read_at_start(&[
            "params/resolution",
            "params/size",
            "params/origin",
            "params/laser_mount",
            "params/fov_deg",
            "params/max_range",
            "params/publish_every_scans",
        ]);
        module
    }

    fn schedule(&self) -> Schedule {
        Schedule::new().on_items(&self.scans).on_change(&self.pose)
    }

    /// Parameters valid alone but not together (an extent of no cells, or too many):
    /// `petrel check` says so before anything runs.
    fn check(&self, _agent: &petrel_actors::AgentView) -> Vec<petrel_actors::CheckProblem> {
        super::check_built(self.build_core())
    }

    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let mut core = self.build_core()?;
        self.map.set(core.grid());
        self.core = Some(core);
        let every = *self.publish_every.read().value;
        self.gate = PublishGate::new(u32::try_from(every).unwrap_or(u32::MAX));
        Ok(())
    }

    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let core = super::initialized(&mut self.core);
        self.pending.extend(self.scans.drain());
        let pose = self.pose.read();
        let (mut mapped, mut changed) = (0, false);
        // A scan is mapped with the first pose written at or after it: the pose estimated
        // from the same simulation step, not the previous one (which would smear the map
        // while turning). The declared default (version 0) is no pose yet: on a paused clock
        // it bears the very time of the first scan, which was then mapped at the origin.
        let no_pose = pose.version == 0;
        while let Some(scan) = self.pending.front() {
            if (no_pose || pose.written < scan.stamp) && self.pending.len() <= MAX_PENDING {
                break;
            }
            changed |= core.update(*pose.value, &scan.value) > 0;
            mapped += 1;
            self.pending.pop_front();
        }
        if self.gate.update(mapped, changed) {
            self.map.set(core.grid());
        }
        Ok(())
    }

    /// What changed since the last publication is published, so the last map is never lost
    /// to `params/publish_every_scans`.
    async fn cleanup(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        if let Some(core) = self.core.as_mut().filter(|_| self.gate.pending()) {
            self.map.set(core.grid());
            self.gate.published();
        }
        Ok(())
    }
}

impl MapperModule {
    /// The mapping core the parameters describe (what `init` builds and `check` tries).
    fn build_core(&self) -> anyhow::Result<Mapper> {
        let (res, size, origin) = (
            self.resolution.value(),
            self.size.value(),
            self.origin.value(),
        );
        let (width, height) = super::grid_cells(res, size)?;
        let params = MapperParams {
            width,
            height,
            resolution: res,
            origin: (origin.0.x, origin.0.y),
            laser_mount: self.laser_mount.value(),
            fov: Some(self.fov_deg.value().to_radians()).filter(|&f| f != 0.0),
            max_range: Some(self.max_range.value()).filter(|&r| r != 0.0),
            ..MapperParams::default()
        };
        Mapper::new(params).map_err(|e| param_error(e, &[("width", "size"), ("fov", "fov_deg")]))
    }
}
