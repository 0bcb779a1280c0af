//! The `context.manager` module: the imperative shell around [`Engine`].
//!
//! It loads the rules file, looks up every property the rules read or change, feeds changed
//! values to the engine (only the expressions reading them are evaluated again), and carries
//! out the engine's actions: writing parameters, relinking inputs, starting and stopping
//! modules, and restoring what it changed when a context ends. Every activation and
//! deactivation is traced and pushed to `out/changes`; `out/active` lists the active contexts.

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use std::time::Duration;

use anyhow::anyhow;
use petrel_actors::expr::{Clock, PropId};
use petrel_actors::{
    AnyHandle, AnyValue, Context, FilePath, Input, Module, Output, Param, Ports, PropertyType,
    QueueWriter, Range, Schedule, TypeInfo,
};
use serde::{Deserialize, Serialize};
use tokio::time::Instant;

use crate::engine::{Action, Engine, Schema};
use crate::rules::{LoadedRules, RuleError};
use targets::Targets;

mod apply;
mod check;
mod memory;
mod targets;

pub use check::check_rules;
pub use memory::ContextMemory;

/// One context activation or deactivation, as pushed to `out/changes`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContextChange {
    /// Seconds since the manager started.
    pub time_s: f64,
    /// The context.
    pub context: String,
    /// Whether it became active.
    pub active: bool,
}

impl PropertyType for ContextChange {
    const TYPE_NAME: &'static str = "ContextChange";
}

/// The handles looked up for a rules file, by address: looked up at every effect applied, so
/// hashed with a fast hasher.
type Handles = foldhash::HashMap<Arc<str>, AnyHandle>;

/// The handles looked up for a rules file, as the engine's schema.
impl<S: std::hash::BuildHasher> Schema for HashMap<Arc<str>, AnyHandle, S> {
    fn property(&self, path: &str) -> Option<(TypeInfo, AnyValue)> {
        self.get(path).map(|h| (h.type_info(), h.value()))
    }

    fn refuses(&self, path: &str, value: &AnyValue) -> Option<String> {
        let handle = self.get(path)?;
        handle.check(value).err().map(|e| e.to_string())
    }
}

/// A property the rules read: its id in the engine, its handle, and the last version fed.
struct Watched {
    prop: PropId,
    handle: AnyHandle,
    seen: u64,
}

/// `context.manager`: runs a context rules file in an agent.
pub struct ContextManager {
    rules: Param<FilePath>,
    tick_ms: Param<i64>,
    reload: Param<i64>,
    active: Output<String>,
    errors: Output<String>,
    evaluations: Output<i64>,
    changes: QueueWriter<ContextChange>,
    engine: Option<Engine>,
    /// Properties the rules read.
    watched: Vec<Watched>,
    /// Every property the rules mention, by address.
    handles: Handles,
    /// The properties the rules set, with their values from before (see `targets.rs`).
    targets: Targets,
    /// What the rules relinked and started or stopped, as it was before. In address order,
    /// so `state/memory` lists them the same way at every save.
    original_links: BTreeMap<Arc<str>, Option<String>>,
    original_runs: BTreeMap<Arc<str>, bool>,
    /// `state/memory`: what a restarted manager goes on from.
    memory: Output<ContextMemory>,
    /// The `out/active` text published two switches ago, to fill in place.
    active_spare: Option<Arc<String>>,
    /// The `out/active` text published last, with the version of the output it left.
    active_shown: Option<(Arc<String>, u64)>,
    /// The engine's actions, a buffer reused from step to step.
    actions: Vec<Action>,
    /// When `out/evaluations` was last written.
    evaluations_at: Option<Instant>,
    /// The memory published two saves ago, to fill in place (see `save_memory`).
    spare: Option<Arc<ContextMemory>>,
    reload_seen: u64,
    /// The rules file the engine runs, once one loaded: what `params/rules` is put back to
    /// when a reload is refused.
    running_rules: Option<FilePath>,
    started: Option<Instant>,
    /// Contexts whose changes reach their own condition, to name in a loop report.
    self_undoing: Vec<crate::lint::SelfUndoing>,
    /// The context that switched last, to name in a loop report.
    last_switched: Option<Arc<str>>,
    /// Declared so configs can link it to the agent's clock (see `clock`).
    _clock_input: Input<f64>,
    /// The time conditions run on: `in/clock` when linked (a simulator's `out/simTime`, the
    /// same clock as the agent's missions), else wall time.
    clock: Clock,
}

impl Module for ContextManager {
    const TYPE: &'static str = "context.manager";
    const DESCRIPTION: &'static str =
        "Runs context rules: adapts parameters, links and modules to the detected context.";

    fn declare(ports: &mut Ports) -> Self {
        ContextManager {
            rules: ports.param(
                "params/rules",
                FilePath::default(),
                "the context rules file (RON), relative to the config file",
            ),
            tick_ms: ports.param_in(
                "params/tick_ms",
                50,
                Range::new(1.0, 3.6e6),
                "period for time-based conditions (held, age, min_dwell_ms), ms",
            ),
            reload: ports.param(
                "params/reload",
                0,
                "change it (e.g. increment) to re-read the rules file",
            ),
            active: ports.output(
                "out/active",
                String::new(),
                "active contexts, highest priority first",
            ),
            errors: ports.output(
                "out/errors",
                String::new(),
                "problems of the last (re)load, one per line",
            ),
            evaluations: ports.output("out/evaluations", 0, "expression evaluations so far (a statistic: written at most every 100 ms, and when the manager stops)"),
            changes: ports.queue_out("out/changes", 256, "context activations and deactivations"),
            engine: None,
            watched: Vec::new(),
            handles: Handles::default(),
            targets: Targets::default(),
            original_links: BTreeMap::new(),
            original_runs: BTreeMap::new(),
            memory: ports.state(
                "state/memory",
                ContextMemory::default(),
                "the active contexts, what they changed and what was there before: a restarted manager goes on from here",
            ),
            spare: None,
            active_spare: None,
            active_shown: None,
            actions: Vec::new(),
            evaluations_at: None,
            reload_seen: 0,
            running_rules: None,
            started: None,
            self_undoing: Vec::new(),
            last_switched: None,
            _clock_input: ports.input(
                "in/clock",
                0.0,
                "the agent's clock in seconds (link it to a simulator's out/simTime); unlinked: wall time",
            ),
            clock: Clock::Wall,
        }
    }

    fn schedule(&self) -> Schedule {
        // Changes wake the manager; a period is added only when time alone can switch a context.
        let timed = self.engine.as_ref().is_some_and(Engine::uses_time);
        let schedule = match timed {
            true => Schedule::every(Duration::from_millis(self.tick_ms.value().max(1) as u64)),
            false => Schedule::new(),
        };
        let schedule = schedule.on_change(&self.reload);
        self.watched
            .iter()
            .fold(schedule, |s, w| s.on_change(&w.handle))
    }

    fn loop_hint(&self) -> Option<String> {
        let context = self.last_switched.as_deref()?;
        Some(
            match self.self_undoing.iter().find(|s| s.context == context) {
                Some(found) => found.message(),
                None => format!("context `{context}` switched last"),
            },
        )
    }

    async fn init(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        self.started = Some(ctx.now());
        self.clock = Clock::of_module(ctx.blackboard(), ctx.module()).await;
        self.reload_seen = self.reload.read().version;
        let engine = self
            .load(ctx)
            .await
            .map_err(|errors| anyhow!("context rules rejected:\n{errors}"))?;
        self.engine = Some(engine);
        self.resume_memory(ctx).await;
        self.publish_active();
        Ok(())
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        // The version alone, read without a lock: a reload is rare.
        let reload = self.reload.version();
        if reload != self.reload_seen {
            self.reload_seen = reload;
            self.reload_rules(ctx).await;
        }
        let Some(engine) = self.engine.as_mut() else {
            return Ok(());
        };
        let first = ctx.cause().first();
        let stamp = ctx.now();
        let now = self.clock.now(stamp);
        let wall = self.clock.is_wall();
        for w in &mut self.watched {
            if w.handle.version() != w.seen || first {
                let sample = w.handle.read();
                w.seen = sample.version;
                // On another clock than wall time, a write counts from when it was seen.
                let written = if wall { sample.written } else { now };
                engine.update_prop(w.prop, w.handle.type_info(), &sample.value, written);
            }
        }
        // The actions buffer is reused from step to step (taken while `apply` borrows self).
        let mut actions = std::mem::take(&mut self.actions);
        engine.step_into(now, &mut actions);
        let evaluations = engine.evaluations() as i64;
        let mut switched = false;
        for action in &actions {
            switched |= matches!(action, Action::Activated(_) | Action::Deactivated(_));
            self.apply(ctx, action).await;
        }
        if switched {
            self.publish_active();
        }
        // Only actions change what is switched, applied or saved.
        if !actions.is_empty() {
            self.save_memory();
        }
        actions.clear();
        self.actions = actions;
        // A statistic, like a module's stats: a write per step (a lock, a wake-up check, a
        // value) cost as much as a context switch's own bookkeeping.
        if (self.evaluations_at).is_none_or(|t| stamp.duration_since(t) >= STATS_EVERY) {
            self.evaluations_at = Some(stamp);
            self.evaluations.set(evaluations);
        }
        Ok(())
    }

    async fn cleanup(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        if let Some(engine) = &self.engine {
            self.evaluations.set(engine.evaluations() as i64);
        }
        Ok(())
    }
}

/// `out/evaluations` is written at most this often.
const STATS_EVERY: Duration = Duration::from_millis(100);

impl ContextManager {
    /// Reads the rules file and builds an engine, looking up what it mentions.
    async fn load(&mut self, ctx: &Context) -> Result<Engine, String> {
        let show = |errors: Vec<RuleError>| {
            errors
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join("\n")
        };
        let path = self.rules.get();
        if path.is_empty() {
            return Err("params/rules is empty; expected the path of a context rules file".into());
        }
        let loaded = LoadedRules::load(path.as_path()).map_err(show)?;
        let mut handles = Handles::default();
        for address in check::mentioned(&loaded) {
            // A queue's latest item too, for expressions such as `min(scan/out/ranges) < 0.6`.
            if let Ok(handle) = ctx.blackboard().expr_handle(&address).await {
                handles.insert(Arc::from(address), handle);
            }
        }
        let refused = crate::lint::stops_its_manager(&loaded, ctx.module());
        if !refused.is_empty() {
            return Err(show(refused));
        }
        let engine = Engine::build(&loaded, &handles).map_err(show)?;
        self.self_undoing = crate::lint::self_undoing(&loaded.rules.contexts);
        self.watched = engine
            .properties()
            .filter_map(|(prop, path)| {
                handles.get(path).map(|handle| Watched {
                    prop,
                    handle: handle.clone(),
                    seen: u64::MAX,
                })
            })
            .collect();
        self.handles = handles;
        self.running_rules = Some((*path).clone());
        self.errors.set(String::new());
        tracing::info!(rules = %path, contexts = loaded.rules.contexts.len(), "context rules loaded");
        Ok(engine)
    }

    /// Re-reads the rules; a broken file is rejected and the running rules stay.
    async fn reload_rules(&mut self, ctx: &mut Context) {
        let previous = std::mem::take(&mut self.watched);
        let previous_handles = std::mem::take(&mut self.handles);
        match self.load(ctx).await {
            Ok(mut engine) => {
                if let Some(old) = self.engine.take() {
                    engine.adopt(old);
                }
                // Targets the old rules changed must stay reachable for restoring.
                self.targets.forget_handles();
                for (k, h) in previous_handles {
                    self.handles.entry(k).or_insert(h);
                }
                self.engine = Some(engine);
                self.publish_active();
                tracing::info!("context rules reloaded");
                // The new rules may watch other properties, or depend on time.
                ctx.reschedule();
            }
            Err(errors) => {
                self.watched = previous;
                self.handles = previous_handles;
                // `params/rules` is put back to the rules that run: left naming a file that
                // was refused, a later restart of this manager (a crash) would load it and
                // fail every time, and the supervisor would give the agent up.
                let running = self.running_rules.clone();
                let restored = match &running {
                    Some(path) if *path != *self.rules.get() => {
                        let key = format!("{}/params/rules", ctx.module());
                        match ctx.blackboard().any_handle(&key).await {
                            Ok(h) => h.set(Arc::new(path.clone())).is_ok(),
                            Err(_) => false,
                        }
                    }
                    _ => false,
                };
                let errors = match (restored, running) {
                    (true, Some(path)) => {
                        format!("{errors}\n(params/rules is back to `{path}`, the rules that run)")
                    }
                    _ => errors,
                };
                tracing::error!("context rules not reloaded; the running rules stay:\n{errors}");
                self.errors.set(errors);
            }
        }
    }

    /// Publishes the active contexts in `out/active`, if they changed. Two buffers in turn,
    /// like `state/memory`: the text published two switches ago is written in place once no
    /// reader holds it, so a context switching on and off allocates nothing.
    fn publish_active(&mut self) {
        let mut next = self.active_spare.take().unwrap_or_default();
        let active = Arc::make_mut(&mut next);
        active.clear();
        for (k, name) in self.engine.iter().flat_map(Engine::active).enumerate() {
            if k > 0 {
                active.push_str(", ");
            }
            active.push_str(name);
        }
        // Compared with what this manager wrote last, unless someone wrote since.
        let unchanged = match &self.active_shown {
            Some((shown, version)) if *version == self.active.version() => *shown == next,
            _ => *self.active.get() == *next,
        };
        if unchanged {
            self.active_spare = Some(next);
            return;
        }
        let replaced = self.active.swap(next.clone());
        self.active_shown = Some((next, self.active.version()));
        self.active_spare = Some(replaced);
    }
}
