//! `pnp_reaction`: a condition property changes → the mission's guard transition fires → the
//! bound action starts and enables its module → the module steps and answers → the action
//! ends and the plan goes back to waiting → the mission acknowledges. Compared with the
//! `property_wake` petrel round trip (module A writes, B wakes and answers, A wakes) measured
//! in the same run.
//!
//! The plan loops `LABEL_top; < go ? work; GOTO_LABEL_top : quit ? work >`, `go` bound to
//! `w/in/go > w/out/done`, `work` enabling `w` until `w/out/done >= w/in/go`; `quit` (never
//! true here) gives the plan the goal place a mission needs. The module `bench.trigger` makes
//! the requests (`w/in/go` is linked to its `out/request`), one after the other, each answered
//! by the mission's own acknowledgement: its `out/fired` grown by the four transitions a
//! request fires (`[go]`, `work.start`, `work.end`, the jump back), the last of which leaves
//! the plan waiting again. Both functions are timed the same way: a batch of N round trips,
//! from the bench thread's request to the last answer.

mod common;

use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};

const PING_PONG: &str = r#"Agent(name: "bench", modules: [
    (name: "a", type: "bench.ping", links: {"in/pong": "b/out/value"}),
    (name: "b", type: "bench.echo", links: {"in/value": "a/out/ping"}),
])"#;

fn mission_config(plan: &str) -> String {
    format!(
        r#"Agent(name: "bench", modules: [
    (name: "t", type: "bench.trigger", values: {{"params/firings": 4}}, links: {{"in/ack": "m/out/fired"}}),
    (name: "w", type: "bench.work", values: {{"enabled": false}}, links: {{"in/go": "t/out/request"}}),
    (name: "m", type: "mission.pnp", values: {{
        "params/plan": "{plan}",
        "params/conditions": {{"go": "w/in/go > w/out/done", "quit": "w/in/go < 0"}},
        "params/actions": {{"work": (enable: ["w"], finished: "w/out/done >= w/in/go")}},
    }}),
])"#
    )
}

fn bench(c: &mut Criterion) {
    let rt = common::runtime();
    let mut group = c.benchmark_group("pnp_reaction");

    let dir = std::env::temp_dir().join(format!("petrel-pnp-reaction-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let plan = dir.join("loop.plan");
    std::fs::write(
        &plan,
        "LABEL_top; < go ? work; GOTO_LABEL_top : quit ? work >\n",
    )
    .unwrap();

    let (agent, go, batches) = rt.block_on(async {
        let agent = common::start(&mission_config(&plan.display().to_string())).await;
        let bb = agent.blackboard();
        let marking = bb.handle::<String>("m/out/marking").await.unwrap();
        // The mission publishes its initial (waiting) marking at init.
        while marking.get().is_empty() {
            marking.changed().await;
        }
        let go = bb.handle::<i64>("t/in/go").await.unwrap();
        let batches = bb.handle::<i64>("t/out/batches").await.unwrap();
        (agent, go, batches)
    });
    group.bench_function("petrel", |b| {
        b.iter_custom(|iters| {
            // Timed like the baseline: the whole batch, from the bench thread.
            rt.block_on(async {
                let target = *batches.get() + 1;
                let start = Instant::now();
                go.set(iters as i64);
                while *batches.get() < target {
                    batches.changed().await;
                }
                start.elapsed()
            })
        })
    });

    let (ping, pgo, pdone) = rt.block_on(async {
        let agent = common::start(PING_PONG).await;
        let go = agent.blackboard().handle::<i64>("a/in/go").await.unwrap();
        let done = agent
            .blackboard()
            .handle::<i64>("a/out/done")
            .await
            .unwrap();
        (agent, go, done)
    });
    group.bench_function("property_wake_baseline", |b| {
        b.iter_custom(|iters| {
            rt.block_on(async {
                let target = *pdone.get() + 1;
                let start = Instant::now();
                pgo.set(iters as i64);
                while *pdone.get() < target {
                    pdone.changed().await;
                }
                start.elapsed()
            })
        })
    });

    group.finish();
    rt.block_on(agent.stop(Duration::from_secs(1)));
    rt.block_on(ping.stop(Duration::from_secs(1)));
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group! { name = benches; config = common::criterion(); targets = bench }
criterion_main!(benches);
