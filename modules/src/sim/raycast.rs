//! Grid ray traversal (Amanatides & Woo, 1987) and laser ray casting.
//!
//! The traversal visits exactly the cells a ray passes through, in order, with one addition
//! and one comparison per cell, which is what makes a 181-ray scan cheap enough to run at
//! every simulation step.

use super::grid::Grid;

/// Visits the cells crossed by the ray from `(x, y)` (world metres) along unit direction
/// `(dx, dy)` on a grid with the given `origin` and `resolution`, up to distance `max_t`.
///
/// `visit(col, row, t_enter)` receives each cell and the distance at which the ray enters it
/// (0 for the start cell); returning `false` stops the walk, and the function then returns
/// that `t_enter`. If the walk reaches `max_t` it returns `None`.
#[inline]
pub fn traverse(
    origin: (f64, f64),
    resolution: f64,
    (x, y): (f64, f64),
    (dx, dy): (f64, f64),
    max_t: f64,
    mut visit: impl FnMut(i64, i64, f64) -> bool,
) -> Option<f64> {
    let gx = (x - origin.0) / resolution;
    let gy = (y - origin.1) / resolution;
    // A NaN start or direction would never cross a cell boundary nor reach `max_t`.
    if !(gx.is_finite() && gy.is_finite() && dx.is_finite() && dy.is_finite()) {
        return None;
    }
    let mut col = gx.floor() as i64;
    let mut row = gy.floor() as i64;
    let (step_c, t_delta_x, mut t_max_x) = axis(gx, dx, resolution);
    let (step_r, t_delta_y, mut t_max_y) = axis(gy, dy, resolution);
    let mut t = 0.0;
    loop {
        if !visit(col, row, t) {
            return Some(t);
        }
        if t_max_x < t_max_y {
            t = t_max_x;
            t_max_x += t_delta_x;
            col += step_c;
        } else {
            t = t_max_y;
            t_max_y += t_delta_y;
            row += step_r;
        }
        // Also ends a ray that goes nowhere (direction 0: `t` becomes infinite).
        if !(t <= max_t && t.is_finite()) {
            return None;
        }
    }
}

/// Step direction, distance between boundary crossings and distance to the first crossing
/// along one axis; `g` is the position in cell units.
#[inline]
fn axis(g: f64, d: f64, resolution: f64) -> (i64, f64, f64) {
    if d > 0.0 {
        (1, resolution / d, (g.floor() + 1.0 - g) * resolution / d)
    } else if d < 0.0 {
        (-1, -resolution / d, (g - g.floor()) * resolution / -d)
    } else {
        (0, f64::INFINITY, f64::INFINITY)
    }
}

/// Distance from `(x, y)` along `angle` to the first solid cell, or `max_range` if none is
/// closer. A ray starting inside a solid cell returns 0.
#[inline]
pub fn cast_ray(grid: &Grid, x: f64, y: f64, angle: f64, max_range: f64) -> f64 {
    let (s, c) = angle.sin_cos();
    traverse(
        grid.origin(),
        grid.resolution(),
        (x, y),
        (c, s),
        max_range,
        |col, row, _| !grid.is_solid(col, row),
    )
    .map_or(max_range, |t| t.min(max_range))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A 10 m x 10 m room (0.1 m cells) whose walls are the outermost cells.
    fn room() -> Grid {
        let mut g = Grid::new(100, 100, 0.1, 0.0, 0.0).unwrap();
        for i in 0..100 {
            g.set(i, 0, true);
            g.set(i, 99, true);
            g.set(0, i, true);
            g.set(99, i, true);
        }
        g
    }

    #[test]
    fn known_distances_to_walls_at_known_angles() {
        let g = room();
        // Inner wall faces are at x = 0.1, x = 9.9, y = 0.1, y = 9.9.
        let (x, y) = (3.0, 4.0);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
        assert!(close(cast_ray(&g, x, y, 0.0, 20.0), 6.9));
        assert!(close(cast_ray(&g, x, y, PI / 2.0, 20.0), 5.9));
        assert!(close(cast_ray(&g, x, y, PI, 20.0), 2.9));
        assert!(close(cast_ray(&g, x, y, -PI / 2.0, 20.0), 3.9));
        // 45 degrees down-left: hits y = 0.1 after 3.9 * sqrt(2) before reaching x = 0.1.
        assert!(close(
            cast_ray(&g, x, y, -3.0 * PI / 4.0, 20.0),
            2.9 * 2f64.sqrt()
        ));
        // atan2(1, 2): reaches x = 9.9 (dx 6.9) at dy 3.45 < 5.9.
        let a = 1f64.atan2(2.0);
        assert!(close(cast_ray(&g, x, y, a, 20.0), 6.9 / a.cos()));
        // Capped by the range limit.
        assert_eq!(cast_ray(&g, x, y, 0.0, 1.5), 1.5);
    }

    #[test]
    fn rays_stop_at_the_grid_border_and_inside_solid_is_zero() {
        let g = Grid::new(10, 10, 1.0, 0.0, 0.0).unwrap();
        assert!((cast_ray(&g, 2.5, 2.5, 0.0, 100.0) - 7.5).abs() < 1e-12);
        let mut g = g;
        g.set(2, 2, true);
        assert_eq!(cast_ray(&g, 2.5, 2.5, 1.0, 100.0), 0.0);
    }

    #[test]
    fn a_ray_from_nowhere_or_in_no_direction_ends() {
        // Each used to walk for ever: NaN never crosses a boundary nor reaches the limit.
        let walk = |x: f64, dx: f64| {
            let mut cells = 0;
            let end = traverse((0.0, 0.0), 0.1, (x, 1.0), (dx, 0.0), 5.0, |_, _, _| {
                cells += 1;
                cells < 10_000
            });
            (end, cells)
        };
        assert_eq!(walk(f64::NAN, 1.0), (None, 0));
        assert_eq!(walk(1.0, f64::NAN), (None, 0));
        assert_eq!(walk(1.0, 0.0), (None, 1));
        assert_eq!(walk(1.0, 1.0).1, 51);
    }

    #[test]
    fn traversal_matches_dense_sampling() {
        let g = room();
        let mut rng = 12345u64;
        let mut next = || {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (rng >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut g2 = g.clone();
        for _ in 0..60 {
            g2.set((next() * 100.0) as i64, (next() * 100.0) as i64, true);
        }
        for _ in 0..200 {
            let (x, y, a) = (0.2 + next() * 9.6, 0.2 + next() * 9.6, next() * 2.0 * PI);
            if g2.is_solid(g2.cell_of(x, y).0, g2.cell_of(x, y).1) {
                continue;
            }
            let r = cast_ray(&g2, x, y, a, 30.0);
            // Just before the hit is free, just after is solid (sampled densely).
            let at = |t: f64| g2.cell_of(x + t * a.cos(), y + t * a.sin());
            let (c, rw) = at(r + 1e-6);
            assert!(g2.is_solid(c, rw), "no wall right after the hit");
            let mut t = 0.0;
            while t < r - 1e-6 {
                let (c, rw) = at(t);
                assert!(!g2.is_solid(c, rw), "ray passed through a wall");
                t += 0.001;
            }
        }
    }
}
