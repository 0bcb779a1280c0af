//! Whole-system navigation tests: the shipped RON configs run as real agents (simulator,
//! localizer, mapper, planner, avoidance, goal sequencer, recorder) on tokio's paused clock,
//! so simulated time runs as fast as the CPU allows and nothing sleeps on the wall clock.

#[path = "common/bounded.rs"]
mod bounded;

use std::path::Path;
use std::time::Duration;

use petrel::actors::{status, Agent, AgentExit, ConfigFile, DEFAULT_STOP_TIMEOUT};

/// Virtual (paused-clock) time after which a test gives up waiting for the agent to finish.
const GUARD: Duration = Duration::from_secs(120);

/// Loads `configs/<name>` with `overlay` (RON module list) laid on top.
fn config(name: &str, overlay: &str) -> ConfigFile {
    let mut file = ConfigFile::load(Path::new("configs").join(name))
        .unwrap_or_else(|e| panic!("{name} should load:\n{e}"));
    let overlay = ConfigFile::parse(
        "overlay.ron",
        &format!(r#"Agent(name: "robot1", modules: [{overlay}])"#),
    )
    .unwrap_or_else(|e| panic!("overlay should parse:\n{e}"));
    file.overlay(overlay);
    file
}

async fn start(file: &ConfigFile) -> Agent {
    Agent::start(file, &petrel::modules::builtin())
        .await
        .unwrap_or_else(|e| panic!("agent should start:\n{e}"))
}

async fn finished(agent: &Agent) -> AgentExit {
    tokio::time::timeout(GUARD, agent.finished())
        .await
        .expect("the mission should end by itself")
}

/// Runs a navigation config to its end and checks every goal was reached without collision.
async fn navigate(name: &str) {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("map.png");
    let file = config(
        name,
        &format!(
            r#"(name: "recorder", type: "sim.recorder", values: {{"params/png": {:?}}})"#,
            png.display().to_string()
        ),
    );
    let agent = start(&file).await;
    let exit = finished(&agent).await;
    let bb = agent.blackboard().clone();
    let get_i = |p: &'static str| {
        let bb = bb.clone();
        async move { *bb.get::<i64>(p).await.unwrap() }
    };
    let (reached, collisions) = (
        get_i("goals/out/reached").await,
        get_i("robot/out/collisions").await,
    );
    let sim_time = *bb.get::<f64>("robot/out/simTime").await.unwrap();
    let map = bb
        .get::<petrel::actors::OccupancyGrid>("mapper/out/map")
        .await
        .unwrap();
    let goals = bb
        .get::<petrel::actors::types::Path2>("goals/params/goals")
        .await
        .unwrap();
    let distance = *bb.get::<f64>("recorder/out/distance").await.unwrap();
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    println!("{name}: {exit:?}, {reached} goals, {distance:.1} m, {sim_time:.1} s sim, {collisions} collisions");
    assert_eq!(exit.code, 0, "{name}: {}", exit.reason);
    assert!(
        exit.reason.contains("all 3 goals reached"),
        "{}",
        exit.reason
    );
    assert_eq!(reached, 3, "{name}");
    assert_eq!(collisions, 0, "{name}");
    assert!(
        distance > 20.0 && sim_time < 400.0,
        "{name}: {distance} m in {sim_time} s"
    );
    assert_eq!(summary.failures(), 0, "{name}:\n{summary}");
    let png = image::open(&png)
        .expect("the recorder wrote a PNG at cleanup")
        .to_rgb8();
    check_png(name, &png, &map, &goals.0, distance);
}

/// The PNG shows the map the robot built, every goal where it is (reached: a red ring with a
/// small white centre), and the trajectory (blue to orange) about as long as the distance driven.
fn check_png(
    name: &str,
    png: &image::RgbImage,
    map: &petrel::actors::OccupancyGrid,
    goals: &[petrel::actors::Point2],
    distance: f64,
) {
    // The renderer's documented scale: the largest of 1..=8 pixels per cell within 1000 px.
    let scale = (1000 / map.width.max(map.height)).clamp(1, 8);
    assert_eq!(
        png.dimensions(),
        (map.width * scale, map.height * scale),
        "{name}: one square of pixels per map cell"
    );
    let px_per_m = scale as f64 / map.resolution;
    let ring = (0.3 * px_per_m).max(4.0);
    let at = |x: f64, y: f64| {
        let col = (x - map.origin.x()) * px_per_m;
        let row = png.height() as f64 - (y - map.origin.y()) * px_per_m;
        png.get_pixel(col as u32, row as u32).0
    };
    // The last goal is where the robot stopped, drawn over it: check the others.
    for (i, g) in goals.iter().enumerate().take(goals.len() - 1) {
        let (x, y) = (g.0.x, g.0.y);
        assert_eq!(at(x, y), [255, 255, 255], "{name}: goal {i} centre");
        assert_eq!(
            at(x - 0.6 * ring / px_per_m, y),
            [205, 30, 45],
            "{name}: goal {i} drawn reached (a ring with a small centre)"
        );
    }
    // Trajectory pixels: the blue-to-orange ramp (r = 30 + 225t, g = 90 + 50t, b = 220 - 200t).
    let on_ramp = |p: &image::Rgb<u8>| {
        let [r, g, b] = p.0.map(f64::from);
        let t = (r - 30.0) / 225.0;
        (0.0..=1.0).contains(&t)
            && (g - (90.0 + 50.0 * t)).abs() <= 1.5
            && (b - (220.0 - 200.0 * t)).abs() <= 1.5
    };
    let drawn = png.pixels().filter(|p| on_ramp(p)).count() as f64;
    assert!(
        drawn >= 0.5 * distance * px_per_m,
        "{name}: {drawn} trajectory pixels for {distance:.1} m at {px_per_m} px/m"
    );
}

#[tokio::test(start_paused = true)]
async fn the_robot_visits_three_goals_in_the_cluttered_world() {
    navigate("navigate.ron").await;
}

#[tokio::test(start_paused = true)]
async fn the_robot_visits_three_goals_in_the_warehouse() {
    navigate("navigate-warehouse.ron").await;
}

#[tokio::test(start_paused = true)]
async fn a_mission_that_runs_out_of_time_fails_with_a_non_zero_code() {
    let file = config(
        "navigate.ron",
        r#"(name: "goals", type: "nav.goal_sequencer", values: {"params/timeout_s": 5.0}),
           (name: "recorder", type: "sim.recorder", values: {"params/png": ""})"#,
    );
    let agent = start(&file).await;
    let exit = finished(&agent).await;
    let sim_time = *agent
        .blackboard()
        .get::<f64>("robot/out/simTime")
        .await
        .unwrap();
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
    assert_eq!(exit.code, 1, "{}", exit.reason);
    assert!(
        exit.reason
            .contains("timeout after 5.0 s; 0 of 3 goals reached"),
        "{}",
        exit.reason
    );
    assert!(
        (5.0..5.2).contains(&sim_time),
        "stopped right after the timeout: {sim_time}"
    );
}

#[tokio::test(start_paused = true)]
async fn the_reactive_layer_wanders_without_collisions() {
    let file = config(
        "reactive.ron",
        r#"(name: "recorder", type: "sim.recorder", values: {"params/png": ""})"#,
    );
    let agent = start(&file).await;
    // 5x real time: 6 s of (virtual) wall time are 30 s of simulated time.
    tokio::time::sleep(Duration::from_secs(6)).await;
    let bb = agent.blackboard().clone();
    let sim_time = *bb.get::<f64>("robot/out/simTime").await.unwrap();
    let distance = *bb.get::<f64>("recorder/out/distance").await.unwrap();
    let collisions = *bb.get::<i64>("robot/out/collisions").await.unwrap();
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
    assert!((29.0..=30.1).contains(&sim_time), "{sim_time}");
    assert!(distance > 8.0, "it moves: {distance} m");
    assert_eq!(collisions, 0);
}

#[tokio::test(start_paused = true)]
async fn a_missing_world_file_fails_init_naming_the_file() {
    let file = ConfigFile::parse(
        "bad.ron",
        r#"Agent(name: "robot1", modules: [
            (name: "robot", type: "sim.world", restart: temporary,
             values: {"params/world": "configs/worlds/nowhere.txt"}),
        ])"#,
    )
    .unwrap();
    let agent = start(&file).await;
    let bb = agent.blackboard().clone();
    for _ in 0..100 {
        if *bb.get::<String>("robot/stats/status").await.unwrap() == status::FAILED {
            break;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    let report = summary.module("robot").unwrap();
    let error = report.last_error.clone().unwrap_or_default();
    assert_eq!(report.status, status::FAILED);
    assert!(
        error.contains("init failed: ")
            && error.contains("/configs/worlds/nowhere.txt: cannot read"),
        "{error}"
    );
}

#[test]
fn every_shipped_config_checks() {
    let mut checked = Vec::new();
    let dirs = ["configs", "configs/rescue"];
    for entry in dirs.iter().flat_map(|d| std::fs::read_dir(d).unwrap()) {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        // Agent configs; `*.rules.ron` are context rules, checked with the config naming them.
        if name.ends_with(".ron") && !name.ends_with(".rules.ron") {
            let out = bounded::output_within_deadline(
                std::process::Command::new(env!("CARGO_BIN_EXE_petrel"))
                    .args(["check", path.to_str().unwrap()]),
            );
            assert!(
                out.status.success(),
                "{name}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            checked.push(name);
        }
    }
    assert!(
        checked.len() >= 9,
        "pipeline, chaos, contexts-demo, reactive, navigate, navigate-warehouse, rescue robot, -warehouse, -chaos: {checked:?}"
    );
}
