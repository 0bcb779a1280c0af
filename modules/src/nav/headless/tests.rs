//! End-to-end headless missions in the shipped worlds.

use std::path::{Path, PathBuf};

use super::*;
use crate::sim::render::{save_png, RenderLayers};
use crate::sim::{load_world, WorldMap};

fn world_file(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../configs/worlds")
        .join(name)
}

fn check(
    name: &str,
    world: &WorldMap,
    start: Pose2,
    goals: &[Pose2],
    params: &MissionParams,
) -> MissionSummary {
    let s = run_mission(&world.grid, start, goals, params).unwrap();
    // Keep a picture of the run for humans (target/ is ignored by git).
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/petrel-missions");
    if std::fs::create_dir_all(&out).is_ok() {
        let layers = RenderLayers {
            trajectory: &s.trajectory,
            goals,
            reached: s.reached,
            robot: Some((s.final_pose, 0.2)),
            ..RenderLayers::default()
        };
        save_png(&out.join(format!("{name}.png")), &s.map, &layers).unwrap();
    }
    println!(
        "{name}: reached {}/{} in {:.1} s sim ({} steps), {:.1} m, {} collisions, {} replans",
        s.reached, s.goals, s.sim_time, s.steps, s.distance, s.collisions, s.replans
    );
    assert!(
        s.done,
        "{name}: reached only {} of {} goals (gave up: {})",
        s.reached, s.goals, s.gave_up
    );
    assert_eq!(s.collisions, 0, "{name}: collisions");
    s
}

#[test]
fn three_goals_in_the_cluttered_world_without_collisions() {
    let world = load_world(&world_file("cluttered.txt")).unwrap();
    assert_eq!((world.starts.len(), world.goals.len()), (1, 3));
    let s = check(
        "cluttered",
        &world,
        world.starts[0],
        &world.goals,
        &MissionParams::default(),
    );
    assert!(s.sim_time < 240.0, "bounded time: {}", s.sim_time);
}

#[test]
fn three_goals_in_the_warehouse_without_collisions() {
    let world = load_world(&world_file("warehouse.yaml")).unwrap();
    let goals = [
        Pose2::new(9.75, 11.8, 0.0),
        Pose2::new(18.5, 18.5, 0.0),
        Pose2::new(1.5, 14.5, 0.0),
    ];
    let s = check(
        "warehouse",
        &world,
        Pose2::new(1.0, 1.0, 0.0),
        &goals,
        &MissionParams::default(),
    );
    assert!(s.sim_time < 240.0, "bounded time: {}", s.sim_time);
}

fn noisy_short_mission() -> MissionSummary {
    let text = "# resolution: 0.1\n".to_string()
        + &"#".repeat(60)
        + "\n"
        + &format!("#{}#\n", " ".repeat(58)).repeat(12)
        + &format!("#{}{}{}#\n", " ".repeat(25), "#".repeat(6), " ".repeat(27)).repeat(14)
        + &format!("#{}#\n", " ".repeat(58)).repeat(12)
        + &"#".repeat(60);
    let world = crate::sim::parse_ascii(Path::new("inline.txt"), &text).unwrap();
    let params = MissionParams {
        seed: 9,
        robot: crate::sim::RobotConfig {
            odom_noise: Some(crate::sim::OdomNoise {
                trans_std: 0.01,
                rot_std: 0.01,
                rot_per_trans_std: 0.005,
            }),
            laser: Some(crate::sim::LaserConfig {
                range_noise_std: 0.01,
                ..Default::default()
            }),
            ..Default::default()
        },
        localizer: LocalizerParams {
            lost_episodes: vec![(3.0, 4.0)],
            lost_drift_speed: 0.05,
            lost_heading_rate: 0.02,
            ..Default::default()
        },
        ..MissionParams::default()
    };
    run_mission(
        &world.grid,
        Pose2::new(1.0, 1.9, 0.0),
        &[Pose2::new(5.0, 1.9, 0.0)],
        &params,
    )
    .unwrap()
}

#[test]
fn a_noisy_mission_is_reproducible_bit_for_bit_and_reports_lost_localization() {
    let (a, b) = (noisy_short_mission(), noisy_short_mission());
    assert!(
        a.done && a.collisions == 0,
        "{} reached, {} collisions",
        a.reached,
        a.collisions
    );
    assert_eq!(a.trajectory, b.trajectory);
    assert_eq!(
        (a.steps, a.final_pose, a.replans),
        (b.steps, b.final_pose, b.replans)
    );
    assert_eq!(a.map, b.map);
    assert!(
        a.min_quality < 0.9,
        "the lost episode shows in the quality: {}",
        a.min_quality
    );
}

#[test]
fn mission_parameters_are_validated() {
    let grid = crate::sim::Grid::new(10, 10, 0.1, 0.0, 0.0).unwrap();
    let bad = MissionParams {
        control_hz: 30.0,
        ..MissionParams::default()
    };
    let e = run_mission(&grid, Pose2::new(0.5, 0.5, 0.0), &[], &bad).unwrap_err();
    assert_eq!(
        e.to_string(),
        "invalid parameter `control_hz`: expected a divisor of sim_hz = 100, got 30"
    );
}

/// The wedge of `nav::avoidance`'s tests, with the planner and the mapper: a robot that
/// squeezed between two walls and a teammate's body (a robot that broke down) reaches goals
/// on every side of it, whichever way it faced. Before the heading search it stood there
/// turning in 22 of these 32 runs.
#[test]
fn a_robot_wedged_beside_a_broken_down_teammate_reaches_goals_on_every_side() {
    let mut g = Grid::new(50, 40, 0.1, 0.0, 0.0).unwrap();
    g.fill_rect(0.0, 0.0, 5.0, 0.2);
    g.fill_rect(0.0, 0.0, 0.2, 4.0);
    g.fill_rect(0.0, 3.8, 5.0, 4.0);
    g.fill_rect(4.8, 0.0, 5.0, 4.0);
    let params = MissionParams {
        still_robots: vec![Pose2::new(1.0, 1.0, 0.0)],
        max_sim_time: 40.0,
        ..MissionParams::default()
    };
    for goal in [(1.5, 1.8), (3.0, 0.6), (0.5, 2.5), (4.0, 3.0)] {
        for h in 0..8 {
            let heading = std::f64::consts::TAU * h as f64 / 8.0;
            let s = run_mission(
                &g,
                Pose2::new(0.87, 0.57, heading),
                &[Pose2::new(goal.0, goal.1, 0.0)],
                &params,
            )
            .unwrap();
            let end = s.final_pose;
            assert!(
                s.done,
                "goal {goal:?}, start heading {:.0} deg: stopped at ({:.2}, {:.2}) after {:.1} s",
                heading.to_degrees(),
                end.x(),
                end.y(),
                s.sim_time
            );
            assert_eq!(s.collisions, 0, "goal {goal:?}, heading {heading}");
        }
    }
}
