//! The `context.manager` module: the imperative shell around [`Engine`].
//!
//! It loads the rules file, looks up every property the rules read or change, feeds changed
//! values to the engine (only the expressions reading them are evaluated again), and carries
//! out the engine's actions: writing parameters, relinking inputs, starting and stopping
//! modules, and restoring what it changed when a context ends. Every activation and
//! deactivation is traced and pushed to `out/changes`; `out/active` lists the active contexts.

use std::collections::hash_map::Entry;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use anyhow::{anyhow, Context as _};
use petrel_actors::expr::{parse, properties, PropId};
use petrel_actors::{
    status, AnyHandle, AnyValue, Context, FilePath, Module, Output, Param, Ports, PropertyType,
    QueueWriter, Registry, Schedule, TypeInfo,
};
use serde::{Deserialize, Serialize};
use tokio::time::Instant;

use crate::engine::{to_property, Action, Engine, Schema};
use crate::rules::{LoadedRules, RuleError};

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

/// Property types and samples, looked up beforehand.
struct Table(HashMap<String, (TypeInfo, AnyValue)>);

impl Schema for Table {
    fn property(&self, path: &str) -> Option<(TypeInfo, AnyValue)> {
        self.0.get(path).cloned()
    }
}

impl Schema for Registry {
    fn property(&self, path: &str) -> Option<(TypeInfo, AnyValue)> {
        self.get(path).ok()
    }
}

/// Every property address a rules file mentions (expressions, targets, links, modules).
fn mentioned(loaded: &LoadedRules) -> Vec<String> {
    let mut paths = Vec::new();
    for r in &loaded.rules.contexts {
        let sources = std::iter::once(&r.when)
            .chain(&r.until)
            .chain(r.set.values());
        for src in sources {
            if let Ok(ast) = parse(src) {
                paths.extend(properties(&ast));
            }
        }
        paths.extend(r.set.keys().cloned());
        paths.extend(r.relink.iter().flat_map(|(a, b)| [a.clone(), b.clone()]));
        let modules = r
            .enable
            .iter()
            .chain(&r.disable)
            .chain(&r.start)
            .chain(&r.stop);
        paths.extend(modules.map(|m| format!("{m}/enabled")));
    }
    paths.sort();
    paths.dedup();
    paths
}

/// Checks a rules file against an agent's registry (what `petrel check` does); returns the
/// context names.
pub fn check_rules(path: &Path, registry: &Registry) -> Result<Vec<String>, Vec<RuleError>> {
    let loaded = LoadedRules::load(path)?;
    Engine::build(&loaded, registry)?;
    Ok(loaded
        .rules
        .contexts
        .iter()
        .map(|c| c.name.clone())
        .collect())
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
    handles: HashMap<Arc<str>, AnyHandle>,
    /// What the rules changed, as it was before: values, links, running states.
    original_values: HashMap<Arc<str>, AnyValue>,
    original_links: HashMap<Arc<str>, Option<String>>,
    original_runs: HashMap<Arc<str>, bool>,
    reload_seen: u64,
    started: Option<Instant>,
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
            tick_ms: ports.param(
                "params/tick_ms",
                50,
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
            evaluations: ports.output("out/evaluations", 0, "expression evaluations so far"),
            changes: ports.queue_out("out/changes", 256, "context activations and deactivations"),
            engine: None,
            watched: Vec::new(),
            handles: HashMap::new(),
            original_values: HashMap::new(),
            original_links: HashMap::new(),
            original_runs: HashMap::new(),
            reload_seen: 0,
            started: None,
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

    async fn init(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        self.started = Some(ctx.now());
        self.reload_seen = self.reload.read().version;
        let engine = self
            .load(ctx)
            .await
            .map_err(|errors| anyhow!("context rules rejected:\n{errors}"))?;
        self.engine = Some(engine);
        Ok(())
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let reload = self.reload.read();
        if reload.version != self.reload_seen {
            self.reload_seen = reload.version;
            self.reload_rules(ctx).await;
        }
        let Some(engine) = self.engine.as_mut() else {
            return Ok(());
        };
        let first = ctx.cause().first();
        for w in &mut self.watched {
            if w.handle.version() != w.seen || first {
                let sample = w.handle.read();
                w.seen = sample.version;
                engine.update_prop(w.prop, w.handle.type_info(), &sample.value, sample.written);
            }
        }
        let actions = engine.step(ctx.now());
        let evaluations = engine.evaluations() as i64;
        let mut switched = false;
        for action in &actions {
            switched |= matches!(action, Action::Activated(_) | Action::Deactivated(_));
            self.apply(ctx, action).await;
        }
        if switched {
            self.publish_active();
        }
        self.evaluations.set(evaluations);
        Ok(())
    }
}

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
        let mut table = HashMap::new();
        let mut handles = HashMap::new();
        for address in mentioned(&loaded) {
            if let Ok(handle) = ctx.blackboard().any_handle(&address).await {
                table.insert(address.clone(), (handle.type_info(), handle.value()));
                handles.insert(Arc::from(address), handle);
            }
        }
        let engine = Engine::build(&loaded, &Table(table)).map_err(show)?;
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
                tracing::error!("context rules not reloaded; the running rules stay:\n{errors}");
                self.errors.set(errors);
                self.watched = previous;
                self.handles = previous_handles;
            }
        }
    }

    /// Publishes the active contexts in `out/active`.
    fn publish_active(&mut self) {
        let mut active = String::new();
        for (k, name) in self.engine.iter().flat_map(Engine::active).enumerate() {
            if k > 0 {
                active.push_str(", ");
            }
            active.push_str(name);
        }
        self.active.set(active);
    }

    async fn apply(&mut self, ctx: &Context, action: &Action) {
        if let Err(e) = self.try_apply(ctx, action).await {
            tracing::error!(?action, error = %e, "context effect failed");
            self.errors.set(format!("{e:#}"));
        }
    }

    async fn try_apply(&mut self, ctx: &Context, action: &Action) -> anyhow::Result<()> {
        let bb = ctx.blackboard();
        match action {
            Action::Activated(context) | Action::Deactivated(context) => {
                let now_active = matches!(action, Action::Activated(_));
                if tracing::enabled!(tracing::Level::INFO) {
                    let trigger = self.trigger_values(context);
                    let what = if now_active {
                        "activated"
                    } else {
                        "deactivated"
                    };
                    tracing::info!(%context, active = now_active, %trigger, "context {what}");
                }
                let time_s = self
                    .started
                    .map_or(0.0, |t| ctx.now().duration_since(t).as_secs_f64());
                self.changes.push(ContextChange {
                    time_s,
                    context: context.to_string(),
                    active: now_active,
                });
            }
            Action::Set {
                target,
                value,
                context,
            } => {
                let handle = self.handle(target)?.clone();
                let info = handle.type_info();
                let old = handle.value();
                let new = to_property(value, info).map_err(|e| anyhow!("{target}: {e}"))?;
                let first = match self.original_values.entry(target.clone()) {
                    Entry::Vacant(slot) => {
                        slot.insert(old.clone());
                        true
                    }
                    Entry::Occupied(_) => false,
                };
                // Continuous expressions update often: the first change is news, the rest detail.
                // Values are formatted only when someone listens.
                if first && tracing::enabled!(tracing::Level::INFO) {
                    let (old, new) = (info.short(&old), info.short(&new));
                    tracing::info!(%context, %target, %old, %new, "context sets");
                } else if tracing::enabled!(tracing::Level::DEBUG) {
                    let (old, new) = (info.short(&old), info.short(&new));
                    tracing::debug!(%context, %target, %old, %new, "context updates");
                }
                handle.set(new)?;
            }
            Action::Restore(target) => {
                if let Some(original) = self.original_values.remove(target) {
                    let handle = self.handle(target)?;
                    tracing::info!(%target, value = %handle.type_info().short(&original), "context restores");
                    handle.set(original)?;
                }
            }
            Action::Release(target) => {
                self.original_values.remove(target);
            }
            Action::Link {
                input,
                source,
                context,
            } => {
                if !self.original_links.contains_key(input) {
                    self.original_links
                        .insert(input.clone(), bb.link_of(input).await?);
                }
                tracing::info!(%context, %input, %source, "context relinks");
                bb.link(input, source).await?;
            }
            Action::RestoreLink(input) => match self.original_links.remove(input) {
                Some(Some(original)) => {
                    tracing::info!(%input, source = %original, "context restores link");
                    bb.link(input, &original).await?;
                }
                Some(None) => {
                    tracing::info!(%input, "context removes its link");
                    bb.unlink(input).await?;
                }
                None => {}
            },
            Action::ReleaseLink(input) => {
                self.original_links.remove(input);
            }
            Action::Run {
                module,
                start,
                context,
            } => {
                if !self.original_runs.contains_key(module) {
                    let status = bb.get::<String>(&format!("{module}/stats/status")).await?;
                    let running = !matches!(status.as_str(), status::STOPPED | status::FAILED);
                    self.original_runs.insert(module.clone(), running);
                }
                tracing::info!(%context, %module, start, "context {} module", if *start { "starts" } else { "stops" });
                run(ctx, module, *start).await;
            }
            Action::RestoreRun(module) => {
                if let Some(running) = self.original_runs.remove(module) {
                    run(ctx, module, running).await;
                }
            }
            Action::ReleaseRun(module) => {
                self.original_runs.remove(module);
            }
        }
        Ok(())
    }

    fn handle(&self, address: &str) -> anyhow::Result<&AnyHandle> {
        self.handles
            .get(address)
            .with_context(|| format!("`{address}` is not in the blackboard"))
    }

    /// The current values of the properties `context`'s conditions read, for traces.
    fn trigger_values(&self, context: &str) -> String {
        let Some(engine) = &self.engine else {
            return String::new();
        };
        let shown: Vec<String> = engine
            .condition_reads(context)
            .into_iter()
            .filter_map(|(prop, path)| {
                let w = self.watched.iter().find(|w| w.prop == prop)?;
                let value = w.handle.type_info().short(&w.handle.value());
                Some(format!("{path}={value}"))
            })
            .collect();
        shown.join(" ")
    }
}

/// Starts or stops a module; one already in that state is left as it is.
async fn run(ctx: &Context, module: &str, start: bool) {
    let result = if start {
        ctx.modules().start(module).await
    } else {
        ctx.modules().stop(module).await
    };
    if let Err(e) = result {
        tracing::debug!(%module, start, error = %e, "module left as it was");
    }
}
