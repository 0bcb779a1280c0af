//! The shipped patrol example (configs/examples/patrol.*) on the simulated robot, on tokio's
//! paused clock: it reaches its goal, and with faults injected into the mission module every
//! simulated ten seconds each waypoint is still reached exactly twice.

use std::time::Duration;

use petrel::actors::{Agent, AgentExit, ConfigFile, DEFAULT_STOP_TIMEOUT};
use petrel::plans::mission::MissionMemory;

/// The patrol config with `overlay` (a RON agent body after `name`) laid on top, without PNG.
fn patrol(overlay: &str) -> ConfigFile {
    let mut file =
        ConfigFile::load("configs/examples/patrol.ron").unwrap_or_else(|e| panic!("{e}"));
    let text = format!(
        r#"Agent(name: "robot1", {overlay} modules: [(name: "recorder", type: "sim.recorder", values: {{"params/png": ""}})])"#
    );
    file.overlay(ConfigFile::parse("overlay.ron", &text).unwrap_or_else(|e| panic!("{e}")));
    file
}

async fn run(file: &ConfigFile, fault_every: Option<Duration>) -> (AgentExit, MissionMemory, u64) {
    let agent = Agent::start(file, petrel::Petrel::new().registry())
        .await
        .unwrap_or_else(|e| panic!("{e}"));
    let deadline = tokio::time::Instant::now() + Duration::from_secs(120);
    let exit = loop {
        let wait = fault_every.unwrap_or(Duration::from_secs(120));
        match tokio::time::timeout(wait, agent.finished()).await {
            Ok(exit) => break exit,
            Err(_) => {
                assert!(
                    tokio::time::Instant::now() < deadline,
                    "the patrol should end"
                );
                let bb = agent.blackboard();
                bb.set("mission/control/fault", "panic".to_string())
                    .await
                    .unwrap();
                // The fault fails the mission's next step, whenever it comes.
            }
        }
    };
    let memory = (*agent
        .blackboard()
        .get::<MissionMemory>("mission/state/memory")
        .await
        .unwrap())
    .clone();
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    let restarts = summary.module("mission").unwrap().restarts;
    (exit, memory, restarts)
}

fn assert_patrolled(exit: &AgentExit, memory: &MissionMemory) {
    assert_eq!(exit.code, 0, "{}", exit.reason);
    assert_eq!(exit.reason, "mission `patrol` ended: goal");
    for waypoint in ["goto_A", "goto_B", "goto_C"] {
        let a = &memory.actions[waypoint];
        assert_eq!(
            (a.starts, a.ends, a.failures),
            (2, 2, 0),
            "{waypoint}:\n{}",
            memory.report()
        );
    }
    let dock = &memory.actions["goto_dock"];
    assert_eq!(
        (dock.starts, dock.failures),
        (1, 1),
        "the dock is out of reach: {}",
        memory.report()
    );
    assert_eq!(memory.actions["say_no_way_there"].ends, 1, "the rule ran");
    assert_eq!(memory.actions["goto_home"].ends, 1);
}

#[tokio::test(start_paused = true)]
async fn the_patrol_example_reaches_its_goal() {
    let (exit, memory, _) = run(&patrol(""), None).await;
    assert_patrolled(&exit, &memory);
}

#[tokio::test(start_paused = true)]
async fn the_patrol_completes_with_faults_injected_into_the_mission() {
    // The overlay's supervision block is merged: the default (5 restarts in 10 s) would give up.
    let file = patrol("supervision: (max_restarts: 50, within_s: 10.0),");
    let (exit, memory, restarts) = run(&file, Some(Duration::from_secs(1))).await;
    assert_patrolled(&exit, &memory);
    assert!(restarts >= 5, "the mission was restarted {restarts} times");
}
