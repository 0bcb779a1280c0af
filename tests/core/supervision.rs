//! Supervision: strategies, restart policies, intensity and give-up, backoff, hangs, state and
//! queue delivery across restarts, shutdown order, runtime control. All on the paused clock.

use petrel::actors::{status, Agent, DEFAULT_STOP_TIMEOUT, EXIT_GAVE_UP};

use crate::support::{advance, start};

/// Deterministic backoff for tests: 10 ms, no jitter.
const QUICK: &str = "supervision: (backoff: (min_ms: 10, max_ms: 10, jitter: 0.0)),";

async fn int(agent: &Agent, address: &str) -> i64 {
    *agent
        .blackboard()
        .get::<i64>(address)
        .await
        .unwrap_or_else(|e| panic!("{address}: {e}"))
}

async fn text(agent: &Agent, address: &str) -> String {
    agent
        .blackboard()
        .get::<String>(address)
        .await
        .unwrap()
        .to_string()
}

async fn inject(agent: &Agent, module: &str, fault: &str) {
    agent
        .blackboard()
        .set(&format!("{module}/control/fault"), fault.to_string())
        .await
        .unwrap();
}

#[tokio::test(start_paused = true)]
async fn one_for_one_restarts_the_failed_module_which_keeps_its_state_and_params() {
    let agent = start(&format!(
        r#"Agent(name: "r1", {QUICK} modules: [
            (name: "a", type: "demo.counter", values: {{"params/period_ms": 10}}),
            (name: "b", type: "demo.counter", values: {{"params/period_ms": 10}}),
        ])"#
    ))
    .await;
    advance(55).await;
    agent
        .blackboard()
        .set("b/params/increment", 10.0)
        .await
        .unwrap();
    advance(10).await;
    assert_eq!(int(&agent, "b/state/count").await, 6);
    inject(&agent, "b", "panic").await;
    advance(7).await; // the fault hits b's step at 70 ms; its restart is due at 80 ms
    assert_eq!(text(&agent, "b/stats/status").await, status::RESTARTING);
    advance(40).await;
    assert_eq!(
        (
            int(&agent, "a/stats/restarts").await,
            int(&agent, "b/stats/restarts").await
        ),
        (0, 1)
    );
    assert_eq!(int(&agent, "b/stats/failures").await, 1);
    let count = int(&agent, "b/state/count").await;
    assert!(
        (8..=10).contains(&count),
        "state survived and counting went on: {count}"
    );
    let value = *agent.blackboard().get::<f64>("b/out/value").await.unwrap();
    assert_eq!(
        value,
        count as f64 * 10.0,
        "the changed parameter survived the restart"
    );
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    assert!(summary
        .module("b")
        .unwrap()
        .last_error
        .as_deref()
        .unwrap()
        .contains("fault injected"));
}

#[tokio::test(start_paused = true)]
async fn one_for_all_and_rest_for_one_restart_their_group() {
    let agent = start(&format!(
        r#"Agent(name: "r1", {QUICK}
            groups: [(name: "all", strategy: one_for_all), (name: "rest", strategy: rest_for_one)],
            modules: [
                (name: "a1", type: "demo.counter", group: "all"),
                (name: "a2", type: "demo.counter", group: "all"),
                (name: "a3", type: "demo.counter", group: "all"),
                (name: "r1", type: "demo.counter", group: "rest"),
                (name: "r2", type: "demo.counter", group: "rest"),
                (name: "r3", type: "demo.counter", group: "rest"),
                (name: "solo", type: "demo.counter"),
            ])"#
    ))
    .await;
    advance(20).await;
    inject(&agent, "a2", "panic").await;
    inject(&agent, "r2", "error").await;
    advance(200).await;
    let mut restarts = Vec::new();
    for m in ["a1", "a2", "a3", "r1", "r2", "r3", "solo"] {
        restarts.push(int(&agent, &format!("{m}/stats/restarts")).await);
    }
    assert_eq!(restarts, [1, 1, 1, 0, 1, 1, 0]);
    for m in ["a1", "a3", "r3"] {
        assert_eq!(
            int(&agent, &format!("{m}/stats/failures")).await,
            0,
            "{m} was restarted, not failed"
        );
    }
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn restart_policies_decide_who_comes_back() {
    let agent = start(&format!(
        r#"Agent(name: "r1", {QUICK} modules: [
            (name: "perm", type: "demo.counter"),
            (name: "trans", type: "demo.counter", restart: transient),
            (name: "temp", type: "demo.counter", restart: temporary),
        ])"#
    ))
    .await;
    advance(10).await;
    for m in ["perm", "trans", "temp"] {
        inject(&agent, m, "panic").await;
    }
    advance(250).await;
    assert_eq!(text(&agent, "perm/stats/status").await, status::RUNNING);
    assert_eq!(text(&agent, "trans/stats/status").await, status::RUNNING);
    assert_eq!(text(&agent, "temp/stats/status").await, status::FAILED);
    assert_eq!(int(&agent, "temp/stats/restarts").await, 0);
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

const ALWAYS_FAILING: &str = r#"(name: "laser", type: "test.faulty", values: {"params/mode": "init"}),
    (name: "log", type: "test.event_log", links: {"in/events": "_supervisor/events"}),
    (name: "count", type: "demo.counter", values: {"params/period_ms": 10}),"#;

#[tokio::test(start_paused = true)]
async fn beyond_the_intensity_stop_agent_ends_the_run_naming_the_module() {
    let agent = start(&format!(
        r#"Agent(name: "r1",
            supervision: (max_restarts: 3, within_s: 10.0, on_give_up: stop_agent,
                          backoff: (min_ms: 10, max_ms: 10, jitter: 0.0)),
            modules: [{ALWAYS_FAILING}])"#
    ))
    .await;
    // Bounded: an agent that never gave up would fail the test, not hang it (paused clock:
    // the minute passes as soon as nothing else is due).
    let exit = tokio::time::timeout(std::time::Duration::from_secs(60), agent.finished())
        .await
        .expect("the supervisor gives up within a minute");
    assert_eq!(exit.code, EXIT_GAVE_UP);
    assert!(
        exit.reason.contains(
            "the agent-wide restart limit (supervision max_restarts: 3 within_s: 10) was reached; restarts so far: `laser` 3; the last failure was module `laser` (failure 4)"
        ),
        "{}",
        exit.reason
    );
    assert!(
        exit.reason.contains("no such device /dev/laser0"),
        "{}",
        exit.reason
    );
    advance(1).await;
    let kinds = text(&agent, "log/out/kinds").await;
    assert!(kinds.ends_with("failed:laser gave_up:laser "), "{kinds}");
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    assert_eq!(
        (
            summary.module("laser").unwrap().failures,
            summary.module("laser").unwrap().restarts
        ),
        (4, 3)
    );
}

/// A module stopped while its restart waits out a backoff is summed up as `failed` (what it
/// last did), not `restarting` (a restart that will not come).
#[tokio::test(start_paused = true)]
async fn a_module_stopped_while_its_restart_waits_is_summed_up_as_failed() {
    let agent = start(
        r#"Agent(name: "r1",
            supervision: (max_restarts: 10, within_s: 60.0,
                          backoff: (min_ms: 60000, max_ms: 60000, jitter: 0.0)),
            modules: [(name: "laser", type: "test.faulty", values: {"params/mode": "init"})])"#,
    )
    .await;
    advance(100).await;
    assert_eq!(text(&agent, "laser/stats/status").await, status::RESTARTING);
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    let laser = summary.module("laser").unwrap();
    assert_eq!((laser.status.as_str(), laser.failures), (status::FAILED, 1));
}

#[tokio::test(start_paused = true)]
async fn beyond_the_intensity_disable_module_keeps_the_agent_running() {
    let agent = start(&format!(
        r#"Agent(name: "r1",
            supervision: (max_restarts: 2, on_give_up: disable_module,
                          backoff: (min_ms: 10, max_ms: 10, jitter: 0.0)),
            modules: [{ALWAYS_FAILING}])"#
    ))
    .await;
    advance(505).await;
    assert_eq!(text(&agent, "laser/stats/status").await, status::FAILED);
    assert_eq!(int(&agent, "laser/stats/restarts").await, 2);
    assert_eq!(
        *agent
            .blackboard()
            .get::<f64>("count/out/value")
            .await
            .unwrap(),
        50.0,
        "the rest runs on"
    );
    assert!(text(&agent, "log/out/kinds")
        .await
        .ends_with("gave_up:laser "));
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_group_beyond_its_intensity_fails_to_the_agent() {
    let agent = start(
        r#"Agent(name: "r1",
            supervision: (max_restarts: 1, on_give_up: disable_module, backoff: (min_ms: 10, max_ms: 10, jitter: 0.0)),
            groups: [(name: "sensors", max_restarts: 1)],
            modules: [
                (name: "laser", type: "test.faulty", group: "sensors", values: {"params/mode": "init"}),
                (name: "log", type: "test.event_log", links: {"in/events": "_supervisor/events"}),
            ])"#,
    )
    .await;
    advance(200).await;
    let kinds = text(&agent, "log/out/kinds").await;
    assert_eq!(
        kinds,
        "failed:laser restarted:laser failed:laser escalated:sensors restarted:laser failed:laser escalated:sensors gave_up:laser "
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn backoff_doubles_between_restarts_up_to_its_maximum() {
    let agent = start(&format!(
        r#"Agent(name: "r1",
            supervision: (max_restarts: 10, within_s: 60.0, backoff: (min_ms: 100, max_ms: 400, jitter: 0.0)),
            modules: [{ALWAYS_FAILING}])"#
    ))
    .await;
    advance(1150).await;
    let times = agent
        .blackboard()
        .get::<Vec<f64>>("log/out/restart_ms")
        .await
        .unwrap();
    assert_eq!(*times, [100.0, 300.0, 700.0, 1100.0]);
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_hanging_step_is_dropped_by_the_watchdog_and_the_module_restarted() {
    let agent = start(&format!(
        r#"Agent(name: "r1", {QUICK} modules: [
            (name: "count", type: "demo.counter", watchdog_ms: 50, values: {{"params/period_ms": 10}}),
        ])"#
    ))
    .await;
    advance(25).await;
    inject(&agent, "count", "hang").await;
    advance(20).await;
    assert_eq!(
        text(&agent, "count/stats/status").await,
        status::RUNNING,
        "hanging, not yet detected"
    );
    advance(60).await;
    assert_eq!(int(&agent, "count/stats/restarts").await, 1);
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    let error = summary.module("count").unwrap().last_error.clone().unwrap();
    assert!(
        error.contains("hang: a step ran longer than its 50ms watchdog"),
        "{error}"
    );
}

/// A kill must end the killed instance, not only its actor: its step loop runs as a task of
/// its own, which the kill aborts. Were it left running, the stuck step would hold the module
/// for ever (and a module's loop that went on would step beside its next instance).
#[tokio::test(start_paused = true)]
async fn a_module_killed_at_the_stop_timeout_is_dropped_with_its_stuck_step() {
    use std::sync::atomic::Ordering;
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "stuck", type: "test.drop_count"),
        ])"#,
    )
    .await;
    advance(10).await;
    inject(&agent, "stuck", "hang").await;
    advance(10).await;
    let before = crate::support::DROPS.load(Ordering::SeqCst);
    let summary = agent
        .stop_modules(std::time::Duration::from_millis(100))
        .await;
    assert_eq!(
        summary.module("stuck").unwrap().status,
        "killed",
        "{summary:?}"
    );
    // The abort takes effect at the task's next poll: let the ready tasks run.
    advance(1).await;
    assert_eq!(
        crate::support::DROPS.load(Ordering::SeqCst),
        before + 1,
        "the killed instance (and its stuck step) should be dropped"
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn modules_stop_in_reverse_start_order() {
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "first", type: "test.stop_order"),
            (name: "second", type: "test.stop_order"),
            (name: "third", type: "test.stop_order"),
        ])"#,
    )
    .await;
    agent.stop_modules(DEFAULT_STOP_TIMEOUT).await;
    let mut order = Vec::new();
    for m in ["first", "second", "third"] {
        order.push(int(&agent, &format!("{m}/out/stopped")).await);
    }
    assert!(order[2] < order[1] && order[1] < order[0], "{order:?}");
    agent.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn queued_items_are_delivered_at_least_once_across_consumer_failures() {
    let agent = start(
        r#"Agent(name: "r1",
            supervision: (max_restarts: 1000, backoff: (min_ms: 1, max_ms: 1, jitter: 0.0)),
            modules: [
                (name: "producer", type: "demo.producer", values: {"params/period_ms": 1, "params/batch": 100},
                 capacities: {"out/items": 200000}),
                (name: "consumer", type: "test.flaky_consumer", links: {"in/items": "producer/out/items"}),
            ])"#,
    )
    .await;
    for _ in 0..100 {
        advance(100).await;
        if int(&agent, "producer/state/next").await >= 100_000 {
            break;
        }
    }
    agent
        .blackboard()
        .set("producer/enabled", false)
        .await
        .unwrap();
    advance(50).await;
    assert!(int(&agent, "producer/state/next").await >= 100_000);
    let produced = int(&agent, "producer/state/next").await;
    assert_eq!(
        int(&agent, "consumer/state/next").await,
        produced,
        "every item processed"
    );
    assert_eq!(
        int(&agent, "consumer/state/errors").await,
        0,
        "in order, no gap, no duplicate"
    );
    let restarts = int(&agent, "consumer/stats/restarts").await;
    assert_eq!(restarts, produced / 1000, "one failure per thousand items");
    assert!(
        int(&agent, "consumer/state/deliveries").await > produced,
        "failed batches were redelivered"
    );
    assert_eq!(int(&agent, "consumer/stats/dropped/in/items").await, 0);
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn modules_can_be_stopped_started_and_restarted_while_running() {
    let agent = start(r#"Agent(name: "r1", modules: [(name: "count", type: "demo.counter", values: {"params/period_ms": 10})])"#).await;
    let modules = agent.modules();
    advance(55).await;
    modules.stop("count").await.unwrap();
    assert_eq!(text(&agent, "count/stats/status").await, status::STOPPED);
    advance(100).await;
    assert_eq!(
        int(&agent, "count/state/count").await,
        5,
        "a stopped module does not step"
    );
    modules.start("count").await.unwrap();
    advance(25).await;
    assert_eq!(
        int(&agent, "count/state/count").await,
        7,
        "started again, it continues from its state"
    );
    modules.restart("count").await.unwrap();
    assert_eq!(int(&agent, "count/stats/restarts").await, 1);
    assert_eq!(
        modules.start("count").await.unwrap_err(),
        "module `count` is already running"
    );
    assert_eq!(
        modules.stop("nope").await.unwrap_err(),
        "no module `nope` in agent `r1`"
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_cleanup_tells_a_restart_from_a_stop_and_steps_count_every_instance() {
    let agent =
        start(r#"Agent(name: "r1", modules: [(name: "c", type: "test.cleanup_log")])"#).await;
    let modules = agent.modules();
    let cleanups = agent
        .blackboard()
        .handle::<String>("c/out/cleanups")
        .await
        .unwrap();
    advance(35).await;
    modules.restart("c").await.unwrap();
    assert_eq!(*cleanups.get(), "restart");
    advance(35).await;
    modules.stop("c").await.unwrap();
    assert_eq!(
        *cleanups.get(),
        "restart,stop",
        "stopped on request: not a restart"
    );
    modules.start("c").await.unwrap();
    advance(35).await;
    let steps = int(&agent, "c/state/steps").await;
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    assert_eq!(*cleanups.get(), "restart,stop,stop");
    let c = summary.module("c").unwrap();
    assert_eq!(c.restarts, 1, "{c:?}");
    assert!(steps >= 9, "three instances stepped: {steps}");
    assert_eq!(
        c.steps, steps as u64,
        "the summary counts every instance's steps"
    );
}

#[tokio::test(start_paused = true)]
async fn chaos_soak_twenty_modules_lose_nothing_and_leave_nothing_behind() {
    let tasks_before = tokio::runtime::Handle::current()
        .metrics()
        .num_alive_tasks();
    let mut modules = String::new();
    let mut targets = Vec::new();
    for i in 0..10 {
        modules.push_str(&format!(
            r#"(name: "p{i}", type: "demo.producer", watchdog_ms: 50, values: {{"params/period_ms": 7, "params/batch": 3}},
                capacities: {{"out/items": 100000}}),
               (name: "c{i}", type: "demo.consumer", watchdog_ms: 50, links: {{"in/items": "p{i}/out/items"}}),"#
        ));
        targets.push(format!("p{i}, c{i}"));
    }
    let agent = start(&format!(
        r#"Agent(name: "soak", supervision: (max_restarts: 1000, backoff: (min_ms: 1, max_ms: 50, jitter: 0.2)),
            modules: [{modules}
                (name: "chaos", type: "demo.chaos", values: {{"params/targets": "{}", "params/faults": "panic, hang, error",
                 "params/mean_interval_ms": 50, "params/seed": 42}}),
            ])"#,
        targets.join(", ")
    ))
    .await;
    advance(30_000).await;
    agent.modules().stop("chaos").await.unwrap();
    for i in 0..10 {
        agent.modules().stop(&format!("p{i}")).await.unwrap();
    }
    advance(1_000).await;
    let injected = int(&agent, "chaos/out/injected").await;
    assert!(injected > 400, "chaos did its job: {injected} faults");
    let summary = agent.stop_modules(DEFAULT_STOP_TIMEOUT).await;
    assert!(summary.restarts() > 400, "{summary}");
    for i in 0..10 {
        let produced = int(&agent, &format!("p{i}/state/next")).await;
        let get = |p: &str| format!("c{i}/{p}");
        assert!(produced > 5_000, "p{i} kept producing: {produced}");
        assert_eq!(
            int(&agent, &get("out/received")).await,
            produced,
            "c{i} got everything"
        );
        assert_eq!(int(&agent, &get("out/gaps")).await, 0, "c{i}");
        assert_eq!(int(&agent, &get("out/duplicates")).await, 0, "c{i}");
        assert_eq!(int(&agent, &get("stats/dropped/in/items")).await, 0, "c{i}");
    }
    agent.shutdown().await;
    // Every module actor, restart timer and blackboard task is gone again.
    for _ in 0..10 {
        tokio::task::yield_now().await;
    }
    assert_eq!(
        tokio::runtime::Handle::current()
            .metrics()
            .num_alive_tasks(),
        tasks_before
    );
}

#[tokio::test(start_paused = true)]
async fn module_instances_can_be_added_and_removed_while_running() {
    use petrel::actors::ModuleConfig;
    let agent = start(r#"Agent(name: "r1", modules: [(name: "producer", type: "demo.producer", values: {"params/period_ms": 10})])"#).await;
    let modules = agent.modules();
    advance(55).await;
    let consumer = ModuleConfig {
        name: "late".into(),
        type_name: "demo.consumer".into(),
        links: [("in/items".to_string(), "producer/out/items".into())].into(),
        ..Default::default()
    };
    modules.add(consumer.clone()).await.unwrap();
    advance(100).await;
    assert_eq!(
        int(&agent, "late/out/received").await,
        10,
        "items pushed since it was added"
    );
    assert_eq!(
        modules.add(consumer.clone()).await.unwrap_err(),
        "a module `late` already exists"
    );
    let broken = ModuleConfig {
        name: "broken".into(),
        links: [("in/items".to_string(), "producer/out/nope".into())].into(),
        ..consumer
    };
    let error = modules.add(broken).await.unwrap_err();
    assert!(
        error.contains("module `broken`, `in/items`: module `producer` has no property `out/nope`"),
        "{error}"
    );
    assert!(
        agent
            .blackboard()
            .get::<bool>("broken/enabled")
            .await
            .is_err(),
        "a refused module leaves nothing behind"
    );
    assert_eq!(
        modules.remove("producer").await.unwrap_err(),
        "module `producer` cannot be removed: linked from late/in/items"
    );
    modules.remove("late").await.unwrap();
    assert!(agent
        .blackboard()
        .get::<i64>("late/out/received")
        .await
        .is_err());
    assert_eq!(
        modules.start("late").await.unwrap_err(),
        "no module `late` in agent `r1`",
        "a removed module cannot be started again"
    );
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    assert_eq!(
        summary
            .modules
            .iter()
            .map(|m| m.name.as_str())
            .collect::<Vec<_>>(),
        ["producer"]
    );
}

#[tokio::test(start_paused = true)]
async fn a_fault_the_config_sets_fires_once_at_the_first_step_and_not_again_after_the_restart() {
    let agent = start(&format!(
        r#"Agent(name: "r1", {QUICK} modules: [
            (name: "a", type: "demo.counter", values: {{"params/period_ms": 10, "control/fault": "error"}}),
        ])"#
    ))
    .await;
    advance(100).await;
    assert_eq!(int(&agent, "a/stats/failures").await, 1);
    assert_eq!(int(&agent, "a/stats/restarts").await, 1);
    assert_eq!(
        text(&agent, "a/control/fault").await,
        "",
        "a fault fires once"
    );
    assert_eq!(text(&agent, "a/stats/status").await, status::RUNNING);
    assert!(
        int(&agent, "a/state/count").await > 0,
        "the restarted instance counts"
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}
