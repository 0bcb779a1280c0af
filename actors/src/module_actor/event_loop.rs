//! A running module's event loop: it waits on its signal, period, timeout and stop request,
//! and steps the module with the bookkeeping around each step (fairness, stats, the step
//! budget, the loop watch, injected faults).

use std::future::Future;
use std::time::Duration;

use tokio::time::Instant;

use super::loops::{report_loop, Loop};
use super::ticker::{tick, Ticker};
use super::{status, Running, TIME_SLICE};
use crate::cell::cause;
use crate::loop_watch;
use crate::module::{Cause, Module, Schedule, WatchTarget};

/// Marks a module's signal as taken by its step loop, until dropped.
struct Live(std::sync::Arc<crate::cell::Signal>);

impl Live {
    fn mark(signal: &std::sync::Arc<crate::cell::Signal>) -> Live {
        signal.set_live(true);
        Live(signal.clone())
    }
}

impl Drop for Live {
    fn drop(&mut self) {
        self.0.set_live(false);
    }
}

impl<M: Module> Running<M> {
    /// Waits for events and steps until asked to stop; an error is the module's failure.
    pub(super) async fn run(&mut self) -> anyhow::Result<()> {
        self.builtins
            .enabled
            .ep
            .subscribe_with(&self.signal, cause::ENABLED);
        self.stop.attach(&self.signal);
        // Taken as running while this loop lives, however it ends (an error, a panic, a kill).
        let _live = Live::mark(&self.signal);
        let (mut ticker, mut timeout) = self.arm();
        let mut enabled = self.builtins.enabled.value();
        self.signal.set_quiet(!enabled);
        self.publish(if enabled {
            status::RUNNING
        } else {
            status::DISABLED
        });
        // Every module steps once after init; later steps need an event.
        let mut pending: Option<u8> = Some(0);
        let mut last_step = Instant::now();
        // When the current run of back-to-back steps began (see TIME_SLICE).
        let mut slice_start: Option<Instant> = None;
        loop {
            if self.stop.is_requested() {
                return Ok(());
            }
            if enabled {
                if let Some(causes) = pending.take() {
                    self.step(causes).await?;
                    // A module that wakes itself (an input linked to its own output, a busy
                    // producer) finds its signal already raised, so its waits never suspend:
                    // spend tokio's cooperative budget, so that every so many steps it yields
                    // to the other modules and to the stop path, on any number of workers.
                    tokio::task::consume_budget().await;
                    // The budget counts steps, not time: 128 steps of 200 µs hold a worker for
                    // 26 ms, and a periodic module beside twenty such modules got 12 of its
                    // 3000 periods. A module with work already waiting also yields once its
                    // steps in a row have taken a time slice (read on tokio's clock, so a
                    // paused-clock run keeps its order).
                    if self.signal.pending() {
                        let now = Instant::now();
                        let start = *slice_start.get_or_insert(now);
                        if now.duration_since(start) >= TIME_SLICE {
                            tokio::task::yield_now().await;
                            slice_start = None;
                        }
                    } else {
                        slice_start = None;
                    }
                    if timeout.is_some() {
                        last_step = Instant::now();
                    }
                    if std::mem::take(&mut self.ctx.reschedule) {
                        (ticker, timeout) = self.arm();
                    }
                    continue;
                }
            }
            // One signal carries every event (data, `enabled`, stop), so a purely event-driven
            // module waits on a single `Notify`: the hot path of `property_wake`.
            let causes = if ticker.is_none() && timeout.is_none() {
                self.signal.wait().await
            } else {
                tokio::select! {
                    biased;
                    c = self.signal.wait() => c,
                    _ = tick(&mut ticker) => cause::PERIOD | self.signal.take(),
                    _ = tokio::time::sleep_until(last_step + timeout.unwrap_or_default()), if timeout.is_some() => cause::TIMEOUT,
                }
            };
            if causes & cause::ENABLED != 0 {
                let now_enabled = self.builtins.enabled.value();
                if now_enabled != enabled {
                    enabled = now_enabled;
                    // Data events while disabled are recorded in the signal and picked up by
                    // the next wait; they need not wake this module until it is enabled.
                    self.signal.set_quiet(!enabled);
                    self.span
                        .in_scope(|| tracing::info!(enabled, "enabled changed"));
                    self.publish(if enabled {
                        status::RUNNING
                    } else {
                        status::DISABLED
                    });
                }
            }
            if causes & cause::STEPS != 0 {
                pending = Some(pending.unwrap_or(0) | (causes & cause::STEPS));
            }
        }
    }

    /// Applies the module's schedule: subscribes its watches (again: subscribing is idempotent),
    /// sets its watchdog, and returns its ticker and timeout.
    fn arm(&mut self) -> (Option<Ticker>, Option<Duration>) {
        let Schedule {
            period,
            timeout,
            watchdog,
            watches,
        } = self.module.schedule();
        self.watchdog = self.config_watchdog.or(watchdog);
        for watch in &watches {
            match &watch.0 {
                WatchTarget::Value(ep) => ep.subscribe(&self.signal),
                WatchTarget::Queue(reader) => reader.subscribe(&self.signal),
            }
        }
        let ticker = period.map(Ticker::new);
        (ticker, timeout)
    }

    async fn step(&mut self, causes: u8) -> anyhow::Result<()> {
        self.ctx.cause = Cause(causes);
        // A step woken by time starts a new chain; one woken by writes continues theirs.
        let raised = self.signal.take_hop();
        let hops = if causes & (cause::PERIOD | cause::TIMEOUT) != 0 {
            0
        } else {
            raised.hops
        };
        self.ctx.hops = hops;
        // The step's time is read once, here if the step is timed, else when first needed.
        let started = self.stats.wants_timing().then(Instant::now);
        match started {
            Some(t) => self.ctx.clock.begin_at(t),
            None => self.ctx.clock.begin(),
        }
        // Its run-queue wait too, when the step budget asks (`long_steps.rs`).
        let queue_mark = started.and_then(|_| self.run_queue_mark());
        self.ctx.settle.timed = started.is_some();
        self.ctx.settle.waited = Duration::ZERO;
        // A span per step for timelines (`--trace-out`); disabled, it costs a callsite check.
        let span = tracing::trace_span!("step");
        let mark = self.step_mark.clone();
        let in_step = mark.enter();
        // Taken for the step rather than cloned: no reference count traffic per step.
        let hold = self.hold.take();
        let me = self.signal.id();
        let result = {
            // Polled in place, each poll in the span, with the hop current and marked on the
            // agent's thread: wrapping the step in a combinator per concern moved the whole
            // future at each layer, a copy of the largest futures (a mission's) at every step.
            let mut step = std::pin::pin!(self.run_step());
            std::future::poll_fn(|cx| {
                let _in_span = span.enter();
                let mut poll = || loop_watch::in_poll(hops, me, || step.as_mut().poll(cx));
                match &hold {
                    Some((hold, slot)) => hold.marked(*slot, poll),
                    None => poll(),
                }
            })
            .await
        };
        self.hold = hold;
        drop(in_step);
        // A looping step (a ring of modules) reads the step's time, which its writes have read
        // already, rather than the clock again.
        let clock = &self.ctx.clock;
        if let Some(steps) = self.loops.observe(hops, || clock.now().into_std()) {
            let woken_by_itself = raised.waker == self.signal.id();
            let hint = self.module.loop_hint();
            let blackboard = self.ctx.blackboard().clone();
            let module = self.ctx.module().to_string();
            let found = Loop {
                hops,
                steps,
                woken_by_itself,
                hint,
            };
            report_loop(&self.span, &blackboard, &module, found).await;
        }
        if result.is_ok() {
            // The step is done with what it took from its queues.
            for reader in &self.readers {
                reader.ack();
            }
            self.ctx.steps += 1;
            if let Some(started) = started {
                // The modules it let run while it settled are not its time.
                let took = started.elapsed().saturating_sub(self.ctx.settle.waited);
                if self.stats.record(self.ctx.steps, started, took) {
                    self.publish_stats();
                }
                self.watch_step_budget(took, queue_mark);
            }
        }
        self.ctx.clock.end();
        result
    }

    /// Runs the module's step (or the fault injected), under its watchdog if it has one.
    async fn run_step(&mut self) -> anyhow::Result<()> {
        let fault = self.take_fault();
        if fault.is_none() && self.watchdog.is_none() {
            // The usual step, awaited in place (see `step`).
            return self.module.step(&mut self.ctx).await;
        }
        let step = async {
            match fault.as_deref() {
                Some("panic") => panic!("fault injected through control/fault: panic"),
                Some("error") => anyhow::bail!("fault injected through control/fault: error"),
                Some("hang") => std::future::pending().await,
                // What a runaway computation and a read that never returns do: hold the
                // thread without ever yielding. Only a process exit ends them.
                Some("spin") => loop {
                    std::hint::spin_loop()
                },
                Some("block") => loop {
                    std::thread::park()
                },
                _ => self.module.step(&mut self.ctx).await,
            }
        };
        match self.watchdog {
            Some(deadline) => match tokio::time::timeout(deadline, step).await {
                Ok(result) => result,
                Err(_) => anyhow::bail!("hang: a step ran longer than its {deadline:?} watchdog"),
            },
            None => step.await,
        }
    }

    /// A fault injected through `control/fault` since the last step, if any. It fires once:
    /// `control/fault` is emptied, so a restarted instance does not fail again.
    fn take_fault(&mut self) -> Option<String> {
        // `control/...` cannot be linked, so its own cell is the one written: no `ArcSwap` load
        // at every step.
        if self.builtins.fault.ep.own.version() == self.fault_seen {
            return None;
        }
        let fault = self.builtins.fault.read().value.to_string();
        if !fault.is_empty() {
            self.builtins.fault.set(String::new());
        }
        self.fault_seen = self.builtins.fault.ep.version();
        match fault.as_str() {
            "" => None,
            "panic" | "error" | "hang" | "spin" | "block" => Some(fault),
            other => {
                self.span.in_scope(|| {
                    tracing::warn!(fault = other, "unknown fault ignored: control/fault takes panic, error, hang, spin or block")
                });
                None
            }
        }
    }
}
