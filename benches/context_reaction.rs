//! `context_reaction`: a property changes → a context activates (or ends) → a parameter
//! changes → the module reading it is woken and answers; against `property_wake`'s petrel round
//! trip in the same run, and with 1 000 rules of which one reads the changed property
//! (`rules_1000`) against a single rule (`rules_1`).
//!
//! Like `property_wake`, it is driven from inside the runtime: module `a` (bench.ping) flips
//! `a/out/ping` between 0 and 1; the rule follows it into `target/in/value`; `target` (an echo)
//! answers into `a/in/pong`. One round trip = three wake-ups (a → contexts → target → a).
//! `three_wakes_floor` makes the same three wake-ups with an echo where the manager is.

mod common;

use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};

/// Rules: `react` reads the trigger; `others` more rules read a property that never changes.
fn rules(others: usize) -> String {
    let mut rules = String::from(
        r#"Contexts(contexts: [(name: "react", when: "a/out/ping > 0.5", set: {"target/in/value": "1.0"}),"#,
    );
    for i in 0..others {
        rules.push_str(&format!(
            r#"(name: "idle{i}", when: "idle/in/value > {i}.5"),"#
        ));
    }
    rules.push_str("])");
    rules
}

fn config(rules_path: &std::path::Path) -> String {
    format!(
        r#"Agent(name: "bench", modules: [
            (name: "a", type: "bench.ping", values: {{"params/alternate": true}}, links: {{"in/pong": "target/out/value"}}),
            (name: "idle", type: "bench.idle"),
            (name: "target", type: "bench.echo"),
            (name: "contexts", type: "context.manager", values: {{"params/rules": {:?}, "params/tick_ms": 100000}}),
        ])"#,
        rules_path.display().to_string()
    )
}

/// `a` → `relay` → `target` → `a`: three echoes' hand-overs, as a context reaction makes.
const THREE_WAKES: &str = r#"Agent(name: "bench", modules: [
    (name: "a", type: "bench.ping", values: {"params/alternate": true}, links: {"in/pong": "target/out/value"}),
    (name: "relay", type: "bench.echo", links: {"in/value": "a/out/ping"}),
    (name: "target", type: "bench.echo", links: {"in/value": "relay/out/value"}),
])"#;

fn bench(c: &mut Criterion) {
    let rt = common::runtime();
    let mut group = c.benchmark_group("context_reaction");
    let dir = std::env::temp_dir().join(format!("petrel-context-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, others) in [("rules_1", 0), ("rules_1000", 999)] {
        let path = dir.join(format!("{name}.ron"));
        std::fs::write(&path, rules(others)).unwrap();
        let rig = rt.block_on(common::PingPong::start_with(&config(&path)));
        group.bench_function(name, |b| {
            b.iter_custom(|iters| rt.block_on(rig.round_trips(iters)))
        });
        rt.block_on(rig.agent.stop(Duration::from_secs(1)));
    }
    // The same three wake-ups with an echo in the manager's place: what a reaction costs
    // before the manager's own step (its floor while the manager is a module of its own).
    let three = rt.block_on(common::PingPong::start_with(THREE_WAKES));
    group.bench_function("three_wakes_floor", |b| {
        b.iter_custom(|iters| rt.block_on(three.round_trips(iters)))
    });
    rt.block_on(three.agent.stop(Duration::from_secs(1)));
    let ping_pong = rt.block_on(common::PingPong::start());
    group.bench_function("property_wake_baseline", |b| {
        b.iter_custom(|iters| rt.block_on(ping_pong.round_trips(iters)))
    });
    group.finish();
    rt.block_on(ping_pong.agent.stop(Duration::from_secs(1)));
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group! { name = benches; config = common::criterion(); targets = bench }
criterion_main!(benches);
