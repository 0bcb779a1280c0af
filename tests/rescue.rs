//! Whole-system rescue tests: the shipped rescue configs (simulator with camera, scan-matching
//! localizer, mapper, explorer, planner, avoidance, victim detector and mapper, the mission
//! plan, context rules, supervision, recorder) run as real agents on tokio's paused clock, in
//! an ASCII world and in a map_server YAML world, with and without injected faults. Each must
//! end with the plan at its goal.

use std::path::Path;
use std::time::Duration;

use petrel::actors::types::Path2;
use petrel::actors::{Agent, ConfigFile, DEFAULT_STOP_TIMEOUT};

/// Virtual (paused-clock) time after which a test gives up waiting for the agent to finish.
const GUARD: Duration = Duration::from_secs(300);

/// Loads `configs/rescue/<name>`, writes the PNG into `dir` and adds the context manager its
/// `contexts:` field names (the CLI adds it; these tests start the agent themselves).
fn config(name: &str, dir: &Path, extra: &str) -> ConfigFile {
    let mut file = ConfigFile::load(Path::new("configs/rescue").join(name))
        .unwrap_or_else(|e| panic!("{name} should load:\n{e}"));
    let rules = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/rescue/robot.rules.ron");
    let overlay = format!(
        r#"Agent(name: "rescue1", modules: [
            (name: "recorder", type: "sim.recorder", values: {{"params/png": {:?}}}),
            (name: "contexts", type: "context.manager", values: {{"params/rules": {:?}}}),
            {extra}
        ])"#,
        dir.join("rescue.png").display().to_string(),
        rules.display().to_string()
    );
    let overlay = ConfigFile::parse("overlay.ron", &overlay)
        .unwrap_or_else(|e| panic!("overlay should parse:\n{e}"));
    file.overlay(overlay);
    file
}

/// What a rescue run achieved.
struct Outcome {
    exit_code: u8,
    plan_result: String,
    victims: usize,
    found: usize,
    false_victims: usize,
    worst_position_error: f64,
    collisions: i64,
    max_pose_error: f64,
    restarts: u64,
    /// Starts of each mission action (from its `state/memory`).
    starts: std::collections::BTreeMap<String, u32>,
}

async fn rescue(name: &str) -> Outcome {
    rescue_with(name, "").await
}

/// [`rescue`] with `extra` module entries overlaid on the config.
async fn rescue_with(name: &str, extra: &str) -> Outcome {
    let dir = tempfile::tempdir().unwrap();
    let file = config(name, dir.path(), extra);
    let agent = Agent::start(&file, petrel::Petrel::new().registry())
        .await
        .unwrap_or_else(|e| panic!("agent should start:\n{e}"));
    let exit = tokio::time::timeout(GUARD, agent.finished())
        .await
        .expect("the mission should end by itself");
    let bb = agent.blackboard().clone();
    let truth = bb.get::<Path2>("robot/out/worldVictims").await.unwrap();
    let found = bb.get::<Path2>("victims/out/victims").await.unwrap();
    let collisions = *bb.get::<i64>("robot/out/collisions").await.unwrap();
    let sim_time = *bb.get::<f64>("robot/out/simTime").await.unwrap();
    let max_pose_error = *bb.get::<f64>("recorder/out/poseErrorMax").await.unwrap();
    let plan_result = bb.get::<String>("mission/out/result").await.unwrap();
    let memory = bb
        .get::<petrel::plans::mission::MissionMemory>("mission/state/memory")
        .await
        .unwrap();
    let starts = memory
        .actions
        .iter()
        .map(|(name, stats)| (name.clone(), stats.starts))
        .collect();
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    let mut matched = 0;
    let mut worst = 0.0f64;
    for v in truth.points() {
        let nearest = found
            .points()
            .iter()
            .map(|f| (f.0 - v.0).norm())
            .fold(f64::INFINITY, f64::min);
        if nearest <= 0.5 {
            matched += 1;
            worst = worst.max(nearest);
        }
    }
    let restarts = summary.modules.iter().map(|m| m.restarts).sum();
    println!(
        "{name}: {} ({}, plan {plan_result}) at {sim_time:.1} s simulated, victims {matched}/{} (+{} false, worst error {worst:.2} m), {collisions} collisions, pose error max {max_pose_error:.3} m, {restarts} restarts",
        exit.code,
        exit.reason,
        truth.points().len(),
        found.points().len().saturating_sub(matched)
    );
    assert!(std::fs::read(dir.path().join("rescue.png"))
        .unwrap()
        .starts_with(b"\x89PNG"));
    Outcome {
        exit_code: exit.code,
        plan_result: plan_result.to_string(),
        victims: truth.points().len(),
        found: matched,
        false_victims: found.points().len().saturating_sub(matched),
        worst_position_error: worst,
        collisions,
        max_pose_error,
        restarts,
        starts,
    }
}

fn assert_rescued(o: &Outcome, victims: usize) {
    assert_eq!(o.plan_result, "goal", "the plan reached its goal");
    assert_eq!(o.exit_code, 0, "the mission ended the run at its goal");
    assert_eq!(o.victims, victims);
    assert_eq!(o.found, victims, "every victim found within 0.5 m");
    assert_eq!(o.false_victims, 0);
    assert!(o.worst_position_error <= 0.5);
    assert_eq!(o.collisions, 0);
    // Odometry drift grows with the route: the warehouse's search of 1,230 simulated seconds
    // (the searched floor counting only where a victim would be whole in view) peaks at
    // 0.16 m; the ASCII world's at less than 0.15 m.
    assert!(
        o.max_pose_error <= 0.2,
        "localization error {}",
        o.max_pose_error
    );
}

#[tokio::test(start_paused = true)]
async fn every_victim_is_found_in_the_ascii_rescue_world() {
    let o = rescue("robot.ron").await;
    assert_rescued(&o, 6);
    assert_eq!(o.restarts, 0);
}

#[tokio::test(start_paused = true)]
async fn every_victim_is_found_in_the_map_server_warehouse() {
    let o = rescue("robot-warehouse.ron").await;
    assert_rescued(&o, 5);
}

#[tokio::test(start_paused = true)]
async fn the_rescue_finishes_with_faults_injected() {
    let o = rescue("robot-chaos.ron").await;
    assert_rescued(&o, 6);
    assert!(
        o.restarts >= 2,
        "faults were injected and healed: {}",
        o.restarts
    );
}

#[tokio::test(start_paused = true)]
async fn the_rescue_recovers_when_localization_is_lost() {
    // The localizer's simulated errors instead of scan matching: lost from 60 s to 64 s of
    // simulated time (its estimate drifts away), then it converges again.
    let lost = r#"(name: "localizer", type: "nav.localizer", values: {
        "params/scan_matching": false, "params/lost_episodes": [60.0, 64.0],
        "params/lost_drift_speed": 0.1, "params/recovery_time": 1.0}),"#;
    let o = rescue_with("robot.ron", lost).await;
    assert_eq!(o.plan_result, "goal", "the plan reached its goal");
    assert_eq!(o.exit_code, 0);
    let recovers = o.starts.get("recover").copied().unwrap_or(0);
    assert!(
        recovers >= 1,
        "being lost started `recover`: {:?}",
        o.starts
    );
    assert_eq!(o.found, o.victims, "every victim found");
    assert_eq!(o.false_victims, 0);
    assert_eq!(o.collisions, 0);
}

/// The shipped mission plan against scripted worlds (`petrel plan simulate`'s simulator):
/// which actions start, and how the plan ends.
fn simulate_mission(script: &str) -> (String, petrel::plans::PlanStatus) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/rescue");
    let plan = petrel::plans::load_plan(&dir.join("mission.plan"), Some(&dir.join("mission.er")))
        .unwrap_or_else(|e| panic!("mission.plan should load: {e}"))
        .plan;
    let script = petrel::plans::Script::parse(script, "script").unwrap();
    let mut out = Vec::new();
    let status = petrel::plans::simulate(&plan, &script, 200, &mut out).unwrap();
    (String::from_utf8(out).unwrap(), status)
}

#[test]
fn the_mission_plan_interrupts_exploring_for_a_victim_and_resumes() {
    let (trace, status) = simulate_mission("finish explore 6\ncond victim_waiting 2 6");
    assert_eq!(status, petrel::plans::PlanStatus::Goal, "{trace}");
    for call in [
        "explore.interrupt",
        "approach.start",
        "confirm.start",
        "report.start",
        "say_every_victim_reported.start",
    ] {
        assert!(trace.contains(call), "no {call} in\n{trace}");
    }
    assert_eq!(
        trace.matches("explore.start").count(),
        2,
        "explores again after the report:\n{trace}"
    );
    assert!(!trace.contains("dismiss.start"), "{trace}");
}

#[test]
fn the_mission_plan_recovers_when_lost_dismisses_what_it_cannot_confirm_and_fails_on_time() {
    let (trace, status) = simulate_mission("finish explore 8\ncond lost 2 3");
    assert_eq!(status, petrel::plans::PlanStatus::Goal, "{trace}");
    assert!(
        trace.contains("recover.start") && trace.matches("explore.start").count() == 2,
        "{trace}"
    );

    let (trace, status) =
        simulate_mission("finish explore 6\ncond victim_waiting 2 6\nfail confirm 1");
    assert_eq!(status, petrel::plans::PlanStatus::Goal, "{trace}");
    assert!(
        trace.contains("dismiss.start") && !trace.contains("report.start"),
        "{trace}"
    );

    let (trace, status) =
        simulate_mission("finish explore 6\ncond victim_waiting 2 6\nfail approach 1");
    assert_eq!(
        status,
        petrel::plans::PlanStatus::Goal,
        "an unreachable victim is confirmed from afar:\n{trace}"
    );
    assert!(
        trace.contains("confirm.start") && trace.contains("report.start"),
        "{trace}"
    );

    let (trace, status) = simulate_mission("finish explore -1\ncond time_up 5 200");
    assert_eq!(status, petrel::plans::PlanStatus::Fail, "{trace}");
    assert!(trace.contains("say_time_is_up.start"), "{trace}");
}
