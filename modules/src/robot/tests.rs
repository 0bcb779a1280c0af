//! The robot modules running as real agents on tokio's paused clock.

use std::time::Duration;

use petrel_actors::{status, Agent, ConfigFile, Pose2, Twist2, DEFAULT_STOP_TIMEOUT};

/// The cluttered world, from this crate's directory (where `cargo test` runs unit tests).
pub(super) const WORLD: &str = "../configs/worlds/cluttered.txt";

pub(super) async fn start(modules: &str) -> Agent {
    let text = format!(r#"Agent(name: "r", modules: [{modules}])"#);
    let file = ConfigFile::parse("test.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    Agent::start(&file, &crate::builtin())
        .await
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The base driven by obstacle avoidance toward a point 2 m ahead, 5x faster than real time.
fn reactive() -> String {
    format!(
        r#"(name: "robot", type: "sim.world", values: {{"params/world": "{WORLD}", "params/time_scale": 5.0}},
            links: {{"in/controlSpeed": "avoid/out/controlSpeed"}}),
           (name: "avoid", type: "nav.obstacle_avoidance",
            values: {{"in/localTargetPose": (x: 2.0, y: 0.0, theta: 0.0), "params/maxSpeed": 0.5, "params/maxTurn": 1.0}},
            links: {{"in/laserScan": "robot/out/laserScan"}})"#
    )
}

/// Samples `robot/out/actualSpeed` and `avoid/out/controlSpeed` every 20 ms for `ms`.
async fn sample(agent: &Agent, ms: u64) -> Vec<(Twist2, Twist2)> {
    let bb = agent.blackboard();
    let mut out = Vec::new();
    for _ in 0..ms / 20 {
        tokio::time::sleep(Duration::from_millis(20)).await;
        let actual = *bb.get::<Twist2>("robot/out/actualSpeed").await.unwrap();
        let command = *bb.get::<Twist2>("avoid/out/controlSpeed").await.unwrap();
        out.push((actual, command));
    }
    out
}

#[tokio::test(start_paused = true)]
async fn lowering_max_speed_while_running_slows_the_robot_down() {
    let agent = start(&reactive()).await;
    let before = sample(&agent, 2000).await;
    let fastest = before.iter().map(|(a, _)| a.v).fold(0.0, f64::max);
    assert!(fastest > 0.45, "cruises near maxSpeed first: {fastest}");
    // What a context rule does on rough terrain.
    agent
        .blackboard()
        .set("avoid/params/maxSpeed", 0.2)
        .await
        .unwrap();
    // Braking from 0.5 to 0.2 m/s at 1.5 m/s² takes 0.2 s of simulated time (40 ms here).
    tokio::time::sleep(Duration::from_millis(100)).await;
    let after = sample(&agent, 2000).await;
    let sim_time = *agent
        .blackboard()
        .get::<f64>("robot/out/simTime")
        .await
        .unwrap();
    let collisions = *agent
        .blackboard()
        .get::<i64>("robot/out/collisions")
        .await
        .unwrap();
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
    for (actual, command) in &after {
        assert!(
            actual.v <= 0.2 + 1e-9 && command.v <= 0.2 + 1e-9,
            "{actual:?} {command:?}"
        );
        assert!(
            command.omega.abs() <= 1.0 + 1e-9,
            "maxTurn bounds turning: {command:?}"
        );
    }
    assert!(after.iter().any(|(a, _)| a.v > 0.15), "still moving");
    assert!(sim_time > 20.0, "5x real time: {sim_time}");
    assert_eq!(collisions, 0);
}

#[tokio::test(start_paused = true)]
async fn a_picture_folder_that_cannot_be_made_fails_once_without_restarts() {
    let png = r#""params/png": "/proc/no/such/dir/x.png""#;
    let agent = start(&format!(
        r#"(name: "world", type: "sim.world", values: {{"params/world": "{WORLD}", {png}}}),
           (name: "recorder", type: "sim.recorder", values: {{{png}}})"#
    ))
    .await;
    // Long enough for every restart the default policy would make.
    tokio::time::sleep(Duration::from_secs(60)).await;
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    for module in ["world", "recorder"] {
        let report = summary.module(module).unwrap();
        let error = report.last_error.clone().unwrap_or_default();
        assert!(
            error.contains("params/png is `/proc/no/such/dir/x.png`, but its folder /proc/no/such/dir cannot be created"),
            "{module}: {error}"
        );
        assert_eq!(
            (report.status.as_str(), report.failures, report.restarts),
            (status::FAILED, 1, 0),
            "{module}: {error}"
        );
    }
}

#[tokio::test(start_paused = true)]
async fn bad_parameters_fail_init_naming_the_parameter() {
    let cases = [
        (
            "sim.world",
            format!(r#""params/world": "{WORLD}", "params/start": [1.0, 2.0]"#),
            "`params/start`: expected `[x, y, heading_deg]`",
        ),
        (
            "sim.world",
            format!(r#""params/world": "{WORLD}", "params/start": [0.0, 0.0, 0.0]"#),
            "overlaps a wall",
        ),
        (
            "sim.world",
            r#""params/world": """#.to_string(),
            "params/world is empty",
        ),
        (
            "nav.localizer",
            r#""params/lost_episodes": [3.0]"#.to_string(),
            "`params/lost_episodes`: expected pairs",
        ),
        (
            "nav.localizer",
            r#""params/lost_episodes": [3.0, 1.0]"#.to_string(),
            "`params/lost_episodes`: expected [start, end)",
        ),
        (
            "nav.localizer",
            r#""params/scan_matching": true, "params/drift_per_meter": 0.1"#.to_string(),
            "do not apply; remove them",
        ),
        (
            "nav.mapper",
            r#""params/size": (x: 0.0, y: 5.0)"#.to_string(),
            "`params/size`",
        ),
        (
            "nav.goal_sequencer",
            r#""params/goals": []"#.to_string(),
            "params/goals is empty",
        ),
        (
            "sim.recorder",
            r#""params/png": "/proc/no/such/dir/x.png""#.to_string(),
            "params/png is `/proc/no/such/dir/x.png`",
        ),
    ];
    let modules: Vec<String> = cases
        .iter()
        .enumerate()
        .map(|(i, (ty, values, _))| {
            format!(r#"(name: "m{i}", type: "{ty}", values: {{{values}}})"#)
        })
        .collect();
    let agent = start(&modules.join(",\n")).await;
    tokio::time::sleep(Duration::from_millis(50)).await;
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    for (i, (ty, _, expected)) in cases.iter().enumerate() {
        let report = summary.module(&format!("m{i}")).unwrap();
        let error = report.last_error.clone().unwrap_or_default();
        assert_eq!(report.status, status::FAILED, "{ty} case {i}");
        assert!(
            error.contains("init failed") && error.contains(expected),
            "{ty} case {i}: {error}"
        );
    }
}

#[test]
fn out_of_range_parameters_are_refused_before_anything_starts_naming_the_range() {
    let cases = [
        (
            "sim.world",
            "params/max_speed",
            "-1.0",
            "= -1: expected a value in 0.01..=20",
        ),
        (
            "nav.localizer",
            "params/lost_below",
            "2.0",
            "= 2: expected a value in 0..=1",
        ),
        (
            "nav.mapper",
            "params/resolution",
            "0.0",
            "= 0: expected a value in 0.01..=1",
        ),
        (
            "nav.path_planner",
            "params/occupied_threshold",
            "300",
            "= 300: expected a value in 1..=100",
        ),
        (
            "nav.path_planner",
            "params/lookahead",
            "0.0",
            "= 0: expected a value in 0.05..=100",
        ),
        (
            "nav.obstacle_avoidance",
            "params/maxSpeed",
            "-0.5",
            "= -0.5: expected a value in 0.01..=20",
        ),
        (
            "nav.goal_sequencer",
            "params/timeout_s",
            "0.0",
            "= 0: expected a value in 0.1..=1e7",
        ),
        (
            "sim.world",
            "params/time_scale",
            "1e-300",
            "= 1e-300: expected a value in 0.01..=1000",
        ),
        (
            "sim.world",
            "params/laser/rays",
            "1000000000",
            "= 1e9: expected a value in 1..=10000",
        ),
        (
            "sim.world",
            "params/radius",
            "NaN",
            "= NaN: expected a value in 0.01..=5",
        ),
        (
            "sim.world",
            "params/drive",
            "\"tracked\"",
            "= \"tracked\": expected one of \"differential\", \"holonomic\"",
        ),
    ];
    for (ty, path, value, expected) in cases {
        let text = format!(
            r#"Agent(name: "r", modules: [(name: "m", type: "{ty}", values: {{"{path}": {value}}})])"#
        );
        let file = ConfigFile::parse("test.ron", &text).unwrap();
        let error = match file.build(&crate::builtin()) {
            Ok(_) => panic!("{ty} {path} = {value} was accepted"),
            Err(e) => e.to_string(),
        };
        assert!(
            error.contains(&format!("`m/{path}` {expected}")),
            "{ty} {path} = {value}: {error}"
        );
    }
}

#[tokio::test(start_paused = true)]
async fn time_scale_sets_the_pace_of_simulated_time_in_both_modes() {
    for deterministic in [true, false] {
        let agent = start(&format!(
            r#"(name: "robot", type: "sim.world", values: {{"params/world": "{WORLD}",
                "params/time_scale": 4.0, "params/deterministic": {deterministic}}})"#
        ))
        .await;
        tokio::time::sleep(Duration::from_secs(2)).await;
        let t = *agent
            .blackboard()
            .get::<f64>("robot/out/simTime")
            .await
            .unwrap();
        agent.stop(DEFAULT_STOP_TIMEOUT).await;
        assert!(
            (t - 8.0).abs() < 0.05,
            "deterministic {deterministic}: {t} s"
        );
    }
}

/// A host that stalled: following the wall clock, the world catches up several simulation
/// steps at its next tick, and each reaches the localizer on its own, as if it had come on
/// time. Before, the localizer got the whole batch at once and published one pose for it, so
/// a mapper put every scan of the batch at that last pose.
#[tokio::test(start_paused = true)]
async fn catching_up_with_the_wall_clock_hands_over_one_simulation_step_at_a_time() {
    let agent = start(&format!(
        r#"(name: "robot", type: "sim.world", values: {{"params/world": "{WORLD}",
            "params/deterministic": false, "in/controlSpeed": (v: 0.2, omega: 0.1)}}),
           (name: "localizer", type: "nav.localizer",
            links: {{"in/odometry": "robot/out/odometry", "in/simTime": "robot/out/simTime"}})"#
    ))
    .await;
    let bb = agent.blackboard();
    let sim_time = bb.handle::<f64>("robot/out/simTime").await.unwrap();
    let pose = bb
        .handle::<Pose2>("localizer/out/estimatedPose")
        .await
        .unwrap();
    tokio::time::sleep(Duration::from_millis(205)).await;
    let (t0, v0) = (sim_time.value(), pose.version());
    // The host stalls for 5.5 steps (10 ms each): no tick runs meanwhile.
    tokio::time::advance(Duration::from_micros(55_000)).await;
    let mut yields = 0;
    while sim_time.value() < t0 + 0.045 && yields < 1000 {
        tokio::task::yield_now().await;
        yields += 1;
    }
    let steps = ((sim_time.value() - t0) / 0.01).round() as u64;
    let poses = pose.version() - v0;
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
    assert!(steps >= 5, "the world caught up {steps} steps");
    assert_eq!(poses, steps, "one pose per simulation step caught up");
}

#[tokio::test(start_paused = true)]
async fn a_restarted_recorder_goes_on_with_the_runs_record() {
    use crate::sim::run_record::RunRecord;
    let agent = start(&format!(
        r#"{},
           (name: "recorder", type: "sim.recorder", values: {{"params/sample_m": 0.01}},
            links: {{"in/pose": "robot/out/pose", "in/simTime": "robot/out/simTime"}})"#,
        reactive()
    ))
    .await;
    let bb = agent.blackboard();
    tokio::time::sleep(Duration::from_secs(2)).await;
    agent.modules().restart("recorder").await.unwrap();
    // What the first instance had when it stopped for the restart.
    let before = bb.get::<RunRecord>("recorder/state/run").await.unwrap();
    assert!(before.trajectory.len() > 10, "{before:?}");
    assert!(before.wall_before > 0.0);
    // Saved again within 5 simulated seconds (1 s at 5x): the new instance went on from it.
    tokio::time::sleep(Duration::from_secs(2)).await;
    let after = bb.get::<RunRecord>("recorder/state/run").await.unwrap();
    assert!(
        after.trajectory.len() > before.trajectory.len()
            && after.trajectory.starts_with(&before.trajectory),
        "{} points, then {}",
        before.trajectory.len(),
        after.trajectory.len()
    );
    assert!(after.wall_before >= before.wall_before);
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_restarted_world_goes_on_where_it_was() {
    use petrel_actors::Pose2;
    let agent = start(&reactive()).await;
    let bb = agent.blackboard();
    tokio::time::sleep(Duration::from_secs(2)).await;
    let before = *bb.get::<Pose2>("robot/out/pose").await.unwrap();
    let t_before = *bb.get::<f64>("robot/out/simTime").await.unwrap();
    assert!(t_before > 5.0, "it ran: t = {t_before}");
    agent.modules().restart("robot").await.unwrap();
    tokio::time::sleep(Duration::from_millis(100)).await;
    // Neither back at time 0 nor back at the start: where the first instance stopped.
    let t_after = *bb.get::<f64>("robot/out/simTime").await.unwrap();
    let after = *bb.get::<Pose2>("robot/out/pose").await.unwrap();
    assert!(t_after >= t_before, "{t_after} after {t_before}");
    assert!(
        (after.position().0 - before.position().0).norm() < 0.5,
        "{after:?} after {before:?}"
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_recorder_that_saw_no_pose_leaves_the_last_picture_alone() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("run.png");
    std::fs::write(&png, b"the last run's picture").unwrap();
    // `in/pose` linked to a pose nobody writes (a replay refused at its start).
    let agent = start(&format!(
        r#"(name: "robot", type: "sim.world", values: {{"params/world": "{WORLD}", "enabled": false}}),
           (name: "recorder", type: "sim.recorder", values: {{"params/png": {:?}}},
            links: {{"in/pose": "robot/out/pose", "in/simTime": "robot/out/simTime"}})"#,
        png.display().to_string()
    ))
    .await;
    tokio::time::sleep(Duration::from_secs(1)).await;
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
    assert_eq!(std::fs::read(&png).unwrap(), b"the last run's picture");
}

/// A count or a quality that stays the same is not written again at every simulation step:
/// its readers are not woken, and a recording does not hold the same number 100 times a second.
#[tokio::test(start_paused = true)]
async fn collisions_and_quality_are_written_only_when_they_change() {
    let agent = start(&format!(
        r#"(name: "robot", type: "sim.world", values: {{"params/world": "{WORLD}",
            "params/command_timeout_s": 0.0, "in/controlSpeed": (v: 0.0, omega: 0.5)}}),
           (name: "localizer", type: "nav.localizer",
            links: {{"in/odometry": "robot/out/odometry", "in/simTime": "robot/out/simTime"}})"#
    ))
    .await;
    let bb = agent.blackboard();
    let sim_time = bb.handle::<f64>("robot/out/simTime").await.unwrap();
    let collisions = bb.handle::<i64>("robot/out/collisions").await.unwrap();
    let quality = bb.handle::<f64>("localizer/out/quality").await.unwrap();
    tokio::time::sleep(Duration::from_millis(1_000)).await;
    let steps = sim_time.version();
    let (collisions, quality) = (collisions.version(), quality.version());
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
    assert!(steps > 50, "{steps} steps");
    assert!(
        collisions <= 1,
        "collisions written {collisions} times in {steps} steps"
    );
    assert!(
        quality <= 1,
        "quality written {quality} times in {steps} steps"
    );
}
