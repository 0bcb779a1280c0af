//! A failing module is reported; with `restart: temporary` it stays stopped, and the agent and
//! the other modules keep going.

use petrel::actors::{status, DEFAULT_STOP_TIMEOUT};

use crate::support::{advance, start};

#[tokio::test(start_paused = true)]
async fn panics_errors_and_init_failures_stop_only_that_module() {
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "panics", type: "test.faulty", restart: temporary, values: {"params/mode": "panic"}),
            (name: "errors", type: "test.faulty", restart: temporary,
             values: {"params/mode": "error", "params/fail_at": 5}),
            (name: "no_device", type: "test.faulty", restart: temporary, values: {"params/mode": "init"}),
            (name: "count", type: "demo.counter", values: {"params/period_ms": 10}),
        ])"#,
    )
    .await;
    let bb = agent.blackboard().clone();
    advance(205).await;
    assert_eq!(
        *bb.get::<f64>("count/out/value").await.unwrap(),
        20.0,
        "the healthy module kept running"
    );
    for (module, steps) in [("panics", 3), ("errors", 5), ("no_device", 0)] {
        assert_eq!(
            *bb.get::<String>(&format!("{module}/stats/status"))
                .await
                .unwrap(),
            status::FAILED,
            "{module}"
        );
        assert_eq!(
            *bb.get::<i64>(&format!("{module}/stats/failures"))
                .await
                .unwrap(),
            1,
            "{module}"
        );
        assert_eq!(
            *bb.get::<i64>(&format!("{module}/state/steps"))
                .await
                .unwrap(),
            steps,
            "{module} stopped stepping"
        );
    }
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    let error = |m: &str| {
        summary
            .module(m)
            .unwrap()
            .last_error
            .clone()
            .unwrap_or_default()
    };
    assert!(
        error("panics").contains("wheel encoder exploded at step 3"),
        "{}",
        error("panics")
    );
    assert!(
        error("errors").contains("lost the serial link at step 5"),
        "{}",
        error("errors")
    );
    assert!(
        error("no_device").contains("init failed: no such device /dev/laser0"),
        "{}",
        error("no_device")
    );
    assert_eq!(summary.module("count").unwrap().status, status::STOPPED);
    assert_eq!(summary.failures(), 3);
}

#[tokio::test(start_paused = true)]
async fn an_unrecoverable_init_failure_is_reported_once_and_not_restarted() {
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "calibrated", type: "test.faulty", values: {"params/mode": "bad_file"}),
            (name: "log", type: "test.event_log", links: {"in/events": "_supervisor/events"}),
            (name: "count", type: "demo.counter", values: {"params/period_ms": 10}),
        ])"#,
    )
    .await;
    let bb = agent.blackboard().clone();
    // Far beyond every backoff delay and the default intensity window.
    advance(30_000).await;
    let stat = |path: &'static str| {
        let bb = bb.clone();
        async move {
            *bb.get::<i64>(&format!("calibrated/stats/{path}"))
                .await
                .unwrap()
        }
    };
    assert_eq!(stat("failures").await, 1, "reported once");
    assert_eq!(stat("restarts").await, 0, "never restarted");
    assert_eq!(
        *bb.get::<String>("calibrated/stats/status").await.unwrap(),
        status::FAILED
    );
    assert_eq!(
        bb.get::<String>("log/out/kinds").await.unwrap().trim_end(),
        "failed:calibrated",
        "one failure event, no restart, no give-up"
    );
    assert_eq!(
        *bb.get::<f64>("count/out/value").await.unwrap(),
        3000.0,
        "the rest runs on"
    );
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    let error = summary.module("calibrated").unwrap().last_error.clone();
    assert_eq!(
        error.as_deref(),
        Some("could not start: init failed: calibration.yaml:3:1: expected a number")
    );
}
