//! `property_read`: reading a linked input through a handle, against the primitive it is built
//! on (a `parking_lot::RwLock<Arc<T>>` read and pointer clone).

mod common;

use std::sync::Arc;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};

fn bench(c: &mut Criterion) {
    let rt = common::runtime();
    let mut group = c.benchmark_group("property_read");
    let (agent, input) = rt.block_on(async {
        let agent = common::start(
            r#"Agent(name: "bench", modules: [
                (name: "a", type: "bench.echo", values: {"in/value": 1.5}),
                (name: "b", type: "bench.echo", links: {"in/value": "a/out/value"}),
            ])"#,
        )
        .await;
        let input = agent
            .blackboard()
            .handle::<f64>("b/in/value")
            .await
            .unwrap();
        (agent, input)
    });
    assert_eq!(*input.get(), 1.5);
    group.bench_function("petrel", |b| b.iter(|| *std::hint::black_box(&input).get()));
    let floor = parking_lot::RwLock::new(Arc::new(1.5_f64));
    group.bench_function("floor", |b| {
        b.iter(|| *std::hint::black_box(&floor).read().clone())
    });
    group.finish();
    rt.block_on(agent.stop(Duration::from_secs(1)));
}

criterion_group! { name = benches; config = common::criterion(); targets = bench }
criterion_main!(benches);
