//! Obstacle avoidance tests.

use super::*;
use crate::sim::{Grid, LaserConfig, RobotConfig, World};
use rand::{Rng, SeedableRng};

/// A 181-ray, 180 degree scan of the straight wall `x = d` in front of the robot.
fn wall_scan(d: f64) -> LaserScan {
    let ranges: Vec<f64> = (0..181)
        .map(|i| {
            let a = -PI / 2.0 + PI * i as f64 / 180.0;
            if a.cos() > 1e-9 {
                (d / a.cos()).min(8.0)
            } else {
                8.0
            }
        })
        .collect();
    LaserScan {
        angle_min: -PI / 2.0,
        angle_increment: PI / 180.0,
        range_max: 8.0,
        ranges: ranges.into(),
    }
}

fn open_scan() -> LaserScan {
    LaserScan {
        angle_min: -PI / 2.0,
        angle_increment: PI / 180.0,
        range_max: 8.0,
        ranges: vec![8.0; 181].into(),
    }
}

/// Robot-frame positions of the centre along the arc of `cmd` for `t` seconds.
fn sweep(cmd: Twist2, t: f64) -> impl Iterator<Item = (f64, f64)> {
    (0..=200).map(move |i| {
        let p = crate::sim::kinematics::integrate(Pose2::default(), cmd, t * i as f64 / 200.0);
        (p.x(), p.y())
    })
}

#[test]
fn never_commands_forward_motion_into_a_wall_directly_ahead() {
    let params = AvoidanceParams::default();
    let mut a = Avoidance::new(params.clone()).unwrap();
    let mut d = 0.201;
    while d < 2.5 {
        for k in -7..=7 {
            let target = Pose2::new(3.0, 3.0 * 0.1 * k as f64, 0.0); // beyond the wall
            let cmd = a.step(&wall_scan(d), target);
            assert!(cmd.v >= 0.0);
            if d <= params.robot_radius + params.safety_margin {
                assert_eq!(cmd.v, 0.0, "wall at {d}: must not move forward");
            }
            for (x, _) in sweep(cmd, params.brake_time) {
                assert!(
                    x + params.robot_radius <= d + 1e-9,
                    "wall at {d}, target {k}: {cmd:?} reaches x = {x}"
                );
            }
        }
        d += 0.013;
    }
    // Far from the wall it drives at full speed.
    assert_eq!(
        a.step(&wall_scan(5.0), Pose2::new(1.0, 0.0, 0.0)),
        Twist2::new(params.max_speed, 0.0)
    );
}

#[test]
fn steers_toward_the_target_and_turns_in_place_when_it_is_behind() {
    let mut a = Avoidance::new(AvoidanceParams::default()).unwrap();
    let left = a.step(&open_scan(), Pose2::new(0.6, 0.4, 0.0));
    assert!(left.v > 0.0 && left.omega > 0.0, "{left:?}");
    let right = a.step(&open_scan(), Pose2::new(0.6, -0.4, 0.0));
    assert!(right.v > 0.0 && right.omega < 0.0, "{right:?}");
    let behind = a.step(&open_scan(), Pose2::new(-1.0, -0.1, 0.0));
    assert!(behind.v == 0.0 && behind.omega < 0.0, "{behind:?}");
    assert_eq!(
        a.step(&open_scan(), Pose2::new(0.01, 0.0, 0.0)),
        Twist2::default()
    );
    assert!(Avoidance::new(AvoidanceParams {
        max_turn: f64::NAN,
        ..AvoidanceParams::default()
    })
    .is_err());
}

#[test]
fn chosen_arcs_keep_the_disc_off_every_laser_point_in_random_clutter() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let params = AvoidanceParams::default();
    let mut a = Avoidance::new(params.clone()).unwrap();
    let mut moved = 0;
    for _ in 0..60 {
        let mut g = Grid::new(80, 80, 0.05, -2.0, -2.0).unwrap();
        for _ in 0..12 {
            let (x, y) = (rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0));
            g.fill_rect(
                x,
                y,
                x + rng.random_range(0.05..0.6),
                y + rng.random_range(0.05..0.6),
            );
        }
        if g.disc_collides(0.0, 0.0, params.robot_radius) {
            continue;
        }
        let mut w = World::new(g, 0);
        let laser = LaserConfig {
            range_max: 4.0,
            ..LaserConfig::default()
        };
        let id = w
            .add_robot(RobotConfig::with_laser(laser), Pose2::default())
            .unwrap();
        let scan = w.step(1e-6).unwrap()[id].scan.clone().unwrap();
        let target = Pose2::new(
            rng.random_range(-1.0..2.0),
            rng.random_range(-1.5..1.5),
            0.0,
        );
        let cmd = a.step(&scan, target);
        assert!(
            cmd.v.abs() <= params.max_speed && cmd.omega.abs() <= params.max_turn && cmd.vy == 0.0
        );
        if cmd.v > 0.0 {
            moved += 1;
        }
        let points: Vec<(f64, f64)> = (0..scan.ranges.len())
            .filter(|&i| scan.ranges[i] < scan.range_max)
            .map(|i| {
                (
                    scan.ranges[i] * scan.angle(i).cos(),
                    scan.ranges[i] * scan.angle(i).sin(),
                )
            })
            .collect();
        for (x, y) in sweep(cmd, params.brake_time) {
            for &(px, py) in &points {
                assert!(
                    (px - x).hypot(py - y) >= params.robot_radius - 1e-9,
                    "{cmd:?} hits ({px}, {py})"
                );
            }
        }
    }
    assert!(moved > 20, "most scenes allow some forward motion: {moved}");
}

#[test]
fn free_arc_length_matches_brute_force() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    for _ in 0..300 {
        let points: Vec<(f64, f64)> = (0..5)
            .map(|_| (rng.random_range(-1.0..2.0), rng.random_range(-1.5..1.5)))
            .collect();
        let (v, omega) = (rng.random_range(0.1..1.0), rng.random_range(-2.0..2.0));
        let r = 0.2;
        let free = free_arc_length(&points, v, omega, r, 0.0);
        // Walk the arc in 1 mm steps until a point is within r.
        let mut s = 0.0;
        let cap = if omega.abs() / v < 1e-9 {
            3.0
        } else {
            (PI * v / omega.abs()).min(3.0)
        };
        while s < cap {
            let (x, y) = arc_point(v, omega, s);
            if points.iter().any(|&(px, py)| (px - x).hypot(py - y) < r) {
                break;
            }
            s += 0.001;
        }
        assert!(
            (free - s.min(cap)).abs() < 0.002 + 1e-9,
            "free {free} vs walked {s} for v {v}, omega {omega}"
        );
    }
}
