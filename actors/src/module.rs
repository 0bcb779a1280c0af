//! The [`Module`] trait: what a functional module (driver, localizer, planner...) implements.
//!
//! Lifecycle of one instance: [`declare`](Module::declare) its properties (type, default, doc)
//! → the runtime applies config values and links → [`init`](Module::init) (may open
//! resources, may fail cleanly) → [`step`](Module::step) each time an event of its
//! [`Schedule`] occurs → [`cleanup`](Module::cleanup) when the agent stops.
//! A module never names another module: it only reads and writes its own properties, and the
//! configuration links them.

use std::future::Future;
use std::sync::Arc;
use std::time::Duration;

use tokio::time::Instant;

use crate::agent::{AgentControl, ModuleControl};
use crate::blackboard::Blackboard;
use crate::cell::{cause, Endpoint};
use crate::handle::{AnyHandle, Input, Output, QueueReader};
use crate::ports::Ports;
use crate::queue::ReaderEndpoint;
use crate::step_clock::StepClock;
use crate::types::PropertyType;

/// A functional module. Each instance runs as a supervised actor of its agent.
///
/// ```
/// use petrel_actors::{Context, Input, Module, Output, Ports, Schedule};
///
/// /// Doubles its input.
/// struct Double { input: Input<f64>, out: Output<f64> }
///
/// impl Module for Double {
///     const TYPE: &'static str = "example.double";
///     const DESCRIPTION: &'static str = "Writes twice its input.";
///     fn declare(ports: &mut Ports) -> Self {
///         Double {
///             input: ports.input("in/value", 0.0, "value to double"),
///             out: ports.output("out/value", 0.0, "twice in/value"),
///         }
///     }
///     fn schedule(&self) -> Schedule {
///         Schedule::new().on_change(&self.input)
///     }
///     async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
///         self.out.set(2.0 * self.input.value());
///         Ok(())
///     }
/// }
/// ```
pub trait Module: Send + Sized + 'static {
    /// The type name configs use, e.g. `demo.scale`.
    const TYPE: &'static str;
    /// One line saying what the module does, for `petrel modules`.
    const DESCRIPTION: &'static str;

    /// Declares the module's properties and builds the instance from their handles.
    ///
    /// Must not do I/O or depend on anything but `ports`: it also runs to describe the type
    /// and to check configs. Mistakes (bad paths, duplicates) are reported by the runtime.
    fn declare(ports: &mut Ports) -> Self;

    /// The events that make the module step; asked after [`init`](Module::init), and again
    /// when a step calls [`Context::reschedule`].
    fn schedule(&self) -> Schedule;

    /// Checks, before anything runs, what [`init`](Module::init) will read from the configured
    /// values (a world file that must parse, a range two parameters must respect): `petrel
    /// check` and `petrel run` call it on an instance declared over the config's values, and
    /// report each problem at the property it names, in the config file. `agent` tells the
    /// other modules of the agent, for parameters that name them. Must not have side effects.
    /// The default finds nothing.
    fn check(&self, _agent: &AgentView) -> Vec<CheckProblem> {
        Vec::new()
    }

    /// What makes this module wake itself, said when the runtime finds it re-triggering
    /// itself without progress (e.g. the context rule whose change undoes its own condition).
    /// The runtime already names the link cycle, if there is one.
    fn loop_hint(&self) -> Option<String> {
        None
    }

    /// Prepares the module after config values and links are in place; an error stops it
    /// cleanly. Return an [`Unrecoverable`] error for what a restart cannot fix (a file that
    /// does not parse): the supervisor then reports it once and does not restart the module.
    fn init(&mut self, _ctx: &mut Context) -> impl Future<Output = anyhow::Result<()>> + Send {
        async { Ok(()) }
    }

    /// Does one unit of work. An error (or a panic) is a module failure.
    fn step(&mut self, ctx: &mut Context) -> impl Future<Output = anyhow::Result<()>> + Send;

    /// Releases resources when the module instance stops: the agent stops, the module is
    /// stopped on request, or it is restarted or moved ([`Context::restarting`] tells which).
    fn cleanup(&mut self, _ctx: &mut Context) -> impl Future<Output = anyhow::Result<()>> + Send {
        async { Ok(()) }
    }
}

/// A problem [`Module::check`] found in a configured value.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CheckProblem {
    /// The property it is about (`params/world`), where the config file is pointed at.
    pub path: String,
    /// What is wrong and what was expected.
    pub message: String,
}

impl CheckProblem {
    /// A problem with the value of `path`.
    pub fn new(path: &str, message: impl Into<String>) -> Self {
        CheckProblem {
            path: path.into(),
            message: message.into(),
        }
    }
}

/// What [`Module::check`] may see of the rest of its agent: the modules the config declares.
pub struct AgentView<'a> {
    registry: &'a crate::Registry,
}

impl<'a> AgentView<'a> {
    pub(crate) fn new(registry: &'a crate::Registry) -> Self {
        AgentView { registry }
    }

    /// The type of the agent's module `name` (`sim.body`), if the agent has one of that name.
    pub fn module_type(&self, name: &str) -> Option<&'a str> {
        self.registry.module_type(name)
    }

    /// The agent's module names, in config order.
    pub fn modules(&self) -> &'a [String] {
        self.registry.modules()
    }

    /// Why `names` (a parameter's list of modules) is not a list of this agent's modules, each
    /// once and of type `want` (any type when `None`); see [`module_names_problem`].
    pub fn names_problem(&self, names: &[&str], want: Option<&str>) -> Option<String> {
        module_names_problem(names, want, |name| self.module_type(name))
    }
}

/// Why `names` (a parameter's list of modules: a world's bodies, chaos targets) is not a list
/// of an agent's modules, each once and of type `want` (any type when `None`), given the type
/// of each module the agent has (`type_of`). One message for `petrel check` and for a
/// module's `init`, which asks the running agent.
pub fn module_names_problem<'t>(
    names: &[&str],
    want: Option<&str>,
    type_of: impl Fn(&str) -> Option<&'t str>,
) -> Option<String> {
    let expected = match want {
        Some(t) => format!("{t} modules"),
        None => "this agent's modules".to_string(),
    };
    for (i, name) in names.iter().enumerate() {
        if names[..i].contains(name) {
            return Some(format!("`{name}` is named twice; expected each once"));
        }
        match (type_of(name), want) {
            (None, _) => {
                return Some(format!(
                    "this agent has no module `{name}`; expected the names of {expected}"
                ))
            }
            (Some(t), Some(want)) if t != want => {
                return Some(format!("`{name}` is a {t}, expected a {want} module"))
            }
            _ => {}
        }
    }
    None
}

/// An error from [`Module::init`] that a restart cannot fix: the module is reported failed
/// once and not restarted (restarting would fail the same way, in a loop).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct Unrecoverable(pub String);

/// Something a module can wait on: an input, parameter or output (a change of its value),
/// or a queue reader (new items).
pub trait Watchable {
    #[doc(hidden)]
    fn watch(&self) -> Watch;
}

/// What a [`Watchable`] hands to a [`Schedule`]; opaque.
#[derive(Clone)]
pub struct Watch(pub(crate) WatchTarget);

#[derive(Clone)]
pub(crate) enum WatchTarget {
    Value(Arc<Endpoint>),
    Queue(Arc<ReaderEndpoint>),
}

impl<T: PropertyType> Watchable for Input<T> {
    fn watch(&self) -> Watch {
        Watch(WatchTarget::Value(self.ep.clone()))
    }
}

impl<T: PropertyType> Watchable for Output<T> {
    fn watch(&self) -> Watch {
        Watch(WatchTarget::Value(self.ep.clone()))
    }
}

impl Watchable for AnyHandle {
    fn watch(&self) -> Watch {
        Watch(WatchTarget::Value(self.ep.clone()))
    }
}

impl<T: PropertyType> Watchable for QueueReader<T> {
    fn watch(&self) -> Watch {
        Watch(WatchTarget::Queue(self.reader.clone()))
    }
}

/// When a module steps: any combination of a period, changes of properties, new queue items,
/// and a timeout. With none of them the module steps only once, right after init.
#[derive(Clone, Default)]
pub struct Schedule {
    pub(crate) period: Option<Duration>,
    pub(crate) timeout: Option<Duration>,
    pub(crate) watchdog: Option<Duration>,
    pub(crate) watches: Vec<Watch>,
}

impl Schedule {
    /// An empty schedule.
    pub fn new() -> Self {
        Schedule::default()
    }

    /// A schedule that steps every `period`.
    pub fn every(period: Duration) -> Self {
        Schedule::new().period(period)
    }

    /// Steps every `period`, on a fixed grid from the start (no drift); ticks missed while a
    /// step ran late are skipped, not bunched up.
    pub fn period(mut self, period: Duration) -> Self {
        self.period = Some(period.max(Duration::from_micros(1)));
        self
    }

    /// Steps when the value seen through `property` changes, or when the queue has new items.
    pub fn on_change(mut self, property: &impl Watchable) -> Self {
        self.watches.push(property.watch());
        self
    }

    /// Steps when `queue` has new items (same as [`on_change`](Schedule::on_change)).
    pub fn on_items<T: PropertyType>(self, queue: &QueueReader<T>) -> Self {
        self.on_change(queue)
    }

    /// Declares that a step never takes longer than `deadline`: a step that does is a failure
    /// (a hang): it is dropped and the module restarted. A config's `watchdog_ms` overrides it.
    /// (An async step is dropped at its next `.await`; a step that blocks its thread cannot be
    /// interrupted, so steps must not block: use `tokio::task::spawn_blocking` for heavy work.)
    pub fn watchdog(mut self, deadline: Duration) -> Self {
        self.watchdog = Some(deadline);
        self
    }

    /// Steps when nothing else made the module step for `timeout`.
    pub fn timeout(mut self, timeout: Duration) -> Self {
        self.timeout = Some(timeout);
        self
    }
}

/// Why a step runs: one or more of the schedule's events.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Cause(pub(crate) u8);

impl Cause {
    /// The period elapsed.
    pub fn period(self) -> bool {
        self.0 & cause::PERIOD != 0
    }
    /// A watched property changed.
    pub fn changed(self) -> bool {
        self.0 & cause::CHANGE != 0
    }
    /// A watched queue has new items.
    pub fn items(self) -> bool {
        self.0 & cause::ITEMS != 0
    }
    /// The timeout elapsed with no other event.
    pub fn timeout(self) -> bool {
        self.0 & cause::TIMEOUT != 0
    }
    /// The first step after init, whatever the schedule.
    pub fn first(self) -> bool {
        self.0 == 0
    }
}

/// What the runtime tells a module while it runs.
pub struct Context {
    pub(crate) modules: ModuleControl,
    pub(crate) blackboard: Blackboard,
    pub(crate) control: AgentControl,
    pub(crate) agent: Arc<str>,
    pub(crate) module: Arc<str>,
    pub(crate) cause: Cause,
    /// Steps in a row that led to this one through writes (see `loop_watch.rs`).
    pub(crate) hops: u32,
    pub(crate) steps: u64,
    /// The step time, shared with the module's output handles.
    pub(crate) clock: Arc<StepClock>,
    pub(crate) reschedule: bool,
    pub(crate) restarting: bool,
    /// What [`Context::settle`] needs (see `settle.rs`).
    pub(crate) settle: crate::settle::Settle,
}

impl Context {
    pub(crate) fn new(
        agent: &str,
        module: &str,
        modules: ModuleControl,
        blackboard: Blackboard,
        control: AgentControl,
        clock: Arc<StepClock>,
    ) -> Self {
        Context {
            modules,
            blackboard,
            control,
            agent: agent.into(),
            module: module.into(),
            hops: 0,
            cause: Cause(0),
            steps: 0,
            clock,
            reschedule: false,
            restarting: false,
            settle: Default::default(),
        }
    }

    /// The agent's blackboard: to look up other properties by address ([`Blackboard::any_handle`],
    /// [`Blackboard::handle`]), set them, or relink while running. Each call is a message to the
    /// blackboard actor: keep it out of hot loops; keep the handles it returns instead.
    pub fn blackboard(&self) -> &Blackboard {
        &self.blackboard
    }

    /// Stop, start, restart, add and remove the agent's modules (for mission and context layers).
    pub fn modules(&self) -> &ModuleControl {
        &self.modules
    }

    /// Asks the runtime to apply [`Module::schedule`] again after this step, e.g. when the
    /// module has started watching other properties (new watches are added; old ones stay).
    pub fn reschedule(&mut self) {
        self.reschedule = true;
    }

    /// Asks the agent to stop: `petrel run` then stops every module and exits with `code`
    /// (0 = success), printing `reason`. For modules that decide when a run is over (a mission).
    pub fn stop_agent(&self, code: u8, reason: impl Into<String>) {
        self.control.stop(code, reason.into());
    }

    /// The agent this module runs in.
    pub fn agent(&self) -> &str {
        &self.agent
    }

    /// This module instance's name.
    pub fn module(&self) -> &str {
        &self.module
    }

    /// In [`Module::cleanup`]: whether this instance stops only to be started again at once
    /// (a supervisor's restart, a restart on request, or a move off the agent's thread), so a
    /// module that prints a summary at the end of a run prints it only when the run ends.
    /// False when the agent stops or the module is stopped on request, and outside `cleanup`.
    pub fn restarting(&self) -> bool {
        self.restarting
    }

    /// Whether this step is part of a loop: the last of thousands of steps in a row, each woken
    /// by the previous one's writes, with no tick, timeout or outside write between them. The
    /// runtime reports such a loop itself; a module that logs at every step should log less.
    pub fn in_a_loop(&self) -> bool {
        self.hops >= crate::loop_watch::LOOP_HOPS
    }

    /// Why this step runs.
    pub fn cause(&self) -> Cause {
        self.cause
    }

    /// How many steps ran before this one, since the instance started.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The step's time (tokio time: follows a paused test clock): read from the clock once per
    /// step, when first needed, and the same for everything the step writes (values and queue
    /// items are stamped with it). Outside a step (in `init`, `cleanup`) it is the current time.
    pub fn now(&self) -> Instant {
        self.clock.now()
    }
}
