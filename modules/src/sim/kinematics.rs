//! Planar base kinematics: command limiting and exact pose integration.

use nalgebra::{Isometry2, Vector2};
use petrel_actors::{Pose2, Twist2};

use super::error::{positive, ParamError};

/// How a base can move.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum DriveKind {
    /// Unicycle / differential drive: forward speed and turn rate; `vy` is always 0.
    #[default]
    Differential,
    /// Omnidirectional: forward, sideways and turn rate independently.
    Holonomic,
}

/// Speed and acceleration limits of a base; commands are clamped to them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Largest |forward speed|, m/s (default 0.7).
    pub max_speed: f64,
    /// Largest |sideways speed| for holonomic bases, m/s (default 0.5).
    pub max_lateral_speed: f64,
    /// Largest |turn rate|, rad/s (default 2.0).
    pub max_turn: f64,
    /// Largest change of linear speed, m/s² (default 1.5).
    pub max_accel: f64,
    /// Largest change of turn rate, rad/s² (default 4.0).
    pub max_turn_accel: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_speed: 0.7,
            max_lateral_speed: 0.5,
            max_turn: 2.0,
            max_accel: 1.5,
            max_turn_accel: 4.0,
        }
    }
}

impl Limits {
    /// Checks every limit is finite and positive.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("max_speed", self.max_speed)?;
        positive("max_lateral_speed", self.max_lateral_speed)?;
        positive("max_turn", self.max_turn)?;
        positive("max_accel", self.max_accel)?;
        positive("max_turn_accel", self.max_turn_accel)
    }
}

/// The speed a base reaches after `dt` seconds when commanded `cmd` while moving at `current`.
///
/// Speeds are clamped to the maxima, then the change from `current` is clamped by the
/// accelerations. Non-finite command components are read as 0 (stop): a broken controller
/// must not be able to make the robot jump.
pub fn limit_command(
    cmd: Twist2,
    current: Twist2,
    kind: DriveKind,
    limits: &Limits,
    dt: f64,
) -> Twist2 {
    let clean = |x: f64| if x.is_finite() { x } else { 0.0 };
    let toward =
        |from: f64, to: f64, max_delta: f64| from + (to - from).clamp(-max_delta, max_delta);
    let v = clean(cmd.v).clamp(-limits.max_speed, limits.max_speed);
    let vy = match kind {
        DriveKind::Differential => 0.0,
        DriveKind::Holonomic => {
            clean(cmd.vy).clamp(-limits.max_lateral_speed, limits.max_lateral_speed)
        }
    };
    let omega = clean(cmd.omega).clamp(-limits.max_turn, limits.max_turn);
    Twist2 {
        v: toward(current.v, v, limits.max_accel * dt),
        vy: toward(current.vy, vy, limits.max_accel * dt),
        omega: toward(current.omega, omega, limits.max_turn_accel * dt),
    }
}

/// The pose reached after moving with constant body-frame `twist` for `dt` seconds.
///
/// Exact (the SE(2) exponential), not Euler: a unicycle with `v, omega` traces a circle of
/// radius `v / omega` however large `dt` is, which keeps odometry and collision sub-steps
/// consistent with each other.
pub fn integrate(pose: Pose2, twist: Twist2, dt: f64) -> Pose2 {
    let dtheta = twist.omega * dt;
    let (dx, dy) = if dtheta.abs() < 1e-9 {
        (twist.v * dt, twist.vy * dt)
    } else {
        let (s, c) = dtheta.sin_cos();
        let w = twist.omega;
        (
            (twist.v * s + twist.vy * (c - 1.0)) / w,
            (twist.v * (1.0 - c) + twist.vy * s) / w,
        )
    };
    Pose2(pose.0 * Isometry2::new(Vector2::new(dx, dy), dtheta))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-9
    }

    #[test]
    fn straight_line_turn_in_place_and_arc_radius() {
        let p = integrate(Pose2::new(1.0, 2.0, PI / 2.0), Twist2::new(0.5, 0.0), 4.0);
        assert!(close(p.x(), 1.0) && close(p.y(), 4.0) && close(p.theta(), PI / 2.0));

        let p = integrate(Pose2::new(1.0, 2.0, 0.0), Twist2::new(0.0, 1.0), 1.5);
        assert!(close(p.x(), 1.0) && close(p.y(), 2.0) && close(p.theta(), 1.5));

        // v / omega = 2 m: every point of the arc is 2 m from the centre (0, 2), in any steps.
        let mut p = Pose2::new(0.0, 0.0, 0.0);
        for _ in 0..37 {
            p = integrate(p, Twist2::new(1.0, 0.5), 0.1);
            assert!(close((p.x().powi(2) + (p.y() - 2.0).powi(2)).sqrt(), 2.0));
        }
        // A quarter circle: pi/2 rad at 0.5 rad/s.
        let q = integrate(Pose2::new(0.0, 0.0, 0.0), Twist2::new(1.0, 0.5), PI);
        assert!(close(q.x(), 2.0) && close(q.y(), 2.0) && close(q.theta(), PI / 2.0));
    }

    #[test]
    fn holonomic_sideways_motion_rotates_with_the_robot() {
        let t = Twist2 {
            v: 0.0,
            vy: 1.0,
            omega: 0.0,
        };
        let p = integrate(Pose2::new(0.0, 0.0, PI / 2.0), t, 2.0);
        assert!(close(p.x(), -2.0) && close(p.y(), 0.0));
    }

    #[test]
    fn commands_are_clamped_by_speed_and_acceleration() {
        let l = Limits::default();
        let dt = 0.1;
        let out = limit_command(
            Twist2 {
                v: 5.0,
                vy: 1.0,
                omega: -9.0,
            },
            Twist2::default(),
            DriveKind::Differential,
            &l,
            dt,
        );
        assert!(close(out.v, 0.15) && out.vy == 0.0 && close(out.omega, -0.4));
        let mut cur = Twist2::default();
        for _ in 0..100 {
            cur = limit_command(
                Twist2 {
                    v: 5.0,
                    vy: -5.0,
                    omega: 9.0,
                },
                cur,
                DriveKind::Holonomic,
                &l,
                dt,
            );
        }
        assert_eq!(
            cur,
            Twist2 {
                v: 0.7,
                vy: -0.5,
                omega: 2.0
            }
        );
        let nan = limit_command(
            Twist2::new(f64::NAN, f64::INFINITY),
            Twist2::default(),
            DriveKind::Differential,
            &l,
            dt,
        );
        assert_eq!(nan, Twist2::default());
        assert!(Limits {
            max_turn: -1.0,
            ..l
        }
        .validate()
        .unwrap_err()
        .to_string()
        .contains("`max_turn`"));
    }
}
