//! Planning cost map: obstacle clearance (a distance transform) turned into traversal costs.

use petrel_actors::OccupancyGrid;

use crate::sim::error::{non_negative, positive, ParamError};

/// How an occupancy grid becomes a cost map.
#[derive(Clone, Debug, PartialEq)]
pub struct CostParams {
    /// Robot radius, metres (default 0.2).
    pub robot_radius: f64,
    /// Extra clearance the planner insists on beyond the radius, metres (default 0.05).
    pub safety_margin: f64,
    /// Clearance below which cells get more expensive, metres (default 0.6); keeps paths
    /// in the middle of corridors instead of grazing walls.
    pub preferred_clearance: f64,
    /// Extra cost factor at the lethal boundary, fading to 0 at `preferred_clearance` (default 3).
    pub clearance_weight: f64,
    /// Whether unknown (-1) cells may be planned through (default true: explore optimistically).
    pub unknown_is_free: bool,
    /// Occupancy percent from which a cell is an obstacle (default 50).
    pub occupied_threshold: i8,
}

impl Default for CostParams {
    fn default() -> Self {
        CostParams {
            robot_radius: 0.2,
            safety_margin: 0.05,
            preferred_clearance: 0.6,
            clearance_weight: 3.0,
            unknown_is_free: true,
            occupied_threshold: 50,
        }
    }
}

impl CostParams {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("robot_radius", self.robot_radius)?;
        non_negative("safety_margin", self.safety_margin)?;
        non_negative("clearance_weight", self.clearance_weight)?;
        if !(self.preferred_clearance.is_finite()
            && self.preferred_clearance > self.robot_radius + self.safety_margin)
        {
            return Err(ParamError {
                param: "preferred_clearance".into(),
                message: format!(
                    "expected a value > robot_radius + safety_margin, got {}",
                    self.preferred_clearance
                ),
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

    /// Whether a grid value is an obstacle.
    pub fn is_obstacle(&self, value: i8) -> bool {
        value >= self.occupied_threshold || (value < 0 && !self.unknown_is_free)
    }

    /// Clearance below which the robot centre may not be planned.
    pub fn lethal_clearance(&self) -> f64 {
        self.robot_radius + self.safety_margin
    }
}

/// Per-cell clearance and traversal cost for one grid.
#[derive(Clone, Debug)]
pub struct CostMap {
    /// Cells along x.
    pub width: usize,
    /// Cells along y.
    pub height: usize,
    /// Distance from the cell centre to the nearest obstacle cell's edge, metres
    /// (negative inside obstacles). An 8-neighbour chamfer estimate, accurate to a few percent.
    pub clearance: Vec<f32>,
    /// Cost multiplier per metre (>= 1), or infinity where the robot centre may not go.
    pub cost: Vec<f32>,
}

impl CostMap {
    /// Builds the cost map of `grid`.
    pub fn build(grid: &OccupancyGrid, p: &CostParams) -> CostMap {
        let (w, h) = (grid.width as usize, grid.height as usize);
        let res = grid.resolution as f32;
        // Two-pass chamfer distance transform, in cells between centres.
        let mut d: Vec<f32> = grid
            .data
            .iter()
            .map(|&v| if p.is_obstacle(v) { 0.0 } else { f32::INFINITY })
            .collect();
        let diag = std::f32::consts::SQRT_2;
        for row in 0..h {
            for col in 0..w {
                let k = row * w + col;
                let mut v = d[k];
                if col > 0 {
                    v = v.min(d[k - 1] + 1.0)
                }
                if row > 0 {
                    v = v.min(d[k - w] + 1.0);
                    if col > 0 {
                        v = v.min(d[k - w - 1] + diag)
                    }
                    if col + 1 < w {
                        v = v.min(d[k - w + 1] + diag)
                    }
                }
                d[k] = v;
            }
        }
        for row in (0..h).rev() {
            for col in (0..w).rev() {
                let k = row * w + col;
                let mut v = d[k];
                if col + 1 < w {
                    v = v.min(d[k + 1] + 1.0)
                }
                if row + 1 < h {
                    v = v.min(d[k + w] + 1.0);
                    if col + 1 < w {
                        v = v.min(d[k + w + 1] + diag)
                    }
                    if col > 0 {
                        v = v.min(d[k + w - 1] + diag)
                    }
                }
                d[k] = v;
            }
        }
        let lethal = p.lethal_clearance() as f32;
        let pref = p.preferred_clearance as f32;
        let weight = p.clearance_weight as f32;
        let clearance: Vec<f32> = d.iter().map(|&c| c * res - res / 2.0).collect();
        let cost = clearance
            .iter()
            .map(|&c| {
                if c < lethal {
                    f32::INFINITY
                } else {
                    let x = ((pref - c) / (pref - lethal)).max(0.0);
                    1.0 + weight * x * x
                }
            })
            .collect();
        CostMap {
            width: w,
            height: h,
            clearance,
            cost,
        }
    }

    /// Index of `(col, row)` if inside.
    pub fn index(&self, col: i64, row: i64) -> Option<usize> {
        (col >= 0 && row >= 0 && (col as usize) < self.width && (row as usize) < self.height)
            .then(|| row as usize * self.width + col as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use petrel_actors::Pose2;

    #[test]
    fn clearance_and_lethal_band_around_an_obstacle() {
        let mut data = vec![0i8; 41 * 41];
        data[20 * 41 + 20] = 100;
        data[0] = -1;
        let grid = OccupancyGrid {
            width: 41,
            height: 41,
            resolution: 0.05,
            origin: Pose2::default(),
            data: data.into(),
        };
        let m = CostMap::build(&grid, &CostParams::default());
        let at = |c: i64, r: i64| m.index(c, r).unwrap();
        assert!(m.clearance[at(20, 20)] < 0.0);
        assert!((m.clearance[at(30, 20)] - 0.475).abs() < 1e-5); // 10 cells, minus half a cell
        assert!(m.cost[at(24, 20)].is_infinite() && m.cost[at(26, 20)].is_finite());
        assert!(m.cost[at(26, 20)] > m.cost[at(30, 20)] && m.cost[at(40, 20)] == 1.0);
        assert!(m.cost[0].is_finite(), "unknown is free by default");
        let strict = CostParams {
            unknown_is_free: false,
            ..CostParams::default()
        };
        assert!(CostMap::build(&grid, &strict).cost[0].is_infinite());
    }
}
