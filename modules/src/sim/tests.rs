//! Simulator tests: collisions, odometry, scans and determinism.

use super::*;

/// 10 m x 6 m, 0.1 m cells, walls on the border and a wall column at x in [6.0, 6.1].
fn corridor() -> Grid {
    let mut g = Grid::new(100, 60, 0.1, 0.0, 0.0).unwrap();
    for i in 0..100 {
        g.set(i, 0, true);
        g.set(i, 59, true);
    }
    for j in 0..60 {
        g.set(0, j, true);
        g.set(99, j, true);
        g.set(60, j, true);
    }
    g
}

#[test]
fn robot_driven_into_a_wall_stops_counts_and_never_enters_it() {
    let mut w = World::new(corridor(), 1);
    let cfg = RobotConfig {
        limits: Limits {
            max_speed: 2.0,
            max_accel: 100.0,
            ..Limits::default()
        },
        ..RobotConfig::default()
    };
    let id = w.add_robot(cfg, Pose2::new(3.0, 3.0, 0.0)).unwrap();
    w.set_command(id, Twist2::new(2.0, 0.0)).unwrap();
    let mut max_x: f64 = 0.0;
    for _ in 0..300 {
        let out = &w.step(0.05).unwrap()[id];
        max_x = max_x.max(out.ground_truth.x());
        // The disc never overlaps the wall: centre stays at least one radius before x = 6.0.
        assert!(out.ground_truth.x() <= 6.0 - 0.2 + 1e-9);
    }
    let out = &w.step(0.05).unwrap()[id];
    assert_eq!(
        out.collisions, 1,
        "pushing against the wall is one collision event"
    );
    assert_eq!(out.speed, Twist2::default());
    assert!(
        max_x > 6.0 - 0.2 - 0.01,
        "stopped close to the wall, got {max_x}"
    );
    // Back off, then hit again: a second event.
    w.set_command(id, Twist2::new(-1.0, 0.0)).unwrap();
    for _ in 0..20 {
        w.step(0.05).unwrap();
    }
    w.set_command(id, Twist2::new(2.0, 0.0)).unwrap();
    for _ in 0..40 {
        w.step(0.05).unwrap();
    }
    assert_eq!(w.step(0.05).unwrap()[id].collisions, 2);
    assert!(w.pose(id).unwrap().x() <= 5.8 + 1e-9);
}

#[test]
fn a_fast_robot_cannot_tunnel_through_a_thin_wall_in_one_step() {
    let mut w = World::new(corridor(), 1);
    let cfg = RobotConfig {
        limits: Limits {
            max_speed: 50.0,
            max_accel: 1e6,
            ..Limits::default()
        },
        laser: None,
        ..RobotConfig::default()
    };
    let id = w.add_robot(cfg, Pose2::new(5.0, 3.0, 0.0)).unwrap();
    w.set_command(id, Twist2::new(50.0, 0.0)).unwrap();
    // 50 m/s for 0.1 s would end at x = 10 m, far beyond the wall.
    let out = &w.step(0.1).unwrap()[id];
    assert!(out.ground_truth.x() <= 5.8 + 1e-9 && out.collisions == 1);
}

#[test]
fn scans_see_walls_and_odometry_follows_motion() {
    let mut w = World::new(corridor(), 7);
    let id = w
        .add_robot(RobotConfig::default(), Pose2::new(2.0, 3.0, 0.0))
        .unwrap();
    let out = w.step(0.01).unwrap()[id].clone();
    let scan = out.scan.unwrap();
    assert_eq!(scan.ranges.len(), 181);
    assert!((scan.angle(90)).abs() < 1e-12);
    assert!((scan.ranges[90] - 4.0).abs() < 1e-9, "wall face at x = 6.0");
    assert!((scan.ranges[0] - 2.9).abs() < 1e-9 && (scan.ranges[180] - 2.9).abs() < 1e-9);
    assert_eq!(out.odometry.stamp, 0.01);
    w.set_command(id, Twist2::new(0.5, 0.0)).unwrap();
    for _ in 0..200 {
        w.step(0.01).unwrap();
    }
    let out = &w.step(0.01).unwrap()[id];
    assert_eq!(
        out.odometry.pose, out.ground_truth,
        "noise-free odometry is exact"
    );
    assert!(out.ground_truth.x() > 2.8 && out.speed.v == 0.5);
}

#[test]
fn laser_rate_limits_scans_in_simulated_time() {
    let mut w = World::new(corridor(), 7);
    let laser = LaserConfig {
        rate_hz: Some(20.0),
        ..LaserConfig::default()
    };
    let id = w
        .add_robot(RobotConfig::with_laser(laser), Pose2::new(2.0, 3.0, 0.0))
        .unwrap();
    let scans = (0..100)
        .filter(|_| w.step(0.01).unwrap()[id].scan.is_some())
        .count();
    assert_eq!(scans, 20);
}

fn noisy_run(seed: u64) -> Vec<RobotOutput> {
    let mut w = World::new(corridor(), seed);
    let cfg = RobotConfig {
        odom_noise: Some(OdomNoise {
            trans_std: 0.05,
            rot_std: 0.05,
            rot_per_trans_std: 0.02,
        }),
        laser: Some(LaserConfig {
            range_noise_std: 0.02,
            ..LaserConfig::default()
        }),
        ..RobotConfig::default()
    };
    let a = w.add_robot(cfg.clone(), Pose2::new(2.0, 3.0, 0.0)).unwrap();
    let b = w.add_robot(cfg, Pose2::new(2.0, 1.0, 0.0)).unwrap();
    let mut log = Vec::new();
    for k in 0..300 {
        w.set_command(a, Twist2::new(0.6, (k as f64 * 0.05).sin()))
            .unwrap();
        w.set_command(b, Twist2::new(0.4, -0.3)).unwrap();
        log.extend_from_slice(w.step(0.02).unwrap());
    }
    log
}

#[test]
fn same_seed_same_run_bit_for_bit() {
    let (a, b, c) = (noisy_run(42), noisy_run(42), noisy_run(43));
    assert_eq!(a, b);
    assert_ne!(a, c);
    let last = a.last().unwrap();
    assert_ne!(last.odometry.pose, last.ground_truth, "noise is applied");
}

#[test]
fn invalid_robots_and_steps_are_rejected() {
    let mut w = World::new(corridor(), 1);
    let e = w
        .add_robot(RobotConfig::default(), Pose2::new(6.05, 3.0, 0.0))
        .unwrap_err();
    assert_eq!(e.param, "start");
    let e = w
        .add_robot(
            RobotConfig {
                radius: 0.0,
                ..RobotConfig::default()
            },
            Pose2::new(2.0, 3.0, 0.0),
        )
        .unwrap_err();
    assert_eq!(
        e.to_string(),
        "invalid parameter `radius`: expected a finite value > 0, got 0"
    );
    assert_eq!(w.step(-1.0).unwrap_err().param, "dt");
}

#[test]
fn holonomic_base_moves_sideways_and_stops_at_a_wall() {
    let mut w = World::new(corridor(), 1);
    let cfg = RobotConfig {
        drive: DriveKind::Holonomic,
        laser: None,
        ..RobotConfig::default()
    };
    let id = w.add_robot(cfg, Pose2::new(3.0, 3.0, 0.0)).unwrap();
    w.set_command(
        id,
        Twist2 {
            v: 0.0,
            vy: 0.5,
            omega: 0.0,
        },
    )
    .unwrap();
    for _ in 0..200 {
        w.step(0.05).unwrap();
    }
    let out = &w.step(0.05).unwrap()[id];
    // Slid along +y (left of a robot facing +x) up to the wall face at y = 5.9.
    assert!((out.ground_truth.x() - 3.0).abs() < 1e-9);
    assert!(out.ground_truth.y() <= 5.7 + 1e-9 && out.ground_truth.y() > 5.69);
    assert_eq!(out.collisions, 1);
    assert!(w.set_command(7, Twist2::default()).is_err());
}

#[test]
fn a_mounted_laser_measures_from_its_mounting_pose() {
    let mut w = World::new(corridor(), 1);
    let laser = LaserConfig {
        mount: Pose2::new(0.1, 0.0, std::f64::consts::PI),
        ..LaserConfig::default()
    };
    let id = w
        .add_robot(RobotConfig::with_laser(laser), Pose2::new(2.0, 3.0, 0.0))
        .unwrap();
    let scan = w.step(1e-3).unwrap()[id].scan.clone().unwrap();
    // Mounted 0.1 m forward, looking backward: the wall face at x = 0.1 is 2.0 m away.
    assert!((scan.ranges[90] - 2.0).abs() < 1e-9, "{}", scan.ranges[90]);
}

#[test]
fn robots_see_and_block_each_other() {
    let mut w = World::new(corridor(), 1);
    let a = w
        .add_robot(RobotConfig::default(), Pose2::new(1.0, 3.0, 0.0))
        .unwrap();
    let b = w
        .add_robot(
            RobotConfig::default(),
            Pose2::new(4.0, 3.0, std::f64::consts::PI),
        )
        .unwrap();
    assert_eq!(
        w.add_robot(RobotConfig::default(), Pose2::new(4.1, 3.1, 0.0))
            .unwrap_err()
            .param,
        "start"
    );
    let out = w.step(1e-3).unwrap().to_vec();
    // Each sees the other's near side: centres 3 m apart, radius 0.2 -> 2.8 m.
    let ahead = |o: &RobotOutput| o.scan.as_ref().unwrap().ranges[90];
    assert!((ahead(&out[a]) - 2.8).abs() < 1e-6 && (ahead(&out[b]) - 2.8).abs() < 1e-6);
    w.set_command(a, Twist2::new(0.7, 0.0)).unwrap();
    w.set_command(b, Twist2::new(0.7, 0.0)).unwrap();
    for _ in 0..200 {
        let out = w.step(0.05).unwrap();
        let gap = (out[a].ground_truth.x() - out[b].ground_truth.x()).abs();
        assert!(gap >= 0.4 - 1e-9, "robots overlap: centres {gap} m apart");
    }
    let out = w.step(0.05).unwrap();
    assert!(out[a].collisions >= 1 && out[b].collisions >= 1);
}
