//! `queue_fanout`: one producer module pushes fresh images into a queue read by 8 consumer
//! modules; 1 KiB vs 1 MiB payloads. Items are shared, so the payload size must not matter
//! (`petrel_1m` / `petrel_1k` ≈ 1). The `copy_*` functions run the same agent with consumers
//! that copy each item's pixels, as a copying transport would: their 1 MiB / 1 KiB ratio is
//! what a copy in the queue would show.

mod common;

use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};

const READERS: usize = 8;
/// Items pushed per wake-up of the producer.
const CHUNK: i64 = 1024;

fn config(bytes: usize, copy: bool) -> String {
    let sinks: String = (0..READERS)
        .map(|i| {
            format!(
                r#"(name: "sink{i}", type: "bench.qsink", values: {{"params/copy": {copy}}}, links: {{"in/items": "src/out/items"}}),"#
            )
        })
        .collect();
    format!(
        r#"Agent(name: "bench", modules: [(name: "src", type: "bench.qsource", values: {{"params/bytes": {bytes}}}), {sinks}])"#
    )
}

fn bench(c: &mut Criterion) {
    let rt = common::runtime();
    let mut group = c.benchmark_group("queue_fanout");
    for (name, bytes, copy) in [
        ("petrel_1k", 1 << 10, false),
        ("petrel_1m", 1 << 20, false),
        ("copy_1k", 1 << 10, true),
        ("copy_1m", 1 << 20, true),
    ] {
        let (agent, go, counts) = rt.block_on(async {
            let agent = common::start(&config(bytes, copy)).await;
            let bb = agent.blackboard();
            let go = bb.handle::<i64>("src/in/go").await.unwrap();
            let mut counts = Vec::new();
            for i in 0..READERS {
                counts.push(
                    bb.handle::<i64>(&format!("sink{i}/out/count"))
                        .await
                        .unwrap(),
                );
            }
            (agent, go, counts)
        });
        group.bench_function(name, |b| {
            b.iter_custom(|iters| {
                rt.block_on(async {
                    let start = Instant::now();
                    // In chunks well under the queue's capacity, so no reader ever lags into drops.
                    let mut left = iters as i64;
                    while left > 0 {
                        let chunk = left.min(CHUNK);
                        left -= chunk;
                        let target = *counts[0].get() + chunk;
                        go.set(chunk);
                        for count in &counts {
                            while *count.get() < target {
                                count.changed().await;
                            }
                        }
                    }
                    start.elapsed()
                })
            })
        });
        rt.block_on(agent.stop(Duration::from_secs(1)));
    }
    group.finish();
}

criterion_group! { name = benches; config = common::criterion(); targets = bench }
criterion_main!(benches);
