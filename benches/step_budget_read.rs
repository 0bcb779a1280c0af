//! `step_budget_read`: what the step budget pays per checked step to leave the OS's run-queue
//! wait out of a step's time (`RunQueueMark::now` at the start, `elapsed` at the end: two
//! reads of `/proc/thread-self/schedstat`), against what every timed step already pays (two
//! clock reads). Only steps of a module whose window was over the budget in wall time are
//! checked (`actors/src/supervision/long_steps.rs`).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use petrel::actors::run_queue::RunQueueMark;

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("step_budget_read");
    if RunQueueMark::now().is_some() {
        group.bench_function("run_queue_wait", |b| {
            b.iter(|| black_box(RunQueueMark::now()).and_then(|m| m.elapsed()))
        });
    }
    group.bench_function("two_clock_reads", |b| {
        b.iter(|| black_box(std::time::Instant::now()).elapsed())
    });
    group.finish();
}

criterion_group! { name = benches; config = common_criterion(); targets = bench }
criterion_main!(benches);

fn common_criterion() -> Criterion {
    Criterion::default()
        .sample_size(30)
        .warm_up_time(std::time::Duration::from_secs(1))
        .measurement_time(std::time::Duration::from_secs(3))
}
