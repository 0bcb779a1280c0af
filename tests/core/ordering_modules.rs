//! Module types for the ordering and fairness tests (`ordering.rs`): a busy writer, a relay
//! that checks what it reads, a step that blocks its thread until the test opens a gate.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use petrel::actors::{Context, Input, Module, ModuleRegistry, Output, Ports, Schedule};

/// The test registry plus the module types below.
pub fn registry() -> ModuleRegistry {
    let mut r = crate::support::registry();
    r.register::<Writer>()
        .register::<Relay>()
        .register::<Blocker>();
    r
}

/// One sequence for every step of every [`Relay`] in this test binary: a relay takes a number
/// when its step reads its input, so comparing two relays' numbers says which step came first.
static SEQUENCE: AtomicU64 = AtomicU64::new(1);

/// `test.writer`: its `in/value` is linked to its own `out/value`, so each write wakes it
/// again and it writes as fast as it is stepped: 1, 2, 3, ... up to `params/limit`, or until
/// `params/busy_ms` of wall time have passed since its first step; then `out/finished`. With
/// `params/yield` it lets the other ready modules run after each write (so its readers can
/// see every value), else it writes in a tight loop.
pub struct Writer {
    input: Input<f64>,
    limit: Input<i64>,
    yields: Input<bool>,
    busy_ms: Input<i64>,
    out: Output<f64>,
    finished: Output<bool>,
    until: Option<Instant>,
}

impl Module for Writer {
    const TYPE: &'static str = "test.writer";
    const DESCRIPTION: &'static str = "Writes 1, 2, 3, ... in a tight loop.";
    fn declare(ports: &mut Ports) -> Self {
        Writer {
            input: ports.input("in/value", 0.0, "its own output"),
            limit: ports.param("params/limit", 1000, "last value written"),
            yields: ports.param("params/yield", false, "yield after each write"),
            busy_ms: ports.param("params/busy_ms", 20_000, "wall time it writes at most"),
            out: ports.output("out/value", 0.0, "the count"),
            finished: ports.output("out/finished", false, "reached its limit or its time"),
            until: None,
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.input)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let until = *self.until.get_or_insert_with(|| {
            Instant::now() + Duration::from_millis(self.busy_ms.value() as u64)
        });
        let next = self.out.value() + 1.0;
        if next > self.limit.value() as f64 || Instant::now() >= until {
            if !self.finished.value() {
                self.finished.set(true);
            }
            return Ok(());
        }
        self.out.set(next);
        if self.yields.value() {
            tokio::task::yield_now().await;
        }
        Ok(())
    }
}

/// `test.relay`: copies `in/value` to `out/value` on change. Counts in `out/regressions` every
/// read that saw an older value or version than an earlier read, and logs each value it saw
/// with the sequence number its step took in `out/values` and `out/sequence`.
pub struct Relay {
    input: Input<f64>,
    out: Output<f64>,
    regressions: Output<i64>,
    values: Output<Vec<f64>>,
    sequence: Output<Vec<f64>>,
    last: (u64, f64),
}

impl Module for Relay {
    const TYPE: &'static str = "test.relay";
    const DESCRIPTION: &'static str = "Copies in/value on, checking it never goes back.";
    fn declare(ports: &mut Ports) -> Self {
        Relay {
            input: ports.input("in/value", 0.0, "value"),
            out: ports.output("out/value", 0.0, "copy"),
            regressions: ports.output("out/regressions", 0, "reads older than an earlier one"),
            values: ports.output("out/values", Vec::new(), "values seen, in order"),
            sequence: ports.output("out/sequence", Vec::new(), "when each was seen"),
            last: (0, 0.0),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.input)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let seen = self.input.read();
        let at = SEQUENCE.fetch_add(1, Ordering::SeqCst);
        let (version, value) = (seen.version, *seen.value);
        if version < self.last.0 || value < self.last.1 {
            self.regressions.set(self.regressions.value() + 1);
        }
        if version != self.last.0 {
            let mut values = (*self.values.get()).clone();
            let mut sequence = (*self.sequence.get()).clone();
            values.push(value);
            sequence.push(at as f64);
            self.values.set(values);
            self.sequence.set(sequence);
        }
        self.last = (version, value);
        // Only a new value is passed on, so a reader downstream sees each value once.
        if self.out.value() != value {
            self.out.set(value);
        }
        Ok(())
    }
}

/// A gate a [`Blocker`]'s step waits at, opened by the test.
#[derive(Default)]
pub struct Gate {
    open: Mutex<bool>,
    opened: Condvar,
}

impl Gate {
    /// The gate named `name` (made on first use): tests running in parallel use their own.
    pub fn named(name: &str) -> Arc<Gate> {
        static GATES: Mutex<Option<HashMap<String, Arc<Gate>>>> = Mutex::new(None);
        let mut gates = GATES.lock().unwrap();
        gates
            .get_or_insert_with(HashMap::new)
            .entry(name.to_string())
            .or_default()
            .clone()
    }

    /// Lets the step through.
    pub fn open(&self) {
        *self.open.lock().unwrap() = true;
        self.opened.notify_all();
    }

    /// Blocks the calling thread until the gate opens (true) or `deadline` passes (false).
    fn wait(&self, deadline: Duration) -> bool {
        let open = self.open.lock().unwrap();
        let (open, _) = self
            .opened
            .wait_timeout_while(open, deadline, |open| !*open)
            .unwrap();
        *open
    }
}

/// `test.blocker`: when `in/go` holds a value it has not handled yet (0 at first), writes
/// `out/blocked`, then blocks its thread (a long computation, a blocking read) at the gate
/// `params/gate` until the test opens it, for `params/deadline_ms` at most; then writes
/// `out/released`: `opened` or `deadline`. It looks at the value, not at why it steps: a write
/// made before it subscribed is seen by its first step, not signalled.
pub struct Blocker {
    go: Input<i64>,
    handled: i64,
    gate: Input<String>,
    deadline_ms: Input<i64>,
    blocked: Output<bool>,
    released: Output<String>,
}

impl Module for Blocker {
    const TYPE: &'static str = "test.blocker";
    const DESCRIPTION: &'static str = "Blocks its thread until a gate opens.";
    fn declare(ports: &mut Ports) -> Self {
        Blocker {
            go: ports.input("in/go", 0, "blocks when it changes"),
            handled: 0,
            gate: ports.param("params/gate", String::new(), "the gate's name"),
            deadline_ms: ports.param("params/deadline_ms", 20_000, "longest block"),
            blocked: ports.output("out/blocked", false, "inside the blocking step"),
            released: ports.output("out/released", String::new(), "opened or deadline"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.go)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        if self.go.value() == self.handled {
            return Ok(());
        }
        self.handled = self.go.value();
        self.blocked.set(true);
        let gate = Gate::named(&self.gate.get());
        let opened = gate.wait(Duration::from_millis(self.deadline_ms.value() as u64));
        self.released
            .set(if opened { "opened" } else { "deadline" }.to_string());
        Ok(())
    }
}
