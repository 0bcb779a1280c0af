//! Plan execution: sequences, fork/join, interrupts with recovery, goal and fail, events.

use std::collections::BTreeMap;

use petrel::plans::mission::Flags;

use crate::support::{advance, agent_with_mission, finished, start, stop, Plans};

async fn text(agent: &petrel::actors::Agent, addr: &str) -> String {
    (*agent.blackboard().get::<String>(addr).await.unwrap()).clone()
}

async fn num(agent: &petrel::actors::Agent, addr: &str) -> f64 {
    *agent.blackboard().get::<f64>(addr).await.unwrap()
}

async fn on(agent: &petrel::actors::Agent, module: &str) -> bool {
    *agent
        .blackboard()
        .get::<bool>(&format!("{module}/enabled"))
        .await
        .unwrap()
}

#[tokio::test(start_paused = true)]
async fn a_sequence_runs_its_actions_in_order_and_the_goal_ends_the_run_with_0() {
    let plans = Plans::new(&[("seq.plan", "a; b")]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true, "params/actions": {{
            "a": (enable: ["c1"], finished: "c1/out/value >= 3"),
            "b": (enable: ["c2"], finished: "c2/out/value >= 2"),
        }}"#,
        plans.path("seq.plan")
    )))
    .await;
    advance(15).await;
    assert_eq!(text(&agent, "m/out/running").await, "a");
    assert_eq!(text(&agent, "m/out/marking").await, "a.exec");
    assert!(
        on(&agent, "c1").await && !on(&agent, "c2").await,
        "b waits for a"
    );
    let exit = finished(&agent).await;
    assert_eq!(
        (exit.code, exit.reason.as_str()),
        (0, "mission `seq` ended: goal")
    );
    assert_eq!(text(&agent, "m/out/result").await, "goal");
    assert_eq!(text(&agent, "m/out/marking").await, "goal");
    assert_eq!(
        (
            num(&agent, "c1/out/value").await,
            num(&agent, "c2/out/value").await
        ),
        (3.0, 2.0)
    );
    assert!(
        !on(&agent, "c1").await && !on(&agent, "c2").await,
        "ended actions disable their modules"
    );
    assert_eq!(stop(agent).await.failures(), 0);
}

#[tokio::test(start_paused = true)]
async fn each_step_pushes_what_it_fired_in_order_with_the_marking_it_left() {
    use petrel::actors::team::Tap;
    use petrel::plans::mission::PlanFiring;
    let plans = Plans::new(&[("seq.plan", "a; b")]);
    let text_config = agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true, "params/actions": {{
            "a": (enable: ["c1"], finished: "c1/out/value >= 3"),
            "b": (enable: ["c2"], finished: "c2/out/value >= 2"),
        }}"#,
        plans.path("seq.plan")
    ));
    let file = petrel::actors::ConfigFile::parse("test.ron", &text_config).unwrap();
    let prepared = petrel::actors::Agent::prepare(&file, petrel::Petrel::new().registry(), &[])
        .await
        .unwrap();
    // Tapped before any module steps, so the first firing is seen too.
    let Ok(Tap::Queue(mut tap)) = prepared.blackboard().tap("m/out/firings").await else {
        panic!("m/out/firings is a queue");
    };
    let agent = prepared.start().await.unwrap();
    finished(&agent).await;
    let fired = *agent.blackboard().get::<i64>("m/out/fired").await.unwrap();
    let steps: Vec<PlanFiring> = tap
        .take(usize::MAX)
        .into_iter()
        .map(|(_, _, v)| v.downcast_ref::<PlanFiring>().unwrap().clone())
        .collect();
    let all: Vec<&str> = steps
        .iter()
        .flat_map(|s| s.transitions.iter().map(|t| &**t))
        .collect();
    assert_eq!(all.len() as i64, fired, "every firing, once: {steps:?}");
    assert_eq!(&all[..2], ["a.start", "a.end"], "{all:?}");
    assert_eq!(all[2], "b.start", "{all:?}");
    assert!(all.contains(&"b.end"), "{all:?}");
    assert_eq!(
        &*steps[0].marking, "a.exec",
        "the first step leaves a running"
    );
    assert_eq!(&*steps.last().unwrap().marking, "goal");
    assert!(
        steps.windows(2).all(|w| w[0].time_s <= w[1].time_s),
        "in time order: {steps:?}"
    );
    stop(agent).await;
}

#[tokio::test(start_paused = true)]
async fn a_fork_runs_branches_together_and_the_join_waits_for_both() {
    let plans = Plans::new(&[("fork.plan", "{ a } || { b }; c")]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true, "params/actions": {{
            "a": (enable: ["c1"], finished: "c1/out/value >= 2"),
            "b": (enable: ["c2"], finished: "c2/out/value >= 5"),
            "c": (enable: ["c3"], finished: "c3/out/value >= 1"),
        }}"#,
        plans.path("fork.plan")
    )))
    .await;
    advance(5).await;
    assert_eq!(text(&agent, "m/out/running").await, "a, b");
    advance(30).await;
    assert_eq!(
        text(&agent, "m/out/running").await,
        "b",
        "a is done, b still runs"
    );
    assert!(!on(&agent, "c3").await, "c waits for the join");
    assert_eq!(finished(&agent).await.code, 0);
    assert_eq!(num(&agent, "c1/out/value").await, 2.0);
    assert_eq!(num(&agent, "c2/out/value").await, 5.0);
    assert_eq!(num(&agent, "c3/out/value").await, 1.0);
    stop(agent).await;
}

#[tokio::test(start_paused = true)]
async fn an_interrupt_runs_the_recovery_then_restarts_the_action() {
    let plans = Plans::new(&[
        ("long.plan", "a"),
        ("long.er", "*if* stop *during* a *do* fix; restart_action"),
    ]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/rules": "{}", "params/is_mission": true, "params/actions": {{
            "a": (enable: ["c1"], set: {{"c1/state/count": 0, "c1/out/value": 0.0}}, restore: false,
                  finished: "c1/out/value >= 5"),
            "fix": (set: {{"m/in/conditions": {{"stop": false}}}}, restore: false, finished: "true"),
        }}"#,
        plans.path("long.plan"),
        plans.path("long.er")
    )))
    .await;
    advance(35).await;
    assert_eq!(num(&agent, "c1/out/value").await, 3.0);
    // `stop` has no expression: it is read from the mission's `in/conditions`.
    let raise = Flags(BTreeMap::from([("stop".to_string(), true)]));
    agent
        .blackboard()
        .set("m/in/conditions", raise)
        .await
        .unwrap();
    advance(1).await;
    assert_eq!(
        num(&agent, "c1/out/value").await,
        0.0,
        "a restarted from scratch"
    );
    assert_eq!(text(&agent, "m/out/running").await, "a");
    let fired = *agent.blackboard().get::<i64>("m/out/fired").await.unwrap();
    assert_eq!(
        fired, 6,
        "a.start, a.interrupt, fix.start, fix.end, back to a, a.start"
    );
    assert_eq!(finished(&agent).await.code, 0);
    assert_eq!(num(&agent, "c1/out/value").await, 5.0);
    stop(agent).await;
}

#[tokio::test(start_paused = true)]
async fn a_failed_action_can_fail_the_plan_which_ends_the_run_with_1() {
    let plans = Plans::new(&[
        ("f.plan", "a"),
        ("f.er", "*if* action_failed *during* a *do* fail_plan"),
    ]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/rules": "{}", "params/is_mission": true, "params/actions": {{
            "a": (enable: ["c1"], finished: "c1/out/value >= 10", failed: "c1/out/value >= 2"),
        }}"#,
        plans.path("f.plan"),
        plans.path("f.er")
    )))
    .await;
    let exit = finished(&agent).await;
    assert_eq!(
        (exit.code, exit.reason.as_str()),
        (1, "mission `f` ended: fail")
    );
    assert_eq!(text(&agent, "m/out/result").await, "fail");
    assert_eq!(num(&agent, "c1/out/value").await, 2.0);
    assert!(!on(&agent, "c1").await);
    stop(agent).await;
}

#[tokio::test(start_paused = true)]
async fn the_mission_sleeps_until_an_event_and_held_deadlines_wake_it() {
    let plans = Plans::new(&[("idle.plan", "wait; a")]);
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/actions": {{
            "wait": (finished: "held(c1/out/value == 0, 2s)"),
            "a": (finished: "c1/out/value >= 1"),
        }}"#,
        plans.path("idle.plan")
    )))
    .await;
    advance(1990).await;
    assert_eq!(text(&agent, "m/out/running").await, "wait");
    advance(20).await;
    assert_eq!(
        text(&agent, "m/out/running").await,
        "a",
        "the held window closed with no property change"
    );
    advance(10_000).await;
    assert_eq!(text(&agent, "m/out/result").await, "running");
    let summary = stop(agent).await;
    let steps = summary.module("m").unwrap().steps;
    assert!(steps <= 8, "no polling: {steps} steps in 12 s");
}

#[tokio::test(start_paused = true)]
async fn tick_ms_adds_periodic_steps_for_conditions_time_alone_changes() {
    // `age` inside arithmetic gives no deadline to wake on: a tick re-checks it.
    let plans = Plans::new(&[("tick.plan", "a")]);
    let config = |tick: u64| {
        agent_with_mission(&format!(
            r#""params/plan": "{}", "params/tick_ms": {tick}, "params/actions": {{
                "a": (finished: "age(c1/out/value) * 2 > 1"),
            }}"#,
            plans.path("tick.plan")
        ))
    };
    let ticking = start(&config(100)).await;
    let still = start(&config(0)).await;
    advance(450).await;
    assert_eq!(text(&ticking, "m/out/result").await, "running");
    advance(200).await;
    assert_eq!(
        text(&ticking, "m/out/result").await,
        "goal",
        "the 600 ms tick saw it"
    );
    assert_eq!(
        text(&still, "m/out/result").await,
        "running",
        "no event, no tick: no step"
    );
    stop(ticking).await;
    stop(still).await;
}

#[tokio::test(start_paused = true)]
async fn a_sub_plan_whose_action_ends_at_once_ends_without_anything_else_waking_the_mission() {
    // Nothing wakes the mission after `leaf` starts: no tick, no property it reads changes. The
    // firings inside the sub-plan must count as progress, or it waits for ever.
    let plans = Plans::new(&[("leaf.plan", "leaf"), ("top.plan", "sub")]);
    let pnml = petrel::plans::compile_to_pnml(&plans.0.path().join("leaf.plan"), None).unwrap();
    std::fs::write(plans.0.path().join("sub.pnml"), pnml).unwrap();
    let agent = start(&agent_with_mission(&format!(
        r#""params/plan": "{}", "params/is_mission": true,
           "params/actions": {{"leaf": (finished: "true")}}"#,
        plans.path("top.plan")
    )))
    .await;
    let exit = finished(&agent).await;
    assert_eq!(exit.code, 0, "{}", exit.reason);
    assert!(exit.reason.contains("ended: goal"), "{}", exit.reason);
    stop(agent).await;
}
