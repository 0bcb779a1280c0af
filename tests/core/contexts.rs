//! The context manager in a running agent: effects applied and undone, reload, start/stop.

use std::path::Path;

use petrel::actors::{status, DEFAULT_STOP_TIMEOUT};

use crate::support::{advance, start};

fn agent_with_rules(rules_path: &Path) -> String {
    format!(
        r#"Agent(name: "r1", modules: [
            (name: "quality", type: "demo.scale"),
            (name: "odometry", type: "demo.counter", values: {{"params/period_ms": 10, "params/start": 100.0}}),
            (name: "localizer", type: "demo.counter", values: {{"params/period_ms": 10}}),
            (name: "mapper", type: "test.echo", links: {{"in/value": "localizer/out/value"}}),
            (name: "recorder", type: "demo.counter", values: {{"params/period_ms": 10}}),
            (name: "contexts", type: "context.manager", values: {{"params/rules": {:?}, "params/tick_ms": 10}}),
        ])"#,
        rules_path.display().to_string()
    )
}

const LOST: &str = r#"Contexts(contexts: [
    (name: "lost", when: "quality/out/value < 0.3", until: "quality/out/value > 0.5",
     relink: {"mapper/in/value": "odometry/out/value"}, set: {"localizer/params/increment": "0.0"}, stop: ["recorder"]),
])"#;

#[tokio::test(start_paused = true)]
async fn a_context_relinks_sets_and_stops_then_restores_everything() {
    let dir = tempfile::tempdir().unwrap();
    let rules = dir.path().join("rules.ron");
    std::fs::write(&rules, LOST).unwrap();
    let agent = start(&agent_with_rules(&rules)).await;
    let bb = agent.blackboard().clone();
    bb.set("quality/in/value", 0.9).await.unwrap();
    advance(50).await;
    assert!(
        *bb.get::<f64>("mapper/out/value").await.unwrap() < 100.0,
        "mapper follows the localizer"
    );
    bb.set("quality/in/value", 0.1).await.unwrap();
    advance(30).await;
    assert_eq!(
        *bb.get::<String>("contexts/out/active").await.unwrap(),
        "lost"
    );
    assert!(
        *bb.get::<f64>("mapper/out/value").await.unwrap() > 100.0,
        "relinked to odometry"
    );
    assert_eq!(
        *bb.get::<f64>("localizer/params/increment").await.unwrap(),
        0.0
    );
    assert_eq!(
        *bb.get::<String>("recorder/stats/status").await.unwrap(),
        status::STOPPED
    );
    bb.set("quality/in/value", 0.4).await.unwrap();
    advance(30).await;
    assert_eq!(
        *bb.get::<String>("contexts/out/active").await.unwrap(),
        "lost",
        "between thresholds: still lost"
    );
    bb.set("quality/in/value", 0.8).await.unwrap();
    advance(30).await;
    assert_eq!(*bb.get::<String>("contexts/out/active").await.unwrap(), "");
    assert_eq!(
        bb.link_of("mapper/in/value").await.unwrap().as_deref(),
        Some("localizer/out/value"),
        "link restored"
    );
    assert_eq!(
        *bb.get::<f64>("localizer/params/increment").await.unwrap(),
        1.0,
        "value restored"
    );
    assert_eq!(
        *bb.get::<String>("recorder/stats/status").await.unwrap(),
        status::RUNNING,
        "restarted"
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_context_manager_restarted_mid_context_goes_on_and_restores_what_was_there() {
    let dir = tempfile::tempdir().unwrap();
    let rules = dir.path().join("rules.ron");
    std::fs::write(&rules, LOST).unwrap();
    let agent = start(&agent_with_rules(&rules)).await;
    let bb = agent.blackboard().clone();
    bb.set("quality/in/value", 0.1).await.unwrap();
    advance(30).await;
    let active = bb.handle::<String>("contexts/out/active").await.unwrap();
    assert_eq!(*active.get(), "lost");
    assert_eq!(
        *bb.get::<f64>("localizer/params/increment").await.unwrap(),
        0.0
    );

    // The manager crashes while `lost` is active (its next step, woken by the quality), and
    // the supervisor restarts it.
    bb.set("contexts/control/fault", "panic".to_string())
        .await
        .unwrap();
    bb.set("quality/in/value", 0.4).await.unwrap();
    advance(1000).await;
    assert_eq!(*bb.get::<i64>("contexts/stats/restarts").await.unwrap(), 1);
    assert_eq!(
        *active.get(),
        "lost",
        "between thresholds a restarted manager keeps the context it had on"
    );
    bb.set("quality/in/value", 0.8).await.unwrap();
    advance(30).await;
    assert_eq!(*active.get(), "");
    assert_eq!(
        *bb.get::<f64>("localizer/params/increment").await.unwrap(),
        1.0,
        "the value from before the context, not the context's own"
    );
    assert_eq!(
        bb.link_of("mapper/in/value").await.unwrap().as_deref(),
        Some("localizer/out/value"),
        "link restored"
    );
    assert_eq!(
        *bb.get::<String>("recorder/stats/status").await.unwrap(),
        status::RUNNING,
        "restarted"
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn reloading_applies_the_difference_and_a_broken_file_changes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let rules = dir.path().join("rules.ron");
    std::fs::write(&rules, LOST).unwrap();
    let agent = start(&agent_with_rules(&rules)).await;
    let bb = agent.blackboard().clone();
    bb.set("quality/in/value", 0.1).await.unwrap();
    advance(30).await;
    assert_eq!(
        *bb.get::<String>("contexts/out/active").await.unwrap(),
        "lost"
    );

    std::fs::write(
        &rules,
        "Contexts(contexts: [(name: \"lost\", when: \"quality/out/value <\")])",
    )
    .unwrap();
    bb.set("contexts/params/reload", 1_i64).await.unwrap();
    advance(20).await;
    let errors = bb.get::<String>("contexts/out/errors").await.unwrap();
    assert!(errors.contains("rules.ron:1:"), "{errors}");
    assert_eq!(
        *bb.get::<f64>("localizer/params/increment").await.unwrap(),
        0.0,
        "the running rules stay"
    );

    // The new rules keep the relink but drop the parameter change and the stop.
    let kept = r#"Contexts(contexts: [(name: "lost", when: "quality/out/value < 0.3", until: "quality/out/value > 0.5",
        relink: {"mapper/in/value": "odometry/out/value"})])"#;
    std::fs::write(&rules, kept).unwrap();
    bb.set("contexts/params/reload", 2_i64).await.unwrap();
    advance(30).await;
    assert_eq!(*bb.get::<String>("contexts/out/errors").await.unwrap(), "");
    assert_eq!(
        *bb.get::<f64>("localizer/params/increment").await.unwrap(),
        1.0,
        "what the removed rule changed is restored"
    );
    assert_eq!(
        *bb.get::<String>("recorder/stats/status").await.unwrap(),
        status::RUNNING
    );
    assert_eq!(
        bb.link_of("mapper/in/value").await.unwrap().as_deref(),
        Some("odometry/out/value"),
        "the kept effect stays"
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn reloaded_rules_wake_on_the_properties_they_newly_read() {
    let dir = tempfile::tempdir().unwrap();
    let rules = dir.path().join("rules.ron");
    std::fs::write(&rules, LOST).unwrap();
    let agent = start(&agent_with_rules(&rules)).await;
    let bb = agent.blackboard().clone();
    let far = r#"Contexts(contexts: [(name: "far", when: "odometry/out/value > 115.5", stop: ["recorder"])])"#;
    std::fs::write(&rules, far).unwrap();
    bb.set("contexts/params/reload", 1_i64).await.unwrap();
    advance(300).await;
    assert!(*bb.get::<f64>("odometry/out/value").await.unwrap() > 116.0);
    assert_eq!(
        *bb.get::<String>("contexts/out/active").await.unwrap(),
        "far",
        "woken by odometry, read only since the reload"
    );
    assert_eq!(
        *bb.get::<String>("recorder/stats/status").await.unwrap(),
        status::STOPPED
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_reload_applies_the_changed_set_values_of_a_context_that_stays_active() {
    let dir = tempfile::tempdir().unwrap();
    let rules = dir.path().join("rules.ron");
    std::fs::write(&rules, LOST).unwrap();
    let agent = start(&agent_with_rules(&rules)).await;
    let bb = agent.blackboard().clone();
    bb.set("quality/in/value", 0.1).await.unwrap();
    advance(30).await;
    assert_eq!(
        *bb.get::<f64>("localizer/params/increment").await.unwrap(),
        0.0
    );
    std::fs::write(&rules, LOST.replace(r#""0.0""#, r#""0.25""#)).unwrap();
    bb.set("contexts/params/reload", 1_i64).await.unwrap();
    advance(30).await;
    assert_eq!(
        *bb.get::<String>("contexts/out/active").await.unwrap(),
        "lost"
    );
    assert_eq!(
        *bb.get::<f64>("localizer/params/increment").await.unwrap(),
        0.25,
        "the context stays active and applies its new value"
    );
    // It still restores the original value when it ends.
    bb.set("quality/in/value", 0.9).await.unwrap();
    advance(30).await;
    assert_eq!(
        *bb.get::<f64>("localizer/params/increment").await.unwrap(),
        1.0
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_linked_clock_drives_held_in_context_rules() {
    let dir = tempfile::tempdir().unwrap();
    let rules = dir.path().join("rules.ron");
    std::fs::write(
        &rules,
        r#"Contexts(contexts: [(name: "low", when: "held(quality/out/value < 0.3, 5s)")])"#,
    )
    .unwrap();
    // `clk` counts 100 per wall second: as the clock, 5 s of it pass in 50 ms.
    let config = agent_with_rules(&rules).replace(
        r#"(name: "contexts", type: "context.manager","#,
        r#"(name: "clk", type: "demo.counter", values: {"params/period_ms": 10}),
            (name: "contexts", type: "context.manager", links: {"in/clock": "clk/out/value"},"#,
    );
    let agent = start(&config).await;
    let bb = agent.blackboard().clone();
    bb.set("quality/in/value", 0.1).await.unwrap();
    advance(200).await;
    assert_eq!(
        *bb.get::<String>("contexts/out/active").await.unwrap(),
        "low",
        "5 clock seconds held within 200 ms of wall time"
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}
