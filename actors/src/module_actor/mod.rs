//! The actor shell around one module instance: binds it to its cells, runs init, then waits
//! for its schedule's events and steps it, publishing its stats.
//!
//! The step loop is a task of its own that one actor message handler starts and awaits, so a
//! step is a plain function call after a wake-up (no mailbox hop, nor the actor's own layers,
//! on the hot path). ractor still supervises it: a panic or an error ends the actor and reaches
//! the supervisor, and a kill drops the handler, which aborts the task (the running step is
//! dropped at its next poll).

use std::marker::PhantomData;
use std::sync::Arc;
use std::time::Duration;

use ractor::{Actor, ActorProcessingErr, ActorRef};
use tracing::Instrument;

use crate::agent::{AgentControl, ModuleControl};
use crate::blackboard::Blackboard;
use crate::cell::Signal;
use crate::loop_watch::LoopWatch;
use crate::module::{Context, Module, Unrecoverable};
use crate::panic_report::{self, catching};
use crate::ports::{Handle, Ports};
use crate::queue::ReaderEndpoint;
use crate::step_probe::StepMark;
use crate::supervision::LongStepWatch;
use crate::thread_hold::ThreadHold;

mod builtins;
mod event_loop;
mod loops;
mod publish;
mod stats;
mod stop;
mod ticker;

pub use builtins::status;
pub(crate) use builtins::{declare_builtins, Builtins};
use stats::StepStats;
pub(crate) use stop::StopRequest;

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
    /// Taken by the step loop's task when it starts (see `handle`).
    type State = Option<Running<M>>;
    type Arguments = ModuleArgs;

    async fn pre_start(
        &self,
        me: ActorRef<RunLoop>,
        args: ModuleArgs,
    ) -> Result<Option<Running<M>>, ActorProcessingErr> {
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
        let init = catching(&span, module.init(&mut ctx).instrument(span.clone())).await;
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
        Ok(Some(Running {
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
        }))
    }

    async fn post_start(
        &self,
        me: ActorRef<RunLoop>,
        _state: &mut Option<Running<M>>,
    ) -> Result<(), ActorProcessingErr> {
        me.send_message(RunLoop)?;
        Ok(())
    }

    async fn handle(
        &self,
        me: ActorRef<RunLoop>,
        _msg: RunLoop,
        state: &mut Option<Running<M>>,
    ) -> Result<(), ActorProcessingErr> {
        let Some(running) = state.take() else {
            return Ok(()); // one `RunLoop` is sent; a second would find the loop gone
        };
        // The loop is a task of its own on the actor's runtime (the agent's thread, or where
        // `long_steps` put it) rather than polled inside this handler: every wake-up of the
        // module then polls the loop directly, not through the actor's own layers (its select
        // over the kill signal, its `catch_unwind`), a fifth of a hand-over between modules.
        // A kill drops this handler, whose guard aborts the task: as before, the running
        // step is dropped at its next poll.
        let task = tokio::spawn(running.live(me));
        let _abort = AbortOnDrop(task.abort_handle());
        match task.await {
            Ok(outcome) => outcome.map_err(Into::into),
            Err(e) if e.is_panic() => Err(panic_report::message_of(&*e.into_panic()).into()),
            Err(_) => Err("the module's step loop was cancelled".into()),
        }
    }
}

impl<M: Module> Running<M> {
    /// The instance's life after init: its step loop, then (stopped with the agent) its
    /// cleanup in its turn; the failure that ends the actor, if any.
    async fn live(mut self, me: ActorRef<RunLoop>) -> Result<(), String> {
        let span = self.span.clone();
        match failure(catching(&span, self.run().instrument(span.clone())).await) {
            None => {
                // Stopped with the whole agent: clean up in reverse start order, when told.
                self.stop.cleanup_turn().await;
                self.ctx.restarting = self.stop.is_restart();
                let cleanup = catching(
                    &span,
                    self.module.cleanup(&mut self.ctx).instrument(span.clone()),
                )
                .await;
                self.publish(status::STOPPED);
                me.stop(None);
                match failure(cleanup) {
                    None => Ok(()),
                    Some(reason) => Err(format!("cleanup failed: {reason}")),
                }
            }
            Some(reason) => {
                self.publish(status::FAILED);
                Err(reason)
            }
        }
    }
}

/// Aborts a task when dropped: the step loop's task ends with its actor, killed or not.
struct AbortOnDrop(tokio::task::AbortHandle);

impl Drop for AbortOnDrop {
    fn drop(&mut self) {
        self.0.abort();
    }
}
