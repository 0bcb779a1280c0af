//! Bench-only module types and helpers shared by the benchmark targets.
#![allow(dead_code)] // each bench target uses a different subset

use std::time::Duration;

pub mod mission;
pub mod team;

use petrel::actors::{
    Agent, ConfigFile, Context, Image, Input, Module, ModuleRegistry, Output, Ports, QueueReader,
    QueueWriter, Schedule,
};

/// CPU time this process has used (user + system), for benches that measure CPU, not wall time.
pub fn cpu_time() -> Duration {
    let mut usage = std::mem::MaybeUninit::<libc::rusage>::zeroed();
    // SAFETY: getrusage fills the struct it is given.
    let usage = unsafe {
        libc::getrusage(libc::RUSAGE_SELF, usage.as_mut_ptr());
        usage.assume_init()
    };
    let t = |tv: libc::timeval| Duration::new(tv.tv_sec as u64, tv.tv_usec as u32 * 1000);
    t(usage.ru_utime) + t(usage.ru_stime)
}

/// CPU time the calling thread has used (user + system).
pub fn thread_cpu_time() -> Duration {
    let mut usage = std::mem::MaybeUninit::<libc::rusage>::zeroed();
    // SAFETY: getrusage fills the struct it is given.
    let usage = unsafe {
        libc::getrusage(libc::RUSAGE_THREAD, usage.as_mut_ptr());
        usage.assume_init()
    };
    let t = |tv: libc::timeval| Duration::new(tv.tv_sec as u64, tv.tv_usec as u32 * 1000);
    t(usage.ru_utime) + t(usage.ru_stime)
}

/// `configs/navigate.ron` with its recorder drawing no picture.
pub fn navigate() -> ConfigFile {
    let mut file = ConfigFile::load(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/navigate.ron"),
    )
    .unwrap();
    let overlay = ConfigFile::parse(
        "overlay.ron",
        r#"Agent(name: "robot1", modules: [(name: "recorder", type: "sim.recorder", values: {"params/png": ""})])"#,
    )
    .unwrap();
    file.overlay(overlay);
    file
}

/// Short criterion runs: ratios against in-run baselines are what we record.
pub fn criterion() -> criterion::Criterion {
    criterion::Criterion::default()
        .sample_size(30)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
}

/// A two-worker tokio runtime, like `petrel run` on a 2-core machine.
pub fn runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap()
}

/// The built-in types plus the bench modules.
pub fn registry() -> ModuleRegistry {
    let mut r = petrel::Petrel::new().registry().clone();
    r.register::<Echo>()
        .register::<Ping>()
        .register::<QueueSource>()
        .register::<QueueSink>()
        .register::<Idle>()
        .register::<Crashy>()
        .register::<mission::Work>()
        .register::<mission::Trigger>()
        .register::<team::ScanSource>()
        .register::<team::ScanSink>();
    r
}

/// Starts an agent from config text.
pub async fn start(text: &str) -> Agent {
    let text = scheduled(text);
    let file = ConfigFile::parse("bench.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    Agent::start(&file, &registry())
        .await
        .unwrap_or_else(|e| panic!("{e}"))
}

/// `PETREL_BENCH_SCHEDULER=agent_thread` runs the bench agents with `scheduler: agent_thread`,
/// so one build measures both schedulers (unset: the config's own, `agent_thread` by default).
pub fn scheduler() -> String {
    std::env::var("PETREL_BENCH_SCHEDULER").unwrap_or_default()
}

/// Agent config `text` (which starts `Agent(`) with the scheduler [`scheduler`] names, if any,
/// and the step budget `PETREL_BENCH_STEP_BUDGET` gives, if set (e.g. `(mean_us: 1000, steps:
/// 20, held_ms: 0)` to measure the agent without its held-thread watcher).
pub fn scheduled(text: &str) -> String {
    let text = match std::env::var("PETREL_BENCH_STEP_BUDGET") {
        Ok(budget) if !budget.is_empty() => {
            text.replacen("Agent(", &format!("Agent(step_budget: {budget}, "), 1)
        }
        _ => text.to_string(),
    };
    match scheduler().as_str() {
        "" => text,
        name => text.replacen("Agent(", &format!("Agent(scheduler: {name}, "), 1),
    }
}

/// Two modules playing ping-pong through two links: `a` (bench.ping) and `b` (bench.echo).
pub const PING_PONG: &str = r#"Agent(name: "bench", modules: [
    (name: "a", type: "bench.ping", links: {"in/pong": "b/out/value"}),
    (name: "b", type: "bench.echo", links: {"in/value": "a/out/ping"}),
])"#;

/// A running [`PING_PONG`] agent with the handles that drive it.
pub struct PingPong {
    pub agent: Agent,
    go: petrel::actors::PropertyHandle<i64>,
    done: petrel::actors::PropertyHandle<i64>,
}

impl PingPong {
    pub async fn start() -> Self {
        Self::start_with(PING_PONG).await
    }

    /// Starts an agent with a `bench.ping` module named `a`.
    pub async fn start_with(config: &str) -> Self {
        let agent = start(config).await;
        let go = agent.blackboard().handle::<i64>("a/in/go").await.unwrap();
        let done = agent
            .blackboard()
            .handle::<i64>("a/out/done")
            .await
            .unwrap();
        PingPong { agent, go, done }
    }

    /// Plays `n` round trips; returns how long they took.
    pub async fn round_trips(&self, n: u64) -> Duration {
        let target = *self.done.get() + 1;
        let start = std::time::Instant::now();
        self.go.set(n as i64);
        while *self.done.get() < target {
            self.done.changed().await;
        }
        start.elapsed()
    }
}

/// `bench.echo`: copies `in/value` to `out/value` on change.
pub struct Echo {
    input: Input<f64>,
    out: Output<f64>,
}

impl Module for Echo {
    const TYPE: &'static str = "bench.echo";
    const DESCRIPTION: &'static str = "Copies in/value to out/value on change.";
    fn declare(ports: &mut Ports) -> Self {
        Echo {
            input: ports.input("in/value", 0.0, "value"),
            out: ports.output("out/value", 0.0, "copy"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.input)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        self.out.set(self.input.value());
        Ok(())
    }
}

/// `bench.ping`: when `in/go` is set to N, plays N round trips: writes `out/ping`, waits for
/// `in/pong` to answer, and so on; then increments `out/done`. With `params/alternate`, the
/// ping alternates between 0 and 1 instead of counting up.
pub struct Ping {
    alternate: Input<bool>,
    go: Input<i64>,
    pong: Input<f64>,
    ping: Output<f64>,
    done: Output<i64>,
    go_seen: u64,
    remaining: i64,
}

impl Module for Ping {
    const TYPE: &'static str = "bench.ping";
    const DESCRIPTION: &'static str = "Plays in/go round trips through out/ping and in/pong.";
    fn declare(ports: &mut Ports) -> Self {
        Ping {
            alternate: ports.param(
                "params/alternate",
                false,
                "ping 0, 1, 0, ... instead of 1, 2, 3, ...",
            ),
            go: ports.input("in/go", 0, "rounds to play"),
            pong: ports.input("in/pong", 0.0, "the answer"),
            ping: ports.output("out/ping", 0.0, "the question"),
            done: ports.output("out/done", 0, "batches finished"),
            go_seen: 0,
            remaining: 0,
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.go).on_change(&self.pong)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let go = self.go.read();
        if go.version != self.go_seen {
            self.go_seen = go.version;
            self.remaining = *go;
        } else if self.remaining > 0 && self.pong.value() == self.ping.value() {
            self.remaining -= 1;
            if self.remaining == 0 {
                self.done.set(self.done.value() + 1);
                return Ok(());
            }
        } else {
            return Ok(());
        }
        let next = if self.alternate.value() {
            1.0 - self.ping.value()
        } else {
            self.ping.value() + 1.0
        };
        self.ping.set(next);
        Ok(())
    }
}

/// `bench.qsource`: when `in/go` is set to N, pushes N fresh `Image` items of `params/bytes`
/// bytes (a new item each time; its pixels taken in turn from a pool of 16 buffers made at
/// init, so the timed loop does not fill megabytes, yet a queue that copied pixels would).
pub struct QueueSource {
    go: Input<i64>,
    bytes: Input<i64>,
    items: QueueWriter<Image>,
    pool: Vec<std::sync::Arc<[u8]>>,
    next: usize,
}

impl Module for QueueSource {
    const TYPE: &'static str = "bench.qsource";
    const DESCRIPTION: &'static str = "Pushes in/go images into out/items.";
    fn declare(ports: &mut Ports) -> Self {
        QueueSource {
            go: ports.input("in/go", 0, "items to push"),
            bytes: ports.param("params/bytes", 1024, "payload size"),
            items: ports.queue_out("out/items", 1 << 16, "images"),
            pool: Vec::new(),
            next: 0,
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.go)
    }
    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let n = self.bytes.value() as usize;
        self.pool = (0..16u8).map(|i| vec![7 + i; n].into()).collect();
        Ok(())
    }
    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if ctx.cause().first() {
            return Ok(());
        }
        for _ in 0..self.go.value() {
            let data = self.pool[self.next % self.pool.len()].clone();
            self.next += 1;
            self.items.push(Image {
                width: data.len() as u32,
                height: 1,
                encoding: "mono8".into(),
                data,
            });
        }
        Ok(())
    }
}

/// `bench.qsink`: drains `in/items`, counting them in `out/count`. With `params/copy` it
/// copies each item's pixels first: what a transport that copies per reader would pay (the
/// baseline that shows a copy is visible in the 1 MiB / 1 KiB ratio).
pub struct QueueSink {
    items: QueueReader<Image>,
    copy: Input<bool>,
    count: Output<i64>,
}

impl Module for QueueSink {
    const TYPE: &'static str = "bench.qsink";
    const DESCRIPTION: &'static str = "Counts the items it drains.";
    fn declare(ports: &mut Ports) -> Self {
        QueueSink {
            items: ports.queue_in("in/items", "images"),
            copy: ports.param("params/copy", false, "copy each item's pixels"),
            count: ports.output("out/count", 0, "items seen"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_items(&self.items)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let items = self.items.drain();
        let copy = self.copy.value();
        let mut seen = 0;
        for item in &items {
            // Touch the payload: it must be readable (every buffer starts at 7 or more).
            let first = if copy {
                std::hint::black_box(item.data.to_vec())[0]
            } else {
                item.data[0]
            };
            seen += i64::from(first >= 7);
        }
        if seen > 0 {
            self.count.set(self.count.value() + seen);
        }
        Ok(())
    }
}

/// `bench.idle`: waits for an input that never changes.
pub struct Idle {
    input: Input<f64>,
}

impl Module for Idle {
    const TYPE: &'static str = "bench.idle";
    const DESCRIPTION: &'static str = "Waits for in/value to change.";
    fn declare(ports: &mut Ports) -> Self {
        Idle {
            input: ports.input("in/value", 0.0, "never changes"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.input)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        Ok(())
    }
}

/// `bench.crashy`: counts its first steps in `out/started`; crashes when told through
/// `control/fault` and woken by `in/kick`.
pub struct Crashy {
    kick: Input<i64>,
    started: Output<i64>,
}

impl Module for Crashy {
    const TYPE: &'static str = "bench.crashy";
    const DESCRIPTION: &'static str = "Counts its (re)starts.";
    fn declare(ports: &mut Ports) -> Self {
        Crashy {
            kick: ports.input("in/kick", 0, "wakes it"),
            started: ports.output("out/started", 0, "instances started"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.kick)
    }
    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if ctx.cause().first() {
            self.started.set(self.started.value() + 1);
        }
        Ok(())
    }
}

/// `len` tokio tasks chained by `watch` channels, each passing on what it reads: the floor of
/// a chain built on task wake-ups. Returns the chain's head and the end's receiver; spawned on
/// the runtime whose context this is called in.
#[allow(dead_code)] // Not every bench measures a chain.
pub fn watch_chain(
    len: usize,
) -> (
    tokio::sync::watch::Sender<f64>,
    tokio::sync::watch::Receiver<f64>,
) {
    let (head, mut rx) = tokio::sync::watch::channel(0.0_f64);
    for _ in 0..len {
        let (tx, next) = tokio::sync::watch::channel(0.0_f64);
        tokio::spawn(async move {
            while rx.changed().await.is_ok() {
                let v = *rx.borrow_and_update();
                let _ = tx.send(v);
            }
        });
        rx = next;
    }
    (head, rx)
}
