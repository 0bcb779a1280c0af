//! The searched map: the floor a camera has looked at well enough to see a victim there.
//!
//! A laser maps a room in one glance, but a camera resolves a victim only between a minimum
//! depth (nearer, the victim's foot leaves the bottom of the image) and a maximum distance
//! (farther, its pattern is too small), inside a field of view narrower than the laser's.
//! Exploration that ends when the laser map has no frontier left therefore leaves floor the
//! camera never looked at. This map records, frame by frame, the cells that were in view. A
//! victim may stand anywhere on a cell, so a cell is searched by a frame only when a victim
//! standing at any of its corners (where the cell comes nearest to the camera and farthest off
//! its heading) would be seen: at least `min_range` ahead of the camera along its heading (the
//! depth decides where the foot falls in the image, not the distance), whole in the image (its
//! bearing plus its half-width seen from there, `atan(victim_radius / distance)`, within
//! `fov / 2` less a degree: the detector leaves a victim cut by the image's border for a later
//! frame), the cell's centre within `max_range`, and the straight line from the camera to that
//! centre crossing only known free cells of the navigation map (walls and unknown space hide
//! what lies behind them; an occupied cell in view is itself searched, its face was seen).
//! Judged by their centres alone, cells were counted where a victim on their near or outer
//! part was cut by the image's border or had its foot below it: in the rescue world, one in
//! ten victims on counted cells nearer than 1.5 m went unseen in a frame (a rescue team missed
//! a victim whose one sighting nearby, from 1 m, was cut by the border); judged by their
//! corners, one in a hundred
//! (`the_searched_map_counts_only_floor_where_a_victim_would_be_seen`).
//! One glimpse is not a search: a detector confirms a victim over several frames, so a cell
//! counts as searched once it was in view in `min_views` frames.
//! A cell at the edge of unknown space (beside a cell the navigation map does not know yet)
//! counts only from nearer than `edge_range`: the laser reaches about as far as the camera, so
//! the floor at the far edge of what a scan mapped is in view as soon as it is mapped, and
//! counting it there would leave the unknown space beyond it no frontier to explore. Seen from
//! nearer, where the laser would have mapped what lies beyond if it could, it counts: space no
//! scan can map (behind glass, outside the walls) does not keep a search going forever.
//! Frames too dark or too bright to detect anything are not counted by the module that
//! feeds this map ([`crate::robot`]'s `nav.searched`), which reads the image's brightness;
//! nor are frames taken while the robot turned fast ([`heading_change`] since the frame
//! before, against `params/max_turn_deg`): a turn smears a victim's pattern over the
//! exposure. In wall-time rescue runs the detector found a victim in one frame of five turning
//! 6° or more a frame, against 24 of 25 below 3°, and a robot turning in place beside a victim
//! counted the floor around it as searched without ever seeing it: the mission ended with that
//! victim unreported. The exposure is not known there: a dark room's long exposure smears a
//! slower turn too, which is why the rescue rules also slow a robot down in the dark.
//!
//! The map shares the navigation map's geometry, so the explorer can read both cell by cell.

use petrel_actors::{OccupancyGrid, Pose2};

use crate::sim::error::{positive, ParamError};
use crate::sim::raycast::traverse;

/// Angle kept free inside the image's border, radians (1°): the detector drops a victim whose
/// columns touch the border, and smooths texture over three columns (of 160 over 60°).
const EDGE_MARGIN: f64 = 1.0 * std::f64::consts::PI / 180.0;

/// A cell's corners from its centre, in cells: where a victim standing on the cell comes
/// nearest to the camera and farthest off its heading.
const CORNERS: [(f64, f64); 4] = [(-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)];

/// Value of a searched cell in the published grid (ROS convention: 0 = free, known).
pub const SEARCHED: i8 = 0;
/// Value of a cell not searched yet (ROS convention: -1 = unknown).
pub const NOT_SEARCHED: i8 = -1;

/// Searched-map parameters: what the camera and its detector can resolve.
#[derive(Clone, Debug, PartialEq)]
pub struct SearchParams {
    /// The camera's horizontal field of view, radians, centred on its heading (default 60°).
    pub fov: f64,
    /// Radius of what is searched for, metres (default 0.25, a victim): a cell counts only where
    /// a victim standing anywhere on it would be whole in view. 0: where all of the cell is in
    /// the field of view.
    pub victim_radius: f64,
    /// A cell counts only where all of it lies at least this far ahead of the camera, along its
    /// heading, metres (default 1.0: the detector finds a victim from about 1.0 m ahead; nearer,
    /// its foot leaves the image).
    pub min_range: f64,
    /// Cells whose centre is farther than this are not searched, metres (default 3.5).
    pub max_range: f64,
    /// Navigation-map value from which a cell blocks the view (default 50, as the planner).
    pub occupied_threshold: i8,
    /// Frames a cell must be in view in to be searched (default 3, the sightings a victim
    /// mapper wants before it believes a victim), 1..=255.
    pub min_views: u8,
    /// A cell beside unknown space counts only from this near, metres (default 3.0: half a metre
    /// inside the laser's 3.5 m); more than `min_range`; `max_range` or more makes no
    /// difference.
    pub edge_range: f64,
}

impl Default for SearchParams {
    fn default() -> Self {
        SearchParams {
            fov: 60f64.to_radians(),
            victim_radius: 0.25,
            min_range: 1.0,
            max_range: 3.5,
            occupied_threshold: 50,
            min_views: 3,
            edge_range: 3.0,
        }
    }
}

impl SearchParams {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), ParamError> {
        if !(self.fov > 0.0 && self.fov < std::f64::consts::TAU) {
            return Err(ParamError {
                param: "fov".into(),
                message: format!("expected an angle in (0, 2π) rad, got {}", self.fov),
            });
        }
        positive("max_range", self.max_range)?;
        if !(self.victim_radius >= 0.0 && self.victim_radius.is_finite()) {
            return Err(ParamError {
                param: "victim_radius".into(),
                message: format!("expected metres >= 0, got {}", self.victim_radius),
            });
        }
        if !(self.min_range >= 0.0 && self.min_range < self.max_range) {
            return Err(ParamError {
                param: "min_range".into(),
                message: format!(
                    "expected 0 <= min_range < max_range ({}), got {}",
                    self.max_range, self.min_range
                ),
            });
        }
        // Not capped by max_range: at or beyond it, it makes no difference.
        if self.edge_range.is_nan() || self.edge_range <= self.min_range {
            return Err(ParamError {
                param: "edge_range".into(),
                message: format!(
                    "expected more than min_range ({}), got {}",
                    self.min_range, self.edge_range
                ),
            });
        }
        if self.min_views == 0 {
            return Err(ParamError {
                param: "min_views".into(),
                message: "expected 1..=255 frames, got 0".into(),
            });
        }
        if !(1..=100).contains(&self.occupied_threshold) {
            return Err(ParamError {
                param: "occupied_threshold".into(),
                message: format!("expected 1..=100, got {}", self.occupied_threshold),
            });
        }
        Ok(())
    }
}

/// The cells searched so far, on the navigation map's geometry.
#[derive(Clone, Debug)]
pub struct SearchedMap {
    params: SearchParams,
    /// Geometry of the navigation map the cells belong to (data left empty).
    geometry: OccupancyGrid,
    /// Frames each cell was in view in, up to `min_views`.
    views: Vec<u8>,
    /// Cells searched (in view in `min_views` frames).
    count: usize,
    /// The last published grid, reused until a cell changes.
    published: Option<OccupancyGrid>,
}

impl SearchedMap {
    /// Nothing searched yet.
    pub fn new(params: SearchParams) -> Result<Self, ParamError> {
        params.validate()?;
        Ok(SearchedMap {
            params,
            geometry: OccupancyGrid::default(),
            views: Vec::new(),
            count: 0,
            published: None,
        })
    }

    /// Marks what a camera at `camera` (its position and heading, world frame) sees on `map`;
    /// returns how many cells this frame made searched. A map of another geometry than the last
    /// one starts the searched map afresh (nothing it held would line up).
    pub fn look(&mut self, camera: Pose2, map: &OccupancyGrid) -> usize {
        let (w, h) = (map.width as i64, map.height as i64);
        if w == 0 || h == 0 || map.resolution <= 0.0 || map.data.len() < (w * h) as usize {
            return 0;
        }
        if !self.same_geometry(map) {
            self.geometry = OccupancyGrid {
                data: Vec::new().into(),
                ..map.clone()
            };
            self.views = vec![0; (w * h) as usize];
            self.count = 0;
            self.published = None;
        }
        let p = &self.params;
        let res = map.resolution;
        // Work in the grid's frame: cell (c, r) spans [c, c + 1) x [r, r + 1) times res.
        let local = map.origin.0.inverse() * camera.0;
        let (cx, cy) = (local.translation.x, local.translation.y);
        let heading = local.rotation.angle();
        let blocks = |c: i64, r: i64| {
            let v = map.data[(r * w + c) as usize];
            v < 0 || v >= p.occupied_threshold
        };
        let borders_unknown = |c: i64, r: i64| {
            [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|(dc, dr)| {
                let (nc, nr) = (c + dc, r + dr);
                nc >= 0 && nr >= 0 && nc < w && nr < h && map.data[(nr * w + nc) as usize] < 0
            })
        };
        // Whether a victim standing at (dx, dy) from the camera is whole in the image and its
        // foot too (nearer than `min_range` ahead, along the heading, the foot leaves the image).
        let in_view = |dx: f64, dy: f64| {
            let d = dx.hypot(dy);
            let off = (dy.atan2(dx) - heading + std::f64::consts::PI)
                .rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            d > 0.0
                && d * off.cos() >= p.min_range
                && off.abs() + (p.victim_radius / d).atan() <= p.fov / 2.0 - EDGE_MARGIN
        };
        let camera_cell = ((cx / res).floor() as i64, (cy / res).floor() as i64);
        let reach = (p.max_range / res).ceil() as i64 + 1;
        let mut added = 0;
        for r in (camera_cell.1 - reach).max(0)..=(camera_cell.1 + reach).min(h - 1) {
            for c in (camera_cell.0 - reach).max(0)..=(camera_cell.0 + reach).min(w - 1) {
                let k = (r * w + c) as usize;
                if self.views[k] >= p.min_views || map.data[k] < 0 {
                    continue;
                }
                let (dx, dy) = ((c as f64 + 0.5) * res - cx, (r as f64 + 0.5) * res - cy);
                let d = dx.hypot(dy);
                if d > p.max_range || d > p.edge_range && borders_unknown(c, r) {
                    continue;
                }
                // A victim may stand anywhere on the cell: the centre first (most cells are out
                // of view), then every corner.
                if !in_view(dx, dy)
                    || !CORNERS
                        .iter()
                        .all(|(kx, ky)| in_view(dx + kx * res, dy + ky * res))
                {
                    continue;
                }
                let mut clear = true;
                traverse(
                    (0.0, 0.0),
                    res,
                    (cx, cy),
                    (dx / d, dy / d),
                    d,
                    |col, row, _| {
                        if (col, row) == (c, r) {
                            return false;
                        }
                        // The camera's own cell never hides anything (the robot stands in it).
                        let outside = col < 0 || row < 0 || col >= w || row >= h;
                        if (col, row) != camera_cell && (outside || blocks(col, row)) {
                            clear = false;
                            return false;
                        }
                        true
                    },
                );
                if clear {
                    self.views[k] += 1;
                    if self.views[k] == p.min_views {
                        added += 1;
                    }
                }
            }
        }
        if added > 0 {
            self.count += added;
            self.published = None;
        }
        added
    }

    /// Whether cell `(col, row)` of the navigation map was searched.
    pub fn is_searched(&self, col: i64, row: i64) -> bool {
        let (w, h) = (self.geometry.width as i64, self.geometry.height as i64);
        col >= 0
            && row >= 0
            && col < w
            && row < h
            && self.views[(row * w + col) as usize] >= self.params.min_views
    }

    /// Searched area, square metres.
    pub fn area(&self) -> f64 {
        self.count as f64 * self.geometry.resolution * self.geometry.resolution
    }

    /// The searched map as a grid of the navigation map's geometry: [`SEARCHED`] or
    /// [`NOT_SEARCHED`] per cell (empty before the first look).
    pub fn grid(&mut self) -> OccupancyGrid {
        if self.published.is_none() {
            let min = self.params.min_views;
            let data: Vec<i8> = self
                .views
                .iter()
                .map(|&v| if v >= min { SEARCHED } else { NOT_SEARCHED })
                .collect();
            self.published = Some(OccupancyGrid {
                data: data.into(),
                ..self.geometry.clone()
            });
        }
        self.published.clone().expect("just published")
    }

    fn same_geometry(&self, map: &OccupancyGrid) -> bool {
        let g = &self.geometry;
        g.width == map.width
            && g.height == map.height
            && g.resolution == map.resolution
            && g.origin == map.origin
            && !self.views.is_empty()
    }
}

/// How far the heading turned from pose `from` to pose `to`, in degrees, 0 to 180: the shorter
/// way round.
pub fn heading_change(from: &Pose2, to: &Pose2) -> f64 {
    from.0.rotation.angle_to(&to.0.rotation).abs().to_degrees()
}

#[cfg(test)]
mod tests;
