//! `inspect_overhead`: the CPU time of `configs/navigate.ron` (one virtual second on tokio's
//! paused clock: 10 s of simulated time, as fast as the CPU allows) with the web console open
//! and one WebSocket client watching every property, against the same run without a console.
//! CPU time of the whole process (server and client included), from `getrusage`.
//!
//! The console pushes each property at most 10 times a (virtual) second, as it would in a real
//! run at wall-clock speed: navigate's 1 s here is 1 s of wall time at its 10x time scale.

mod common;

use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use futures_util::{SinkExt, StreamExt};
use petrel::actors::{Agent, ConfigFile, DEFAULT_STOP_TIMEOUT};
use petrel::console::{AgentSource, Console, ConsoleOptions, LogTail};
use tokio_tungstenite::tungstenite::Message;

/// A client that watches every property and reads what is pushed; returns the bytes read.
async fn watch_everything(addr: std::net::SocketAddr) -> tokio::task::JoinHandle<usize> {
    let stream = tokio::net::TcpStream::connect(addr).await.unwrap();
    let url = format!("ws://{addr}/api/ws?agent=robot1");
    let (mut socket, _) = tokio_tungstenite::client_async(url, stream).await.unwrap();
    socket
        .send(Message::Text(r#"{"watch": "all"}"#.into()))
        .await
        .unwrap();
    tokio::spawn(async move {
        let mut read = 0;
        while let Some(Ok(message)) = socket.next().await {
            read += message.len();
        }
        read
    })
}

/// One run; returns the CPU time it took.
fn run(file: &ConfigFile, console: bool) -> Duration {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .start_paused(true)
        .build()
        .unwrap();
    let start = common::cpu_time();
    rt.block_on(async {
        let agent = Agent::start(file, &common::registry()).await.unwrap();
        let watching = match console {
            true => {
                let console = Console::start(
                    ConsoleOptions {
                        addr: "127.0.0.1:0".parse().unwrap(),
                        token: None,
                    },
                    vec![AgentSource::new("robot1", agent.blackboard().clone())],
                    LogTail::default(),
                )
                .await
                .unwrap();
                let client = watch_everything(console.local_addr()).await;
                Some((console, client))
            }
            false => None,
        };
        tokio::time::sleep(Duration::from_secs(1)).await;
        agent.stop(DEFAULT_STOP_TIMEOUT).await;
        if let Some((console, client)) = watching {
            console.stop().await;
            let read = client.await.unwrap();
            assert!(read > 10_000, "the client saw the values ({read} bytes)");
        }
    });
    common::cpu_time() - start
}

fn inspect_overhead(c: &mut Criterion) {
    let file = common::navigate();
    let mut g = c.benchmark_group("inspect_overhead");
    g.bench_function("navigate_console_watching_everything", |b| {
        b.iter_custom(|iters| (0..iters).map(|_| run(&file, true)).sum())
    });
    g.bench_function("navigate_without_console", |b| {
        b.iter_custom(|iters| (0..iters).map(|_| run(&file, false)).sum())
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = common::criterion()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(10));
    targets = inspect_overhead
}
criterion_main!(benches);
