//! The mission survives its own restart and a snapshot: it goes on from `state/memory`, never
//! running a finished action again.

use petrel::actors::ConfigFile;
use petrel::plans::mission::MissionMemory;

use crate::support::{advance, finished, start, stop, Plans};

/// Counters c1..c3 and a restartable mission `m` running `a; b; c`, each action counting its
/// own counter from 0 to 20 (200 ms).
fn config(plans: &Plans) -> String {
    let action = |c: &str| {
        format!(
            r#"(enable: ["{c}"], set: {{"{c}/state/count": 0, "{c}/out/value": 0.0}}, restore: false, finished: "{c}/out/value >= 20")"#
        )
    };
    format!(
        r#"Agent(name: "r1", supervision: (max_restarts: 100, within_s: 1.0), modules: [
            (name: "c1", type: "demo.counter", values: {{"enabled": false, "params/period_ms": 10}}),
            (name: "c2", type: "demo.counter", values: {{"enabled": false, "params/period_ms": 10}}),
            (name: "c3", type: "demo.counter", values: {{"enabled": false, "params/period_ms": 10}}),
            (name: "m", type: "mission.pnp", values: {{
                "params/plan": "{}", "params/is_mission": true,
                "params/actions": {{"a": {}, "b": {}, "c": {}}},
            }}),
        ])"#,
        plans.path("abc.plan"),
        action("c1"),
        action("c2"),
        action("c3")
    )
}

async fn memory(agent: &petrel::actors::Agent) -> MissionMemory {
    (*agent
        .blackboard()
        .get::<MissionMemory>("m/state/memory")
        .await
        .unwrap())
    .clone()
}

#[tokio::test(start_paused = true)]
async fn faults_injected_into_the_mission_never_rerun_an_action() {
    let plans = Plans::new(&[("abc.plan", "a; b; c")]);
    let agent = start(&config(&plans)).await;
    // A panic every 70 ms through the whole mission (about 600 ms): each action is hit.
    for _ in 0..8 {
        advance(70).await;
        agent
            .blackboard()
            .set("m/control/fault", "panic".to_string())
            .await
            .unwrap();
        // The fault fails the mission's next step: make it step.
        let wake = *agent.blackboard().get::<i64>("m/state/wake").await.unwrap();
        agent
            .blackboard()
            .set("m/state/wake", wake + 1)
            .await
            .unwrap();
    }
    let exit = finished(&agent).await;
    assert_eq!(exit.code, 0, "{}", exit.reason);
    let memory = memory(&agent).await;
    for a in ["a", "b", "c"] {
        let stats = &memory.actions[a];
        assert_eq!((stats.starts, stats.ends), (1, 1), "{a}: {memory:?}");
    }
    let fired = *agent.blackboard().get::<i64>("m/out/fired").await.unwrap();
    assert_eq!(fired, 6, "a, b and c started and ended once each");
    let summary = stop(agent).await;
    let m = summary.module("m").unwrap();
    assert!(
        m.restarts >= 5,
        "the mission restarted: {} restarts",
        m.restarts
    );
}

#[tokio::test(start_paused = true)]
async fn a_snapshot_taken_mid_mission_resumes_the_plan_where_it_was() {
    let plans = Plans::new(&[("abc.plan", "a; b; c")]);
    let agent = start(&config(&plans)).await;
    advance(300).await;
    assert_eq!(
        *agent
            .blackboard()
            .get::<String>("m/out/running")
            .await
            .unwrap(),
        "b"
    );
    let snapshot = agent.snapshot().await.unwrap();
    stop(agent).await;
    let file = ConfigFile::parse("snapshot.ron", &snapshot).unwrap_or_else(|e| panic!("{e}"));
    let resumed = petrel::actors::Agent::start(&file, petrel::Petrel::new().registry())
        .await
        .unwrap();
    let exit = finished(&resumed).await;
    assert_eq!(exit.code, 0, "{}", exit.reason);
    let memory = memory(&resumed).await;
    assert_eq!(
        memory.actions["a"].starts, 1,
        "a is not run again: {memory:?}"
    );
    assert_eq!(memory.actions["b"].starts, 1, "b goes on: {memory:?}");
    assert_eq!(memory.actions["c"].starts, 1);
    let fired = *resumed
        .blackboard()
        .get::<i64>("m/out/fired")
        .await
        .unwrap();
    assert_eq!(
        fired, 6,
        "a, b and c started and ended once each, across the snapshot"
    );
    stop(resumed).await;
}
