//! `remote_scan`: 181-ray laser scans from one agent's queue to another agent's queue input
//! at 1 kHz over the team transport (reliable), against `zenoh_floor`: the same scans, paced
//! the same way, encoded to the same JSON, put by a raw zenoh publisher and decoded in the
//! subscriber callback. Both report **process CPU time per scan** (all threads), so the ratio
//! is what petrel's runtime adds to moving a scan; each run also checks that nothing was lost.

mod common;

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use common::team::{free_port, process_cpu, raw_session, scan, start};
use criterion::{criterion_group, criterion_main, Criterion};
use petrel::actors::team::LinkStatus;
use petrel::actors::{LaserScan, PropertyHandle};
use tokio::sync::Notify;
use zenoh::qos::CongestionControl;

fn bench(c: &mut Criterion) {
    let rt = common::runtime();
    let mut group = c.benchmark_group("remote_scan");

    let pair = rt.block_on(ScanPair::start());
    group.bench_function("petrel", |b| b.iter_custom(|n| rt.block_on(pair.scans(n))));
    let lost = pair.lost.value();
    println!(
        "remote_scan/petrel: {} scans received, {lost} lost",
        pair.received.value()
    );
    assert_eq!(lost, 0, "reliable remote scans must not be lost");

    let floor = rt.block_on(Floor::start());
    group.bench_function("zenoh_floor", |b| {
        b.iter_custom(|n| rt.block_on(floor.scans(n)))
    });
    group.finish();
}

struct ScanPair {
    remaining: PropertyHandle<i64>,
    received: PropertyHandle<i64>,
    lost: PropertyHandle<i64>,
    _agents: Vec<(petrel::actors::Agent, petrel::team::Team)>,
}

impl ScanPair {
    async fn start() -> Self {
        let (pa, pb) = (free_port(), free_port());
        let team = format!("scan{}", std::process::id());
        let config = common::team::config;
        let a = start(&config(
            "a",
            &team,
            pa,
            None,
            r#"(name: "lidar", type: "bench.scans"),"#,
        ))
        .await;
        let b = start(&config("b", &team, pb, Some(pa), r#"
            (name: "sink", type: "bench.scan_sink", links: {"in/scans": "petrel://a/lidar/out/scans"}),"#)).await;
        let bb = |x: &(petrel::actors::Agent, petrel::team::Team)| x.0.blackboard().clone();
        let status = bb(&b)
            .handle::<LinkStatus>("sink/stats/links/in/scans")
            .await
            .unwrap();
        while status.get().state != "live" {
            status.changed().await;
        }
        ScanPair {
            remaining: bb(&a).handle("lidar/in/remaining").await.unwrap(),
            received: bb(&b).handle("sink/out/received").await.unwrap(),
            lost: bb(&b).handle("sink/out/lost").await.unwrap(),
            _agents: vec![a, b],
        }
    }

    /// Sends `n` scans at 1 kHz; returns the CPU time it took until the last one was read.
    /// Like the floor's driver, this one does not wake for every scan: it waits out the
    /// sending time, then for the last scans.
    async fn scans(&self, n: u64) -> Duration {
        let target = self.received.value() + n as i64;
        let cpu = process_cpu();
        self.remaining.set(n as i64);
        tokio::time::sleep(Duration::from_millis(n)).await;
        while self.received.value() < target {
            self.received.changed().await;
        }
        process_cpu() - cpu
    }
}

struct Floor {
    session: zenoh::Session,
    received: Arc<AtomicU64>,
    arrived: Arc<Notify>,
    _rx: zenoh::Session,
    _sub: zenoh::pubsub::Subscriber<()>,
}

impl Floor {
    async fn start() -> Self {
        let port = free_port();
        let session = raw_session(Some(port), None).await;
        let rx = raw_session(None, Some(port)).await;
        let received = Arc::new(AtomicU64::new(0));
        let arrived = Arc::new(Notify::new());
        let (r, a) = (received.clone(), arrived.clone());
        let sub = rx
            .declare_subscriber("floor/scans")
            .callback(move |sample| {
                let scan: LaserScan = serde_json::from_slice(&sample.payload().to_bytes()).unwrap();
                std::hint::black_box(scan);
                r.fetch_add(1, Ordering::Relaxed);
                a.notify_one();
            })
            .await
            .unwrap();
        let floor = Floor {
            session,
            received,
            arrived,
            _rx: rx,
            _sub: sub,
        };
        // Scans put before the sessions know each other are lost: send until one arrives.
        while floor.received.load(Ordering::Relaxed) == 0 {
            floor.put(0).await;
            let _ = tokio::time::timeout(Duration::from_millis(20), floor.arrived.notified()).await;
        }
        floor
    }

    async fn put(&self, i: u64) {
        let payload = serde_json::to_vec(&scan(i)).unwrap();
        let attachment = format!("v=1;seq={i};stamp_ns=1;type=LaserScan;zid=0123456789abcdef");
        self.session
            .put("floor/scans", payload)
            .congestion_control(CongestionControl::Block)
            .attachment(attachment)
            .await
            .unwrap();
    }

    async fn scans(&self, n: u64) -> Duration {
        let target = self.received.load(Ordering::Relaxed) + n;
        let cpu = process_cpu();
        let mut ticks = tokio::time::interval(Duration::from_millis(1));
        for i in 0..n {
            ticks.tick().await;
            self.put(i).await;
        }
        while self.received.load(Ordering::Relaxed) < target {
            self.arrived.notified().await;
        }
        process_cpu() - cpu
    }
}

criterion_group! {
    name = benches;
    config = common::criterion()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(100))
        .measurement_time(Duration::from_millis(500));
    targets = bench
}
criterion_main!(benches);
