//! `periodic_jitter`: how far a 1 kHz module's periods stray from 1 ms, alone and while 20
//! other modules of its agent run busy steps (each wakes itself at once and spins on the CPU
//! for `params/spin_us` per step, so together they keep every worker busy).
//!
//! Not a criterion measurement: criterion times repeated calls, and jitter is a distribution
//! over one long run. This target prints percentiles (p50, p99, max of |period − 1 ms|, µs),
//! the alone row being the in-run baseline. Run with `cargo bench --bench periodic_jitter`;
//! `PETREL_JITTER_SECS` sets each run's length (default 3 s).
//!
//! On an agent thread (the default scheduler) the busy row is run again with the busy modules'
//! threads below the agent's (`long_steps_nice`, any process may), and both rows with
//! `realtime_priority: 50` (the agent's and the fine timer's threads under `SCHED_FIFO`), last,
//! since the timer thread keeps its priority for the rest of the process; where the OS refuses
//! it, those rows say so.

mod common;

use std::sync::Mutex;
use std::time::{Duration, Instant};

use petrel::actors::{Agent, ConfigFile, Context, Input, Module, Output, Ports, Schedule};

/// Every step time of the `bench.periodic` module, in order.
static STEPS: Mutex<Vec<Instant>> = Mutex::new(Vec::new());

const PERIOD: Duration = Duration::from_millis(1);

/// The `long_steps_nice` of the `with_20_busy_nice` row: the busy modules' threads that many
/// nice levels below the agent's (no privilege needed, unlike the real-time rows).
const LONG_STEPS_NICE: u8 = 10;

/// `bench.periodic`: steps every millisecond and notes when.
struct Periodic;

impl Module for Periodic {
    const TYPE: &'static str = "bench.periodic";
    const DESCRIPTION: &'static str = "Steps at 1 kHz and notes when.";
    fn declare(_ports: &mut Ports) -> Self {
        Periodic
    }
    fn schedule(&self) -> Schedule {
        Schedule::every(PERIOD)
    }
    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if ctx.cause().period() {
            STEPS.lock().unwrap().push(Instant::now());
        }
        Ok(())
    }
}

/// `bench.busy`: its input is linked to its own output, so every step wakes it again; each
/// step spins for `params/spin_us` before writing.
struct Busy {
    input: Input<f64>,
    spin_us: Input<i64>,
    out: Output<f64>,
}

impl Module for Busy {
    const TYPE: &'static str = "bench.busy";
    const DESCRIPTION: &'static str = "Spins, then wakes itself.";
    fn declare(ports: &mut Ports) -> Self {
        Busy {
            input: ports.input("in/value", 0.0, "its own output"),
            spin_us: ports.param("params/spin_us", 200, "CPU time per step"),
            out: ports.output("out/value", 0.0, "steps done"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.input)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let until = Instant::now() + Duration::from_micros(self.spin_us.value() as u64);
        while Instant::now() < until {
            std::hint::spin_loop();
        }
        self.out.set(self.input.value() + 1.0);
        Ok(())
    }
}

fn config(busy: usize, realtime: Option<u8>, nice: Option<u8>) -> String {
    let mut modules = String::from(r#"(name: "p", type: "bench.periodic"),"#);
    // On an agent thread (the default), busy modules are what `long_steps` is for: off the
    // agent's thread.
    let long = match common::scheduler().as_str() {
        "agent_thread" | "" => "long_steps: true, ",
        _ => "",
    };
    for i in 0..busy {
        modules.push_str(&format!(
            r#"(name: "b{i}", type: "bench.busy", {long}links: {{"in/value": "b{i}/out/value"}}),"#
        ));
    }
    let realtime = realtime.map_or(String::new(), |p| format!("realtime_priority: {p}, "));
    let nice = nice.map_or(String::new(), |n| format!("long_steps_nice: {n}, "));
    format!(r#"Agent(name: "bench", {realtime}{nice}modules: [{modules}])"#)
}

/// What one run measured.
struct Run {
    /// |period − 1 ms| of every period, sorted, in µs.
    jitter: Vec<f64>,
    /// Steps the busy modules made, the stop included.
    busy_steps: u64,
    /// How long stopping the agent took.
    stop: Duration,
}

/// Runs the periodic module beside `busy` busy modules for `length`, then stops the agent
/// (1 s stop timeout: a module not stopped by then is killed and named in the summary). An
/// error says the agent was refused (a `realtime_priority` the OS does not allow).
fn run(
    rt: &tokio::runtime::Runtime,
    busy: usize,
    (realtime, nice): (Option<u8>, Option<u8>),
    length: Duration,
) -> Result<Run, String> {
    let mut registry = common::registry();
    registry.register::<Periodic>().register::<Busy>();
    let text = common::scheduled(&config(busy, realtime, nice));
    let file = ConfigFile::parse("jitter.ron", &text).unwrap();
    let agent = rt
        .block_on(Agent::start(&file, &registry))
        .map_err(|e| e.to_string())?;
    STEPS.lock().unwrap().clear();
    std::thread::sleep(length);
    let steps = std::mem::take(&mut *STEPS.lock().unwrap());
    let stopping = Instant::now();
    let summary = rt.block_on(agent.stop(Duration::from_secs(1)));
    let stop = stopping.elapsed();
    let busy_steps: u64 = summary
        .modules
        .iter()
        .filter(|m| m.module_type == "bench.busy")
        .map(|m| m.steps)
        .sum();
    // The first periods after start-up are left out (the agent was still settling).
    let mut jitter: Vec<f64> = steps
        .windows(2)
        .skip(10)
        .map(|w| ((w[1] - w[0]).as_secs_f64() - PERIOD.as_secs_f64()).abs() * 1e6)
        .collect();
    jitter.sort_by(f64::total_cmp);
    let killed = summary
        .modules
        .iter()
        .filter(|m| m.status == "killed")
        .count();
    if killed > 0 {
        println!("periodic_jitter: {killed} module(s) killed at the stop timeout");
    }
    Ok(Run {
        jitter,
        busy_steps,
        stop,
    })
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    match sorted.len() {
        0 => f64::NAN,
        n => sorted[((n - 1) as f64 * p).round() as usize],
    }
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return; // `cargo bench -- --list` style probes
    }
    let secs = std::env::var("PETREL_JITTER_SECS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3.0);
    let length = Duration::from_secs_f64(secs);
    let rt = common::runtime();
    let mut rows = vec![
        ("alone", 0, (None, None)),
        ("with_20_busy", 20, (None, None)),
    ];
    if common::scheduler() != "shared" {
        rows.push(("with_20_busy_nice", 20, (None, Some(LONG_STEPS_NICE))));
        rows.push(("alone_realtime", 0, (Some(50), None)));
        rows.push(("with_20_busy_realtime", 20, (Some(50), None)));
    }
    for (name, busy, priorities) in rows {
        let Run {
            jitter,
            busy_steps,
            stop,
        } = match run(&rt, busy, priorities, length) {
            Ok(run) => run,
            Err(e) => {
                println!("periodic_jitter/{name}: not run: {e}");
                continue;
            }
        };
        println!(
            "periodic_jitter/{name}: {} periods in {secs} s; |period - 1 ms| p50 {:.0} µs, p90 {:.0} µs, p99 {:.0} µs, max {:.0} µs (goal p99 <= 100 µs); stop took {:.0} ms ({busy_steps} busy steps, the stop included)",
            jitter.len(),
            percentile(&jitter, 0.5),
            percentile(&jitter, 0.9),
            percentile(&jitter, 0.99),
            jitter.last().copied().unwrap_or(f64::NAN),
            stop.as_secs_f64() * 1e3,
        );
    }
}
