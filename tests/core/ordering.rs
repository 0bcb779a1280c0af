//! What the scheduler guarantees within an agent, pinned before it changes: a reader never
//! sees a value older than one it already saw; a chain of modules steps in causal order; a step
//! that blocks its thread does not hold up the other modules; a module writing in a tight loop
//! starves neither the others nor the stop.
//!
//! These run on the wall clock (a paused clock never advances while a module is always
//! runnable), each wait bounded by [`DEADLINE`]; the ordering and fairness tests run on a
//! current-thread runtime (one thread for everything, like `--workers 1`), on two workers, and
//! on two workers with `scheduler: agent_thread` (the agent's modules on a thread of its own).

use std::time::Duration;

use petrel::actors::{status, Agent, PropertyHandle, PropertyType, RunSummary};

use crate::ordering_modules::{registry, Gate};
use crate::support::config;

/// The longest any wait of these tests may take before the test fails.
const DEADLINE: Duration = Duration::from_secs(20);

/// Where the agent's modules run: `Shared` on the test's runtime (`scheduler: shared`),
/// `AgentThread` with `scheduler: agent_thread` (the default).
#[derive(Clone, Copy, PartialEq)]
enum On {
    Shared,
    AgentThread,
}

/// Starts agent `r` from `text` (which begins `Agent(name: "r", `), scheduled as `on` says.
async fn start(on: On, text: &str) -> Agent {
    let scheduler = match on {
        On::Shared => "shared",
        On::AgentThread => "agent_thread",
    };
    let text = text.replacen(
        r#"Agent(name: "r", "#,
        &format!(r#"Agent(name: "r", scheduler: {scheduler}, "#),
        1,
    );
    Agent::start(&config(&text), &registry())
        .await
        .unwrap_or_else(|e| panic!("agent should start:\n{e}"))
}

async fn handle<T: PropertyType>(agent: &Agent, address: &str) -> PropertyHandle<T> {
    agent.blackboard().handle::<T>(address).await.unwrap()
}

/// Waits until `holds` is true of the value of `address`; fails the test after [`DEADLINE`].
async fn wait_for<T: PropertyType + std::fmt::Debug>(
    agent: &Agent,
    address: &str,
    holds: impl Fn(&T) -> bool,
) {
    wait_until(&handle::<T>(agent, address).await, address, holds).await;
}

/// Waits until `holds` is true of the value `h` sees (`address` names it in the failure);
/// fails the test after [`DEADLINE`]. Needs no blackboard request, unlike [`wait_for`].
async fn wait_until<T: PropertyType + std::fmt::Debug>(
    h: &PropertyHandle<T>,
    address: &str,
    holds: impl Fn(&T) -> bool,
) {
    let waited = tokio::time::timeout(DEADLINE, async {
        while !holds(&h.get()) {
            h.changed().await;
        }
    })
    .await;
    assert!(
        waited.is_ok(),
        "{address} still {:?} after {DEADLINE:?}",
        h.get()
    );
}

async fn stop(agent: Agent) -> RunSummary {
    agent.stop(Duration::from_secs(5)).await
}

fn assert_all_stopped(summary: &RunSummary) {
    for m in &summary.modules {
        assert_eq!(m.status, status::STOPPED, "{}: {summary:?}", m.name);
    }
}

/// `w` writes 1..=2000, letting the readers run after each write; `r1` and `r2` read it, `r3`
/// reads `r1`.
async fn readers_never_go_back(on: On) {
    let agent = start(
        on,
        r#"Agent(name: "r", modules: [
            (name: "w", type: "test.writer", links: {"in/value": "w/out/value"}, values: {"params/limit": 2000, "params/yield": true}),
            (name: "r1", type: "test.relay", links: {"in/value": "w/out/value"}),
            (name: "r2", type: "test.relay", links: {"in/value": "w/out/value"}),
            (name: "r3", type: "test.relay", links: {"in/value": "r1/out/value"}),
        ])"#,
    )
    .await;
    for reader in ["r1", "r2", "r3"] {
        // No wake-up is lost: every reader steps after the last write.
        wait_for::<f64>(&agent, &format!("{reader}/out/value"), |v| *v == 2000.0).await;
        let bb = agent.blackboard();
        let regressions = *bb
            .get::<i64>(&format!("{reader}/out/regressions"))
            .await
            .unwrap();
        assert_eq!(
            regressions, 0,
            "{reader} read an older value than it had seen"
        );
        let values = bb
            .get::<Vec<f64>>(&format!("{reader}/out/values"))
            .await
            .unwrap();
        assert!(
            values.windows(2).all(|w| w[0] < w[1]),
            "{reader} saw {values:?}"
        );
    }
    assert_all_stopped(&stop(agent).await);
}

#[tokio::test(flavor = "current_thread")]
async fn a_reader_never_sees_a_value_older_than_one_it_saw_on_one_thread() {
    readers_never_go_back(On::Shared).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_reader_never_sees_a_value_older_than_one_it_saw_on_two_workers() {
    readers_never_go_back(On::Shared).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_reader_never_sees_a_value_older_than_one_it_saw_on_the_agents_thread() {
    readers_never_go_back(On::AgentThread).await;
}

/// `w` writes 1..=300; `c0` → `c1` → `c2` → `c3` pass it on. Every value a relay saw, its
/// predecessor saw first, in an earlier step.
async fn chain_in_causal_order(on: On) {
    let agent = start(
        on,
        r#"Agent(name: "r", modules: [
            (name: "w", type: "test.writer", links: {"in/value": "w/out/value"}, values: {"params/limit": 300}),
            (name: "c0", type: "test.relay", links: {"in/value": "w/out/value"}),
            (name: "c1", type: "test.relay", links: {"in/value": "c0/out/value"}),
            (name: "c2", type: "test.relay", links: {"in/value": "c1/out/value"}),
            (name: "c3", type: "test.relay", links: {"in/value": "c2/out/value"}),
        ])"#,
    )
    .await;
    wait_for::<f64>(&agent, "c3/out/value", |v| *v == 300.0).await;
    let bb = agent.blackboard();
    let mut logs = Vec::new();
    for relay in ["c0", "c1", "c2", "c3"] {
        let values = bb
            .get::<Vec<f64>>(&format!("{relay}/out/values"))
            .await
            .unwrap();
        let sequence = bb
            .get::<Vec<f64>>(&format!("{relay}/out/sequence"))
            .await
            .unwrap();
        assert_eq!(values.last(), Some(&300.0), "{relay} saw the last value");
        logs.push((relay, values, sequence));
    }
    for pair in logs.windows(2) {
        let ((before, seen_before, at_before), (after, seen_after, at_after)) =
            (&pair[0], &pair[1]);
        // 0 is every output's initial value, which nobody passed on.
        let passed = seen_after
            .iter()
            .zip(at_after.iter())
            .filter(|(v, _)| **v != 0.0);
        for (value, at) in passed {
            let earlier = seen_before
                .iter()
                .position(|v| v == value)
                .map(|i| at_before[i]);
            assert!(
                earlier.is_some_and(|earlier| earlier < *at),
                "{after} saw {value} at step #{at}; {before} saw it at {earlier:?}"
            );
        }
    }
    assert_all_stopped(&stop(agent).await);
}

#[tokio::test(flavor = "current_thread")]
async fn a_chain_of_modules_steps_in_causal_order_on_one_thread() {
    chain_in_causal_order(On::Shared).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_chain_of_modules_steps_in_causal_order_on_two_workers() {
    chain_in_causal_order(On::Shared).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_chain_of_modules_steps_in_causal_order_on_the_agents_thread() {
    chain_in_causal_order(On::AgentThread).await;
}

/// Two workers, like `petrel run` on this machine: a step that blocks one of them must not hold
/// up the modules that are ready on the other. (On one thread it does; with
/// `scheduler: agent_thread` the blocker is declared `long_steps: true`, which puts it on the
/// shared workers, away from the agent's thread.)
async fn blocking_step_holds_up_nobody(on: On, gate_name: &str) {
    let long_steps = match on {
        On::Shared => "",
        On::AgentThread => "long_steps: true, ",
    };
    let agent = start(
        on,
        &format!(
            r#"Agent(name: "r", modules: [
            (name: "b", type: "test.blocker", {long_steps}values: {{"params/gate": "{gate_name}"}}),
            (name: "e", type: "test.echo"),
            (name: "c", type: "demo.counter", values: {{"params/period_ms": 10}}),
        ])"#
        ),
    )
    .await;
    // Every handle is made before `b` blocks: the blackboard actor's task may be queued on the
    // worker `b` holds (tokio's LIFO slot cannot be stolen), so no request to it is made until
    // `b` is released. Reads and writes through handles go straight to the cells.
    let go = handle::<i64>(&agent, "b/in/go").await;
    let blocked = handle::<bool>(&agent, "b/out/blocked").await;
    let released = handle::<String>(&agent, "b/out/released").await;
    let echo_in = handle::<f64>(&agent, "e/in/value").await;
    let echo_out = handle::<f64>(&agent, "e/out/value").await;
    let count = handle::<i64>(&agent, "c/state/count").await;
    go.set(1);
    wait_until(&blocked, "b/out/blocked", |b| *b).await;
    // While `b` holds its thread: the echo answers and the periodic module keeps counting.
    let counted = count.value();
    echo_in.set(7.0);
    wait_until(&echo_out, "e/out/value", |v| *v == 7.0).await;
    wait_until(&count, "c/state/count", |c| *c >= counted + 5).await;
    assert_eq!(*released.get(), "", "b is still inside its step");
    Gate::named(gate_name).open();
    wait_until(&released, "b/out/released", |r| r == "opened").await;
    assert_all_stopped(&stop(agent).await);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_blocking_step_does_not_hold_up_the_other_modules() {
    blocking_step_holds_up_nobody(
        On::Shared,
        "a_blocking_step_does_not_hold_up_the_other_modules",
    )
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_blocking_step_declared_long_does_not_hold_up_the_agents_thread() {
    blocking_step_holds_up_nobody(
        On::AgentThread,
        "a_blocking_step_declared_long_does_not_hold_up_the_agents_thread",
    )
    .await;
}

/// Under the default scheduler a module not declared `long_steps` whose step blocks holds the
/// agent's thread, and every other module of the agent with it: the watcher outside the thread
/// names it while it still holds (a `held` event, read here by a module on the shared runtime),
/// and once the step returns the supervisor moves it off the thread (a `moved` event), where
/// its steps run from then on.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_step_holding_the_agents_thread_is_named_while_it_holds_and_its_module_moved() {
    let gate = "a_step_holding_the_agents_thread_is_named";
    let text = format!(
        r#"Agent(name: "r", step_budget: (mean_us: 0, steps: 20, held_ms: 50), modules: [
            (name: "log", type: "test.event_log", long_steps: true, links: {{"in/events": "_supervisor/events"}}),
            (name: "b", type: "test.blocker", values: {{"params/gate": "{gate}"}}),
            (name: "c", type: "demo.counter", values: {{"params/period_ms": 10}}),
        ])"#
    );
    let agent = Agent::start(&config(&text), &registry())
        .await
        .unwrap_or_else(|e| panic!("agent should start:\n{e}"));
    // Handles go straight to the cells: they work while the agent's thread is held.
    let go = handle::<i64>(&agent, "b/in/go").await;
    let blocked = handle::<bool>(&agent, "b/out/blocked").await;
    let released = handle::<String>(&agent, "b/out/released").await;
    let kinds = handle::<String>(&agent, "log/out/kinds").await;
    go.set(1);
    wait_until(&blocked, "b/out/blocked", |b| *b).await;
    wait_until(&kinds, "log/out/kinds", |k| k.contains("held:b")).await;
    assert_eq!(
        *released.get(),
        "",
        "named while b is still inside its step"
    );
    Gate::named(gate).open();
    wait_until(&released, "b/out/released", |r| r == "opened").await;
    wait_until(&kinds, "log/out/kinds", |k| k.contains("moved:b")).await;
    let kinds = kinds.get();
    assert!(
        !kinds.contains("moved:c") && !kinds.contains("failed"),
        "only b moves, and a move is no failure: {kinds}"
    );
    assert_all_stopped(&stop(agent).await);
}

/// `w` writes in a tight loop for up to 20 s; beside it the echo answers, the periodic module
/// counts, and the stop stops `w` (not killed after the stop timeout) — all while `w` is still
/// writing, so none of it waited for `w` to finish.
async fn tight_loop_starves_nobody(on: On) {
    let agent = start(
        on,
        r#"Agent(name: "r", modules: [
            (name: "w", type: "test.writer", links: {"in/value": "w/out/value"}, values: {"params/limit": 1000000000000}),
            (name: "e", type: "test.echo"),
            (name: "c", type: "demo.counter", values: {"params/period_ms": 10}),
        ])"#,
    )
    .await;
    wait_for::<f64>(&agent, "w/out/value", |v| *v > 1000.0).await;
    let counted = handle::<i64>(&agent, "c/state/count").await.value();
    handle::<f64>(&agent, "e/in/value").await.set(3.0);
    wait_for::<f64>(&agent, "e/out/value", |v| *v == 3.0).await;
    wait_for::<i64>(&agent, "c/state/count", |c| *c >= counted + 5).await;
    let finished = handle::<bool>(&agent, "w/out/finished").await;
    assert!(!finished.value(), "w was still writing");
    let summary = stop(agent).await;
    assert_all_stopped(&summary);
    assert!(!finished.value(), "w was stopped while still writing");
}

#[tokio::test(flavor = "current_thread")]
async fn a_module_writing_in_a_tight_loop_starves_nobody_on_one_thread() {
    tight_loop_starves_nobody(On::Shared).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_module_writing_in_a_tight_loop_starves_nobody_on_two_workers() {
    tight_loop_starves_nobody(On::Shared).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_module_writing_in_a_tight_loop_starves_nobody_on_the_agents_thread() {
    tight_loop_starves_nobody(On::AgentThread).await;
}
