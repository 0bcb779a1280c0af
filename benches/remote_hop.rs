//! `remote_hop`: a round trip between two agents over the team transport (two zenoh sessions
//! in one process, TCP loopback): agent A's module writes, B's linked input wakes B's module,
//! which answers through a link back to A. Against `zenoh_floor`: the same round trip as two
//! raw zenoh puts, each answered from the subscriber callback, with the same payload and
//! attachment bytes petrel sends. Both are timed the same way: whole batches, by wall clock,
//! from a task on the same runtime.

mod common;

use std::sync::Arc;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};
use petrel::actors::PropertyHandle;
use tokio::sync::Notify;
use zenoh::Wait;

fn bench(c: &mut Criterion) {
    let rt = common::runtime();
    let mut group = c.benchmark_group("remote_hop");

    let pair = rt.block_on(RemotePair::start());
    rt.block_on(pair.round_trips(10)); // links live
    group.bench_function("petrel", |b| {
        b.iter_custom(|iters| rt.block_on(pair.round_trips(iters)))
    });

    let floor = rt.block_on(Floor::start());
    group.bench_function("zenoh_floor", |b| {
        b.iter_custom(|iters| rt.block_on(floor.round_trips(iters)))
    });
    group.finish();
}

/// `bench.ping` on agent `a` and `bench.echo` on agent `b`, linked to each other remotely.
struct RemotePair {
    go: PropertyHandle<i64>,
    done: PropertyHandle<i64>,
    _agents: Vec<(petrel::actors::Agent, petrel::team::Team)>,
}

impl RemotePair {
    async fn start() -> Self {
        use common::team::{config, free_port, start};
        let (pa, pb) = (free_port(), free_port());
        let team = format!("hop{}", std::process::id());
        let a = start(&config(
            "a",
            &team,
            pa,
            None,
            r#"
            (name: "a", type: "bench.ping", links: {"in/pong": "petrel://b/b/out/value"}),"#,
        ))
        .await;
        let b = start(&config(
            "b",
            &team,
            pb,
            Some(pa),
            r#"
            (name: "b", type: "bench.echo", links: {"in/value": "petrel://a/a/out/ping"}),"#,
        ))
        .await;
        let go = a.0.blackboard().handle::<i64>("a/in/go").await.unwrap();
        let done = a.0.blackboard().handle::<i64>("a/out/done").await.unwrap();
        RemotePair {
            go,
            done,
            _agents: vec![a, b],
        }
    }

    async fn round_trips(&self, n: u64) -> Duration {
        let target = *self.done.get() + 1;
        let start = Instant::now();
        self.go.set(n as i64);
        while *self.done.get() < target {
            self.done.changed().await;
        }
        start.elapsed()
    }
}

/// Two raw sessions: `ping` is answered with `pong` from the subscriber callback; the answer
/// wakes the driving task.
struct Floor {
    x: zenoh::Session,
    answered: Arc<Notify>,
    _y: zenoh::Session,
    _subs: Vec<zenoh::pubsub::Subscriber<()>>,
}

const PAYLOAD: &str = "1.0";

fn attachment(seq: u64) -> String {
    format!(
        "v=1;seq={seq};stamp_ns=1732300000000000000;type=f64;zid=0123456789abcdef0123456789abcdef"
    )
}

impl Floor {
    async fn start() -> Self {
        let port = common::team::free_port();
        let x = common::team::raw_session(Some(port), None).await;
        let y = common::team::raw_session(None, Some(port)).await;
        let pong = y.declare_publisher("floor/pong").await.unwrap();
        let echo = y
            .declare_subscriber("floor/ping")
            .callback(move |sample| {
                let _ = sample.payload().to_bytes();
                pong.put(PAYLOAD).attachment(attachment(1)).wait().unwrap();
            })
            .await
            .unwrap();
        let answered = Arc::new(Notify::new());
        let a = answered.clone();
        let back = x
            .declare_subscriber("floor/pong")
            .callback(move |sample| {
                let _ = sample.payload().to_bytes();
                a.notify_one();
            })
            .await
            .unwrap();
        let floor = Floor {
            x,
            answered,
            _y: y,
            _subs: vec![echo, back],
        };
        // Pings sent before the sessions know each other's subscribers are lost: ping until
        // one is answered.
        let ping = floor.x.declare_publisher("floor/ping").await.unwrap();
        loop {
            ping.put(PAYLOAD).attachment(attachment(0)).await.unwrap();
            let answered = floor.answered.notified();
            if tokio::time::timeout(Duration::from_millis(20), answered)
                .await
                .is_ok()
            {
                break;
            }
        }
        floor
    }

    async fn round_trips(&self, n: u64) -> Duration {
        let ping = self.x.declare_publisher("floor/ping").await.unwrap();
        let start = Instant::now();
        for i in 0..n {
            ping.put(PAYLOAD).attachment(attachment(i)).await.unwrap();
            self.answered.notified().await;
        }
        start.elapsed()
    }
}

criterion_group! {
    name = benches;
    config = common::criterion();
    targets = bench
}
criterion_main!(benches);
