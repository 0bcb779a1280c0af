//! Getting out of a wedge: which way to turn when no forward arc is admissible (pure).
//!
//! The arc search only looks along the robot's heading. Next to an obstacle that is already
//! inside (or at) the safety margin, every arc that starts along the heading may approach it,
//! so none is admissible; turning toward the target then leads back into the same wedge (a
//! robot squeezed between a wall and a teammate's body turned back and forth for minutes).
//! Turning in place is always safe, so the way out is a heading search: for every heading the
//! laser sees, how far the robot could drive straight along it, and how much closer to the
//! target that would bring it. The best such heading is where to turn, and the point reached
//! along it is what to steer for until the target's own direction is open again.
//!
//! Stateless on purpose: while the robot turns in place the geometry only rotates, so the
//! search finds the same world heading at every scan, and the robot keeps turning toward it.

use std::f64::consts::PI;

use super::free_arc_length;

/// Headings tried, radians apart (5 degrees).
const HEADING_STEP: f64 = PI / 36.0;
/// Headings this close to the edge of the laser's field of view are not tried: the disc's
/// side that sweeps past them is partly outside what the laser saw.
const FOV_GUARD: f64 = PI / 9.0;

/// A way out: turn to `heading` (robot frame, radians), then drive to `point`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Escape {
    pub heading: f64,
    pub point: (f64, f64),
}

/// The robot's footprint and how far ahead one escape looks.
#[derive(Clone, Copy, Debug)]
pub(super) struct Reach {
    pub radius: f64,
    pub margin: f64,
    /// Shortest drive worth turning for (the slowest arc's braking distance).
    pub min_step: f64,
    /// Longest drive one escape plans (what the controller looks ahead).
    pub max_step: f64,
}

/// How far the robot can drive straight along `heading` (robot frame) among `points`, by the
/// same rules as the arc search; `buf` is scratch space.
pub(super) fn straight_free_length(
    points: &[(f64, f64)],
    heading: f64,
    reach: Reach,
    buf: &mut Vec<(f64, f64)>,
) -> f64 {
    let (s, c) = heading.sin_cos();
    buf.clear();
    buf.extend(points.iter().map(|&(x, y)| (x * c + y * s, y * c - x * s)));
    free_arc_length(buf, 1.0, 0.0, reach.radius, reach.margin)
}

/// The visible heading (within `fov`, robot frame) whose straight drive brings the robot
/// closest to `target`, if any brings it closer by a useful amount.
pub(super) fn escape(
    points: &[(f64, f64)],
    target: (f64, f64),
    fov: (f64, f64),
    reach: Reach,
    buf: &mut Vec<(f64, f64)>,
) -> Option<Escape> {
    // At most one turn, whatever angles a scan claims; a NaN field of view (a scan with
    // hostile angles) leaves nothing to try.
    if fov.0.is_nan() || fov.1.is_nan() {
        return None;
    }
    let (lo, hi) = (fov.0.max(-PI) + FOV_GUARD, fov.1.min(PI) - FOV_GUARD);
    if lo > hi {
        return None;
    }
    let now = target.0.hypot(target.1);
    let mut best: Option<(f64, Escape)> = None;
    let steps = ((hi - lo) / HEADING_STEP).floor() as usize;
    for i in 0..=steps {
        let heading = lo + HEADING_STEP * i as f64;
        let free = straight_free_length(points, heading, reach, buf);
        let step = free.min(reach.max_step).min(now);
        if step < reach.min_step.min(now) {
            continue;
        }
        let point = (step * heading.cos(), step * heading.sin());
        let left = (target.0 - point.0).hypot(target.1 - point.1);
        // Worth turning for only if it gains a quarter of the shortest step; ties go to
        // the heading nearer the current one (less turning).
        if now - left < 0.25 * reach.min_step {
            continue;
        }
        let better = best.is_none_or(|(b, e)| {
            left < b - 1e-9 || (left < b + 1e-9 && heading.abs() < e.heading.abs())
        });
        if better {
            best = Some((left, Escape { heading, point }));
        }
    }
    best.map(|(_, e)| e)
}
