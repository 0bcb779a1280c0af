//! Agent assembly: from a checked config to a running blackboard, supervisor and modules.

use std::sync::Arc;
use std::time::Duration;

use ractor::{Actor, ActorRef};
use tokio::task::JoinHandle;

use crate::agent_thread::AgentThread;
use crate::blackboard::Blackboard;
use crate::config::{ConfigErrors, ConfigFile, ModuleConfig, Scheduler};
use crate::module_types::ModuleRegistry;
use crate::step_probe::StepProbe;
use crate::summary::RunSummary;
use crate::supervision::Intensity;
use crate::supervisor::{
    AgentSupervisor, ControlRequest, GroupSpec, ModuleSpec, SupervisorArgs, SupervisorMsg,
};
use crate::thread_hold::HoldWatcher;

/// How long a module gets to finish its step and cleanup when the agent stops, before it is killed.
pub const DEFAULT_STOP_TIMEOUT: Duration = Duration::from_secs(5);

/// Why an agent did not start.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    /// The config has errors; nothing was started.
    #[error("{0}")]
    Config(#[from] ConfigErrors),
    /// An actor could not be spawned.
    #[error("could not start the agent: {0}")]
    Spawn(String),
}

/// The exit code a module gives [`Context::stop_agent`](crate::Context::stop_agent) to make
/// its agent die, as `kill -9` of its process would (128 + 9, what a shell reports for such a
/// process): `petrel run` drops a dying agent's team membership without a goodbye and stops
/// its modules, and the other agents of the run go on; an agent alone in its process ends the
/// process at once with this code. Fault scenarios (`sim.fault`) use it.
pub const EXIT_DIED: u8 = 137;

/// Why an agent's run should end, as requested by one of its modules or its supervisor.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AgentExit {
    /// Process exit code for `petrel run` (0 = success).
    pub code: u8,
    /// What happened, for people.
    pub reason: String,
}

/// Lets modules and the supervisor ask for the end of the run; the first request wins.
#[derive(Clone)]
pub(crate) struct AgentControl {
    exit: Arc<tokio::sync::watch::Sender<Option<AgentExit>>>,
}

impl AgentControl {
    pub fn new() -> Self {
        AgentControl {
            exit: Arc::new(tokio::sync::watch::channel(None).0),
        }
    }

    pub fn stop(&self, code: u8, reason: String) {
        self.exit.send_if_modified(|exit| {
            if exit.is_some() {
                return false;
            }
            tracing::info!(code, %reason, "agent stop requested");
            *exit = Some(AgentExit { code, reason });
            true
        });
    }
}

/// A running agent: one blackboard, one supervisor, its modules.
pub struct Agent {
    control: AgentControl,
    probe: StepProbe,
    name: String,
    blackboard: Blackboard,
    supervisor: ActorRef<SupervisorMsg>,
    joins: Vec<JoinHandle<()>>,
    /// Where its actors run under `scheduler: agent_thread`; ends with the agent.
    thread: Option<AgentThread>,
}

impl Agent {
    /// Checks `config` against `types` and, if it is sound, starts the agent: the blackboard
    /// with every property, value and link in place, then each module in config order.
    pub async fn start(config: &ConfigFile, types: &ModuleRegistry) -> Result<Agent, StartError> {
        Self::start_without(config, types, &[]).await
    }

    /// Like [`start`](Agent::start), but the modules named in `not_started` are declared (their
    /// properties exist, links to them hold) and never started: a replay publishes their
    /// outputs in their place.
    pub async fn start_without(
        config: &ConfigFile,
        types: &ModuleRegistry,
        not_started: &[String],
    ) -> Result<Agent, StartError> {
        Self::prepare(config, types, not_started)
            .await?
            .start()
            .await
    }

    /// The first half of [`start_without`](Agent::start_without): the blackboard runs with
    /// every property, value and link in place, and no module has started yet. What must see
    /// every write from the first step on (a recorder's taps) attaches to
    /// [`PreparedAgent::blackboard`]; then [`PreparedAgent::start`] starts the modules.
    pub async fn prepare(
        config: &ConfigFile,
        types: &ModuleRegistry,
        not_started: &[String],
    ) -> Result<PreparedAgent, StartError> {
        // A module's panic is then one ERROR event in its span, not a print beside the log.
        crate::panic_report::install();
        let registry = config.build(types)?;
        let events = registry.events_writer();
        let hold_events = registry.events_writer();
        let cfg = &config.config;
        // The clock counts from the first agent's start, and, before any module reads it, a
        // resumed agent's time goes on from its snapshot.
        crate::expr::start_wall_clock();
        if let Some(secs) = cfg.clock_s {
            crate::expr::continue_from(secs);
        }
        let ms = Duration::from_millis;
        let groups = cfg
            .groups
            .iter()
            .map(|g| GroupSpec {
                name: g.name.clone(),
                strategy: g.strategy,
                intensity: Intensity::new(g.max_restarts, Duration::from_secs_f64(g.within_s)),
            })
            .collect();
        let modules = cfg
            .modules
            .iter()
            .filter(|m| !not_started.contains(&m.name))
            .filter_map(|m| {
                Some(ModuleSpec {
                    name: m.name.clone(),
                    module_type: *types.get(&m.type_name)?,
                    group: m
                        .group
                        .as_ref()
                        .and_then(|g| cfg.groups.iter().position(|x| &x.name == g)),
                    policy: m.restart,
                    watchdog: m.watchdog_ms.map(ms),
                    shutdown_timeout: ms(m
                        .shutdown_timeout_ms
                        .unwrap_or(cfg.supervision.shutdown_timeout_ms)),
                    long_steps: m.long_steps,
                })
            })
            .collect();
        let name = cfg.name.clone();
        let thread = match cfg.scheduler {
            Scheduler::Shared => None,
            Scheduler::AgentThread => AgentThread::start(&name, cfg.realtime_priority)
                .map_err(|e| StartError::Spawn(format!("the agent's thread: {e}")))?,
        };
        // Actors run on the runtime they are spawned from: the agent's thread, if it has one.
        let spawned = match &thread {
            Some(thread) => thread.run(Blackboard::spawn(registry)).await,
            None => Ok(Blackboard::spawn(registry).await),
        };
        let (blackboard, bb_join) = spawned
            .map_err(StartError::Spawn)?
            .map_err(|e| StartError::Spawn(e.to_string()))?;
        // Where its long-step modules run: the shared runtime, or threads below the agent's.
        let long_steps_runtime = match (&thread, cfg.long_steps_nice) {
            (Some(thread), Some(offset)) => Some(
                crate::long_step_threads::runtime(offset, &thread.shared())
                    .map_err(StartError::Spawn)?,
            ),
            (Some(thread), None) => Some(thread.shared()),
            (None, _) => None,
        };
        // Only an agent's own thread can be held by one module for all the others.
        let hold_watcher = match (&thread, cfg.step_budget.held_ms) {
            (Some(_), held_ms) if held_ms > 0 => Some(HoldWatcher {
                hold: Arc::default(),
                held: ms(held_ms),
                events: hold_events,
                agent: Arc::from(name.as_str()),
            }),
            _ => None,
        };
        let control = AgentControl::new();
        let probe = StepProbe::default();
        let args = SupervisorArgs {
            types: types.clone(),
            agent: Arc::from(name.as_str()),
            blackboard: blackboard.clone(),
            control: control.clone(),
            supervision: cfg.supervision.clone(),
            groups,
            modules,
            events,
            probe: probe.clone(),
            scheduler: cfg.scheduler,
            shared: long_steps_runtime,
            step_budget: cfg.step_budget,
            hold: hold_watcher.as_ref().map(|w| w.hold.clone()),
        };
        Ok(PreparedAgent {
            pending: Some((args, bb_join)),
            blackboard,
            thread,
            hold_watcher,
        })
    }

    /// Waits until a module (e.g. a mission that reached its goal) or the supervisor asks for
    /// the run to end, and says why. Pending forever if nobody asks.
    pub async fn finished(&self) -> AgentExit {
        let mut rx = self.control.exit.subscribe();
        let exit = rx
            .wait_for(Option::is_some)
            .await
            .ok()
            .and_then(|exit| exit.clone());
        match exit {
            Some(exit) => exit,
            // The sender lives in `self`, so this cannot happen while the agent exists.
            None => std::future::pending().await,
        }
    }

    /// Runtime control of this agent's modules (stop, start, restart while running).
    pub fn modules(&self) -> ModuleControl {
        ModuleControl {
            supervisor: self.supervisor.clone(),
        }
    }

    /// The agent's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Which of the agent's modules are inside a step, readable from any thread (a stop
    /// watchdog names with it the modules that hold their threads).
    pub fn step_probe(&self) -> StepProbe {
        self.probe.clone()
    }

    /// The agent's blackboard, to read, set and relink properties while it runs.
    pub fn blackboard(&self) -> &Blackboard {
        &self.blackboard
    }

    /// How every module is doing right now.
    pub async fn summary(&self) -> RunSummary {
        let modules = ractor::call!(self.supervisor, SupervisorMsg::Report).unwrap_or_default();
        RunSummary {
            agent: self.name.clone(),
            modules,
        }
    }

    /// The whole blackboard as RON config text (see [`crate::snapshot`](crate#snapshots)).
    pub async fn snapshot(&self) -> Result<String, crate::BlackboardError> {
        self.blackboard.snapshot().await
    }

    /// Stops every module in reverse start order (running their cleanup, killing any that takes
    /// longer than `timeout`), and reports how each fared. The blackboard stays readable
    /// (e.g. for a snapshot) until [`shutdown`](Agent::shutdown).
    pub async fn stop_modules(&self, timeout: impl Into<Option<Duration>>) -> RunSummary {
        let timeout = timeout.into();
        let modules =
            ractor::call!(self.supervisor, SupervisorMsg::StopAll, timeout).unwrap_or_default();
        RunSummary {
            agent: self.name.clone(),
            modules,
        }
    }

    /// Stops the supervisor and the blackboard (after [`stop_modules`](Agent::stop_modules)).
    pub async fn shutdown(self) {
        self.supervisor.stop(None);
        self.blackboard.stop();
        for join in self.joins {
            let _ = join.await;
        }
        drop(self.thread);
        // A panic's backtrace is written from a thread of its own: written before the agent
        // is said to be stopped, so a process ending now does not lose it.
        if crate::panic_report::pending() {
            let _ = tokio::task::spawn_blocking(crate::panic_report::flush).await;
        }
        tracing::info!(agent = %self.name, "agent stopped");
    }

    /// Stops the modules, then the agent; reports how each module fared.
    pub async fn stop(self, timeout: impl Into<Option<Duration>>) -> RunSummary {
        let summary = self.stop_modules(timeout).await;
        self.shutdown().await;
        summary
    }
}

/// An agent whose blackboard runs and whose modules have not started (see
/// [`Agent::prepare`]). Dropped without [`start`](PreparedAgent::start), it stops its blackboard.
pub struct PreparedAgent {
    pending: Option<(SupervisorArgs, JoinHandle<()>)>,
    blackboard: Blackboard,
    thread: Option<AgentThread>,
    hold_watcher: Option<HoldWatcher>,
}

impl PreparedAgent {
    /// The agent's blackboard, already holding every property.
    pub fn blackboard(&self) -> &Blackboard {
        &self.blackboard
    }

    /// Starts the supervisor, which starts each module in config order.
    pub async fn start(mut self) -> Result<Agent, StartError> {
        let (args, bb_join) = self.pending.take().expect("started once");
        let control = args.control.clone();
        let probe = args.probe.clone();
        let name = args.agent.to_string();
        let spawn = Actor::spawn(None, AgentSupervisor, args);
        let spawned = match &self.thread {
            Some(thread) => thread
                .run(spawn)
                .await
                .and_then(|r| r.map_err(|e| e.to_string())),
            None => spawn.await.map_err(|e| e.to_string()),
        };
        let (supervisor, sup_join) = match spawned {
            Ok(spawned) => spawned,
            Err(e) => {
                self.blackboard.stop();
                return Err(StartError::Spawn(e));
            }
        };
        if let Some(watcher) = self.hold_watcher.take() {
            crate::thread_hold::watch(watcher, supervisor.clone());
        }
        Ok(Agent {
            control,
            probe,
            name,
            blackboard: self.blackboard.clone(),
            supervisor,
            joins: vec![sup_join, bb_join],
            thread: self.thread.take(),
        })
    }
}

impl Drop for PreparedAgent {
    fn drop(&mut self) {
        if self.pending.is_some() {
            self.blackboard.stop();
        }
    }
}

/// Stops, starts and restarts an agent's modules while it runs (for tools, plans and contexts).
#[derive(Clone)]
pub struct ModuleControl {
    pub(crate) supervisor: ActorRef<SupervisorMsg>,
}

impl ModuleControl {
    async fn request(&self, request: ControlRequest) -> Result<(), String> {
        match ractor::call!(self.supervisor, SupervisorMsg::Control, request) {
            Ok(result) => result,
            Err(e) => Err(format!("the agent supervisor is not answering: {e}")),
        }
    }

    /// Stops module `name` (cleanup runs); it stays stopped until started again.
    pub async fn stop(&self, name: &str) -> Result<(), String> {
        self.request(ControlRequest::Stop(name.into())).await
    }

    /// Starts module `name` again after a stop; it finds its properties as it left them.
    pub async fn start(&self, name: &str) -> Result<(), String> {
        self.request(ControlRequest::Start(name.into())).await
    }

    /// Adds a module instance while the agent runs (elasticity): its properties are declared,
    /// its values and links applied (all checked as in a config), then it starts.
    pub async fn add(&self, config: ModuleConfig) -> Result<(), String> {
        self.request(ControlRequest::Add(Box::new(config))).await
    }

    /// Stops module `name` and removes it and its properties; refused while other properties
    /// link into it (unlink them first).
    pub async fn remove(&self, name: &str) -> Result<(), String> {
        self.request(ControlRequest::Remove(name.into())).await
    }

    /// Stops and starts module `name` (counted in its `stats/restarts`).
    pub async fn restart(&self, name: &str) -> Result<(), String> {
        self.request(ControlRequest::Restart(name.into())).await
    }
}
