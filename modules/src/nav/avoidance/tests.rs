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

/// Drives robot 1 by the controller alone toward a fixed world `target`, beside a still
/// robot 0 at (1, 1) in the corner of two walls, for `seconds`; returns robot 1's final pose
/// and its collision count.
fn wedged_run(start: Pose2, target: (f64, f64), seconds: f64) -> (Pose2, u64) {
    let mut g = Grid::new(40, 30, 0.1, 0.0, 0.0).unwrap();
    g.fill_rect(0.0, 0.0, 4.0, 0.2);
    g.fill_rect(0.0, 0.0, 0.2, 3.0);
    let mut w = World::new(g, 3);
    let laser = LaserConfig {
        rate_hz: Some(10.0),
        ..LaserConfig::default()
    };
    let body = RobotConfig {
        laser: None,
        ..RobotConfig::default()
    };
    w.add_robot(body, Pose2::new(1.0, 1.0, 0.0)).unwrap();
    let me = w.add_robot(RobotConfig::with_laser(laser), start).unwrap();
    let mut a = Avoidance::new(AvoidanceParams::default()).unwrap();
    let dt = 0.02;
    let mut collisions = 0;
    for _ in 0..(seconds / dt) as usize {
        let out = w.step(dt).unwrap()[me].clone();
        collisions = out.collisions;
        if let Some(scan) = out.scan {
            let p = out.ground_truth.0;
            let t = p.inverse() * nalgebra::Point2::new(target.0, target.1);
            w.set_command(me, a.step(&scan, Pose2::new(t.x, t.y, 0.0)))
                .unwrap();
        }
    }
    (w.pose(me).unwrap(), collisions)
}

/// A robot that squeezed between a wall and a teammate's body, 5 cm from the body (inside
/// the safety margin), used to turn back and forth there for good: every arc along its
/// heading approached the body, and turning toward the target led back into the same wedge.
/// The heading search turns it to a way out, from any heading, for targets on either side.
#[test]
fn a_robot_wedged_beside_a_body_gets_out_from_any_heading() {
    for target in [(2.0, 0.6), (0.5, 1.5)] {
        for h in 0..12 {
            let heading = TAU * h as f64 / 12.0;
            let (end, collisions) = wedged_run(Pose2::new(0.87, 0.57, heading), target, 30.0);
            let left = (end.x() - target.0).hypot(end.y() - target.1);
            assert!(
                left < 0.1,
                "target {target:?}, start heading {:.0} deg: stopped at ({:.2}, {:.2}), {left:.2} m short",
                heading.to_degrees(),
                end.x(),
                end.y()
            );
            assert_eq!(collisions, 0, "target {target:?}, heading {heading}");
        }
    }
}

#[test]
fn the_way_out_is_the_visible_heading_that_gains_most_and_none_when_nothing_gains() {
    let reach = Reach {
        radius: 0.2,
        margin: 0.05,
        min_step: 0.1,
        max_step: 0.5,
    };
    let mut buf = Vec::new();
    // A wall across the whole view 0.3 m ahead, open to the right beyond y = -0.4.
    let wall: Vec<(f64, f64)> = (0..=40).map(|i| (0.3, -0.4 + 0.05 * i as f64)).collect();
    let fov = (-PI / 2.0, PI / 2.0);
    let out = escape::escape(&wall, (2.0, 0.0), fov, reach, &mut buf).unwrap();
    assert!(
        out.heading < -0.5,
        "turns right, toward the opening: {out:?}"
    );
    let free = straight_free_length(&wall, out.heading, reach, &mut buf);
    let step = out.point.0.hypot(out.point.1);
    assert!(
        step <= free + 1e-9 && step >= reach.min_step,
        "{out:?}, free {free}"
    );
    // Straight ahead is blocked at once. At the end of a dead end (walls ahead and 0.3 m to
    // either side), no visible heading is open far enough to gain: the search says so.
    assert!(straight_free_length(&wall, 0.0, reach, &mut buf) < reach.min_step);
    let mut dead_end: Vec<(f64, f64)> = (0..=12).map(|i| (0.3, -0.3 + 0.05 * i as f64)).collect();
    for i in 0..=6 {
        dead_end.extend([(0.05 * i as f64, 0.3), (0.05 * i as f64, -0.3)]);
    }
    assert_eq!(
        escape::escape(&dead_end, (2.0, 0.0), fov, reach, &mut buf),
        None
    );
    // A field of view too narrow for the guard, or NaN, leaves nothing to try; a scan
    // claiming an enormous one is searched over one turn at most.
    assert_eq!(
        escape::escape(&[], (2.0, 0.0), (-0.1, 0.1), reach, &mut buf),
        None
    );
    assert_eq!(
        escape::escape(&[], (2.0, 0.0), (f64::NAN, 1.0), reach, &mut buf),
        None
    );
    assert!(escape::escape(&[], (2.0, 0.0), (-1e300, 1e300), reach, &mut buf).is_some());
    // In the open, straight at the target gains most.
    let open = escape::escape(&[], (2.0, 0.0), fov, reach, &mut buf).unwrap();
    assert!(
        open.heading.abs() < 1e-9 && (open.point.0 - 0.5).abs() < 1e-9,
        "{open:?}"
    );
}

/// At the target's position, a target with a heading turns the robot in place toward it (a
/// planner asking to face its goal); the identity stays put.
#[test]
fn at_the_target_it_turns_in_place_to_the_targets_heading() {
    let mut a = Avoidance::new(AvoidanceParams::default()).unwrap();
    let scan = open_scan();
    assert_eq!(a.step(&scan, Pose2::default()), Twist2::default());
    let left = a.step(&scan, Pose2::new(0.0, 0.0, 0.6));
    assert_eq!(left.v, 0.0);
    assert!(left.omega > 0.0, "{left:?}");
    let right = a.step(&scan, Pose2::new(0.0, 0.0, -2.5));
    assert_eq!(right.v, 0.0);
    assert!(right.omega < 0.0, "{right:?}");
}
