//! Scan-matching localization: odometry predicts, the laser corrects against the map being built.
//!
//! The matcher keeps its own likelihood field: every cell that laser endpoints hit often enough
//! spreads a Gaussian bump (`sigma`) around it, so a scan's fit is the mean field value under
//! its endpoints (1 = every endpoint on a known wall). A new scan is placed at the pose
//! odometry predicts and then hill-climbed in x, y and heading with halving steps (the
//! classic incremental matcher: between two scans odometry errs by millimetres, so a local
//! search from the prediction finds the fit without a costly window search). The scan is then
//! added to the field at the corrected pose, once the robot moved enough, and only when it
//! fitted (a robot that lost itself must not draw a second, shifted map over the first).
//! The fit is the localization quality.

use petrel_actors::{cell_to_world, world_to_cell, LaserScan, Pose2};

use crate::sim::error::{positive, ParamError};

/// Scan matcher parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanMatcherParams {
    /// Field cells along x.
    pub width: u32,
    /// Field cells along y.
    pub height: u32,
    /// Field cell size, metres (default 0.05).
    pub resolution: f64,
    /// World x, y of the field's lower-left corner.
    pub origin: (f64, f64),
    /// Laser pose in the robot frame.
    pub laser_mount: Pose2,
    /// Width of the bump around each wall cell, metres (default 0.05).
    pub sigma: f64,
    /// First hill-climbing step in x and y, metres (default 0.04); halved down to 1/16.
    pub step_xy: f64,
    /// First hill-climbing step in heading, radians (default 0.02).
    pub step_theta: f64,
    /// Largest correction accepted for one scan, metres (default 0.1); a larger one is a
    /// false fit and is refused.
    pub max_correction: f64,
    /// Use every n-th ray (default 2).
    pub ray_stride: usize,
    /// Fit below which a scan is not added to the field (default 0.5).
    pub min_fit_to_map: f64,
    /// Travel (m) or turn (rad / 2) after which a scan is added to the field (default 0.05).
    pub map_every: f64,
}

impl Default for ScanMatcherParams {
    fn default() -> Self {
        ScanMatcherParams {
            width: 400,
            height: 400,
            resolution: 0.05,
            origin: (0.0, 0.0),
            laser_mount: Pose2::default(),
            sigma: 0.05,
            step_xy: 0.04,
            step_theta: 0.02,
            max_correction: 0.1,
            ray_stride: 2,
            min_fit_to_map: 0.5,
            map_every: 0.05,
        }
    }
}

impl ScanMatcherParams {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), ParamError> {
        let cells = self.width as u64 * self.height as u64;
        if cells == 0 || cells > crate::sim::Grid::MAX_CELLS as u64 {
            return Err(ParamError {
                param: "width".into(),
                message: format!(
                    "expected a field of 1 to {} cells, got {} x {}",
                    crate::sim::Grid::MAX_CELLS,
                    self.width,
                    self.height
                ),
            });
        }
        for (name, v) in [
            ("resolution", self.resolution),
            ("sigma", self.sigma),
            ("step_xy", self.step_xy),
            ("step_theta", self.step_theta),
            ("max_correction", self.max_correction),
            ("map_every", self.map_every),
        ] {
            positive(name, v)?;
        }
        if !(0.0..=1.0).contains(&self.min_fit_to_map) {
            return Err(ParamError {
                param: "min_fit_to_map".into(),
                message: format!("expected a number in [0, 1], got {}", self.min_fit_to_map),
            });
        }
        if self.ray_stride == 0 {
            return Err(ParamError {
                param: "ray_stride".into(),
                message: "expected at least 1, got 0".into(),
            });
        }
        Ok(())
    }
}

/// How often endpoints must hit a cell before it counts as a wall. One: the first scan alone
/// must give the second something to match, and a stray hit only adds a small bump.
const HITS_FOR_WALL: u8 = 1;
/// Weight of the motion prior against the fit (a mean in 0..1).
const PRIOR_WEIGHT: f64 = 0.01;
/// Position and heading errors of odometry between two scans that the prior tolerates.
const PRIOR_XY: f64 = 0.05;
const PRIOR_THETA: f64 = 0.05;
/// Fewest endpoints for a scan to be matched at all (a robot facing open space has none).
const MIN_POINTS: usize = 10;

/// The likelihood field and the hill-climbing matcher.
#[derive(Clone, Debug)]
pub struct ScanMatcher {
    params: ScanMatcherParams,
    field: Vec<f32>,
    hits: Vec<u8>,
    walls: usize,
    /// Cell offsets a hit's bump reaches.
    kernel: Vec<(i64, i64)>,
}

impl ScanMatcher {
    /// An empty field.
    pub fn new(params: ScanMatcherParams) -> Result<Self, ParamError> {
        params.validate()?;
        let n = params.width as usize * params.height as usize;
        let radius = (2.0 * params.sigma / params.resolution).ceil() as i64;
        let mut kernel = Vec::new();
        for dy in -radius..=radius {
            for dx in -radius..=radius {
                kernel.push((dx, dy));
            }
        }
        Ok(ScanMatcher {
            params,
            field: vec![0.0; n],
            hits: vec![0; n],
            walls: 0,
            kernel,
        })
    }

    /// Cells counted as walls so far.
    pub fn wall_cells(&self) -> usize {
        self.walls
    }

    /// Endpoints of every `stride`-th ray that hit something, in the robot frame.
    pub fn endpoints(&self, scan: &LaserScan, stride: usize) -> Vec<(f64, f64)> {
        let mount = self.params.laser_mount.0;
        scan.ranges
            .iter()
            .enumerate()
            .step_by(stride.max(1))
            .filter(|(_, &r)| r.is_finite() && r > 0.0 && r < scan.range_max - 1e-6)
            .map(|(i, &r)| {
                let a = scan.angle(i);
                let p = mount * nalgebra::Point2::new(r * a.cos(), r * a.sin());
                (p.x, p.y)
            })
            .collect()
    }

    /// Field value at a world point, bilinear between cell centres (0 outside).
    fn value_at(&self, x: f64, y: f64) -> f64 {
        let p = &self.params;
        let gx = (x - p.origin.0) / p.resolution - 0.5;
        let gy = (y - p.origin.1) / p.resolution - 0.5;
        let (cx, cy) = (gx.floor(), gy.floor());
        let (fx, fy) = ((gx - cx) as f32, (gy - cy) as f32);
        let (cx, cy) = (cx as i64, cy as i64);
        let at = |c: i64, r: i64| -> f32 {
            if c < 0 || r < 0 || c >= p.width as i64 || r >= p.height as i64 {
                0.0
            } else {
                self.field[r as usize * p.width as usize + c as usize]
            }
        };
        let top = at(cx, cy + 1) * (1.0 - fx) + at(cx + 1, cy + 1) * fx;
        let bottom = at(cx, cy) * (1.0 - fx) + at(cx + 1, cy) * fx;
        (bottom * (1.0 - fy) + top * fy) as f64
    }

    /// Mean field value under `points` (robot frame) placed at `pose`: the fit, 0..1.
    pub fn fit(&self, pose: Pose2, points: &[(f64, f64)]) -> f64 {
        if points.is_empty() {
            return 0.0;
        }
        let (s, c) = pose.theta().sin_cos();
        let sum: f64 = points
            .iter()
            .map(|&(px, py)| self.value_at(pose.x() + c * px - s * py, pose.y() + s * px + c * py))
            .sum();
        sum / points.len() as f64
    }

    /// The pose near `predicted` where `points` fit the field best, and that fit; `None`
    /// when there is nothing to match (empty field or too few endpoints) or the best fit lies
    /// further than `max_correction` (a false fit).
    pub fn best_pose(&self, predicted: Pose2, points: &[(f64, f64)]) -> Option<(Pose2, f64)> {
        if self.walls == 0 || points.len() < MIN_POINTS {
            return None;
        }
        let p = &self.params;
        let (mut x, mut y, mut t) = (predicted.x(), predicted.y(), predicted.theta());
        // The motion prior: odometry errs little between two scans, so a pose far from its
        // prediction must fit clearly better (along a corridor, where every shift fits the
        // same, the estimate stays with odometry instead of wandering).
        let (px, py, pt) = (x, y, t);
        let prior = |x: f64, y: f64, t: f64| {
            PRIOR_WEIGHT
                * (((x - px).powi(2) + (y - py).powi(2)) / (PRIOR_XY * PRIOR_XY)
                    + (t - pt).powi(2) / (PRIOR_THETA * PRIOR_THETA))
        };
        let score = |pose: Pose2, x: f64, y: f64, t: f64| self.fit(pose, points) - prior(x, y, t);
        let mut best = score(predicted, x, y, t);
        let (mut sxy, mut st) = (p.step_xy, p.step_theta);
        for _level in 0..5 {
            // Climb at this step size until no neighbour is better, at most a few moves.
            for _ in 0..8 {
                let mut moved = false;
                for (dx, dy, dt) in [
                    (sxy, 0.0, 0.0),
                    (-sxy, 0.0, 0.0),
                    (0.0, sxy, 0.0),
                    (0.0, -sxy, 0.0),
                    (0.0, 0.0, st),
                    (0.0, 0.0, -st),
                ] {
                    let (nx, ny, nt) = (x + dx, y + dy, t + dt);
                    let f = score(Pose2::new(nx, ny, nt), nx, ny, nt);
                    if f > best + 1e-9 {
                        (best, x, y, t, moved) = (f, x + dx, y + dy, t + dt, true);
                    }
                }
                if !moved {
                    break;
                }
            }
            sxy *= 0.5;
            st *= 0.5;
        }
        let moved = (x - predicted.x()).hypot(y - predicted.y());
        let pose = Pose2::new(x, y, t);
        (moved <= p.max_correction).then(|| (pose, self.fit(pose, points)))
    }

    /// Adds endpoints (robot frame) seen from `pose` to the field.
    pub fn add(&mut self, pose: Pose2, points: &[(f64, f64)]) {
        let p = &self.params;
        let (w, h) = (p.width as i64, p.height as i64);
        let origin = Pose2::new(p.origin.0, p.origin.1, 0.0);
        let (s, c) = pose.theta().sin_cos();
        for &(px, py) in points {
            let (x, y) = (pose.x() + c * px - s * py, pose.y() + s * px + c * py);
            let (col, row) = world_to_cell(&origin, p.resolution, x, y);
            if col < 0 || row < 0 || col >= w || row >= h {
                continue;
            }
            let i = (row * w + col) as usize;
            if self.hits[i] >= HITS_FOR_WALL {
                continue;
            }
            self.hits[i] += 1;
            if self.hits[i] < HITS_FOR_WALL {
                continue;
            }
            self.walls += 1;
            // The bump is centred on the exact endpoint, not on its cell, so the field carries
            // no half-cell bias.
            let inv = -0.5 / (p.sigma * p.sigma);
            for &(dx, dy) in &self.kernel {
                let (cc, rr) = (col + dx, row + dy);
                if cc >= 0 && rr >= 0 && cc < w && rr < h {
                    let centre = cell_to_world(&origin, p.resolution, cc, rr).0;
                    let (cx, cy) = (centre.x, centre.y);
                    let v = (((cx - x).powi(2) + (cy - y).powi(2)) * inv).exp() as f32;
                    let cell = &mut self.field[(rr * w + cc) as usize];
                    *cell = cell.max(v);
                }
            }
        }
    }

    /// The parameters.
    pub fn params(&self) -> &ScanMatcherParams {
        &self.params
    }
}

/// What the localizer knows after a scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanOutcome {
    /// The corrected pose.
    pub pose: Pose2,
    /// Fit of the scan at that pose, 0..1 (the localization quality).
    pub fit: f64,
    /// Whether the scan was matched (false: nothing to match yet, or a refused fit).
    pub matched: bool,
}

/// Odometry prediction + scan matching: the whole localizer, pure.
#[derive(Clone, Debug)]
pub struct ScanLocalizer {
    matcher: ScanMatcher,
    estimate: Option<Pose2>,
    last_odometry: Option<Pose2>,
    last_added: Option<Pose2>,
    quality: f64,
}

impl ScanLocalizer {
    /// A localizer that starts where the first odometry sample says.
    pub fn new(params: ScanMatcherParams) -> Result<Self, ParamError> {
        Ok(ScanLocalizer {
            matcher: ScanMatcher::new(params)?,
            estimate: None,
            last_odometry: None,
            last_added: None,
            quality: 1.0,
        })
    }

    /// Moves the estimate by the odometry increment since the previous sample.
    pub fn odometry(&mut self, odometry: Pose2) -> Pose2 {
        let estimate = match (self.estimate, self.last_odometry) {
            (Some(e), Some(prev)) => Pose2(e.0 * (prev.0.inverse() * odometry.0)),
            _ => odometry,
        };
        self.estimate = Some(estimate);
        self.last_odometry = Some(odometry);
        estimate
    }

    /// Corrects the estimate with a scan taken at the latest odometry sample.
    pub fn scan(&mut self, scan: &LaserScan) -> ScanOutcome {
        let predicted = self.pose();
        let points = self
            .matcher
            .endpoints(scan, self.matcher.params().ray_stride);
        let (pose, fit, matched) = match self.matcher.best_pose(predicted, &points) {
            Some((pose, fit)) => (pose, fit, true),
            None if self.matcher.wall_cells() == 0 => (predicted, 1.0, false),
            None => (predicted, self.matcher.fit(predicted, &points), false),
        };
        self.estimate = Some(pose);
        self.quality = fit;
        let far = self.last_added.is_none_or(|last| {
            let d = (pose.x() - last.x()).hypot(pose.y() - last.y());
            let turn = (pose.theta() - last.theta()).sin().abs() * 0.5;
            d.max(turn) >= self.matcher.params().map_every
        });
        let young = self.matcher.wall_cells() < 50;
        if far && (young || fit >= self.matcher.params().min_fit_to_map) {
            // Every ray draws the field (a denser wall), every n-th one is matched (faster).
            let all = self.matcher.endpoints(scan, 1);
            self.matcher.add(pose, &all);
            self.last_added = Some(pose);
        }
        ScanOutcome { pose, fit, matched }
    }

    /// The current estimate (the origin before any odometry).
    pub fn pose(&self) -> Pose2 {
        self.estimate.unwrap_or_default()
    }

    /// The fit of the latest scan, 0..1 (1 before any wall was seen).
    pub fn quality(&self) -> f64 {
        self.quality
    }
}

#[cfg(test)]
mod tests;
