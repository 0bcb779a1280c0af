//! `restart`: from a module's panic to the first step of its new instance, against spawning the
//! same module fresh (after a stop) to its first step.

mod common;

use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};

const CONFIG: &str = r#"Agent(name: "bench",
    supervision: (max_restarts: 100000, within_s: 0.001, backoff: (min_ms: 0, max_ms: 0, jitter: 0.0)),
    modules: [(name: "m", type: "bench.crashy")],
)"#;

fn bench(c: &mut Criterion) {
    let rt = common::runtime();
    let mut group = c.benchmark_group("restart");
    let (agent, fault, kick, started) = rt.block_on(async {
        let agent = common::start(CONFIG).await;
        let bb = agent.blackboard();
        let fault = bb.handle::<String>("m/control/fault").await.unwrap();
        let kick = bb.handle::<i64>("m/in/kick").await.unwrap();
        let started = bb.handle::<i64>("m/out/started").await.unwrap();
        (agent, fault, kick, started)
    });
    // Keep the panic hook quiet: each iteration panics on purpose.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    group.bench_function("petrel_restart", |b| {
        b.iter_custom(|iters| {
            rt.block_on(async {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let target = *started.get() + 1;
                    let start = Instant::now();
                    fault.set("panic".into());
                    kick.set(*kick.get() + 1);
                    while *started.get() < target {
                        started.changed().await;
                    }
                    total += start.elapsed();
                }
                total
            })
        })
    });
    std::panic::set_hook(hook);
    let modules = agent.modules();
    group.bench_function("spawn_floor", |b| {
        b.iter_custom(|iters| {
            rt.block_on(async {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    modules.stop("m").await.unwrap();
                    let target = *started.get() + 1;
                    let start = Instant::now();
                    modules.start("m").await.unwrap();
                    while *started.get() < target {
                        started.changed().await;
                    }
                    total += start.elapsed();
                }
                total
            })
        })
    });
    group.finish();
    rt.block_on(agent.stop(Duration::from_secs(1)));
}

criterion_group! { name = benches; config = common::criterion(); targets = bench }
criterion_main!(benches);
