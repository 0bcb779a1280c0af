//! Shared helpers and test-only module types.

use std::time::Duration;

use petrel::actors::{
    Agent, ConfigFile, Context, Input, Module, ModuleRegistry, Output, Ports, Schedule, State,
};

/// Built-in module types plus the test modules below.
pub fn registry() -> ModuleRegistry {
    let mut r = petrel::Petrel::new().registry().clone();
    r.register::<Echo>()
        .register::<TickLog>()
        .register::<Faulty>()
        .register::<EventLog>()
        .register::<StopOrder>()
        .register::<DropCount>()
        .register::<CleanupLog>()
        .register::<FlakyConsumer>()
        .register::<ImageSource>()
        .register::<ImageSink>();
    r
}

/// Parses `text` as `test.ron`.
pub fn config(text: &str) -> ConfigFile {
    ConfigFile::parse("test.ron", text).unwrap_or_else(|e| panic!("config should parse:\n{e}"))
}

/// The errors `ConfigFile::build` gives for config `text` (as `bad.ron`), one per line; panics
/// if it is accepted.
pub fn refused(text: &str) -> String {
    let file = ConfigFile::parse("bad.ron", text).unwrap();
    let Err(errors) = file.build(&registry()) else {
        panic!("should be refused: {text}");
    };
    let errors: Vec<String> = errors.0.iter().map(ToString::to_string).collect();
    errors.join("\n")
}

/// Starts an agent from config text with the test registry.
pub async fn start(text: &str) -> Agent {
    Agent::start(&config(text), &registry())
        .await
        .unwrap_or_else(|e| panic!("agent should start:\n{e}"))
}

/// Advances the paused clock by `ms`, letting every ready task run first.
pub async fn advance(ms: u64) {
    tokio::time::sleep(Duration::from_millis(ms)).await;
}

/// `test.echo`: copies `in/value` to `out/value` on every change, counting its steps.
pub struct Echo {
    input: Input<f64>,
    out: Output<f64>,
    steps: State<i64>,
}

impl Module for Echo {
    const TYPE: &'static str = "test.echo";
    const DESCRIPTION: &'static str = "Copies in/value to out/value on change.";
    fn declare(ports: &mut Ports) -> Self {
        Echo {
            input: ports.input("in/value", 0.0, "value"),
            out: ports.output("out/value", 0.0, "copy"),
            steps: ports.state("state/steps", 0, "steps after the first"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.input)
    }
    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if !ctx.cause().first() {
            self.steps.set(self.steps.value() + 1);
        }
        self.out.set(self.input.value());
        Ok(())
    }
}

/// `test.ticklog`: records the (paused-clock) time of each periodic step, in ms since init.
pub struct TickLog {
    period_ms: Input<i64>,
    work_ms: Input<i64>,
    times: Output<Vec<f64>>,
    origin: Option<tokio::time::Instant>,
}

impl Module for TickLog {
    const TYPE: &'static str = "test.ticklog";
    const DESCRIPTION: &'static str = "Records when each periodic step ran.";
    fn declare(ports: &mut Ports) -> Self {
        TickLog {
            period_ms: ports.param("params/period_ms", 100, "period"),
            work_ms: ports.param("params/work_ms", 0, "time each step takes"),
            times: ports.output("out/times", Vec::new(), "step times, ms since init"),
            origin: None,
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::every(Duration::from_millis(self.period_ms.value() as u64))
    }
    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        self.origin = Some(tokio::time::Instant::now());
        Ok(())
    }
    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if ctx.cause().period() {
            let origin = self.origin.expect("set in init");
            let mut times = (*self.times.get()).clone();
            times.push(ctx.now().duration_since(origin).as_secs_f64() * 1e3);
            self.times.set(times);
            tokio::time::sleep(Duration::from_millis(self.work_ms.value() as u64)).await;
        }
        Ok(())
    }
}

/// `test.faulty`: counts steps and fails at step `params/fail_at` by panicking or erroring,
/// or fails its init.
pub struct Faulty {
    mode: Input<String>,
    fail_at: Input<i64>,
    steps: State<i64>,
}

impl Module for Faulty {
    const TYPE: &'static str = "test.faulty";
    const DESCRIPTION: &'static str = "Fails on purpose.";
    fn declare(ports: &mut Ports) -> Self {
        Faulty {
            mode: ports.param(
                "params/mode",
                "panic".to_string(),
                "panic, error, init or bad_file",
            ),
            fail_at: ports.param("params/fail_at", 3, "step that fails"),
            steps: ports.state("state/steps", 0, "steps so far"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::every(Duration::from_millis(10))
    }
    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        anyhow::ensure!(*self.mode.get() != "init", "no such device /dev/laser0");
        if *self.mode.get() == "bad_file" {
            let why = "calibration.yaml:3:1: expected a number";
            return Err(petrel::actors::Unrecoverable(why.into()).into());
        }
        Ok(())
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let steps = self.steps.value() + 1;
        self.steps.set(steps);
        if steps == self.fail_at.value() {
            match self.mode.get().as_str() {
                "panic" => panic!("wheel encoder exploded at step {steps}"),
                _ => anyhow::bail!("lost the serial link at step {steps}"),
            }
        }
        Ok(())
    }
}

/// `test.event_log`: reads `_supervisor/events`; publishes the kinds seen (`kind:module` joined
/// by spaces) and the times of `restarted` events, in ms since the agent started.
pub struct EventLog {
    events: petrel::actors::QueueReader<petrel::actors::SupervisorEvent>,
    kinds: Output<String>,
    restart_ms: Output<Vec<f64>>,
}

impl Module for EventLog {
    const TYPE: &'static str = "test.event_log";
    const DESCRIPTION: &'static str = "Records supervision events.";
    fn declare(ports: &mut Ports) -> Self {
        EventLog {
            events: ports.queue_in("in/events", "supervision events"),
            kinds: ports.output("out/kinds", String::new(), "kind:module ..."),
            restart_ms: ports.output("out/restart_ms", Vec::new(), "times of restarts"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_items(&self.events)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let (mut kinds, mut times) = (
            (*self.kinds.get()).clone(),
            (*self.restart_ms.get()).clone(),
        );
        for e in self.events.drain() {
            kinds.push_str(&format!("{}:{} ", e.kind, e.module));
            if e.kind == "restarted" {
                times.push((e.time_s * 1e3).round());
            }
        }
        self.kinds.set(kinds);
        self.restart_ms.set(times);
        Ok(())
    }
}

/// `test.cleanup_log`: counts its steps in `state/steps` (across instances), and its cleanup
/// appends `restart` or `stop` to `out/cleanups`, as [`Context::restarting`] tells it.
pub struct CleanupLog {
    steps: State<i64>,
    cleanups: Output<String>,
}

impl Module for CleanupLog {
    const TYPE: &'static str = "test.cleanup_log";
    const DESCRIPTION: &'static str = "Notes whether each cleanup was for a restart.";
    fn declare(ports: &mut Ports) -> Self {
        CleanupLog {
            steps: ports.state("state/steps", 0, "steps of every instance"),
            cleanups: ports.output(
                "out/cleanups",
                String::new(),
                "restart or stop, per cleanup",
            ),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::every(Duration::from_millis(10))
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        self.steps.set(*self.steps.get() + 1);
        Ok(())
    }
    async fn cleanup(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let mut log = (*self.cleanups.get()).clone();
        if !log.is_empty() {
            log.push(',');
        }
        log.push_str(if ctx.restarting() { "restart" } else { "stop" });
        self.cleanups.set(log);
        Ok(())
    }
}

static STOP_SEQUENCE: std::sync::atomic::AtomicI64 = std::sync::atomic::AtomicI64::new(0);

/// `test.stop_order`: its cleanup records a global sequence number in `out/stopped`.
pub struct StopOrder {
    stopped: Output<i64>,
}

impl Module for StopOrder {
    const TYPE: &'static str = "test.stop_order";
    const DESCRIPTION: &'static str = "Records when its cleanup ran.";
    fn declare(ports: &mut Ports) -> Self {
        StopOrder {
            stopped: ports.output("out/stopped", 0, "global cleanup sequence number"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new()
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        Ok(())
    }
    async fn cleanup(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        self.stopped
            .set(STOP_SEQUENCE.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1);
        Ok(())
    }
}

/// Instances of `test.drop_count` dropped so far (only
/// `supervision::a_module_killed_at_the_stop_timeout_is_dropped_with_its_stuck_step` uses it).
pub static DROPS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// `test.drop_count`: a module that steps every 10 ms and counts, in [`DROPS`], its instances
/// dropped.
pub struct DropCount;

impl Module for DropCount {
    const TYPE: &'static str = "test.drop_count";
    const DESCRIPTION: &'static str = "Steps every 10 ms; counts its instances dropped.";
    fn declare(_ports: &mut Ports) -> Self {
        DropCount
    }
    fn schedule(&self) -> Schedule {
        Schedule::every(Duration::from_millis(10))
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        Ok(())
    }
}

impl Drop for DropCount {
    fn drop(&mut self) {
        DROPS.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
    }
}

/// Items on which `test.flaky_consumer` has panicked (first delivery only).
static FLAKY_PANICS: std::sync::atomic::AtomicI64 = std::sync::atomic::AtomicI64::new(-1);

/// `test.flaky_consumer`: processes numbered items, committing its progress at the end of each
/// step; panics in the middle of a batch on item numbers ≡ 500 (mod 1000), once each.
pub struct FlakyConsumer {
    items: petrel::actors::QueueReader<i64>,
    next: State<i64>,
    errors: State<i64>,
    deliveries: State<i64>,
}

impl Module for FlakyConsumer {
    const TYPE: &'static str = "test.flaky_consumer";
    const DESCRIPTION: &'static str = "Checks numbered items, panicking now and then.";
    fn declare(ports: &mut Ports) -> Self {
        FlakyConsumer {
            items: ports.queue_in("in/items", "numbered items"),
            next: ports.state("state/next", 0, "next number expected"),
            errors: ports.state("state/errors", 0, "items out of order (gap or duplicate)"),
            deliveries: ports.state(
                "state/deliveries",
                0,
                "items received, redeliveries included",
            ),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_items(&self.items)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let (mut next, mut errors) = (self.next.value(), self.errors.value());
        let batch = self.items.drain();
        // Deliveries are counted as they happen, so redeliveries show.
        self.deliveries
            .set(self.deliveries.value() + batch.len() as i64);
        for item in batch {
            let n = *item.value;
            if n % 1000 == 500 && FLAKY_PANICS.fetch_max(n, std::sync::atomic::Ordering::SeqCst) < n
            {
                panic!("flaky consumer fails in the middle of a batch at item {n}");
            }
            if n != next {
                errors += 1;
            }
            next = n + 1;
        }
        // Progress is committed when the step completes, as the runtime acknowledges the batch.
        self.next.set(next);
        self.errors.set(errors);
        Ok(())
    }
}

/// The address of an image's pixel bytes, to tell a shared buffer from a copy.
fn address(image: &petrel::actors::Image) -> i64 {
    image.data.as_ptr() as i64
}

/// `test.image_source`: pushes a fresh 640×480 image per step, and publishes where its pixel
/// bytes live.
pub struct ImageSource {
    out: petrel::actors::QueueWriter<petrel::actors::Image>,
    addresses: Output<Vec<f64>>,
}

impl Module for ImageSource {
    const TYPE: &'static str = "test.image_source";
    const DESCRIPTION: &'static str = "Pushes images, publishing their byte addresses.";
    fn declare(ports: &mut Ports) -> Self {
        ImageSource {
            out: ports.queue_out("out/images", 16, "images"),
            addresses: ports.output("out/addresses", Vec::new(), "byte addresses pushed"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::every(Duration::from_millis(10))
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let image = petrel::actors::Image {
            width: 640,
            height: 480,
            encoding: "mono8".into(),
            data: vec![7; 640 * 480].into(),
        };
        let mut addresses = self.addresses.get().to_vec();
        addresses.push(address(&image) as f64);
        self.out.push(image);
        self.addresses.set(addresses);
        Ok(())
    }
}

/// `test.image_sink`: publishes where the pixel bytes of each image it receives live.
pub struct ImageSink {
    input: petrel::actors::QueueReader<petrel::actors::Image>,
    addresses: Output<Vec<f64>>,
}

impl Module for ImageSink {
    const TYPE: &'static str = "test.image_sink";
    const DESCRIPTION: &'static str = "Publishes the byte addresses of the images it receives.";
    fn declare(ports: &mut Ports) -> Self {
        ImageSink {
            input: ports.queue_in("in/images", "images"),
            addresses: ports.output("out/addresses", Vec::new(), "byte addresses received"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_items(&self.input)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let mut addresses = self.addresses.get().to_vec();
        addresses.extend(self.input.drain().iter().map(|i| address(&i.value) as f64));
        self.addresses.set(addresses);
        Ok(())
    }
}

/// Waits (at most 20 s) until `ready` holds for property `key` of `agent`.
pub async fn until<T: petrel::actors::PropertyType>(
    agent: &Agent,
    key: &str,
    ready: impl Fn(&T) -> bool,
) -> T {
    let handle = agent.blackboard().handle::<T>(key).await.unwrap();
    let waited = tokio::time::timeout(Duration::from_secs(20), async {
        loop {
            let value = handle.get();
            if ready(&value) {
                return (*value).clone();
            }
            handle.changed().await;
        }
    })
    .await;
    waited.unwrap_or_else(|_| panic!("{key} never got there: {:?}", handle.get()))
}
