//! The step semantics: a pure function of the plan, the state and the
//! environment's answers.
//!
//! One step: (1) nothing if the plan is in its goal or fail state; (2) step
//! once every executable with a marked execution place (shared by name; a
//! sub-plan steps its own net); (2b) if a running executable failed where no
//! output transition of its execution place asks `A.failed`, the plan fails
//! (nothing else would ever take that token); (3) compute the enabled transitions once, on
//! the marking after (2); (4) fire them in document order, skipping those an
//! earlier firing of this step disabled, each firing moving the tokens and
//! then making its calls in label order. Transitions enabled by this step's
//! firings wait for the next step.
//!
//! Cost: only the output transitions of marked places are examined; the set
//! of marked places is kept incrementally. Nothing is proportional to the
//! net size, except the goal / fail check (proportional to the number of
//! goal / fail places).

use std::collections::HashSet;
use std::fmt;
use std::sync::Arc;

use crate::hot::Hot;
use crate::label::CallKind;
use crate::model::Plan;

mod key;
mod step;
pub(crate) use key::FAILED_BIT;
pub use step::{step, step_with};

/// What the runtime around a plan provides: external conditions and actions.
///
/// Sub-plans are handled inside the executor; the environment only sees
/// actions. Object-safe, so the mission module can pass `&mut dyn Environment`.
pub trait Environment {
    /// The value of an external condition; `None` when the condition is
    /// unknown (it then counts as false and is reported once per plan state).
    fn condition(&mut self, name: &str) -> Option<bool>;
    /// Steps action `name` once (its execution place is marked).
    fn step_action(&mut self, name: &str);
    /// Whether action `name` finished (the atom `name.finished`).
    fn action_finished(&mut self, name: &str) -> bool;
    /// Whether action `name` failed (the atom `name.failed`).
    fn action_failed(&mut self, name: &str) -> bool;
    /// A transition called `name.kind`. `Start` means the action restarts
    /// from scratch (step count 0); after `End` / `Fail` it is done with;
    /// after `Interrupt` it is kept for a later `Resume` or `Start`.
    fn call(&mut self, name: &str, kind: CallKind);

    /// [`condition`](Self::condition) `plan.conditions()[c]`. The step asks by position, so
    /// an environment that resolved a plan's names once answers without looking a name up
    /// at every guard; by default it asks by name.
    fn condition_at(&mut self, plan: &Plan, c: usize) -> Option<bool> {
        self.condition(&plan.conditions()[c])
    }

    /// [`action_finished`](Self::action_finished) of `plan.executables()[e]` (see
    /// [`condition_at`](Self::condition_at)).
    fn action_finished_at(&mut self, plan: &Plan, e: usize) -> bool {
        self.action_finished(&plan.executables()[e].name)
    }

    /// [`action_failed`](Self::action_failed) of `plan.executables()[e]` (see
    /// [`condition_at`](Self::condition_at)).
    fn action_failed_at(&mut self, plan: &Plan, e: usize) -> bool {
        self.action_failed(&plan.executables()[e].name)
    }
}

/// Where a plan stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PlanStatus {
    /// Neither goal nor fail.
    Running,
    /// Every goal place holds exactly its goal marking.
    Goal,
    /// Every fail place holds exactly its fail marking.
    Fail,
}

impl PlanStatus {
    /// `running`, `goal` or `fail`.
    pub fn as_str(self) -> &'static str {
        match self {
            PlanStatus::Running => "running",
            PlanStatus::Goal => "goal",
            PlanStatus::Fail => "fail",
        }
    }
}

/// A call made during a step (sub-plans included).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CallRecord {
    /// Executable name (shared with the plan: recording a call does not copy it).
    pub executable: Arc<str>,
    /// The call.
    pub kind: CallKind,
}

impl fmt::Display for CallRecord {
    /// `name.kind`, e.g. `azione1.start`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{}", self.executable, self.kind)
    }
}

/// What one step did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct StepReport {
    /// Top-level transitions fired, as indices into [`Plan::transitions`], in order.
    pub fired: Vec<usize>,
    /// Transitions fired inside sub-plans: progress too, which may enable more in the next
    /// step (a sub-plan's action that ends at once), though `fired` does not list them.
    pub sub_fired: usize,
    /// Every call made, sub-plans included, in order.
    pub calls: Vec<CallRecord>,
    /// External conditions found unknown for the first time.
    pub unknown_conditions: Vec<String>,
    /// The action whose failure no transition handles, which failed the plan in this step
    /// (a sub-plan's action named as `sub/action`).
    pub unhandled_failure: Option<String>,
}

/// Tokens one place may hold before a running plan stops as a runaway (see
/// [`PlanState::runaway`]).
pub const MAX_PLACE_TOKENS: u32 = 1000;

/// The run-time state of a plan: marking and sub-plan states.
#[derive(Debug, Clone)]
pub struct PlanState {
    tokens: Vec<u32>,
    /// The marked places, sorted: a few words a step walks several times, cheaper to walk,
    /// insert into and remove from than a tree while few places are marked (the usual plan).
    marked: Vec<u32>,
    subs: Vec<Option<Box<PlanState>>>,
    /// The executables that are sub-plans (the `Some`s of `subs`), so that walking the
    /// sub-plan states does not cost the number of executables.
    sub_execs: Vec<usize>,
    /// The executable whose unhandled failure failed the plan.
    failed: Option<u32>,
    /// Unhandled failures are not looked for (the analysis: "any action may fail" would make
    /// every marking reach fail, hiding livelocks).
    pub(crate) ignore_unhandled: bool,
    reported: HashSet<String>,
    scratch: Scratch,
}

/// Buffers a step fills and empties, kept so that a step does not allocate.
#[derive(Debug, Clone, Default)]
struct Scratch {
    running: Vec<usize>,
    candidates: Vec<u32>,
    enabled: Vec<usize>,
}

impl Scratch {
    /// Gives back the buffers a step took (its own, emptied: nothing to free).
    fn put_back(&mut self, running: Vec<usize>, candidates: Vec<u32>, enabled: Vec<usize>) {
        self.running = running;
        self.candidates = candidates;
        self.enabled = enabled;
    }
}

impl PlanState {
    /// The initial state of `plan` (sub-plans at their initial marking).
    pub fn new(plan: &Plan) -> PlanState {
        let tokens: Vec<u32> = plan.places().iter().map(|p| p.initial).collect();
        let marked = tokens
            .iter()
            .enumerate()
            .filter(|(_, t)| **t > 0)
            .map(|(i, _)| i as u32)
            .collect();
        let subs: Vec<_> = plan
            .executables()
            .iter()
            .map(|e| e.subplan.as_ref().map(|sp| Box::new(PlanState::new(sp))))
            .collect();
        let sub_execs = (0..subs.len()).filter(|&e| subs[e].is_some()).collect();
        PlanState {
            tokens,
            marked,
            subs,
            sub_execs,
            failed: None,
            ignore_unhandled: false,
            reported: HashSet::new(),
            scratch: Scratch::default(),
        }
    }

    /// Tokens in place `place` (index into [`Plan::places`]).
    pub fn tokens(&self, place: usize) -> u32 {
        self.tokens[place]
    }

    /// Why the plan must stop, if a place holds more than [`MAX_PLACE_TOKENS`] tokens: an
    /// unbounded net (a loop that forks a branch each time round and never joins it) would
    /// otherwise start its actions millions of times and grow without end. `petrel plan check`
    /// warns of it (`unbounded`) but cannot be sure, as it leaves every guard open. A mission
    /// and `petrel plan simulate` stop it alike.
    pub fn runaway(&self, plan: &Plan) -> Option<String> {
        let (place, tokens) = self.marked().find(|&(_, k)| k > MAX_PLACE_TOKENS)?;
        Some(format!(
            "place '{}' holds {tokens} tokens (more than {MAX_PLACE_TOKENS}): the plan makes tokens faster than it uses them, e.g. a loop that starts a parallel branch each time round and never joins it (`petrel plan check` warns `unbounded`)",
            plan.places()[place].label
        ))
    }

    /// Marked places with their tokens, in document order.
    pub fn marked(&self) -> impl Iterator<Item = (usize, u32)> + '_ {
        self.marked
            .iter()
            .map(|&p| (p as usize, self.tokens[p as usize]))
    }

    /// The state of sub-plan executable `exec`, if it is a sub-plan.
    pub fn subplan_state(&self, exec: usize) -> Option<&PlanState> {
        self.subs.get(exec).and_then(|s| s.as_deref())
    }

    /// Names of the actions whose execution place is marked, sub-plans'
    /// included (e.g. to interrupt them when a mission is aborted).
    pub fn running_actions(&self, plan: &Plan) -> Vec<String> {
        let mut out = Vec::new();
        for e in self.running(plan) {
            let exe = &plan.executables()[e];
            match (&exe.subplan, self.subs[e].as_deref()) {
                (Some(sp), Some(sub)) => out.extend(sub.running_actions(sp)),
                _ => out.push(exe.name.clone()),
            }
        }
        out
    }

    /// Goal, fail or running, from the current marking; fail after an unhandled failure.
    pub fn status(&self, plan: &Plan) -> PlanStatus {
        if self.failed.is_some() {
            return PlanStatus::Fail;
        }
        status_of(plan, &self.tokens)
    }

    /// The action whose failure no transition handled, if that failed the plan
    /// (`sub/action` inside a sub-plan).
    pub fn unhandled_failure(&self, plan: &Plan) -> Option<String> {
        let e = self.failed? as usize;
        let exe = &plan.executables()[e];
        match (&exe.subplan, self.subs[e].as_deref()) {
            (Some(sp), Some(sub)) => Some(match sub.unhandled_failure(sp) {
                Some(inner) => format!("{}/{inner}", exe.name),
                None => exe.name.clone(),
            }),
            _ => Some(exe.name.clone()),
        }
    }

    fn add(&mut self, place: usize, n: u32) {
        self.tokens[place] = self.tokens[place].saturating_add(n);
        if let Err(at) = self.marked.binary_search(&(place as u32)) {
            self.marked.insert(at, place as u32);
        }
    }

    fn take(&mut self, place: usize, n: u32) {
        self.tokens[place] -= n;
        if self.tokens[place] == 0 {
            if let Ok(at) = self.marked.binary_search(&(place as u32)) {
                self.marked.remove(at);
            }
        }
    }

    /// Executables with a marked execution place, each once, in index order.
    fn running(&self, plan: &Plan) -> Vec<usize> {
        let mut ex = Vec::new();
        self.running_into(plan, &mut ex);
        ex
    }

    /// Like [`running`](Self::running), into `ex` (cleared first).
    fn running_into(&self, plan: &Plan, ex: &mut Vec<usize>) {
        let pe = &plan.hot().place_exec;
        ex.clear();
        for &p in &self.marked {
            let e = pe[p as usize];
            if e != Hot::NO_EXEC {
                ex.push(e as usize);
            }
        }
        if ex.len() > 1 {
            ex.sort_unstable();
            ex.dedup();
        }
    }
}

/// Goal, fail or running for marking `tokens` of `plan`: goal when every goal place holds exactly
/// its goal marking (checked first), fail likewise.
pub(crate) fn status_of(plan: &Plan, tokens: &[u32]) -> PlanStatus {
    let exact = |ps: &[(usize, u32)]| !ps.is_empty() && ps.iter().all(|&(p, n)| tokens[p] == n);
    if exact(plan.goal_places()) {
        PlanStatus::Goal
    } else if exact(plan.fail_places()) {
        PlanStatus::Fail
    } else {
        PlanStatus::Running
    }
}
