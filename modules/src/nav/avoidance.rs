//! Reactive obstacle avoidance: a small dynamic-window controller on the raw laser scan.
//!
//! Candidate arcs `(v, omega)` are scored by how close they bring the robot to the local
//! target, how much free space they leave and how fast they are. An arc is admissible only if
//! the robot, inflated by `safety_margin`, can travel at least `v * brake_time` along it
//! before touching any laser point; the fastest forward motion therefore shrinks to zero as a
//! wall ahead gets close, and no forward command is ever given into a wall. Turning in place
//! is always considered safe (the footprint is a disc).

use std::f64::consts::{PI, TAU};

use petrel_actors::{LaserScan, Pose2, Twist2};

use self::escape::{straight_free_length, Escape, Reach};
use crate::sim::error::{non_negative, positive, ParamError};

/// Obstacle avoidance parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct AvoidanceParams {
    /// Largest forward speed commanded, m/s (default 0.5).
    pub max_speed: f64,
    /// Largest turn rate commanded, rad/s (default 1.5).
    pub max_turn: f64,
    /// Robot radius, metres (default 0.2).
    pub robot_radius: f64,
    /// Extra distance kept from laser points, metres (default 0.05).
    pub safety_margin: f64,
    /// Free distance required per m/s of speed, seconds (default 1.0): covers braking and latency.
    pub brake_time: f64,
    /// How far ahead (in time) arcs are compared against the target, seconds (default 1.0).
    pub lookahead_time: f64,
    /// Bearing to the target beyond which the robot turns in place first, radians (default 0.8).
    pub turn_in_place_bearing: f64,
    /// Distance to the target under which the robot stops, metres (default 0.05); there it
    /// turns in place to the target's own heading, if that is not zero.
    pub stop_distance: f64,
    /// Weight of free space along an arc (capped at 1 m) in the score (default 0.3).
    pub clearance_weight: f64,
    /// Laser pose in the robot frame (default identity).
    pub laser_mount: Pose2,
}

impl Default for AvoidanceParams {
    fn default() -> Self {
        AvoidanceParams {
            max_speed: 0.5,
            max_turn: 1.5,
            robot_radius: 0.2,
            safety_margin: 0.05,
            brake_time: 1.0,
            lookahead_time: 1.0,
            turn_in_place_bearing: 0.8,
            stop_distance: 0.05,
            clearance_weight: 0.3,
            laser_mount: Pose2::default(),
        }
    }
}

impl AvoidanceParams {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("max_speed", self.max_speed)?;
        positive("max_turn", self.max_turn)?;
        positive("robot_radius", self.robot_radius)?;
        non_negative("safety_margin", self.safety_margin)?;
        positive("brake_time", self.brake_time)?;
        positive("lookahead_time", self.lookahead_time)?;
        positive("turn_in_place_bearing", self.turn_in_place_bearing)?;
        non_negative("stop_distance", self.stop_distance)?;
        non_negative("clearance_weight", self.clearance_weight)
    }
}

/// A target's heading below this, radians, is no turn to make (the planner's "stay" is the
/// identity; a heading it asks for is beyond its tolerance, at least 0.01 rad).
const HEADING_DEADBAND: f64 = 1e-3;
const SPEED_SAMPLES: usize = 6;
const TURN_SAMPLES: usize = 21;
/// Arcs are followed for at most half a turn: beyond that the robot would come back into the
/// area behind it that a 180 degree laser does not see.
const MAX_ARC_ANGLE: f64 = PI;
const MAX_LOOK: f64 = 3.0;

/// The reactive controller (stateless apart from its parameters and point buffers).
#[derive(Clone, Debug)]
pub struct Avoidance {
    params: AvoidanceParams,
    points: Vec<(f64, f64)>,
    /// Scratch space for the heading search.
    rotated: Vec<(f64, f64)>,
}

impl Avoidance {
    /// A controller with the given parameters.
    pub fn new(params: AvoidanceParams) -> Result<Self, ParamError> {
        params.validate()?;
        Ok(Avoidance {
            params,
            points: Vec::new(),
            rotated: Vec::new(),
        })
    }

    /// The velocity command toward `target` (robot frame) given the latest `scan`.
    ///
    /// When the target's own direction is in view but blocked right ahead, the robot steers
    /// for the best way out instead (see `escape`), and when no forward arc is admissible at
    /// all, it turns in place toward that way out.
    pub fn step(&mut self, scan: &LaserScan, target: Pose2) -> Twist2 {
        self.collect_points(scan);
        let p = self.params.clone();
        let (tx, ty) = (target.x(), target.y());
        if !(tx.is_finite() && ty.is_finite()) {
            return Twist2::default();
        }
        let turn_toward =
            |angle: f64| Twist2::new(0.0, (2.0 * angle).clamp(-p.max_turn, p.max_turn));
        if tx.hypot(ty) < p.stop_distance {
            // There: turn in place to the target's heading (a planner that was asked to face
            // its goal), or stay.
            let heading = target.theta();
            return match heading.is_finite() && heading.abs() > HEADING_DEADBAND {
                true => turn_toward(heading),
                false => Twist2::default(),
            };
        }
        let fov = self.field_of_view(scan);
        let goal = if self.blocked_toward((tx, ty), fov) {
            self.escape((tx, ty), fov).map_or((tx, ty), |e| e.point)
        } else {
            (tx, ty)
        };
        let bearing = goal.1.atan2(goal.0);
        if bearing.abs() > p.turn_in_place_bearing {
            return turn_toward(bearing);
        }
        let mut best: Option<(f64, Twist2)> = None;
        for i in 1..=SPEED_SAMPLES {
            let v = p.max_speed * i as f64 / SPEED_SAMPLES as f64;
            for j in 0..TURN_SAMPLES {
                let omega = p.max_turn * (2.0 * j as f64 / (TURN_SAMPLES - 1) as f64 - 1.0);
                let free = free_arc_length(&self.points, v, omega, p.robot_radius, p.safety_margin);
                if free < v * p.brake_time {
                    continue;
                }
                let s = free.min(v * p.lookahead_time);
                let (ex, ey) = arc_point(v, omega, s);
                let score = -(ex - goal.0).hypot(ey - goal.1)
                    + p.clearance_weight * free.min(1.0)
                    + 0.05 * v / p.max_speed;
                if best.is_none_or(|(b, _)| score > b) {
                    best = Some((score, Twist2::new(v, omega)));
                }
            }
        }
        if let Some((_, cmd)) = best {
            return cmd;
        }
        // Nothing forward is safe: turn in place toward the way out; without one, toward
        // the target if it is off to one side, otherwise toward the side with more room.
        match self.escape((tx, ty), fov) {
            Some(way_out) => turn_toward(way_out.heading),
            None if bearing.abs() > 0.2 => turn_toward(bearing),
            None => turn_toward(self.roomier_side(scan)),
        }
    }

    /// The footprint and step lengths of the heading search.
    fn reach(&self) -> Reach {
        let p = &self.params;
        Reach {
            radius: p.robot_radius,
            margin: p.safety_margin,
            min_step: p.max_speed / SPEED_SAMPLES as f64 * p.brake_time,
            max_step: p.max_speed * p.lookahead_time,
        }
    }

    /// Whether `target` lies in view and the robot could not drive straight toward it even
    /// the slowest arc's braking distance (or the distance to the target, if shorter).
    fn blocked_toward(&mut self, target: (f64, f64), fov: (f64, f64)) -> bool {
        let bearing = target.1.atan2(target.0);
        if !(fov.0..=fov.1).contains(&bearing) {
            return false;
        }
        let reach = self.reach();
        let needed = reach.min_step.min(target.0.hypot(target.1));
        straight_free_length(&self.points, bearing, reach, &mut self.rotated) < needed
    }

    fn escape(&mut self, target: (f64, f64), fov: (f64, f64)) -> Option<Escape> {
        let reach = self.reach();
        escape::escape(&self.points, target, fov, reach, &mut self.rotated)
    }

    /// The angles the scan covers, robot frame.
    fn field_of_view(&self, scan: &LaserScan) -> (f64, f64) {
        let mount = self.params.laser_mount.theta();
        let last = scan.angle(scan.ranges.len().saturating_sub(1));
        let (a, b) = (scan.angle_min + mount, last + mount);
        (a.min(b), a.max(b))
    }

    fn collect_points(&mut self, scan: &LaserScan) {
        let mount = self.params.laser_mount.0;
        self.points.clear();
        for (i, &r) in scan.ranges.iter().enumerate() {
            if r.is_finite() && r >= 0.0 && r < scan.range_max {
                let (s, c) = scan.angle(i).sin_cos();
                let q = mount * nalgebra::Point2::new(r * c, r * s);
                self.points.push((q.x, q.y));
            }
        }
    }

    /// +1 rad if the left half of the scan has more room, -1 rad otherwise.
    fn roomier_side(&self, scan: &LaserScan) -> f64 {
        let (mut left, mut right) = (0.0, 0.0);
        for (i, &r) in scan.ranges.iter().enumerate() {
            let r = if r.is_finite() { r } else { 0.0 };
            if scan.angle(i) > 0.0 {
                left += r
            } else {
                right += r
            }
        }
        if left >= right {
            1.0
        } else {
            -1.0
        }
    }
}

/// Robot-frame position after travelling arc length `s` on the arc `(v, omega)`, v > 0.
fn arc_point(v: f64, omega: f64, s: f64) -> (f64, f64) {
    let k = omega / v;
    if k.abs() < 1e-9 {
        (s, 0.0)
    } else {
        ((k * s).sin() / k, (1.0 - (k * s).cos()) / k)
    }
}

/// How far (arc length) a disc of `radius` can move forward along the arc `(v, omega)` before
/// coming within `margin` of any of `points`, capped at half a turn and 3 m.
///
/// A point already inside the margin only counts with the bare radius: the robot may slide
/// along a wall it is close to, but never move into it.
pub fn free_arc_length(points: &[(f64, f64)], v: f64, omega: f64, radius: f64, margin: f64) -> f64 {
    let k = omega / v;
    let outer2 = (radius + margin).powi(2);
    let (rho, cy) = if k.abs() < 1e-9 {
        (f64::INFINITY, 0.0)
    } else {
        (1.0 / k.abs(), 1.0 / k)
    };
    let start = (-cy).atan2(0.0);
    let dir = omega.signum();
    let mut free = (MAX_ARC_ANGLE * rho).min(MAX_LOOK);
    for &(px, py) in points {
        let d2 = px * px + py * py;
        let r = if d2 < outer2 { radius } else { radius + margin };
        if d2 < radius * radius {
            return 0.0; // already touching
        }
        if rho.is_infinite() {
            // Straight ahead: the disc first touches the point when its centre reaches x = px - w.
            if py.abs() < r {
                let w = (r * r - py * py).sqrt();
                if px - w >= 0.0 {
                    free = free.min(px - w);
                } else if px > 0.0 {
                    return 0.0; // inside the margin and ahead: any forward motion approaches it
                }
            }
            continue;
        }
        // On an arc the centre moves on a circle of radius rho around (0, cy), in the
        // direction of omega.
        let dp = px.hypot(py - cy);
        if (dp - rho).abs() >= r {
            continue; // the swept annulus never reaches this point
        }
        // Angle (around the centre) between first touching the point and being closest to it.
        let half = ((rho * rho + dp * dp - r * r) / (2.0 * rho * dp))
            .clamp(-1.0, 1.0)
            .acos();
        let ahead = (dir * ((py - cy).atan2(px) - start)).rem_euclid(TAU);
        if ahead < half {
            return 0.0; // inside the margin and the arc approaches it
        }
        if ahead <= TAU - half {
            free = free.min((ahead - half) * rho);
        }
    }
    free
}

mod escape;
#[cfg(test)]
mod tests;
