//! Mission time and failures: unhandled failures end the run, built-in waits and timed actions
//! need no binding, time in an action's conditions counts from its start, the agent's clock.

use std::time::Duration;

use petrel::plans::mission::MissionMemory;

use crate::support::{advance, agent_with_mission, finished, start, stop, Plans};

async fn text(agent: &petrel::actors::Agent, addr: &str) -> String {
    (*agent.blackboard().get::<String>(addr).await.unwrap()).clone()
}

#[tokio::test(start_paused = true)]
async fn an_unhandled_failure_ends_the_run_in_fail_within_a_step() {
    let plans = Plans::new(&[("u.plan", "a; b")]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true, "params/actions": {{
            "a": (enable: ["c1"], finished: "c1/out/value >= 100", failed: "c1/out/value >= 3"),
            "b": (enable: ["c2"], finished: "c2/out/value >= 1"),
        }}"#,
        plans.path("u.plan")
    )))
    .await;
    let t0 = tokio::time::Instant::now();
    let exit = finished(&agent).await;
    assert_eq!(exit.code, 1, "{}", exit.reason);
    assert!(
        exit.reason.contains("action `a` failed (`failed`: c1/out/value >= 3) and no execution rule handles its failure"),
        "{}",
        exit.reason
    );
    // The third count comes after 30 ms; the failure is seen at once.
    assert!(
        t0.elapsed() < Duration::from_millis(100),
        "{:?}",
        t0.elapsed()
    );
    assert_eq!(text(&agent, "m/out/result").await, "fail");
    let memory = agent
        .blackboard()
        .get::<MissionMemory>("m/state/memory")
        .await
        .unwrap();
    assert_eq!(memory.failed_action.as_deref(), Some("a"));
    // The run summary's line: the failure counted, though no plan transition fired for it.
    let a = &memory.actions["a"];
    assert_eq!((a.starts, a.ends, a.failures, a.interrupts), (1, 0, 1, 0));
    assert!(memory.running.is_empty(), "{:?}", memory.running);
    assert!(!memory.actions.contains_key("b"), "b never started");
    stop(agent).await;
}

#[tokio::test(start_paused = true)]
async fn wait_and_timed_actions_need_no_binding_and_either_end_may_come_first() {
    // `slow|1` times out after 1 s; `fast|5` ends first; `wait_2` waits 2 s.
    let plans = Plans::new(&[("w.plan", "slow|1; wait_2; fast|5; say_done")]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true, "params/actions": {{
            "slow": (finished: "c1/out/value > 0"),
            "fast": (enable: ["c2"], finished: "c2/out/value >= 2"),
        }}"#,
        plans.path("w.plan")
    )))
    .await;
    advance(900).await;
    assert_eq!(text(&agent, "m/out/running").await, "slow, wait_1");
    advance(200).await;
    assert_eq!(
        text(&agent, "m/out/running").await,
        "wait_2",
        "slow was interrupted at 1 s"
    );
    advance(1800).await;
    assert_eq!(
        text(&agent, "m/out/running").await,
        "wait_2",
        "2 s from its start at 1 s"
    );
    let exit = finished(&agent).await;
    assert_eq!(exit.code, 0, "{}", exit.reason);
    let memory = agent
        .blackboard()
        .get::<MissionMemory>("m/state/memory")
        .await
        .unwrap();
    assert_eq!(memory.actions["slow"].interrupts, 1);
    assert_eq!(memory.actions["fast"].ends, 1);
    assert_eq!(memory.actions["wait_5"].interrupts, 1);
    assert!(
        (memory.actions["wait_2"].time_s - 2.0).abs() < 0.05,
        "{memory:?}"
    );
    assert_eq!(memory.actions["say_done"].ends, 1);
    stop(agent).await;
}

#[tokio::test(start_paused = true)]
async fn time_in_an_actions_conditions_counts_from_its_start() {
    // `held(..., 1s)` has been true for 3 s when b starts: it must still wait 1 s; `elapsed()`
    // counts from b's start too.
    let plans = Plans::new(&[("h.plan", "a; b")]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true, "params/actions": {{
            "a": (finished: "elapsed() >= 3"),
            "b": (finished: "elapsed() >= 2", failed: "held(c1/out/value == 0, 1s) and elapsed() < 0.5"),
        }}"#,
        plans.path("h.plan")
    )))
    .await;
    let exit = finished(&agent).await;
    assert_eq!(
        exit.code, 0,
        "b must not fail at its start: {}",
        exit.reason
    );
    let memory = agent
        .blackboard()
        .get::<MissionMemory>("m/state/memory")
        .await
        .unwrap();
    assert!(
        (memory.actions["a"].time_s - 3.0).abs() < 0.05,
        "{memory:?}"
    );
    assert!(
        (memory.actions["b"].time_s - 2.0).abs() < 0.05,
        "{memory:?}"
    );
    stop(agent).await;
}

#[tokio::test(start_paused = true)]
async fn a_linked_clock_drives_mission_time() {
    // c1 counts every 10 ms; as a clock it runs 100x faster than the wall clock.
    let plans = Plans::new(&[("c.plan", "wait_50")]);
    let config = agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true"#,
        plans.path("c.plan")
    ))
    .replace(
        r#"(name: "c1", type: "demo.counter", values: {"enabled": false,"#,
        r#"(name: "c1", type: "demo.counter", values: {"enabled": true,"#,
    )
    .replace(
        r#"restart: temporary, values: {"#,
        r#"restart: temporary, links: {"in/clock": "c1/out/value"}, values: {"#,
    );
    let agent = start(&config).await;
    advance(400).await;
    assert_eq!(
        text(&agent, "m/out/result").await,
        "running",
        "40 clock seconds"
    );
    advance(200).await;
    assert_eq!(
        text(&agent, "m/out/result").await,
        "goal",
        "60 clock seconds"
    );
    stop(agent).await;
}
