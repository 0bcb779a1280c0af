//! Fairness between long steps: modules whose steps take long and that always have work
//! waiting let a periodic module step between their time slices, instead of holding a worker
//! for tokio's whole cooperative budget (128 steps). Counted in steps, never timed: how many
//! busy steps run between two steps of the periodic module. Run under each scheduler, each run
//! counting on its own board (`params/board`), since the tests of a binary run in parallel.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use petrel::actors::{Agent, Context, Input, Module, Output, Ports, Schedule};

use crate::support::config;

/// Busy steps so far, by every `test.spinner` of a run, by board.
static BUSY_STEPS: [AtomicU64; 2] = [AtomicU64::new(0), AtomicU64::new(0)];

/// The busy-step count at each step of a run's `test.ticker`, by board.
static SEEN: [Mutex<Vec<u64>>; 2] = [Mutex::new(Vec::new()), Mutex::new(Vec::new())];

/// `test.spinner`: its input is its own output, so it always has work waiting; each step holds
/// its thread for 200 µs (as a long computation does).
struct Spinner {
    input: Input<f64>,
    board: Input<i64>,
    out: Output<f64>,
}

impl Module for Spinner {
    const TYPE: &'static str = "test.spinner";
    const DESCRIPTION: &'static str = "Spins 200 µs a step and wakes itself.";
    fn declare(ports: &mut Ports) -> Self {
        Spinner {
            input: ports.input("in/value", 0.0, "its own output"),
            board: ports.param("params/board", 0, "which run it counts for"),
            out: ports.output("out/value", 0.0, "steps so far"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.input)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let until = Instant::now() + Duration::from_micros(200);
        while Instant::now() < until {
            std::hint::spin_loop();
        }
        BUSY_STEPS[self.board.value() as usize].fetch_add(1, Ordering::Relaxed);
        self.out.set(self.out.value() + 1.0);
        Ok(())
    }
}

/// `test.ticker`: steps every millisecond and notes how many busy steps ran so far.
struct Ticker {
    board: Input<i64>,
    count: Output<i64>,
}

impl Module for Ticker {
    const TYPE: &'static str = "test.ticker";
    const DESCRIPTION: &'static str = "Notes the busy-step count every millisecond.";
    fn declare(ports: &mut Ports) -> Self {
        Ticker {
            board: ports.param("params/board", 0, "which run it counts for"),
            count: ports.output("out/count", 0, "periodic steps so far"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::every(Duration::from_millis(1))
    }
    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if ctx.cause().period() {
            let board = self.board.value() as usize;
            SEEN[board]
                .lock()
                .unwrap()
                .push(BUSY_STEPS[board].load(Ordering::Relaxed));
            self.count.set(self.count.value() + 1);
        }
        Ok(())
    }
}

/// Under `scheduler: shared` (ten spinners and the ticker on two workers), the periodic
/// module waits behind at most one slice of each spinner: about 60 busy steps (50-67 measured
/// on a loaded 2-core VM), 200 with a wide margin. With only tokio's cooperative budget it
/// waited behind 128 steps of each: about 1,300.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn long_steps_with_work_waiting_let_a_periodic_module_step_between_their_slices() {
    spinners_and_a_ticker("shared", 0, 200).await;
}

/// Under `scheduler: agent_thread` every module is on one thread, whose runtime looks at its
/// timers once the ready tasks have run: the ticker waits behind a few rounds of the spinners'
/// slices (135-277 busy steps measured on a loaded 2-core VM, 60 on an idle one), still far
/// below the 1,300 of the cooperative budget alone. (Modules this busy belong on the shared
/// runtime: `long_steps: true`.)
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn on_the_agents_thread_long_steps_also_let_a_periodic_module_step_between_their_slices() {
    spinners_and_a_ticker("agent_thread", 1, 600).await;
}

/// Ten spinners and a 1 kHz ticker in one agent under `scheduler`, counting on `board`: the
/// ticker steps 40 times, with at most `bound` busy steps between two of its steps.
async fn spinners_and_a_ticker(scheduler: &str, board: usize, bound: u64) {
    let mut registry = crate::support::registry();
    registry.register::<Spinner>().register::<Ticker>();
    let spinners: Vec<String> = (0..10)
        .map(|i| {
            format!(
                r#"(name: "s{i}", type: "test.spinner", values: {{"params/board": {board}}}, links: {{"in/value": "s{i}/out/value"}}),"#
            )
        })
        .collect();
    let text = format!(
        r#"Agent(name: "r", scheduler: {scheduler}, modules: [(name: "tick", type: "test.ticker", values: {{"params/board": {board}}}), {}])"#,
        spinners.join("\n")
    );
    let agent = Agent::start(&config(&text), &registry).await.unwrap();
    let count = agent
        .blackboard()
        .handle::<i64>("tick/out/count")
        .await
        .unwrap();
    // 40 periodic steps (bounded: the test fails rather than waits past its deadline).
    let waited = tokio::time::timeout(Duration::from_secs(30), async {
        while *count.get() < 40 {
            count.changed().await;
        }
    })
    .await;
    let summary = agent.stop(Duration::from_secs(10)).await;
    let seen = SEEN[board].lock().unwrap().clone();
    assert!(
        waited.is_ok(),
        "the periodic module stepped {} times: {seen:?}",
        seen.len()
    );
    // Each spinner yields after a 1 ms slice (about five 200 µs steps).
    let worst = seen.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(0);
    assert!(
        worst <= bound,
        "{worst} busy steps ran between two periodic steps: {seen:?}"
    );
    assert!(
        summary.modules.iter().all(|m| m.failures == 0),
        "{summary:?}"
    );
}

/// Steps so far of every `test.self_waker` (only the stop test uses them).
static WAKER_STEPS: AtomicU64 = AtomicU64::new(0);

/// `test.self_waker`: wakes itself after every step (its input is its own output); its cleanup
/// notes in `out/steps_at_cleanup` how many steps every self-waker had made by then.
struct SelfWaker {
    input: Input<f64>,
    out: Output<f64>,
    at_cleanup: Output<i64>,
}

impl Module for SelfWaker {
    const TYPE: &'static str = "test.self_waker";
    const DESCRIPTION: &'static str = "Wakes itself; notes the step total at cleanup.";
    fn declare(ports: &mut Ports) -> Self {
        SelfWaker {
            input: ports.input("in/value", 0.0, "its own output"),
            out: ports.output("out/value", 0.0, "steps so far"),
            at_cleanup: ports.output("out/steps_at_cleanup", -1, "all wakers' steps at cleanup"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.input)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        WAKER_STEPS.fetch_add(1, Ordering::SeqCst);
        self.out.set(self.input.value() + 1.0);
        Ok(())
    }
    async fn cleanup(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        self.at_cleanup
            .set(WAKER_STEPS.load(Ordering::SeqCst) as i64);
        Ok(())
    }
}

/// One thread (the paused-clock runtime), so "at once" is exact: the stop halts every module
/// before any of them cleans up. Stopped one by one, the busy modules kept stepping while the
/// ones after them cleaned up, and a stop took as long as their turns on the workers.
#[tokio::test(start_paused = true)]
async fn an_agent_stop_halts_every_busy_module_before_the_first_cleanup() {
    let mut registry = crate::support::registry();
    registry.register::<SelfWaker>();
    let wakers: Vec<String> = (0..5)
        .map(|i| {
            format!(
                r#"(name: "w{i}", type: "test.self_waker", links: {{"in/value": "w{i}/out/value"}}),"#
            )
        })
        .collect();
    let text = format!(r#"Agent(name: "r", modules: [{}])"#, wakers.join("\n"));
    let agent = Agent::start(&config(&text), &registry).await.unwrap();
    // Every waker has stepped a few times (bounded by the test's own deadline).
    for i in 0..5 {
        let steps = agent
            .blackboard()
            .handle::<f64>(&format!("w{i}/out/value"))
            .await
            .unwrap();
        tokio::time::timeout(Duration::from_secs(30), async {
            while *steps.get() < 10.0 {
                steps.changed().await;
            }
        })
        .await
        .expect("every waker steps");
    }
    agent.stop_modules(Duration::from_secs(10)).await;
    let mut totals = Vec::new();
    for i in 0..5 {
        let at = agent
            .blackboard()
            .get::<i64>(&format!("w{i}/out/steps_at_cleanup"))
            .await
            .unwrap();
        totals.push(*at);
    }
    assert!(totals[0] > 0, "every cleanup ran: {totals:?}");
    assert!(
        totals.iter().all(|&t| t == totals[0]),
        "no module stepped once the first cleanup began: {totals:?}"
    );
    agent.shutdown().await;
}
