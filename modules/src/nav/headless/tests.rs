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
