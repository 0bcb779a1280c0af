//! Occupancy grid mapping from poses and laser scans (log-odds, ray casting).
//!
//! Each ray lowers the log-odds of the cells it crosses and raises the one it ends in; values
//! are clamped so that the map can change its mind quickly when the world changes. Only
//! the cells under the rays are touched, so an update costs O(rays x range / resolution).

use std::sync::Arc;

use petrel_actors::{world_to_cell, LaserScan, OccupancyGrid, Pose2};

use crate::sim::error::{finite, positive, ParamError};
use crate::sim::raycast::traverse;

/// Mapper parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct MapperParams {
    /// Cells along x.
    pub width: u32,
    /// Cells along y.
    pub height: u32,
    /// Cell size, metres (default 0.05).
    pub resolution: f64,
    /// World x, y of the lower-left corner of cell (0, 0).
    pub origin: (f64, f64),
    /// Laser pose in the robot frame (default identity).
    pub laser_mount: Pose2,
    /// Log-odds added to the cell a ray ends in (default 0.85).
    pub log_odds_hit: f64,
    /// Log-odds added to cells a ray passes through (default -0.4).
    pub log_odds_miss: f64,
    /// Lower clamp (default -2.0).
    pub log_odds_min: f64,
    /// Upper clamp (default 3.5).
    pub log_odds_max: f64,
    /// Only rays within this field of view (radians, centred ahead of the laser) are mapped;
    /// `None` maps every ray. With the camera's view, the map holds what the camera saw.
    pub fov: Option<f64>,
    /// Returns further than this are mapped as free space up to it and no further, metres;
    /// `None` maps the laser's whole range.
    pub max_range: Option<f64>,
}

impl Default for MapperParams {
    fn default() -> Self {
        MapperParams {
            width: 400,
            height: 400,
            resolution: 0.05,
            origin: (0.0, 0.0),
            laser_mount: Pose2::default(),
            log_odds_hit: 0.85,
            log_odds_miss: -0.4,
            log_odds_min: -2.0,
            log_odds_max: 3.5,
            fov: None,
            max_range: None,
        }
    }
}

impl MapperParams {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), ParamError> {
        if let Some(fov) = self.fov {
            positive("fov", fov)?;
        }
        if let Some(range) = self.max_range {
            positive("max_range", range)?;
        }
        let cells = self.width as u64 * self.height as u64;
        if cells == 0 || cells > crate::sim::Grid::MAX_CELLS as u64 {
            return Err(ParamError {
                param: "width".into(),
                message: format!(
                    "expected a grid of at least 1 x 1 cells, got {} x {}",
                    self.width, self.height
                ),
            });
        }
        positive("resolution", self.resolution)?;
        finite("origin", self.origin.0 + self.origin.1)?;
        positive("log_odds_hit", self.log_odds_hit)?;
        if !(self.log_odds_miss.is_finite() && self.log_odds_miss < 0.0) {
            return Err(ParamError {
                param: "log_odds_miss".into(),
                message: format!("expected a finite value < 0, got {}", self.log_odds_miss),
            });
        }
        if !(self.log_odds_min < 0.0 && self.log_odds_max > 0.0) {
            return Err(ParamError {
                param: "log_odds_min".into(),
                message: format!(
                    "expected log_odds_min < 0 < log_odds_max, got {} and {}",
                    self.log_odds_min, self.log_odds_max
                ),
            });
        }
        Ok(())
    }
}

/// An incrementally built occupancy grid.
#[derive(Clone, Debug)]
pub struct Mapper {
    params: MapperParams,
    log_odds: Vec<f32>,
    /// ROS cell values kept in step with `log_odds`, so publishing is one copy.
    data: Vec<i8>,
    /// The last published grid; reused until the next update so consumers can cheaply tell
    /// whether the map changed (`Arc::ptr_eq`).
    published: Option<OccupancyGrid>,
}

impl Mapper {
    /// An all-unknown map.
    pub fn new(params: MapperParams) -> Result<Self, ParamError> {
        params.validate()?;
        let n = params.width as usize * params.height as usize;
        Ok(Mapper {
            params,
            log_odds: vec![0.0; n],
            data: vec![-1; n],
            published: None,
        })
    }

    /// Integrates one scan taken with the robot at `pose`; returns how many cells changed
    /// their published value.
    pub fn update(&mut self, pose: Pose2, scan: &LaserScan) -> usize {
        let sensor = pose.0 * self.params.laser_mount.0;
        let (sx, sy, heading) = (
            sensor.translation.x,
            sensor.translation.y,
            sensor.rotation.angle(),
        );
        let (w, h) = (self.params.width as i64, self.params.height as i64);
        let (origin, res) = (self.params.origin, self.params.resolution);
        let origin_pose = Pose2::new(origin.0, origin.1, 0.0);
        let (miss, hit) = (
            self.params.log_odds_miss as f32,
            self.params.log_odds_hit as f32,
        );
        let (lo, hi) = (
            self.params.log_odds_min as f32,
            self.params.log_odds_max as f32,
        );
        let mut changed = 0;
        for (i, &r) in scan.ranges.iter().enumerate() {
            if !(r.is_finite() && r >= 0.0) {
                continue; // invalid reading: no information
            }
            if self
                .params
                .fov
                .is_some_and(|fov| scan.angle(i).abs() > fov / 2.0)
            {
                continue;
            }
            let limit = self.params.max_range.unwrap_or(f64::INFINITY);
            let (s, c) = (heading + scan.angle(i)).sin_cos();
            let is_hit = r < scan.range_max && r <= limit;
            let length = r.min(scan.range_max).min(limit);
            // The hit cell is the one just beyond the measured distance along the ray.
            let hit_cell = is_hit.then(|| {
                let e = length + res * 1e-3;
                world_to_cell(&origin_pose, res, sx + e * c, sy + e * s)
            });
            let mut apply = |col: i64, row: i64, delta: f32| {
                if col >= 0 && row >= 0 && col < w && row < h {
                    let k = (row * w + col) as usize;
                    let l = (self.log_odds[k] + delta).clamp(lo, hi);
                    self.log_odds[k] = l;
                    let v = percent(l);
                    if v != self.data[k] {
                        self.data[k] = v;
                        changed += 1;
                    }
                }
            };
            traverse(origin, res, (sx, sy), (c, s), length, |col, row, _| {
                if Some((col, row)) == hit_cell {
                    return false;
                }
                apply(col, row, miss);
                true
            });
            if let Some((col, row)) = hit_cell {
                apply(col, row, hit);
            }
        }
        if changed > 0 {
            self.published = None;
        }
        changed
    }

    /// The current map (ROS convention: -1 unknown, 0..100 occupancy percent).
    pub fn grid(&mut self) -> OccupancyGrid {
        if self.published.is_none() {
            let p = &self.params;
            self.published = Some(OccupancyGrid {
                width: p.width,
                height: p.height,
                resolution: p.resolution,
                origin: Pose2::new(p.origin.0, p.origin.1, 0.0),
                data: Arc::from(&self.data[..]),
            });
        }
        self.published.clone().expect("just set")
    }

    /// Parameters in use.
    pub fn params(&self) -> &MapperParams {
        &self.params
    }
}

fn percent(l: f32) -> i8 {
    let p = 1.0 - 1.0 / (1.0 + l.exp());
    (p * 100.0).round() as i8
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{Grid, LaserConfig, RobotConfig, World};

    #[test]
    fn one_scan_marks_free_along_rays_and_occupied_at_hits() {
        // 4 m x 4 m room with 0.1 m cells; robot in the middle facing +x.
        let mut g = Grid::new(40, 40, 0.1, 0.0, 0.0).unwrap();
        g.fill_rect(3.0, 0.0, 3.1, 4.0);
        let mut w = World::new(g, 0);
        let laser = LaserConfig {
            range_max: 5.0,
            rays: 361,
            ..LaserConfig::default()
        };
        let id = w
            .add_robot(RobotConfig::with_laser(laser), Pose2::new(1.05, 2.05, 0.0))
            .unwrap();
        let out = w.step(1e-3).unwrap()[id].clone();
        let params = MapperParams {
            width: 40,
            height: 40,
            resolution: 0.1,
            ..MapperParams::default()
        };
        let mut m = Mapper::new(params.clone()).unwrap();
        let changed = m.update(out.ground_truth, out.scan.as_ref().unwrap());
        assert!(changed > 100);
        let grid = m.grid();
        // Free between the robot and the wall on the robot's row, occupied at the wall cell.
        for col in 11..30 {
            assert!(
                grid.get(col, 20).unwrap() < 50 && grid.get(col, 20).unwrap() >= 0,
                "col {col}"
            );
        }
        assert!(grid.get(30, 20).unwrap() > 50);
        // Behind the robot (outside the 180 degree field of view) and behind the wall: unknown.
        assert_eq!(grid.get(5, 20), Some(-1));
        assert_eq!(grid.get(35, 20), Some(-1));
        // Unchanged map: the same shared data is handed out again.
        assert!(Arc::ptr_eq(&grid.data, &m.grid().data));
        // Mapping only a 60 degree cone out to 1 m: the wall 1.95 m ahead is not mapped (free
        // up to 1 m, unknown after), nor is anything beside the robot.
        let mut cone = Mapper::new(MapperParams {
            fov: Some(60f64.to_radians()),
            max_range: Some(1.0),
            ..params
        })
        .unwrap();
        cone.update(out.ground_truth, out.scan.as_ref().unwrap());
        let grid = cone.grid();
        assert!(grid.get(15, 20).unwrap() < 50 && grid.get(15, 20).unwrap() >= 0);
        assert_eq!(grid.get(22, 20), Some(-1));
        assert_eq!(grid.get(30, 20), Some(-1));
        assert_eq!(
            grid.get(10, 28),
            Some(-1),
            "beside the robot, outside the cone"
        );
        let bad = MapperParams {
            fov: Some(0.0),
            ..MapperParams::default()
        };
        assert_eq!(bad.validate().unwrap_err().param, "fov");
    }

    #[test]
    fn repeated_hits_saturate_and_free_space_can_be_reclaimed() {
        let params = MapperParams {
            width: 20,
            height: 1,
            resolution: 0.1,
            ..MapperParams::default()
        };
        let mut m = Mapper::new(params).unwrap();
        let scan = |r: f64| LaserScan {
            angle_min: 0.0,
            angle_increment: 0.1,
            range_max: 1.5,
            ranges: vec![r].into(),
        };
        let pose = Pose2::new(0.05, 0.05, 0.0);
        for _ in 0..20 {
            m.update(pose, &scan(1.0));
        }
        assert_eq!(m.grid().get(10, 0), Some(97)); // clamped at 3.5 log-odds
        assert!(m.grid().get(5, 0).unwrap() <= 12);
        // The obstacle goes away: no-return rays clear it again within a few scans.
        for _ in 0..15 {
            m.update(pose, &scan(1.5));
        }
        assert!(m.grid().get(10, 0).unwrap() < 50);
        assert_eq!(
            m.grid().get(17, 0),
            Some(-1),
            "nothing is traversed past range_max"
        );
    }
}
