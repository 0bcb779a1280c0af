//! `property_wake`: one round trip — module A writes, linked module B wakes, reads and answers
//! through a second link, A wakes — against the same ping-pong between two tokio tasks over
//! `tokio::sync::watch` (the floor) and as ractor calls to an actor holding the value.

mod common;

use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};
use ractor::{Actor, ActorProcessingErr, ActorRef, RpcReplyPort};
use tokio::sync::{mpsc, oneshot, watch};

fn bench(c: &mut Criterion) {
    let rt = common::runtime();
    let mut group = c.benchmark_group("property_wake");

    let ping_pong = rt.block_on(common::PingPong::start());
    group.bench_function("petrel", |b| {
        b.iter_custom(|iters| rt.block_on(ping_pong.round_trips(iters)))
    });

    let floor = rt.block_on(async { spawn_watch_pair() });
    group.bench_function("tokio_watch_floor", |b| {
        b.iter_custom(|iters| rt.block_on(run_batch(&floor, iters)))
    });

    let ractor_pair = rt.block_on(spawn_ractor_pair());
    group.bench_function("ractor_call", |b| {
        b.iter_custom(|iters| rt.block_on(run_batch(&ractor_pair, iters)))
    });

    group.finish();
    rt.block_on(ping_pong.agent.stop(Duration::from_secs(1)));
}

/// A driver task that plays `n` round trips on request and reports the elapsed time.
type Driver = mpsc::UnboundedSender<(u64, oneshot::Sender<Duration>)>;

async fn run_batch(driver: &Driver, iters: u64) -> Duration {
    let (tx, rx) = oneshot::channel();
    driver.send((iters, tx)).unwrap();
    rx.await.unwrap()
}

fn spawn_watch_pair() -> Driver {
    let (ping_tx, mut ping_rx) = watch::channel(0.0_f64);
    let (pong_tx, mut pong_rx) = watch::channel(0.0_f64);
    tokio::spawn(async move {
        while ping_rx.changed().await.is_ok() {
            let v = *ping_rx.borrow_and_update();
            let _ = pong_tx.send(v);
        }
    });
    let (driver, mut requests) = mpsc::unbounded_channel::<(u64, oneshot::Sender<Duration>)>();
    tokio::spawn(async move {
        let mut v = 0.0;
        while let Some((n, reply)) = requests.recv().await {
            let start = Instant::now();
            for _ in 0..n {
                v += 1.0;
                ping_tx.send(v).unwrap();
                pong_rx.changed().await.unwrap();
                pong_rx.borrow_and_update();
            }
            let _ = reply.send(start.elapsed());
        }
    });
    driver
}

struct Holder;

impl Actor for Holder {
    type Msg = (f64, RpcReplyPort<f64>);
    type State = f64;
    type Arguments = ();
    async fn pre_start(&self, _: ActorRef<Self::Msg>, _: ()) -> Result<f64, ActorProcessingErr> {
        Ok(0.0)
    }
    async fn handle(
        &self,
        _: ActorRef<Self::Msg>,
        (v, reply): Self::Msg,
        state: &mut f64,
    ) -> Result<(), ActorProcessingErr> {
        *state = v;
        let _ = reply.send(*state);
        Ok(())
    }
}

async fn spawn_ractor_pair() -> Driver {
    let (holder, _) = Actor::spawn(None, Holder, ()).await.unwrap();
    let (driver, mut requests) = mpsc::unbounded_channel::<(u64, oneshot::Sender<Duration>)>();
    tokio::spawn(async move {
        let mut v = 0.0;
        while let Some((n, reply)) = requests.recv().await {
            let start = Instant::now();
            for _ in 0..n {
                v += 1.0;
                let answer = holder.call(|r| (v, r), None).await.unwrap().unwrap();
                assert_eq!(answer, v);
            }
            let _ = reply.send(start.elapsed());
        }
    });
    driver
}

criterion_group! { name = benches; config = common::criterion(); targets = bench }
criterion_main!(benches);
