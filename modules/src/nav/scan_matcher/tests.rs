use super::*;
use crate::sim::{parse_ascii, OdomNoise, RobotConfig, World};

/// A 10 m x 8 m room with an L-shaped wall and a pillar, so every direction is constrained.
fn room() -> crate::sim::Grid {
    let mut rows = vec!["#".repeat(50)];
    for r in 1..39 {
        let mut row: Vec<char> = format!("#{}#", " ".repeat(48)).chars().collect();
        if (10..25).contains(&r) {
            row[30] = '#';
        }
        if r == 24 {
            for c in row.iter_mut().take(30).skip(18) {
                *c = '#';
            }
        }
        if (30..33).contains(&r) {
            for c in row.iter_mut().take(13).skip(10) {
                *c = '#';
            }
        }
        rows.push(row.into_iter().collect());
    }
    rows.push("#".repeat(50));
    let text = format!("# resolution: 0.2\n{}\n", rows.join("\n"));
    parse_ascii(std::path::Path::new("room.txt"), &text)
        .unwrap()
        .grid
}

fn params() -> ScanMatcherParams {
    ScanMatcherParams {
        width: 200,
        height: 160,
        ..ScanMatcherParams::default()
    }
}

fn scan_at(grid: &crate::sim::Grid, pose: Pose2) -> LaserScan {
    let mut world = World::new(grid.clone(), 3);
    world.add_robot(RobotConfig::default(), pose).unwrap();
    world.step(0.01).unwrap()[0].scan.clone().unwrap()
}

#[test]
fn recovers_a_known_offset() {
    let grid = room();
    let truth = Pose2::new(3.0, 3.0, 0.3);
    let mut m = ScanMatcher::new(params()).unwrap();
    let points = m.endpoints(&scan_at(&grid, truth), 1);
    m.add(truth, &points);
    // A second scan from a nearby true pose, predicted with an error of 8 cm, 5 cm, 0.04 rad.
    let second = Pose2::new(3.3, 3.1, 0.35);
    let points = m.endpoints(&scan_at(&grid, second), 2);
    let predicted = Pose2::new(second.x() + 0.08, second.y() - 0.05, second.theta() + 0.04);
    let before = m.fit(predicted, &points);
    let (found, fit) = m.best_pose(predicted, &points).unwrap();
    let err = (found.x() - second.x()).hypot(found.y() - second.y());
    assert!(err < 0.02, "position error {err} at {found:?}");
    assert!((found.theta() - second.theta()).abs() < 0.01, "{found:?}");
    assert!(fit > 0.7 && fit > before + 0.2, "fit {before} -> {fit}");
    // Too far from the truth for a local search to be trusted: refused, not a false fit.
    let tight = ScanMatcher {
        params: ScanMatcherParams {
            max_correction: 0.02,
            ..params()
        },
        ..m.clone()
    };
    assert!(tight.best_pose(predicted, &points).is_none());
}

#[test]
fn an_empty_field_or_open_space_is_not_matched() {
    let m = ScanMatcher::new(params()).unwrap();
    let grid = room();
    let points = m.endpoints(&scan_at(&grid, Pose2::new(3.0, 3.0, 0.0)), 2);
    assert!(m.best_pose(Pose2::new(3.0, 3.0, 0.0), &points).is_none());
    let mut l = ScanLocalizer::new(params()).unwrap();
    l.odometry(Pose2::new(3.0, 3.0, 0.0));
    let first = l.scan(&scan_at(&grid, Pose2::new(3.0, 3.0, 0.0)));
    assert!(!first.matched && first.fit == 1.0, "{first:?}");
    let bad = ScanMatcherParams {
        ray_stride: 0,
        ..params()
    };
    assert_eq!(ScanMatcher::new(bad).unwrap_err().param, "ray_stride");
}

/// Drives a noisy robot around the room and compares estimate and truth at every scan.
fn noisy_tour(noise: OdomNoise, seed: u64, use_scans: bool) -> (f64, f64) {
    let grid = room();
    let start = Pose2::new(1.0, 1.0, 0.0);
    let mut world = World::new(grid, seed);
    let robot = RobotConfig {
        odom_noise: Some(noise),
        ..RobotConfig::default()
    };
    let id = world.add_robot(robot, start).unwrap();
    let mut loc = ScanLocalizer::new(params()).unwrap();
    let (mut max, mut sum, mut n) = (0.0f64, 0.0, 0);
    // A loop around the room: straight legs and turns, 0.4 m/s, 100 Hz, scans at 20 Hz.
    let legs = [
        (7.5, 0.0),
        (0.0, std::f64::consts::FRAC_PI_2),
        (6.0, 0.0),
        (0.0, std::f64::consts::FRAC_PI_2),
        (7.5, 0.0),
        (0.0, std::f64::consts::FRAC_PI_2),
        (6.0, 0.0),
        (0.0, std::f64::consts::FRAC_PI_2),
    ];
    let mut k = 0u64;
    for _lap in 0..3 {
        for &(dist, turn) in &legs {
            let (v, w, secs): (f64, f64, f64) = if dist > 0.0 {
                (0.4, 0.0, dist / 0.4)
            } else {
                (0.0, 0.6, turn / 0.6)
            };
            let steps = (secs * 100.0).round() as u64;
            world
                .set_command(id, petrel_actors::Twist2::new(v, w))
                .unwrap();
            for _ in 0..steps {
                let out = world.step(0.01).unwrap()[id].clone();
                loc.odometry(out.odometry.pose);
                k += 1;
                if k % 5 == 0 {
                    let est = if use_scans {
                        loc.scan(out.scan.as_ref().unwrap()).pose
                    } else {
                        loc.pose()
                    };
                    let e = (est.x() - out.ground_truth.x()).hypot(est.y() - out.ground_truth.y());
                    max = max.max(e);
                    sum += e;
                    n += 1;
                }
            }
        }
    }
    (sum / n as f64, max)
}

#[test]
fn error_stays_bounded_over_a_noisy_run_where_odometry_alone_drifts() {
    let noise = OdomNoise {
        trans_std: 0.02,
        rot_std: 0.01,
        rot_per_trans_std: 0.05,
    };
    // Over several noise streams: one stream can happen to drift little. Deterministic: the
    // simulator's noise is seeded ChaCha.
    let (mut worst, mut worst_odom) = (0.0, 0.0);
    for seed in [11, 12, 13] {
        let (mean, max) = noisy_tour(noise, seed, true);
        let (mean_odom, max_odom) = noisy_tour(noise, seed, false);
        println!("seed {seed}: scan matching: mean {mean:.3} m, max {max:.3} m; odometry alone: mean {mean_odom:.3} m, max {max_odom:.3} m");
        assert!(max <= 0.15, "seed {seed}: max error {max}");
        (worst, worst_odom) = (worst + max, worst_odom + max_odom);
    }
    assert!(
        worst_odom > 1.5 * worst,
        "odometry alone strays further: {worst_odom} m against {worst} m (sums of the worst errors)"
    );
}
