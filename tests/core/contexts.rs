//! The context manager in a running agent: effects applied and undone, reload, start/stop.

use std::path::{Path, PathBuf};

use petrel::actors::{status, Agent, Blackboard, ConfigFile, FilePath, DEFAULT_STOP_TIMEOUT};

use crate::support::{advance, registry, start};

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

/// An agent running `rules` (written to a temp file, which the test may rewrite and reload).
struct Rig {
    /// Holds the rules file.
    _dir: tempfile::TempDir,
    rules: PathBuf,
    agent: Agent,
    bb: Blackboard,
}

async fn rig(rules_text: &str) -> Rig {
    let dir = tempfile::tempdir().unwrap();
    let rules = dir.path().join("rules.ron");
    std::fs::write(&rules, rules_text).unwrap();
    let agent = start(&agent_with_rules(&rules)).await;
    let bb = agent.blackboard().clone();
    Rig {
        _dir: dir,
        rules,
        agent,
        bb,
    }
}

async fn text(bb: &Blackboard, key: &str) -> String {
    (*bb.get::<String>(key).await.unwrap()).clone()
}

async fn num(bb: &Blackboard, key: &str) -> f64 {
    *bb.get::<f64>(key).await.unwrap()
}

/// Sets the quality `lost` reads and lets 30 ms pass.
async fn quality(bb: &Blackboard, value: f64) {
    bb.set("quality/in/value", value).await.unwrap();
    advance(30).await;
}

/// `lost` is active now (`why`), and once the quality is good again, what it changed is back.
async fn assert_lost_holds_then_undone(bb: &Blackboard, why: &str) {
    assert_eq!(text(bb, "contexts/out/active").await, "lost", "{why}");
    quality(bb, 0.8).await;
    assert_lost_undone(bb).await;
}

/// What `lost` changed is back: the mapper's link, the localizer's increment, the recorder.
async fn assert_lost_undone(bb: &Blackboard) {
    assert_eq!(text(bb, "contexts/out/active").await, "");
    assert_eq!(
        bb.link_of("mapper/in/value").await.unwrap().as_deref(),
        Some("localizer/out/value"),
        "link restored"
    );
    assert_eq!(
        num(bb, "localizer/params/increment").await,
        1.0,
        "the value from before the context restored"
    );
    assert_eq!(
        text(bb, "recorder/stats/status").await,
        status::RUNNING,
        "restarted"
    );
}

#[tokio::test(start_paused = true)]
async fn a_context_relinks_sets_and_stops_then_restores_everything() {
    let r = rig(LOST).await;
    let bb = &r.bb;
    bb.set("quality/in/value", 0.9).await.unwrap();
    advance(50).await;
    assert!(
        num(bb, "mapper/out/value").await < 100.0,
        "mapper follows the localizer"
    );
    quality(bb, 0.1).await;
    assert_eq!(text(bb, "contexts/out/active").await, "lost");
    assert!(
        num(bb, "mapper/out/value").await > 100.0,
        "relinked to odometry"
    );
    assert_eq!(num(bb, "localizer/params/increment").await, 0.0);
    assert_eq!(text(bb, "recorder/stats/status").await, status::STOPPED);
    quality(bb, 0.4).await;
    assert_lost_holds_then_undone(bb, "between thresholds: still lost").await;
    r.agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_context_manager_restarted_mid_context_goes_on_and_restores_what_was_there() {
    let r = rig(LOST).await;
    let bb = &r.bb;
    quality(bb, 0.1).await;
    assert_eq!(text(bb, "contexts/out/active").await, "lost");
    assert_eq!(num(bb, "localizer/params/increment").await, 0.0);

    // The manager crashes while `lost` is active (its next step, woken by the quality), and
    // the supervisor restarts it.
    bb.set("contexts/control/fault", "panic".to_string())
        .await
        .unwrap();
    bb.set("quality/in/value", 0.4).await.unwrap();
    advance(1000).await;
    assert_eq!(*bb.get::<i64>("contexts/stats/restarts").await.unwrap(), 1);
    let why = "between thresholds a restarted manager keeps the context it had on";
    assert_lost_holds_then_undone(bb, why).await;
    r.agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn an_agent_resumed_from_a_snapshot_mid_context_restores_what_was_there_before() {
    let r = rig(LOST).await;
    quality(&r.bb, 0.1).await;
    assert_eq!(num(&r.bb, "localizer/params/increment").await, 0.0);
    r.agent.stop_modules(DEFAULT_STOP_TIMEOUT).await;
    let snapshot = r.agent.snapshot().await.unwrap();
    r.agent.shutdown().await;

    // The snapshot holds the context's value; its memory, the value from before.
    let mut file = ConfigFile::parse("base.ron", &agent_with_rules(&r.rules)).unwrap();
    file.overlay(ConfigFile::parse("snapshot.ron", &snapshot).unwrap_or_else(|e| panic!("{e}")));
    let agent = Agent::start(&file, &registry())
        .await
        .unwrap_or_else(|e| panic!("{e}"));
    let bb = agent.blackboard();
    advance(30).await;
    assert_eq!(num(bb, "localizer/params/increment").await, 0.0);
    assert_lost_holds_then_undone(bb, "resumed with `lost` on").await;
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn reloading_applies_the_difference_and_a_broken_file_changes_nothing() {
    let r = rig(LOST).await;
    let (bb, rules) = (&r.bb, &r.rules);
    quality(bb, 0.1).await;
    assert_eq!(text(bb, "contexts/out/active").await, "lost");

    std::fs::write(
        rules,
        "Contexts(contexts: [(name: \"lost\", when: \"quality/out/value <\")])",
    )
    .unwrap();
    bb.set("contexts/params/reload", 1_i64).await.unwrap();
    advance(20).await;
    let errors = text(bb, "contexts/out/errors").await;
    assert!(errors.contains("rules.ron:1:"), "{errors}");
    assert_eq!(
        num(bb, "localizer/params/increment").await,
        0.0,
        "the running rules stay"
    );

    // The new rules keep the relink but drop the parameter change and the stop.
    let kept = r#"Contexts(contexts: [(name: "lost", when: "quality/out/value < 0.3", until: "quality/out/value > 0.5",
        relink: {"mapper/in/value": "odometry/out/value"})])"#;
    std::fs::write(rules, kept).unwrap();
    bb.set("contexts/params/reload", 2_i64).await.unwrap();
    advance(30).await;
    assert_eq!(text(bb, "contexts/out/errors").await, "");
    assert_eq!(
        num(bb, "localizer/params/increment").await,
        1.0,
        "what the removed rule changed is restored"
    );
    assert_eq!(text(bb, "recorder/stats/status").await, status::RUNNING);
    assert_eq!(
        bb.link_of("mapper/in/value").await.unwrap().as_deref(),
        Some("odometry/out/value"),
        "the kept effect stays"
    );
    r.agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_refused_reload_puts_params_rules_back_so_a_restart_loads_the_rules_that_ran() {
    let r = rig(LOST).await;
    let (bb, rules) = (&r.bb, &r.rules);
    let missing = rules.with_file_name("missing.rules.ron");
    bb.set(
        "contexts/params/rules",
        FilePath::from(missing.to_str().unwrap()),
    )
    .await
    .unwrap();
    bb.set("contexts/params/reload", 1_i64).await.unwrap();
    advance(20).await;
    let errors = text(bb, "contexts/out/errors").await;
    assert!(errors.contains("missing.rules.ron"), "{errors}");
    assert!(errors.contains("params/rules is back to"), "{errors}");
    let now = bb.get::<FilePath>("contexts/params/rules").await.unwrap();
    assert_eq!(now.as_path(), rules.as_path());

    // A crash now restarts the manager on the rules that ran, instead of failing to start
    // until the supervisor gives the agent up.
    bb.set("contexts/control/fault", "panic".to_string())
        .await
        .unwrap();
    quality(bb, 0.1).await;
    advance(1000).await;
    assert_eq!(*bb.get::<i64>("contexts/stats/restarts").await.unwrap(), 1);
    assert_eq!(text(bb, "contexts/stats/status").await, status::RUNNING);
    assert_eq!(text(bb, "contexts/out/active").await, "lost");
    r.agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn reloaded_rules_wake_on_the_properties_they_newly_read() {
    let r = rig(LOST).await;
    let (bb, rules) = (&r.bb, &r.rules);
    let far = r#"Contexts(contexts: [(name: "far", when: "odometry/out/value > 115.5", stop: ["recorder"])])"#;
    std::fs::write(rules, far).unwrap();
    bb.set("contexts/params/reload", 1_i64).await.unwrap();
    advance(300).await;
    assert!(num(bb, "odometry/out/value").await > 116.0);
    assert_eq!(
        text(bb, "contexts/out/active").await,
        "far",
        "woken by odometry, read only since the reload"
    );
    assert_eq!(text(bb, "recorder/stats/status").await, status::STOPPED);
    r.agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_reload_applies_the_changed_set_values_of_a_context_that_stays_active() {
    let r = rig(LOST).await;
    let (bb, rules) = (&r.bb, &r.rules);
    quality(bb, 0.1).await;
    assert_eq!(num(bb, "localizer/params/increment").await, 0.0);
    std::fs::write(rules, LOST.replace(r#""0.0""#, r#""0.25""#)).unwrap();
    bb.set("contexts/params/reload", 1_i64).await.unwrap();
    advance(30).await;
    assert_eq!(text(bb, "contexts/out/active").await, "lost");
    assert_eq!(
        num(bb, "localizer/params/increment").await,
        0.25,
        "the context stays active and applies its new value"
    );
    // It still restores the original value when it ends.
    quality(bb, 0.9).await;
    assert_lost_undone(bb).await;
    r.agent.stop(DEFAULT_STOP_TIMEOUT).await;
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

#[tokio::test(start_paused = true)]
async fn out_evaluations_is_a_statistic_written_now_and_then_and_when_the_manager_stops() {
    let r = rig(LOST).await;
    let bb = &r.bb;
    let evaluations = bb.handle::<i64>("contexts/out/evaluations").await.unwrap();
    let steps = bb.handle::<i64>("contexts/stats/steps").await.unwrap();
    quality(bb, 0.9).await;
    let (writes, first) = (evaluations.read().version, *evaluations.get());
    // Ten switches 30 ms apart (300 ms): the manager steps at each, the statistic is written
    // at most every 100 ms.
    for k in 0..10 {
        quality(bb, if k % 2 == 0 { 0.1 } else { 0.9 }).await;
    }
    let written = evaluations.read().version - writes;
    assert!(
        (1..=4).contains(&written),
        "written {written} times in 300 ms"
    );
    assert!(*evaluations.get() > first, "it follows the evaluations");
    r.agent.stop(DEFAULT_STOP_TIMEOUT).await;
    // At the stop, the count of every evaluation: one per switch at least.
    assert!(*evaluations.get() >= first + 10, "{}", evaluations.get());
    assert!(*steps.get() >= 10, "the manager stepped at each switch");
}
