//! `caterpillar`: end-to-end latency through a chain of 17 modules, each copying its input to
//! its output (the chain copper-rs uses to compare itself with dora and ROS 2), against 17
//! plain tokio tasks chained by `watch` channels.

mod common;

use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};

const LENGTH: usize = 17;

fn config() -> String {
    let mut modules = String::from(r#"(name: "m0", type: "bench.echo"),"#);
    for i in 1..LENGTH {
        modules.push_str(&format!(
            r#"(name: "m{i}", type: "bench.echo", links: {{"in/value": "m{}/out/value"}}),"#,
            i - 1
        ));
    }
    format!(r#"Agent(name: "bench", modules: [{modules}])"#)
}

fn bench(c: &mut Criterion) {
    let rt = common::runtime();
    let mut group = c.benchmark_group("caterpillar");
    let (agent, head, tail) = rt.block_on(async {
        let agent = common::start(&config()).await;
        let head = agent
            .blackboard()
            .handle::<f64>("m0/in/value")
            .await
            .unwrap();
        let tail = agent
            .blackboard()
            .handle::<f64>(&format!("m{}/out/value", LENGTH - 1))
            .await
            .unwrap();
        (agent, head, tail)
    });
    let mut value = 0.0;
    group.bench_function("petrel", |b| {
        b.iter_custom(|iters| {
            rt.block_on(async {
                let start = Instant::now();
                for _ in 0..iters {
                    value += 1.0;
                    head.set(value);
                    while *tail.get() != value {
                        tail.changed().await;
                    }
                }
                start.elapsed()
            })
        })
    });
    rt.block_on(agent.stop(Duration::from_secs(1)));

    let (head, mut tail) = rt.block_on(async { common::watch_chain(LENGTH) });
    group.bench_function("tokio_watch_chain_floor", |b| {
        b.iter_custom(|iters| {
            rt.block_on(async {
                let start = Instant::now();
                for _ in 0..iters {
                    value += 1.0;
                    head.send(value).unwrap();
                    while *tail.borrow_and_update() != value {
                        tail.changed().await.unwrap();
                    }
                }
                start.elapsed()
            })
        })
    });
    group.finish();
}

criterion_group! { name = benches; config = common::criterion(); targets = bench }
criterion_main!(benches);
