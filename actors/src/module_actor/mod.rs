//! The actor shell around one module instance: binds it to its cells, runs init, then waits
//! for its schedule's events and steps it, publishing its stats.
//!
//! The step loop runs inside one actor message handler, so a step is a plain function call
//! after a wake-up (no mailbox hop on the hot path). ractor still supervises it: a panic or an
//! error ends the actor and reaches the supervisor, and a kill drops the running step.

use std::future::Future;
use std::marker::PhantomData;
use std::sync::Arc;
use std::time::Duration;

use ractor::{Actor, ActorProcessingErr, ActorRef};
use tokio::time::Instant;
use tracing::Instrument;

use crate::agent::{AgentControl, ModuleControl};
use crate::blackboard::Blackboard;
use crate::cell::{cause, Signal};
use crate::loop_watch::{self, LoopWatch};
use crate::module::{Cause, Context, Module, Schedule, Unrecoverable, WatchTarget};
use crate::panic_report::catching;
use crate::ports::{Handle, Ports};
use crate::queue::ReaderEndpoint;
use crate::step_probe::StepMark;
use crate::supervision::LongStepWatch;
use crate::thread_hold::ThreadHold;

mod builtins;
mod loops;
mod publish;
mod stats;
mod stop;
mod ticker;

pub use builtins::status;
pub(crate) use builtins::{declare_builtins, Builtins};
use loops::{report_loop, Loop};
use stats::StepStats;
pub(crate) use stop::StopRequest;
use ticker::{tick, Ticker};

/// The longest a module steps back to back, while it has work waiting, before it lets the
/// other tasks of its worker run.
const TIME_SLICE: Duration = Duration::from_millis(1);

pub(crate) struct ModuleArgs {
    pub modules: ModuleControl,
    /// Overrides the module's own watchdog.
    pub watchdog: Option<Duration>,
    pub agent: Arc<str>,
    pub name: String,
    pub blackboard: Blackboard,
    pub control: AgentControl,
    pub stop: Arc<StopRequest>,
    /// Odd while a step runs, for a watchdog outside the runtime.
    pub step_mark: Arc<StepMark>,
    /// On the agent's own thread: the mean step above which the module asks to be moved.
    pub step_budget: Option<crate::config::StepBudget>,
    /// On the agent's own thread: where its polls are marked, and its slot.
    pub hold: Option<(Arc<ThreadHold>, usize)>,
}

pub(crate) struct ModuleActor<M>(PhantomData<fn() -> M>);

impl<M> ModuleActor<M> {
    pub fn new() -> Self {
        ModuleActor(PhantomData)
    }
}

pub(crate) struct Running<M> {
    module: M,
    readers: Vec<Arc<ReaderEndpoint>>,
    watchdog: Option<Duration>,
    /// The config's `watchdog_ms`, which overrides the module's own.
    config_watchdog: Option<Duration>,
    fault_seen: u64,
    ctx: Context,
    builtins: Builtins,
    signal: Arc<Signal>,
    stop: Arc<StopRequest>,
    step_mark: Arc<StepMark>,
    span: tracing::Span,
    stats: StepStats,
    /// Steps the module's earlier instances ran (`stats/steps` counts since the agent started).
    steps_before: u64,
    loops: LoopWatch,
    /// Steps against the agent's `step_budget`, on the agent's own thread only.
    long_steps: Option<LongStepWatch>,
    /// On the agent's own thread: where its step's polls are marked (`thread_hold.rs`).
    hold: Option<(Arc<ThreadHold>, usize)>,
    /// Who to ask for a move, and who is asking.
    supervisor: ActorRef<crate::supervisor::SupervisorMsg>,
    me: ractor::ActorId,
    /// The status this instance wrote last, with the version of `stats/status` it left.
    status_shown: Option<(&'static str, u64)>,
    status_values: publish::StatusValues,
}

/// Why module code failed, if it did: its error, or the panic the hook reported.
fn failure(outcome: Result<anyhow::Result<()>, String>) -> Option<String> {
    match outcome {
        Ok(Ok(())) => None,
        Ok(Err(e)) => Some(format!("{e:#}")),
        Err(panic) => Some(panic),
    }
}

/// The message that starts the step loop; the loop then owns the handler until it stops.
pub(crate) struct RunLoop;

impl<M: Module> Actor for ModuleActor<M> {
    type Msg = RunLoop;
    type State = Running<M>;
    type Arguments = ModuleArgs;

    async fn pre_start(
        &self,
        me: ActorRef<RunLoop>,
        args: ModuleArgs,
    ) -> Result<Running<M>, ActorProcessingErr> {
        let span = tracing::info_span!(parent: None, "module", agent = %args.agent, module = %args.name, r#type = M::TYPE);
        let binding = args.blackboard.bind(&args.name).await?;
        // A restarted instance is given again what its predecessor took but did not acknowledge.
        let readers: Vec<Arc<ReaderEndpoint>> = binding
            .handles
            .values()
            .filter_map(|h| match h {
                Handle::QueueIn(reader) => Some(reader.clone()),
                _ => None,
            })
            .collect();
        for reader in &readers {
            reader.rewind();
        }
        let supervisor = args.modules.supervisor.clone();
        let wait_known = crate::run_queue::run_queue_known();
        let long_steps = args
            .step_budget
            .and_then(|budget| LongStepWatch::new(budget, wait_known));
        let mut ports = Ports::bound(&args.name, binding.handles);
        let builtins = declare_builtins(&mut ports);
        let mut module = M::declare(&mut ports);
        if !ports.errors.is_empty() {
            return Err(ports.errors.join("; ").into());
        }
        builtins.status.set(status::INITIALIZING.into());
        let mut ctx = Context::new(
            &args.agent,
            &args.name,
            args.modules,
            args.blackboard,
            args.control,
            ports.clock.clone(),
        );
        ctx.settle.signal = Some(binding.signal.clone());
        let init = catching(module.init(&mut ctx).instrument(span.clone())).await;
        let unrecoverable =
            matches!(&init, Ok(Err(e)) if e.downcast_ref::<Unrecoverable>().is_some());
        if let Some(reason) = failure(init) {
            builtins.status.set(status::FAILED.into());
            let reason = format!("init failed: {reason}");
            return Err(match unrecoverable {
                true => Box::new(Unrecoverable(reason)),
                false => reason.into(),
            });
        }
        span.in_scope(|| tracing::info!("initialized"));
        // A fault the config sets fires at the first step; one written while the module was
        // down fires at the restarted instance's first step.
        let fault_seen = match builtins.fault.read() {
            f if f.value.is_empty() => f.version,
            _ => 0,
        };
        let steps_before = u64::try_from(*builtins.steps.get()).unwrap_or(0);
        Ok(Running {
            module,
            readers,
            watchdog: args.watchdog,
            config_watchdog: args.watchdog,
            fault_seen,
            ctx,
            builtins,
            signal: binding.signal,
            stop: args.stop,
            step_mark: args.step_mark,
            span,
            stats: StepStats::default(),
            steps_before,
            loops: LoopWatch::default(),
            long_steps,
            hold: args.hold,
            supervisor,
            me: me.get_id(),
            status_shown: None,
            status_values: Default::default(),
        })
    }

    async fn post_start(
        &self,
        me: ActorRef<RunLoop>,
        _state: &mut Running<M>,
    ) -> Result<(), ActorProcessingErr> {
        me.send_message(RunLoop)?;
        Ok(())
    }

    async fn handle(
        &self,
        me: ActorRef<RunLoop>,
        _msg: RunLoop,
        state: &mut Running<M>,
    ) -> Result<(), ActorProcessingErr> {
        let span = state.span.clone();
        match failure(catching(state.run().instrument(span.clone())).await) {
            None => {
                // Stopped with the whole agent: clean up in reverse start order, when told.
                state.stop.cleanup_turn().await;
                state.ctx.restarting = state.stop.is_restart();
                let cleanup = catching(state.module.cleanup(&mut state.ctx).instrument(span)).await;
                state.publish(status::STOPPED);
                me.stop(None);
                match failure(cleanup) {
                    None => Ok(()),
                    Some(reason) => Err(format!("cleanup failed: {reason}").into()),
                }
            }
            Some(reason) => {
                state.publish(status::FAILED);
                Err(reason.into())
            }
        }
    }
}

impl<M: Module> Running<M> {
    /// Waits for events and steps until asked to stop; an error is the module's failure.
    async fn run(&mut self) -> anyhow::Result<()> {
        self.builtins
            .enabled
            .ep
            .subscribe_with(&self.signal, cause::ENABLED);
        self.stop.attach(&self.signal);
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
