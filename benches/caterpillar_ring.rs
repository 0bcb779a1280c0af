//! `caterpillar_ring`: the hand-overs between the modules of one agent, alone. A trigger module
//! (`bench.ping`) writes, 17 modules (`bench.echo`) pass the value on, and the last one's write
//! wakes the trigger again: a ring of 18 inside one agent. The bench thread only starts a batch
//! of laps and waits for its end (one outside wake-up per batch, on every side alike), so what is
//! timed is 18 hand-overs per lap.
//!
//! Baselines, each timed the same way (whole batches from the bench thread):
//! - `tokio_watch_ring_mt`: the same ring of 18 tokio tasks linked by `watch`, on the
//!   multi-thread runtime with the default workers (2 here, like `petrel`'s runtime);
//! - `tokio_watch_ring_ct`: the same ring on a current-thread runtime;
//! - `plain_calls`: the 18 steps called in a loop, each reading its input cell and writing its
//!   output cell (the physical floor: no wake-up at all).

mod common;

use std::sync::Arc;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};
use tokio::sync::{mpsc, oneshot};

/// Modules passing the value on between the trigger's write and its wake-up.
const PASSERS: usize = 17;

/// The trigger `a` (bench.ping) and 17 echo modules, the last linked back to `a/in/pong`.
fn config() -> String {
    let mut modules = format!(
        r#"(name: "a", type: "bench.ping", links: {{"in/pong": "m{}/out/value"}}),"#,
        PASSERS - 1
    );
    modules.push_str(r#"(name: "m0", type: "bench.echo", links: {"in/value": "a/out/ping"}),"#);
    for i in 1..PASSERS {
        modules.push_str(&format!(
            r#"(name: "m{i}", type: "bench.echo", links: {{"in/value": "m{}/out/value"}}),"#,
            i - 1
        ));
    }
    format!(r#"Agent(name: "bench", modules: [{modules}])"#)
}

/// Asks a ring's trigger task for `n` laps; answers when they are done.
type Driver = mpsc::UnboundedSender<(u64, oneshot::Sender<()>)>;

/// 18 tasks in a ring of `watch` channels: the trigger task and 17 passers. Spawned on the
/// runtime whose context this is called in.
fn spawn_watch_ring() -> Driver {
    let (ping_tx, mut pong_rx) = common::watch_chain(PASSERS);
    let (driver, mut requests) = mpsc::unbounded_channel::<(u64, oneshot::Sender<()>)>();
    tokio::spawn(async move {
        let mut v = 0.0;
        while let Some((n, reply)) = requests.recv().await {
            for _ in 0..n {
                v += 1.0;
                ping_tx.send(v).unwrap();
                while *pong_rx.borrow_and_update() != v {
                    pong_rx.changed().await.unwrap();
                }
            }
            let _ = reply.send(());
        }
    });
    driver
}

/// Times `iters` laps from the bench thread: request, then wait for the answer.
fn timed_laps(rt: &tokio::runtime::Runtime, driver: &Driver, iters: u64) -> Duration {
    rt.block_on(async {
        let start = Instant::now();
        let (tx, rx) = oneshot::channel();
        driver.send((iters, tx)).unwrap();
        rx.await.unwrap();
        start.elapsed()
    })
}

/// One of the 18 steps of `plain_calls`: reads its input cell, writes its output cell.
fn plain_step(input: &parking_lot::RwLock<f64>, output: &parking_lot::RwLock<f64>) {
    let v = *input.read();
    *output.write() = std::hint::black_box(v);
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("caterpillar_ring");

    let rt = common::runtime();
    let ring = rt.block_on(common::PingPong::start_with(&config()));
    group.bench_function("petrel", |b| {
        b.iter_custom(|iters| rt.block_on(ring.round_trips(iters)))
    });
    rt.block_on(ring.agent.stop(Duration::from_secs(1)));

    let mt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .unwrap();
    let driver = mt.block_on(async { spawn_watch_ring() });
    group.bench_function("tokio_watch_ring_mt", |b| {
        b.iter_custom(|iters| timed_laps(&mt, &driver, iters))
    });

    let ct = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    let driver = ct.block_on(async { spawn_watch_ring() });
    group.bench_function("tokio_watch_ring_ct", |b| {
        b.iter_custom(|iters| timed_laps(&ct, &driver, iters))
    });

    let cells: Vec<Arc<parking_lot::RwLock<f64>>> = (0..=PASSERS)
        .map(|_| Arc::new(parking_lot::RwLock::new(0.0)))
        .collect();
    group.bench_function("plain_calls", |b| {
        b.iter_custom(|iters| {
            let start = Instant::now();
            let mut v = 0.0;
            for _ in 0..iters {
                v += 1.0;
                // The trigger's write, the 17 passers, the trigger reading the answer back.
                *cells[0].write() = v;
                for i in 0..PASSERS {
                    plain_step(&cells[i], &cells[i + 1]);
                }
                assert_eq!(*cells[PASSERS].read(), v);
            }
            start.elapsed()
        })
    });
    group.finish();
}

criterion_group! { name = benches; config = common::criterion(); targets = bench }
criterion_main!(benches);
