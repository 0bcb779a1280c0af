//! The ground-truth world grid: which cells are solid.

use std::sync::Arc;

use petrel_actors::{cell_to_world, world_to_cell, OccupancyGrid, Point2, Pose2};

use super::error::{finite, positive, ParamError};

/// A binary occupancy grid: the simulator's ground truth.
///
/// Cell `(col, row)` covers `[ox + col*res, ox + (col+1)*res) x [oy + row*res, oy + (row+1)*res)`;
/// row 0 is at the bottom (smallest y), as in ROS. Everything outside the grid counts as
/// solid, so a world is always closed: rays stop and robots collide at its border.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    width: usize,
    height: usize,
    resolution: f64,
    origin_x: f64,
    origin_y: f64,
    /// The same origin as a pose, for the shared world/cell conversion (world files refuse a
    /// rotated origin, so its yaw is 0).
    origin: Pose2,
    /// 1 = solid, 0 = free; `u8` rather than `bool` so the ray caster reads plain bytes.
    cells: Vec<u8>,
}

/// The cell sizes a world or map may have, in metres: a millimetre to ten metres. Beyond, a
/// world is nothing a robot drives in (a resolution of 1e300 passed and printed poses of 300
/// digits).
pub const RESOLUTION: std::ops::RangeInclusive<f64> = 0.001..=10.0;

/// How far from (0, 0) a world or map's corner may lie, in metres on each axis: a thousand
/// kilometres. An origin of 1e308 passed, and the start pose was then refused as outside a
/// world `1e308..=1e308` wide (the cells' extent lost in the rounding).
pub const ORIGIN: std::ops::RangeInclusive<f64> = -1e6..=1e6;

/// Why `origin` (x, y) is no corner a world may have, if it is not.
pub fn origin_problem(x: f64, y: f64) -> Option<String> {
    let inside = |v: f64| ORIGIN.contains(&v);
    (!inside(x) || !inside(y)).then(|| {
        let n = petrel_actors::short_number;
        format!(
            "expected `x, y` in metres within -1e6..=1e6 (a thousand kilometres), got {}, {}",
            n(x),
            n(y)
        )
    })
}

impl Grid {
    /// An all-free grid of `width x height` cells of `resolution` metres, lower-left corner at
    /// `(origin_x, origin_y)`.
    ///
    /// Fails if the resolution is not finite and positive, the origin is not finite, or the
    /// grid is empty or larger than [`Grid::MAX_CELLS`].
    pub fn new(
        width: usize,
        height: usize,
        resolution: f64,
        origin_x: f64,
        origin_y: f64,
    ) -> Result<Self, ParamError> {
        positive("resolution", resolution)?;
        finite("origin_x", origin_x)?;
        finite("origin_y", origin_y)?;
        match width.checked_mul(height) {
            Some(n) if n > 0 && n <= Self::MAX_CELLS => {}
            _ => {
                return Err(ParamError {
                    param: "size".into(),
                    message: format!(
                        "expected between 1 and {} cells, got {width} x {height}",
                        Self::MAX_CELLS
                    ),
                })
            }
        }
        Ok(Grid {
            width,
            height,
            resolution,
            origin_x,
            origin_y,
            origin: Pose2::new(origin_x, origin_y, 0.0),
            cells: vec![0; width * height],
        })
    }

    /// Largest number of cells a grid may have (256 Mi): a guard against absurd file headers.
    pub const MAX_CELLS: usize = 1 << 28;

    /// Cells along x.
    pub fn width(&self) -> usize {
        self.width
    }
    /// Cells along y.
    pub fn height(&self) -> usize {
        self.height
    }
    /// Cell edge length, metres.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }
    /// World coordinates of the lower-left corner of cell (0, 0).
    pub fn origin(&self) -> (f64, f64) {
        (self.origin_x, self.origin_y)
    }
    /// World extent `(min_x, min_y, max_x, max_y)`.
    pub fn bounds(&self) -> (f64, f64, f64, f64) {
        (
            self.origin_x,
            self.origin_y,
            self.origin_x + self.width as f64 * self.resolution,
            self.origin_y + self.height as f64 * self.resolution,
        )
    }

    /// Marks cell `(col, row)` solid or free; out-of-range cells are ignored.
    pub fn set(&mut self, col: i64, row: i64, solid: bool) {
        if self.in_bounds(col, row) {
            self.cells[row as usize * self.width + col as usize] = solid as u8;
        }
    }

    /// Marks every cell whose centre lies in the axis-aligned box `[x0,x1] x [y0,y1]` solid.
    pub fn fill_rect(&mut self, x0: f64, y0: f64, x1: f64, y1: f64) {
        let (c0, r0) = self.cell_of(x0.min(x1), y0.min(y1));
        let (c1, r1) = self.cell_of(x0.max(x1), y0.max(y1));
        for row in r0..=r1 {
            for col in c0..=c1 {
                let (cx, cy) = self.cell_center(col, row);
                if cx >= x0.min(x1) && cx <= x0.max(x1) && cy >= y0.min(y1) && cy <= y0.max(y1) {
                    self.set(col, row, true);
                }
            }
        }
    }

    /// Whether `(col, row)` is inside the grid.
    #[inline]
    pub fn in_bounds(&self, col: i64, row: i64) -> bool {
        col >= 0 && row >= 0 && (col as usize) < self.width && (row as usize) < self.height
    }

    /// Whether cell `(col, row)` is solid; cells outside the grid are solid.
    #[inline]
    pub fn is_solid(&self, col: i64, row: i64) -> bool {
        !self.in_bounds(col, row) || self.cells[row as usize * self.width + col as usize] != 0
    }

    /// The cell containing world point `(x, y)` (may be outside the grid).
    #[inline]
    pub fn cell_of(&self, x: f64, y: f64) -> (i64, i64) {
        world_to_cell(&self.origin, self.resolution, x, y)
    }

    /// World coordinates of the centre of cell `(col, row)`.
    pub fn cell_center(&self, col: i64, row: i64) -> (f64, f64) {
        let centre = cell_to_world(&self.origin, self.resolution, col, row).0;
        (centre.x, centre.y)
    }

    /// Whether a disc of `radius` centred at `(x, y)` overlaps any solid cell (or leaves the grid).
    ///
    /// Exact disc-versus-square test on the cells under the disc's bounding box, so a robot may
    /// touch a wall corner diagonally without being reported as colliding.
    pub fn disc_collides(&self, x: f64, y: f64, radius: f64) -> bool {
        let (c0, r0) = self.cell_of(x - radius, y - radius);
        let (c1, r1) = self.cell_of(x + radius, y + radius);
        let r2 = radius * radius;
        for row in r0..=r1 {
            for col in c0..=c1 {
                if !self.is_solid(col, row) {
                    continue;
                }
                let lx = self.origin_x + col as f64 * self.resolution;
                let ly = self.origin_y + row as f64 * self.resolution;
                let dx = x - x.clamp(lx, lx + self.resolution);
                let dy = y - y.clamp(ly, ly + self.resolution);
                if dx * dx + dy * dy < r2 {
                    return true;
                }
            }
        }
        false
    }

    /// Number of solid cells inside the grid.
    pub fn solid_count(&self) -> usize {
        self.cells.iter().filter(|&&c| c != 0).count()
    }

    /// The grid as a ROS-style occupancy grid (100 solid, 0 free; nothing unknown).
    pub fn to_occupancy(&self) -> OccupancyGrid {
        let data: Arc<[i8]> = self
            .cells
            .iter()
            .map(|&c| if c != 0 { 100 } else { 0 })
            .collect();
        OccupancyGrid {
            width: self.width as u32,
            height: self.height as u32,
            resolution: self.resolution,
            origin: Pose2::new(self.origin_x, self.origin_y, 0.0),
            data,
        }
    }

    /// Whether the straight segment from `a` to `b` keeps a disc of `radius` clear of solid
    /// cells, sampled every `radius / 4` along the way.
    pub fn segment_clear(&self, a: Point2, b: Point2, radius: f64) -> bool {
        let d = b.0 - a.0;
        let n = ((d.norm() / (radius / 4.0).max(1e-6)).ceil() as usize).max(1);
        (0..=n).all(|i| {
            let p = a.0 + d * (i as f64 / n as f64);
            !self.disc_collides(p.x, p.y, radius)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outside_is_solid_and_cells_map_to_coordinates() {
        let g = Grid::new(10, 5, 0.5, -1.0, 2.0).unwrap();
        assert!(g.is_solid(-1, 0) && g.is_solid(0, 5) && !g.is_solid(9, 4));
        assert_eq!(g.cell_of(-1.0, 2.0), (0, 0));
        assert_eq!(g.cell_of(-0.01, 2.49), (1, 0));
        assert_eq!(g.cell_center(1, 1), (-0.25, 2.75));
        assert_eq!(g.bounds(), (-1.0, 2.0, 4.0, 4.5));
    }

    #[test]
    fn disc_collision_is_exact_against_cell_squares() {
        let mut g = Grid::new(20, 20, 0.1, 0.0, 0.0).unwrap();
        g.set(10, 10, true); // square [1.0,1.1] x [1.0,1.1]
        assert!(!g.disc_collides(0.79, 1.05, 0.2));
        assert!(g.disc_collides(0.81, 1.05, 0.2));
        // Diagonal to the corner (1.0, 1.0): distance sqrt(2)*0.15 = 0.212 > 0.2.
        assert!(!g.disc_collides(0.85, 0.85, 0.2));
        assert!(g.disc_collides(0.87, 0.87, 0.2));
    }
}
