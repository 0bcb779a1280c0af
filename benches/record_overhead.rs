//! `record_overhead`: the CPU time of `configs/navigate.ron` (one virtual second on tokio's
//! paused clock: 10 s of simulated time, as fast as the CPU allows) recording every property
//! and queue to MCAP, against the same run without recording. CPU time of the whole process
//! (the recorder's writer thread included), from `getrusage`. With `RECORD_OVERHEAD_THREADS`
//! set, each run also prints its agent thread's CPU time, the process's and the file's size;
//! `RECORD_COMPRESSION=lz4` records with LZ4 chunks instead of the default (zstd), to compare.

mod common;

use std::path::Path;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use petrel::actors::{Agent, ConfigFile, DEFAULT_STOP_TIMEOUT};
use petrel::record::{ChunkCompression, Format, RecordOptions, Recorder};

/// One run; returns the CPU time it took.
fn run(file: &ConfigFile, record: Option<(&Path, Format)>) -> Duration {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .start_paused(true)
        .build()
        .unwrap();
    let start = common::cpu_time();
    let thread_start = common::thread_cpu_time();
    rt.block_on(async {
        let prepared = Agent::prepare(file, &common::registry(), &[])
            .await
            .unwrap();
        // Attached before the modules start, as `petrel run --record` does.
        let recorder = match record {
            Some((path, format)) => {
                let mut options = RecordOptions::everything(path, format);
                options.backlog = 1 << 22;
                if let Ok(c) = std::env::var("RECORD_COMPRESSION") {
                    options.compression = c.parse::<ChunkCompression>().unwrap();
                }
                let mut r = Recorder::start(options).unwrap();
                r.attach("robot1", prepared.blackboard()).await.unwrap();
                Some(r)
            }
            None => None,
        };
        let agent = prepared.start().await.unwrap();
        tokio::time::sleep(Duration::from_secs(1)).await;
        agent.stop(DEFAULT_STOP_TIMEOUT).await;
        if let Some(r) = recorder {
            let report = r.finish().await.unwrap();
            assert_eq!(report.dropped, 0);
            // What a run records, once per format: before/after comparisons must record the same.
            static REPORTED: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
            let line = format!(
                "record_overhead: {:?} recorded {} messages on {} channels",
                record.map(|(_, f)| f),
                report.written,
                report.channels
            );
            let mut reported = REPORTED.lock().unwrap();
            if !reported.contains(&line) {
                eprintln!("{line}");
                reported.push(line);
            }
        }
    });
    let total = common::cpu_time() - start;
    // Where the CPU goes, per run: the agent's thread (this one, on the current-thread
    // runtime) and the rest of the process (the recorder's writer thread).
    if std::env::var_os("RECORD_OVERHEAD_THREADS").is_some() {
        let agent = common::thread_cpu_time() - thread_start;
        let bytes = record.map(|(p, _)| std::fs::metadata(p).map_or(0, |m| m.len()));
        eprintln!(
            "THREADS {:?} agent_us {} total_us {} file_bytes {}",
            record.map(|(_, f)| f),
            agent.as_micros(),
            total.as_micros(),
            bytes.unwrap_or(0)
        );
    }
    total
}

fn record_overhead(c: &mut Criterion) {
    let file = common::navigate();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nav.mcap");
    let mut g = c.benchmark_group("record_overhead");
    g.bench_function("navigate_recording_everything", |b| {
        b.iter_custom(|iters| {
            (0..iters)
                .map(|_| run(&file, Some((&path, Format::Foxglove))))
                .sum()
        })
    });
    g.bench_function("navigate_recording_everything_ros2", |b| {
        b.iter_custom(|iters| {
            (0..iters)
                .map(|_| run(&file, Some((&path, Format::Ros2))))
                .sum()
        })
    });
    g.bench_function("navigate_without_recording", |b| {
        b.iter_custom(|iters| (0..iters).map(|_| run(&file, None)).sum())
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = common::criterion()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(10));
    targets = record_overhead
}
criterion_main!(benches);
