//! `record_overhead`: the CPU time of `configs/navigate.ron` recording every property and queue
//! to MCAP, against the same run without recording. CPU time of the whole process (the
//! recorder's writer thread included), from `getrusage`. Two ways to run it:
//! - `record_overhead`: one virtual second on tokio's paused clock (10 s of simulated time, as
//!   fast as the CPU allows), everything on the bench's thread: the recorder's own work,
//!   repeatable.
//! - `record_overhead_live`: one second of wall time as `petrel run` runs it (a multi-thread
//!   runtime, the agent on its own thread, the simulator paced at 10x real time): what a robot
//!   pays, hand-overs between the agent's thread and the recorder's included.
//!
//! With `RECORD_OVERHEAD_THREADS` set, each run also prints its agent thread's CPU time (paused
//! runs only), the process's and the file's size; `RECORD_COMPRESSION=lz4` records with LZ4
//! chunks instead of the default (zstd), to compare. `RECORD_OVERHEAD_ROUNDS=N` first runs N
//! rounds of the paused runs side by side and prints their ratios (see `rounds`).

mod common;

use std::path::Path;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use petrel::actors::{Agent, ConfigFile, DEFAULT_STOP_TIMEOUT};
use petrel::record::{ChunkCompression, Format, RecordOptions, Recorder};

/// How a run keeps time.
#[derive(Clone, Copy)]
enum Clock {
    /// A current-thread runtime on a paused clock: the agent runs on the bench's thread.
    Paused,
    /// A multi-thread runtime on the wall clock: the agent runs on its own thread.
    Live,
}

/// One run of one second (virtual or wall); returns the CPU time it took.
fn run(file: &ConfigFile, record: Option<(&Path, Format)>, clock: Clock) -> Duration {
    let rt = match clock {
        Clock::Paused => tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .start_paused(true)
            .build()
            .unwrap(),
        Clock::Live => common::runtime(),
    };
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
        let agent = match clock {
            Clock::Paused => common::thread_cpu_time() - thread_start,
            Clock::Live => Duration::ZERO,
        };
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

/// Runs `n` rounds of paused runs side by side (without recording, Foxglove, ROS 2, without
/// again) and prints each format's CPU time over the mean of its round's two runs without:
/// the median of the rounds and their range. Criterion runs each function for ten seconds
/// after the other, and on a shared VM what the same run costs drifts between them by more
/// than the ratio sought (BENCHMARKS.md, session 32); runs a few milliseconds apart share
/// the drift, so their ratio keeps what the recording costs.
fn rounds(file: &ConfigFile, path: &Path, n: usize) {
    let mut ratios = [Vec::new(), Vec::new()];
    for _ in 0..n {
        let before = run(file, None, Clock::Paused);
        let recorded =
            [Format::Foxglove, Format::Ros2].map(|f| run(file, Some((path, f)), Clock::Paused));
        let base = (before + run(file, None, Clock::Paused)).as_secs_f64() / 2.0;
        for (r, took) in ratios.iter_mut().zip(recorded) {
            r.push(took.as_secs_f64() / base);
        }
    }
    for (name, mut r) in ["foxglove", "ros2"].into_iter().zip(ratios) {
        r.sort_by(f64::total_cmp);
        eprintln!(
            "ROUNDS {name} median {:.3} min {:.3} max {:.3} rounds {n}",
            r[r.len() / 2],
            r[0],
            r[r.len() - 1]
        );
    }
}

fn record_overhead(c: &mut Criterion) {
    let file = common::navigate();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nav.mcap");
    if let Some(n) = std::env::var("RECORD_OVERHEAD_ROUNDS")
        .ok()
        .and_then(|n| n.parse().ok())
    {
        rounds(&file, &path, n);
    }
    // A live run takes a second of wall time for about a third of a second of CPU time, which
    // is what criterion measures: a shorter measurement keeps each function near 15 s.
    for (group, clock, measure) in [
        ("record_overhead", Clock::Paused, Duration::from_secs(10)),
        ("record_overhead_live", Clock::Live, Duration::from_secs(4)),
    ] {
        let mut g = c.benchmark_group(group);
        g.measurement_time(measure);
        let runs = |record: Option<Format>| {
            let record = record.map(|format| (path.as_path(), format));
            let file = &file;
            move |b: &mut criterion::Bencher| {
                b.iter_custom(|iters| (0..iters).map(|_| run(file, record, clock)).sum())
            }
        };
        g.bench_function(
            "navigate_recording_everything",
            runs(Some(Format::Foxglove)),
        );
        g.bench_function(
            "navigate_recording_everything_ros2",
            runs(Some(Format::Ros2)),
        );
        g.bench_function("navigate_without_recording", runs(None));
        g.finish();
    }
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
