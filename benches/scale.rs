//! `scale`: start-up time and memory of 1000 trivial modules, and the CPU used by 200 idle
//! modules waiting on events. Not a criterion bench: it prints its measurements.
//! Run with `cargo bench --bench scale`.

mod common;

use std::time::{Duration, Instant};

fn config(n: usize) -> String {
    let modules: String = (0..n)
        .map(|i| format!(r#"(name: "idle{i}", type: "bench.idle"),"#))
        .collect();
    format!(r#"Agent(name: "bench", modules: [{modules}])"#)
}

/// Resident set size of this process, KiB.
fn rss_kib() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

/// CPU time (user + system) this process used, in seconds.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit(") ")
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let ticks: f64 = fields
        .get(11)
        .and_then(|u| u.parse::<f64>().ok())
        .unwrap_or(0.0)
        + fields
            .get(12)
            .and_then(|s| s.parse::<f64>().ok())
            .unwrap_or(0.0);
    ticks / 100.0 // USER_HZ is 100 on Linux
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return; // `cargo bench -- --list` style probes
    }
    let rt = common::runtime();
    let text = config(1000);
    let before = rss_kib();
    let start = Instant::now();
    let agent = rt.block_on(common::start(&text));
    let startup = start.elapsed();
    let rss = rss_kib().saturating_sub(before);
    println!(
        "scale/start_1000: {:.1} ms to start 1000 modules (goal <= 1000 ms)",
        startup.as_secs_f64() * 1e3
    );
    println!(
        "scale/rss_1000: {:.1} MiB resident for 1000 modules (goal <= 64 MiB)",
        rss as f64 / 1024.0
    );
    rt.block_on(agent.stop(Duration::from_secs(5)));

    let agent = rt.block_on(common::start(&config(200)));
    let (cpu0, wall0) = (cpu_seconds(), Instant::now());
    std::thread::sleep(Duration::from_secs(3));
    let share = (cpu_seconds() - cpu0) / wall0.elapsed().as_secs_f64() * 100.0;
    println!("scale/idle_200: {share:.2} % of one core for 200 idle modules (goal <= 1 %)");
    rt.block_on(agent.stop(Duration::from_secs(5)));
}
