//! Carrying out the engine's actions: writing values, relinking, starting and stopping
//! modules, saving what was there first and putting it back; and the traces that say so.

use anyhow::{anyhow, Context as _};
use petrel_actors::expr::Value;
use petrel_actors::{status, AnyHandle, Context};

use super::targets::Target;
use super::{ContextChange, ContextManager};
use crate::engine::Action;

impl ContextManager {
    /// Carries out `action`; a failure is logged and shown in `out/errors`, and the rest goes on.
    pub(super) async fn apply(&mut self, ctx: &Context, action: &Action) {
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
                self.last_switched = Some(context.clone());
                // In a loop the runtime names the context once; a line per switch would flood.
                if tracing::enabled!(tracing::Level::INFO) && !ctx.in_a_loop() {
                    let trigger = self.trigger_values(context);
                    let what = if now_active {
                        "activated"
                    } else {
                        "deactivated"
                    };
                    tracing::info!(%context, active = now_active, %trigger, "context {what}");
                }
                // Made only if someone reads `out/changes` (a linked module, a tap).
                let started = self.started;
                self.changes.push_with(|| ContextChange {
                    time_s: started.map_or(0.0, |t| ctx.now().duration_since(t).as_secs_f64()),
                    context: String::from(&**context),
                    active: now_active,
                });
            }
            Action::Set {
                target,
                value,
                context,
            } => {
                let entry = self.targets.entry(target);
                let handle = match entry.handle.take() {
                    Some(handle) => handle,
                    None => (self.handles.get(target))
                        .with_context(|| format!("`{target}` is not in the blackboard"))?
                        .clone(),
                };
                let set = set(ctx, entry, &handle, value, context);
                entry.handle = Some(handle);
                set?;
            }
            Action::Restore(target) => {
                let Some(entry) = self.targets.get_mut(target) else {
                    return Ok(());
                };
                if let Some(original) = entry.original.take() {
                    let handle = match &entry.handle {
                        Some(handle) => handle,
                        None => (self.handles.get(target))
                            .with_context(|| format!("`{target}` is not in the blackboard"))?,
                    };
                    if !ctx.in_a_loop() {
                        tracing::info!(%target, value = %handle.type_info().short(&original), "context restores");
                    }
                    handle.set_at(original, ctx.now())?;
                }
            }
            Action::Release(target) => {
                if let Some(entry) = self.targets.get_mut(target) {
                    entry.original = None;
                }
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

/// Writes `value` to `target` (its entry and handle), saving the original first if no
/// context has set it yet.
fn set(
    ctx: &Context,
    target: &mut Target,
    handle: &AnyHandle,
    value: &Value,
    context: &str,
) -> anyhow::Result<()> {
    let info = handle.type_info();
    let new = (target.convert(value, info)).map_err(|e| anyhow!("{}: {e}", target.address))?;
    let address = &target.address;
    let first = target.original.is_none();
    if first {
        target.original = Some(handle.value());
    }
    // Continuous expressions update often: the first change is news, the rest detail.
    // Values are formatted only when someone listens.
    if first && tracing::enabled!(tracing::Level::INFO) && !ctx.in_a_loop() {
        let (old, new) = (info.short(&handle.value()), info.short(&new));
        tracing::info!(%context, target = %address, %old, %new, "context sets");
    } else if tracing::enabled!(tracing::Level::DEBUG) {
        let (old, new) = (info.short(&handle.value()), info.short(&new));
        tracing::debug!(%context, target = %address, %old, %new, "context updates");
    }
    // Stamped with the step's time, like the manager's own outputs: no clock read.
    handle.set_at(new, ctx.now())?;
    Ok(())
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
