//! A mission's run: the plan, its state and bindings, and one plan step (a round).

use std::sync::Arc;

use petrel_actors::expr::{Clock, ExprId};
use petrel_actors::{Input, State};
use tokio::time::Instant;

use super::bound::Bound;
use super::config::Flags;
use super::env::mission_env;
use super::memory::MissionMemory;
use super::shown::{marking, Shown};
use super::team::TeamIo;
use crate::exec::{step_with, PlanState, StepReport};
use crate::model::Plan;

/// A mission step's times, read once when the step begins.
#[derive(Clone, Copy)]
pub(super) struct StepTime {
    /// The mission clock (`in/clock` or wall time) as an instant.
    pub now: Instant,
    /// The mission clock in seconds.
    pub secs: f64,
    /// The step's own time ([`petrel_actors::Context::now`]): what its writes are stamped with.
    pub stamp: Instant,
}

/// What init builds.
pub(super) struct Run {
    pub plan: Arc<Plan>,
    pub state: PlanState,
    pub bound: Bound,
    /// The next `held`/`age` deadline, for the timer task that bumps `state/wake`.
    pub timer: super::timer::Timer,
    pub done: bool,
    /// Scratch for the expressions a round changed, kept to avoid allocating per round.
    pub changed: Vec<ExprId>,
    pub clock: Clock,
    /// What is kept in `state/memory`, updated as the plan runs.
    pub memory: MissionMemory,
    /// Other robots' actions and conditions, or this robot's executor (see `team.rs`).
    pub team: TeamIo,
    /// Rounds that fire in a circle without waiting (see `loops.rs`).
    pub loops: super::loops::LoopFinder,
    /// Transition labels and marking texts, kept (see `shown.rs`).
    pub shown: Shown,
    /// The `state/memory` value published before the last one, given back by the cell: filled
    /// in place at the next save when no reader holds it any more (see [`Run::save`]).
    pub spare: Option<Arc<MissionMemory>>,
    /// The last round's report, its buffers reused by the next round.
    pub report: StepReport,
    /// The transitions fired in this module step so far, for `out/firings`.
    pub fired: Vec<usize>,
    /// `in/conditions` as last read.
    pub flags: FlagsSeen,
    /// Spare keys for `memory.running` (see [`MissionEnv::keys`](super::env::MissionEnv::keys)).
    pub keys: Vec<String>,
}

/// Plan steps run back to back in one module step at most (see [`Mission::step`]).
pub(super) const MAX_ROUNDS: usize = 64;

/// What one round did (the details stay in [`Run::report`]).
#[derive(Clone, Copy)]
pub(super) struct Round {
    /// Transitions fired.
    pub fired: usize,
    /// Transitions fired inside sub-plans (not in `fired`).
    pub sub_fired: usize,
    /// Whether it called an action (which may have enabled a module or written its input).
    pub called: bool,
}

/// The mission's `in/conditions` as last read, read again only when its version moved.
#[derive(Default)]
pub(super) struct FlagsSeen {
    seen: Option<u64>,
    flags: Arc<Flags>,
}

impl FlagsSeen {
    /// The current flags of `input`; unless `fresh`, the flags read last (see [`Run::round`]).
    pub fn current(&mut self, input: &Input<Flags>, fresh: bool) -> &Flags {
        if !fresh && self.seen.is_some() {
            return &self.flags;
        }
        let version = input.version();
        if self.seen != Some(version) {
            // Read after the version: a write in between is read now and again next time.
            self.seen = Some(version);
            self.flags = input.get();
        }
        &self.flags
    }
}

impl Run {
    /// One plan step at time `t`: bring expressions up to date with changed properties, then
    /// step. What it did is left in `self.report`; the transitions it fired are added to
    /// `self.fired` unless the plan fires in a circle (the loop report names those).
    ///
    /// `fresh`: a watched property may have changed since the last round (the first round of
    /// a module step, one after the modules it woke ran, or one after a write that raised the
    /// mission's signal). Otherwise the properties are not looked at again: nothing the mission
    /// watches was written, and a write landing meanwhile wakes it again after this step.
    pub fn round(&mut self, t: StepTime, flags: &Input<Flags>, fresh: bool) -> Round {
        if fresh {
            self.refresh_props(t.now);
        }
        self.evaluate(t.now);
        // Flags from the cell only when it changed: an action's `set` may write the mission's
        // own flags (which raises its signal, so the next round is fresh).
        let mut env = mission_env!(self, t, flags, fresh);
        // Every condition is known here (unbound atoms read `in/conditions`), so the report's
        // `unknown_conditions` stays empty.
        step_with(&self.plan, &mut self.state, &mut env, &mut self.report);
        let report = &self.report;
        if report.fired.is_empty() {
            self.loops.waited();
        } else {
            self.note_loop();
        }
        let fired = self.report.fired.len();
        // A looping plan's firings were reported as one cycle: a line each would flood the log.
        if fired > 0 && !self.loops.looping() {
            self.fired.extend_from_slice(&self.report.fired);
            if tracing::enabled!(tracing::Level::INFO) {
                let labels = self.labels(&self.report.fired);
                let calls: Vec<String> = self.report.calls.iter().map(|c| c.to_string()).collect();
                tracing::info!(fired = ?labels, ?calls, "plan step");
            }
        }
        Round {
            fired,
            sub_fired: self.report.sub_fired,
            called: !self.report.calls.is_empty(),
        }
    }

    /// Why the plan must stop, if it must (see [`PlanState::runaway`]).
    pub fn runaway(&self) -> Option<String> {
        self.state.runaway(&self.plan)
    }

    /// Transitions `fired` as the log and `out/firings` show them (shared, not copied).
    pub fn labels(&self, fired: &[usize]) -> Vec<Arc<str>> {
        self.shown.labels(fired)
    }

    /// Reports the plan when its rounds fire in a circle without ever waiting.
    fn note_loop(&mut self) {
        let (shown, state, report) = (&self.shown, &self.state, &self.report);
        let found = self.loops.fired(std::time::Instant::now, || {
            let labels = report.fired.iter();
            let labels = labels.map(|&t| shown.label(t).to_string());
            (state.save(), labels.collect())
        });
        if let Some(found) = found {
            tracing::warn!(
                rounds = found.rounds,
                cycle = ?found.cycle,
                "plan `{}` fires in a circle without waiting for anything: {} comes back after {}; {} rounds in a row fired and none waited for an action, a condition or time (reported at most every {}s; its firings are not logged one by one meanwhile)",
                self.plan.name(),
                marking(&self.plan, &self.state),
                found.cycle.join(" → "),
                found.rounds,
                super::loops::REPORT_EVERY.as_secs()
            );
        }
    }

    /// Brings the expressions up to date with the properties they read, at `now`.
    pub(super) fn refresh(&mut self, now: Instant) {
        self.refresh_props(now);
        self.evaluate(now);
    }

    /// Feeds the expressions the watched properties that changed since they were last read.
    fn refresh_props(&mut self, now: Instant) {
        let wall = self.clock.is_wall();
        for (id, h, seen) in &mut self.bound.watched {
            // A lock-free version check first: most rounds change few properties.
            if *seen == Some(h.version()) {
                continue;
            }
            let s = h.read();
            *seen = Some(s.version);
            // On another clock than wall time, a write counts from when the mission saw it.
            let written = if wall { s.written } else { now };
            self.bound
                .exprs
                .update(*id, h.type_info(), &s.value, written);
        }
    }

    /// Evaluates the expressions whose properties changed, and the time-dependent ones.
    fn evaluate(&mut self, now: Instant) {
        self.bound.exprs.evaluate_into(now, &mut self.changed);
        for &id in &self.changed {
            if let Some(Err(e)) = self.bound.exprs.value(id) {
                // Types were checked at init, so this is a value of unexpected shape: say so.
                tracing::warn!(error = %e, "a binding expression could not be evaluated; it counts as false");
            }
        }
    }

    /// Writes the memory (marking, running actions with what they replaced and their `held`
    /// windows) to `state/memory`, if it changed.
    ///
    /// Copy-on-write with two buffers: the published value is immutable (readers may hold
    /// it), so each save publishes another one; the one it replaces comes back from the cell
    /// and, once no reader holds it, is filled in place at the save after (reusing its
    /// strings, vectors and map entries) instead of a fresh clone of the whole memory.
    pub fn save(&mut self, out: &State<MissionMemory>) {
        self.save_changed(out, false)
    }

    /// Like [`save`](Self::save); `changed` says the memory surely differs from the one
    /// published (a call was counted), which spares comparing them.
    pub fn save_changed(&mut self, out: &State<MissionMemory>, changed: bool) {
        if self.memory.plan != self.plan.name() {
            self.memory.plan = self.plan.name().to_string();
        }
        self.memory.marking.clear();
        self.state.save_into(&mut self.memory.marking);
        for (name, ra) in self.memory.running.iter_mut() {
            let Some(a) = self.bound.actions.get(name) else {
                continue;
            };
            ra.saved = a.saved.as_ref().map(|vs| {
                a.set
                    .iter()
                    .zip(vs)
                    .map(|((h, _), v)| h.type_info().to_dynamic(v).unwrap_or(ron::Value::Unit))
                    .collect()
            });
            ra.held.resize_with(a.exprs().count(), Vec::new);
            for (held, id) in ra.held.iter_mut().zip(a.exprs()) {
                held.clear();
                let states = self.bound.exprs.held_states(id);
                held.extend(states.into_iter().map(|t| t.map(Clock::secs_of)));
            }
        }
        self.memory.serve.clone_from(&self.team.serve);
        self.memory.dispatch = self.team.dispatch.memory();
        if !changed && *out.get() == self.memory {
            return;
        }
        let mut next = match self.spare.take() {
            Some(spare) => spare,
            None => Arc::new(MissionMemory::default()),
        };
        match Arc::get_mut(&mut next) {
            Some(next) => next.clone_from(&self.memory),
            // A reader (a tool, a recorder's tap) still holds it: a fresh copy.
            None => next = Arc::new(self.memory.clone()),
        }
        self.spare = Some(out.swap(next));
    }

    /// Goes on from `memory` (a restart, or a snapshot being resumed): the marking, the
    /// running actions' start times, what they replaced and their `held` windows, and the
    /// team runs this mission serves or started.
    pub fn resume(&mut self, memory: &MissionMemory) -> Result<(), String> {
        if let Some(problem) = super::memory::memory_problem(&self.plan, memory) {
            return Err(problem);
        }
        self.state.restore(&self.plan, &memory.marking)?;
        for (name, ra) in &memory.running {
            let Some(a) = self.bound.actions.get_mut(name) else {
                continue;
            };
            a.saved = ra.saved.as_ref().map(|vs| {
                a.set
                    .iter()
                    .zip(vs)
                    .map(|((h, old), v)| {
                        h.type_info()
                            .from_ron(v.clone())
                            .unwrap_or_else(|_| old.clone())
                    })
                    .collect()
            });
            let origin = Clock::instant(ra.started_s);
            let ids: Vec<ExprId> = a.exprs().collect();
            for (k, id) in ids.into_iter().enumerate() {
                self.bound.exprs.set_origin(id, Some(origin));
                if let Some(held) = ra.held.get(k) {
                    let held: Vec<Option<Instant>> =
                        held.iter().map(|t| t.map(Clock::instant)).collect();
                    self.bound.exprs.restore_held_states(id, &held);
                }
            }
        }
        self.memory = memory.clone();
        // The runs a coordinator started here are still answered, and watchers get every
        // value again.
        self.team.serve = memory.serve.clone();
        // The runs started on other robots keep their numbers, and are asked again.
        self.team.dispatch.restore(&memory.dispatch);
        Ok(())
    }
}
