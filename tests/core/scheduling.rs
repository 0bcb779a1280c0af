//! Scheduling: drift-free periods, enabled/disabled stepping, stats.

use petrel::actors::{status, DEFAULT_STOP_TIMEOUT};

use crate::support::{advance, start};

#[tokio::test(start_paused = true)]
async fn periodic_steps_fall_on_a_fixed_grid_even_when_steps_take_time() {
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "tick", type: "test.ticklog", values: {"params/period_ms": 100, "params/work_ms": 30}),
        ])"#,
    )
    .await;
    advance(1050).await;
    let times = agent
        .blackboard()
        .get::<Vec<f64>>("tick/out/times")
        .await
        .unwrap();
    let expected: Vec<f64> = (1..=10).map(|k| 100.0 * k as f64).collect();
    assert_eq!(*times, expected);
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn changes_while_disabled_make_one_step_when_enabled() {
    let agent = start(r#"Agent(name: "r1", modules: [(name: "e", type: "test.echo")])"#).await;
    let bb = agent.blackboard().clone();
    advance(1).await;
    bb.set("e/enabled", false).await.unwrap();
    for v in [1.0, 2.0, 3.0] {
        bb.set("e/in/value", v).await.unwrap();
        advance(1).await;
    }
    assert_eq!(
        *bb.get::<f64>("e/out/value").await.unwrap(),
        0.0,
        "no step while disabled"
    );
    assert_eq!(*bb.get::<i64>("e/state/steps").await.unwrap(), 0);
    bb.set("e/enabled", true).await.unwrap();
    advance(1).await;
    assert_eq!(
        *bb.get::<f64>("e/out/value").await.unwrap(),
        3.0,
        "the latest value"
    );
    assert_eq!(
        *bb.get::<i64>("e/state/steps").await.unwrap(),
        1,
        "one step for all of them"
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_disabled_module_does_not_step_until_enabled_again() {
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "count", type: "demo.counter", values: {"params/period_ms": 10}),
        ])"#,
    )
    .await;
    let bb = agent.blackboard().clone();
    advance(55).await;
    assert_eq!(*bb.get::<f64>("count/out/value").await.unwrap(), 5.0);
    bb.set("count/enabled", false).await.unwrap();
    advance(100).await;
    assert_eq!(
        *bb.get::<f64>("count/out/value").await.unwrap(),
        5.0,
        "no step while disabled"
    );
    assert_eq!(
        *bb.get::<String>("count/stats/status").await.unwrap(),
        status::DISABLED
    );
    bb.set("count/enabled", true).await.unwrap();
    advance(1).await;
    assert_eq!(
        *bb.get::<f64>("count/out/value").await.unwrap(),
        6.0,
        "the tick missed while disabled runs at once"
    );
    assert_eq!(
        *bb.get::<String>("count/stats/status").await.unwrap(),
        status::RUNNING
    );
    advance(20).await;
    assert_eq!(
        *bb.get::<f64>("count/out/value").await.unwrap(),
        8.0,
        "then the period resumes on its grid"
    );
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    let report = summary.module("count").unwrap();
    assert_eq!(
        (report.status.as_str(), report.steps, report.failures),
        (status::STOPPED, 9, 0)
    );
}

#[tokio::test(start_paused = true)]
async fn stats_report_steps_and_intervals() {
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "count", type: "demo.counter", values: {"params/period_ms": 20}),
        ])"#,
    )
    .await;
    advance(1010).await;
    let bb = agent.blackboard();
    let steps = *bb.get::<i64>("count/stats/steps").await.unwrap();
    assert!(
        (46..=51).contains(&steps),
        "stats are published at most every 100 ms: {steps}"
    );
    let interval = *bb.get::<f64>("count/stats/mean_interval_ms").await.unwrap();
    assert!(
        (interval - 20.0).abs() < 1.0,
        "first step at 0, then every 20 ms: {interval}"
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}
