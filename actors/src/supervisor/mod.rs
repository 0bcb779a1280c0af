//! The agent supervisor actor: the imperative shell around [`crate::supervision`]'s policy.
//!
//! It starts module actors in config order, turns their failures into restart plans (strategy,
//! restart policy, intensity, escalation, backoff), carries the plans out, publishes what it does
//! (traces, `_supervisor/events`, `stats/failures`, `stats/restarts`, `stats/status`), serves
//! runtime control requests, and stops everything in reverse order (all asked at once, cleaned
//! up one by one).

use std::sync::Arc;
use std::time::Duration;

use ractor::{Actor, ActorCell, ActorProcessingErr, ActorRef, RpcReplyPort, SupervisionEvent};
use tokio::task::JoinHandle;
use tokio::time::Instant;

use crate::agent::{AgentControl, ModuleControl};
use crate::blackboard::Blackboard;
use crate::config::{ModuleConfig, Scheduler, StepBudget};
use crate::handle::QueueWriter;
use crate::module_actor::status;
use crate::module_actor::{ModuleArgs, StopRequest};
use crate::module_types::{ModuleRegistry, ModuleType};
use crate::step_probe::StepProbe;
use crate::summary::ModuleReport;
use crate::supervision::{
    Backoff, Intensity, RestartPolicy, Strategy, SupervisionConfig, SupervisorEvent,
};
use crate::thread_hold::ThreadHold;

mod control;
mod restart;
mod stop;

/// Exit code of `petrel run` when the supervisor gives up and stops the agent.
pub const EXIT_GAVE_UP: u8 = 3;

/// One module as the supervisor is told about it.
pub(crate) struct ModuleSpec {
    pub name: String,
    pub module_type: ModuleType,
    pub group: Option<usize>,
    pub policy: RestartPolicy,
    pub watchdog: Option<Duration>,
    pub shutdown_timeout: Duration,
    /// Runs on the shared runtime, not on the agent's thread (`long_steps: true`).
    pub long_steps: bool,
}

/// A supervision group as the supervisor is told about it.
pub(crate) struct GroupSpec {
    pub name: String,
    pub strategy: Strategy,
    pub intensity: Intensity,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SlotState {
    Running,
    /// A restart is scheduled.
    Waiting,
    Stopped,
    Failed,
    /// Removed from the agent; the slot stays so that indices in pending messages stay valid.
    Removed,
}

struct Slot {
    spec: ModuleSpec,
    state: SlotState,
    /// Bumped whenever a scheduled restart must be forgotten.
    generation: u64,
    actor: Option<ActorCell>,
    join: Option<JoinHandle<()>>,
    stop: Arc<StopRequest>,
    backoff: Backoff,
    failures: u64,
    restarts: u64,
    /// Moves off the agent's thread (each starts a new instance, like a restart).
    moves: u64,
    last_error: Option<String>,
    /// Did not stop within its timeout when last stopped.
    killed: bool,
}

impl Slot {
    fn new(spec: ModuleSpec, backoff: crate::supervision::BackoffConfig) -> Self {
        Slot {
            spec,
            state: SlotState::Stopped,
            generation: 0,
            actor: None,
            join: None,
            stop: Arc::default(),
            backoff: Backoff::new(backoff),
            failures: 0,
            restarts: 0,
            moves: 0,
            last_error: None,
            killed: false,
        }
    }
}

pub(crate) struct SupervisorArgs {
    pub types: ModuleRegistry,
    pub agent: Arc<str>,
    pub blackboard: Blackboard,
    pub control: AgentControl,
    pub supervision: SupervisionConfig,
    pub groups: Vec<GroupSpec>,
    pub modules: Vec<ModuleSpec>,
    pub events: QueueWriter<SupervisorEvent>,
    pub probe: StepProbe,
    pub scheduler: Scheduler,
    /// Where modules with `long_steps` are spawned, when the agent's actors run on a thread of
    /// their own: the shared runtime, or the threads `long_steps_nice` puts below the agent's.
    pub shared: Option<tokio::runtime::Handle>,
    /// Modules on the agent's thread whose steps exceed it are moved to `shared`.
    pub step_budget: StepBudget,
    /// Where modules on the agent's thread mark their polls, for the watcher of held threads.
    pub hold: Option<Arc<ThreadHold>>,
}

pub(crate) struct SupervisorState {
    me: ActorRef<SupervisorMsg>,
    types: ModuleRegistry,
    agent: Arc<str>,
    blackboard: Blackboard,
    control: AgentControl,
    config: SupervisionConfig,
    top: Intensity,
    groups: Vec<GroupSpec>,
    slots: Vec<Slot>,
    events: QueueWriter<SupervisorEvent>,
    started: Instant,
    stopping: bool,
    rng: u64,
    probe: StepProbe,
    scheduler: Scheduler,
    shared: Option<tokio::runtime::Handle>,
    step_budget: StepBudget,
    hold: Option<Arc<ThreadHold>>,
}

/// A runtime request about one module.
#[derive(Debug, Clone)]
pub(crate) enum ControlRequest {
    Stop(String),
    Start(String),
    Restart(String),
    Add(Box<ModuleConfig>),
    Remove(String),
}

pub(crate) enum SupervisorMsg {
    /// Stops every module in reverse start order (each within its shutdown timeout, or the given
    /// one), then reports.
    StopAll(Option<Duration>, RpcReplyPort<Vec<ModuleReport>>),
    /// Reports every module's status so far.
    Report(RpcReplyPort<Vec<ModuleReport>>),
    /// Scheduled restarts are due: (slot, generation) pairs.
    Restart(Vec<(usize, u64)>),
    /// A module instance could not be started.
    StartFailed(usize, u64, crate::module_types::SpawnFailure),
    /// Stop, start or restart a module on request.
    Control(ControlRequest, RpcReplyPort<Result<(), String>>),
    /// A module instance on the agent's thread found its mean step above the agent's
    /// `step_budget` (the mean it measured): move it to the shared runtime.
    Move(ractor::ActorId, Duration),
    /// One step of slot `.0`'s module held the agent's thread for over `.1` (seen by the
    /// watcher in `thread_hold.rs`): move it to the shared runtime once the step returned.
    Held(usize, Duration),
}

pub(crate) struct AgentSupervisor;

impl Actor for AgentSupervisor {
    type Msg = SupervisorMsg;
    type State = SupervisorState;
    type Arguments = SupervisorArgs;

    async fn pre_start(
        &self,
        me: ActorRef<SupervisorMsg>,
        args: SupervisorArgs,
    ) -> Result<SupervisorState, ActorProcessingErr> {
        let config = args.supervision;
        let slots = args
            .modules
            .into_iter()
            .map(|spec| Slot::new(spec, config.backoff))
            .collect();
        let seed = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(1, |d| d.as_nanos() as u64);
        let mut state = SupervisorState {
            me,
            types: args.types,
            agent: args.agent,
            blackboard: args.blackboard,
            control: args.control,
            top: Intensity::new(
                config.max_restarts,
                Duration::from_secs_f64(config.within_s),
            ),
            config,
            groups: args.groups,
            slots,
            events: args.events,
            started: Instant::now(),
            stopping: false,
            rng: seed | 1,
            probe: args.probe,
            scheduler: args.scheduler,
            shared: args.shared,
            step_budget: args.step_budget,
            hold: args.hold,
        };
        for i in 0..state.slots.len() {
            state.spawn(i).await;
        }
        tracing::info!(agent = %state.agent, modules = state.slots.len(), "agent started");
        Ok(state)
    }

    async fn handle(
        &self,
        _me: ActorRef<SupervisorMsg>,
        msg: SupervisorMsg,
        state: &mut SupervisorState,
    ) -> Result<(), ActorProcessingErr> {
        match msg {
            SupervisorMsg::StopAll(timeout, reply) => {
                state.stop_all(timeout).await;
                let _ = reply.send(state.report().await);
            }
            SupervisorMsg::Report(reply) => {
                let _ = reply.send(state.report().await);
            }
            SupervisorMsg::Restart(due) => state.restart_now(due).await,
            SupervisorMsg::StartFailed(i, generation, failure) => {
                if state.slots[i].generation == generation {
                    let reason = format!("could not start: {}", failure.reason);
                    match failure.unrecoverable {
                        true => state.on_unrecoverable(i, reason).await,
                        false => state.on_exit(i, true, reason).await,
                    }
                }
            }
            SupervisorMsg::Control(request, reply) => {
                let _ = reply.send(state.control_request(request).await);
            }
            SupervisorMsg::Move(actor, mean) => state.move_to_shared(actor, mean).await,
            SupervisorMsg::Held(slot, held) => state.move_held(slot, held).await,
        }
        Ok(())
    }

    async fn handle_supervisor_evt(
        &self,
        _me: ActorRef<SupervisorMsg>,
        event: SupervisionEvent,
        state: &mut SupervisorState,
    ) -> Result<(), ActorProcessingErr> {
        match event {
            SupervisionEvent::ActorFailed(cell, error) => {
                if let Some(i) = state.slot_of(&cell) {
                    state.on_exit(i, true, error.to_string()).await;
                }
            }
            SupervisionEvent::ActorTerminated(cell, _, _) => {
                if let Some(i) = state.slot_of(&cell) {
                    state.on_exit(i, false, "ended by itself".into()).await;
                }
            }
            _ => {}
        }
        Ok(())
    }
}

impl SupervisorState {
    fn slot_of(&self, cell: &ActorCell) -> Option<usize> {
        self.slots.iter().position(|s| {
            s.actor
                .as_ref()
                .is_some_and(|a| a.get_id() == cell.get_id())
        })
    }

    fn find(&self, name: &str) -> Result<usize, String> {
        self.slots
            .iter()
            .position(|s| s.spec.name == name && s.state != SlotState::Removed)
            .ok_or_else(|| format!("no module `{name}` in agent `{}`", self.agent))
    }

    /// A uniform draw in [0, 1) for backoff jitter (xorshift; quality is not a concern here).
    fn unit(&mut self) -> f64 {
        self.rng ^= self.rng << 13;
        self.rng ^= self.rng >> 7;
        self.rng ^= self.rng << 17;
        (self.rng >> 11) as f64 / (1u64 << 53) as f64
    }

    fn event(&self, module: &str, kind: &str, reason: &str, restarts: u64) {
        let time_s = self.started.elapsed().as_secs_f64();
        self.events.push(SupervisorEvent {
            time_s,
            module: module.into(),
            kind: kind.into(),
            reason: reason.into(),
            restarts: restarts as i64,
        });
    }

    async fn set_stat<T: crate::PropertyType>(&self, i: usize, path: &str, value: T) {
        // The blackboard outlives the modules; if it is gone the agent is stopping anyway.
        let _ = self
            .blackboard
            .set_runtime(&format!("{}/{path}", self.slots[i].spec.name), value)
            .await;
    }

    /// Starts slot `i`'s module; a failure to start comes back as a `StartFailed` message.
    async fn spawn(&mut self, i: usize) {
        let slot = &mut self.slots[i];
        slot.stop = Arc::default();
        slot.killed = false;
        let args = ModuleArgs {
            modules: ModuleControl {
                supervisor: self.me.clone(),
            },
            watchdog: slot.spec.watchdog,
            agent: self.agent.clone(),
            name: slot.spec.name.clone(),
            blackboard: self.blackboard.clone(),
            control: self.control.clone(),
            stop: slot.stop.clone(),
            step_mark: self.probe.mark(&slot.spec.name),
            // Only a module on the agent's own thread can hold up the others.
            step_budget: match (&self.shared, slot.spec.long_steps) {
                (Some(_), false) => Some(self.step_budget),
                _ => None,
            },
            hold: match (&self.hold, slot.spec.long_steps) {
                (Some(hold), false) => {
                    hold.register(i, &slot.spec.name);
                    Some((hold.clone(), i))
                }
                _ => None,
            },
        };
        slot.backoff.started(Instant::now());
        let spawning = slot.spec.module_type.spawn(args, self.me.get_cell());
        // ractor spawns an actor where it is spawned from: a long-step module is spawned from
        // a task on the shared runtime, so that its steps never hold up the agent's thread.
        let spawned = match (&self.shared, slot.spec.long_steps) {
            (Some(shared), true) => crate::agent_thread::run_on(shared, spawning)
                .await
                .unwrap_or_else(|e| {
                    Err(crate::module_types::SpawnFailure {
                        reason: e,
                        unrecoverable: false,
                    })
                }),
            _ => spawning.await,
        };
        match spawned {
            Ok((actor, join)) => {
                slot.actor = Some(actor);
                slot.join = Some(join);
                slot.state = SlotState::Running;
            }
            Err(reason) => {
                slot.state = SlotState::Waiting;
                let _ = self
                    .me
                    .cast(SupervisorMsg::StartFailed(i, slot.generation, reason));
            }
        }
    }

    async fn report(&self) -> Vec<ModuleReport> {
        let mut reports = Vec::with_capacity(self.slots.len());
        for slot in self.slots.iter().filter(|s| s.state != SlotState::Removed) {
            let get = |path: &str| format!("{}/{}", slot.spec.name, path);
            let status = self
                .blackboard
                .get::<String>(&get("stats/status"))
                .await
                .map(|s| s.to_string())
                .unwrap_or_default();
            let status = match slot.killed {
                true => status::KILLED.to_string(),
                false => status,
            };
            let steps = self
                .blackboard
                .get::<i64>(&get("stats/steps"))
                .await
                .map(|s| *s)
                .unwrap_or_default();
            reports.push(ModuleReport {
                name: slot.spec.name.clone(),
                module_type: slot.spec.module_type.name().to_string(),
                status,
                steps: steps as u64,
                failures: slot.failures,
                restarts: slot.restarts,
                moves: slot.moves,
                last_error: slot.last_error.clone(),
            });
        }
        reports
    }
}
