//! The plan's [`Environment`] over the bound properties: conditions from expressions or
//! `in/conditions`, action status from `finished`/`failed`, calls switching modules and
//! keeping the mission's memory (start times, what each action did).

use tokio::time::Instant;

use super::bound::{Bound, BoundAction, Relink};
use super::config::Flags;
use super::memory::{MissionMemory, RunningAction};
use crate::exec::Environment;
use crate::label::CallKind;
use crate::remote::Dispatch;

/// One step's view of the world; expression values were brought up to date before the step.
pub(crate) struct MissionEnv<'a> {
    /// The top plan, whose names `bound.at` has by position.
    pub plan: &'a crate::model::Plan,
    pub bound: &'a mut Bound,
    pub flags: &'a Flags,
    /// The mission clock now, as an instant and in seconds.
    pub now: Instant,
    pub secs: f64,
    /// The mission step's time ([`Context::now`](petrel_actors::Context::now)): the stamp of
    /// every value the step writes through its bindings, like its own outputs' (a step's
    /// writes carry the step's time, and the clock is read once per step).
    pub stamp: Instant,
    pub memory: &'a mut MissionMemory,
    /// Other robots' actions and conditions (`robot#...`): carried out over the team.
    pub dispatch: &'a mut Dispatch,
    /// Names of ended actions' entries in `memory.running`, kept for the next start's entry.
    pub keys: &'a mut Vec<String>,
    /// The plan fires in a circle without waiting (see `loops.rs`): its `say_...` lines would
    /// flood the log (millions a second), so each is said once per circle, then at the debug
    /// level.
    pub looping: bool,
}

/// A [`MissionEnv`] over a [`Run`](super::run::Run)'s fields at step time `$t` (a
/// `StepTime`), `in/conditions` read from `$input` (`$fresh`: from the cell only when it
/// changed). A macro rather than a method: the env borrows some of the run's fields while the
/// caller goes on using others (`state` and `report` to step, `team.serve` and
/// `team.pending` to serve), and a `&mut self` method would borrow them all.
macro_rules! mission_env {
    ($run:expr, $t:expr, $input:expr, $fresh:expr) => {
        $crate::mission::env::MissionEnv {
            plan: &$run.plan,
            bound: &mut $run.bound,
            flags: $run.flags.current($input, $fresh),
            now: $t.now,
            secs: $t.secs,
            stamp: $t.stamp,
            memory: &mut $run.memory,
            dispatch: &mut $run.team.dispatch,
            keys: &mut $run.keys,
            looping: $run.loops.looping(),
        }
    };
}
pub(super) use mission_env;

impl BoundAction {
    /// `start` / `resume`: remember what `set` replaces (once), write it, enable the modules,
    /// ask for the action's links (into `relinks`). Writes are stamped `stamp`.
    pub fn activate(&mut self, relinks: &mut Vec<Relink>, stamp: Instant) {
        if self.saved.is_none() {
            self.saved = Some(self.set.iter().map(|(h, _)| h.value()).collect());
        }
        for (h, v) in &self.set {
            write(h, v.clone(), stamp);
        }
        for e in &self.enable {
            write(e, shared_bool(true), stamp);
        }
        relinks.extend(self.links.iter().map(|(input, source, _)| Relink {
            input: input.clone(),
            source: Some(source.clone()),
        }));
    }

    /// `end` / `interrupt` / `fail`: disable the modules, put back what `set` replaced and
    /// (into `relinks`) the links `link` changed. Writes are stamped `stamp`.
    pub fn deactivate(&mut self, relinks: &mut Vec<Relink>, stamp: Instant) {
        for e in &self.enable {
            write(e, shared_bool(false), stamp);
        }
        if self.restore && self.saved.is_some() {
            relinks.extend(self.links.iter().map(|(input, _, original)| Relink {
                input: input.clone(),
                source: original.clone(),
            }));
        }
        if let Some(saved) = self.saved.take() {
            if self.restore {
                for ((h, _), old) in self.set.iter().zip(saved) {
                    write(h, old, stamp);
                }
            }
        }
    }

    /// Whether `start`/`resume` effects are in place.
    pub fn active(&self) -> bool {
        self.saved.is_some()
    }
}

/// `false` and `true` as values made once: switching a module on or off allocates nothing.
fn shared_bool(b: bool) -> petrel_actors::AnyValue {
    static VALUES: std::sync::OnceLock<[petrel_actors::AnyValue; 2]> = std::sync::OnceLock::new();
    let values = VALUES.get_or_init(|| [std::sync::Arc::new(false), std::sync::Arc::new(true)]);
    values[usize::from(b)].clone()
}

fn write(h: &petrel_actors::AnyHandle, v: petrel_actors::AnyValue, stamp: Instant) {
    // Types were checked at init (`from_ron` into the property's own type, `enabled` is bool).
    if let Err(e) = h.set_at(v, stamp) {
        tracing::error!(property = h.key(), error = %e, "binding write refused");
    }
}

impl MissionEnv<'_> {
    /// Whether `plan` is the top plan (a sub-plan's names are looked up by name).
    fn top(&self, plan: &crate::model::Plan) -> bool {
        std::ptr::eq(plan, self.plan)
    }

    fn expr(&self, id: Option<petrel_actors::expr::ExprId>) -> bool {
        id.and_then(|id| self.bound.exprs.bool(id)).unwrap_or(false)
    }

    /// Counts a call in the action's record and keeps its start time while it runs.
    fn remember(&mut self, name: &str, kind: CallKind) {
        let memory = &mut *self.memory;
        if !memory.actions.contains_key(name) {
            memory.actions.insert(name.to_string(), Default::default());
        }
        let Some(stats) = memory.actions.get_mut(name) else {
            return;
        };
        match kind {
            CallKind::Start | CallKind::Resume => {
                stats.starts += 1;
                let running = RunningAction {
                    started_s: self.secs,
                    ..Default::default()
                };
                match memory.running.get_mut(name) {
                    Some(r) => *r = running,
                    None => {
                        // A key an ended action gave back: a start allocates no name.
                        let mut key = self.keys.pop().unwrap_or_default();
                        key.clear();
                        key.push_str(name);
                        memory.running.insert(key, running);
                    }
                }
                return;
            }
            CallKind::End => stats.ends += 1,
            CallKind::Fail => stats.failures += 1,
            CallKind::Interrupt => stats.interrupts += 1,
        }
        if let Some((key, run)) = memory.running.remove_entry(name) {
            stats.time_s += (self.secs - run.started_s).max(0.0);
            self.keys.push(key);
        }
    }
}

impl Environment for MissionEnv<'_> {
    fn condition(&mut self, name: &str) -> Option<bool> {
        match self.bound.conditions.get(name) {
            Some(&id) => Some(self.bound.exprs.bool(id).unwrap_or(false)),
            None if self.dispatch.has_condition(name) => {
                Some(self.dispatch.condition(name).unwrap_or(false))
            }
            None => Some(self.flags.0.get(name).copied().unwrap_or(false)),
        }
    }

    fn condition_at(&mut self, plan: &crate::model::Plan, c: usize) -> Option<bool> {
        match self
            .top(plan)
            .then(|| self.bound.at.conditions[c])
            .flatten()
        {
            Some(id) => Some(self.bound.exprs.bool(id).unwrap_or(false)),
            None => self.condition(&plan.conditions()[c]),
        }
    }

    fn action_finished_at(&mut self, plan: &crate::model::Plan, e: usize) -> bool {
        match self.top(plan).then(|| self.bound.at.actions[e]).flatten() {
            Some(a) if a.unbound => true,
            Some(a) => self.expr(a.finished),
            None => self.action_finished(&plan.executables()[e].name),
        }
    }

    fn action_failed_at(&mut self, plan: &crate::model::Plan, e: usize) -> bool {
        match self.top(plan).then(|| self.bound.at.actions[e]).flatten() {
            Some(a) => self.expr(a.failed),
            None => self.action_failed(&plan.executables()[e].name),
        }
    }

    fn step_action(&mut self, _name: &str) {
        // Bound modules step on their own schedules; the plan only watches their status.
    }

    fn action_finished(&mut self, name: &str) -> bool {
        match self.bound.actions.get(name) {
            Some(a) if a.unbound => true,
            Some(a) => self.expr(a.finished),
            None => self.dispatch.finished(name),
        }
    }

    fn action_failed(&mut self, name: &str) -> bool {
        match self.bound.actions.get(name) {
            Some(a) => self.expr(a.failed),
            None => self.dispatch.failed(name),
        }
    }

    fn call(&mut self, name: &str, kind: CallKind) {
        self.remember(name, kind);
        let (now, stamp) = (self.now, self.stamp);
        if self.dispatch.has_action(name) {
            tracing::info!(action = name, call = %kind, "sent to its robot");
            self.dispatch.call(name, kind);
            return;
        }
        let Bound {
            actions,
            exprs,
            relinks,
            ..
        } = &mut *self.bound;
        let Some(a) = actions.get_mut(name) else {
            return;
        };
        if a.unbound {
            if std::mem::replace(&mut a.unbound_said, true) {
                tracing::debug!(action = name, call = %kind, "unbound action: nothing to do");
            } else {
                tracing::warn!(action = name, call = %kind, "unbound action: nothing to do (said once per action)");
            }
            return;
        }
        tracing::debug!(action = name, call = %kind, "action call");
        match kind {
            CallKind::Start | CallKind::Resume => {
                // Time in the action's conditions counts from here: a `held` window opened
                // before it ran does not count, and `elapsed()` starts at 0.
                for id in a.exprs() {
                    exprs.set_origin(id, Some(now));
                }
                if let Some(text) = &a.log {
                    // Once per circle: an action outside it (the way out) is still said.
                    let again = self.looping && std::mem::replace(&mut a.said_in_loop, true);
                    a.said_in_loop &= self.looping;
                    match again {
                        true => tracing::debug!(action = name, "{text}"),
                        false => tracing::info!(action = name, "{text}"),
                    }
                }
                a.activate(relinks, stamp);
            }
            CallKind::End | CallKind::Interrupt | CallKind::Fail => a.deactivate(relinks, stamp),
        }
    }
}
