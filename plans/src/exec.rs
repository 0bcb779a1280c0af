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
use crate::model::{Atom, Plan};

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
    /// Every call made, sub-plans included, in order.
    pub calls: Vec<CallRecord>,
    /// External conditions found unknown for the first time.
    pub unknown_conditions: Vec<String>,
    /// The action whose failure no transition handles, which failed the plan in this step
    /// (a sub-plan's action named as `sub/action`).
    pub unhandled_failure: Option<String>,
}

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

/// A state saved and restored (a mission module keeps its plan's marking across restarts).
impl PlanState {
    /// The marking as a compact list of numbers (sub-plans included), for
    /// [`restore`](PlanState::restore).
    pub fn save(&self) -> Vec<u32> {
        let mut key = Vec::new();
        self.encode(&mut key);
        key
    }

    /// Like [`save`](PlanState::save), appending to `out` (a caller that saves often reuses
    /// one buffer).
    pub fn save_into(&self, out: &mut Vec<u32>) {
        self.encode(out);
    }

    /// Sets the marking saved by [`save`](PlanState::save) from a state of the same plan.
    /// A list that does not fit the plan (another plan, an edited snapshot) is refused and
    /// the state left unchanged.
    pub fn restore(&mut self, plan: &Plan, saved: &[u32]) -> Result<(), String> {
        match fits(plan, saved) {
            Some(used) if used == saved.len() => {
                self.decode(saved);
                Ok(())
            }
            _ => Err(format!(
                "the saved marking does not fit plan `{}` (was the plan changed?)",
                plan.name()
            )),
        }
    }
}

/// How many words of `key` a state of `plan` takes, if they are a valid key for it.
fn fits(plan: &Plan, key: &[u32]) -> Option<usize> {
    let n = (*key.first()? & !FAILED_BIT) as usize;
    let pairs = key.get(1..1 + 2 * n)?;
    if pairs
        .chunks_exact(2)
        .any(|p| p[0] as usize >= plan.places().len() || p[1] == 0)
    {
        return None;
    }
    let mut used = 1 + 2 * n;
    for e in plan.executables() {
        if let Some(sp) = &e.subplan {
            used += fits(sp, key.get(used..)?)?;
        }
    }
    Some(used)
}

/// The analysis' view of a state: its marking as a compact key, and back.
impl PlanState {
    /// Appends the marking: the number of marked places, then `place, tokens` for each in
    /// place order, then each sub-plan's own key in executable order. Equal states give equal
    /// keys, and a key costs what is marked, not the net size.
    pub(crate) fn encode(&self, out: &mut Vec<u32>) {
        // An unhandled failure sets the top bit of the count, so it never matches a running key.
        let failed = if self.failed.is_some() { FAILED_BIT } else { 0 };
        out.push(self.marked.len() as u32 | failed);
        for &p in &self.marked {
            out.extend([p, self.tokens[p as usize]]);
        }
        for &e in &self.sub_execs {
            if let Some(sub) = &self.subs[e] {
                sub.encode(out);
            }
        }
    }

    /// Sets the marking to `key` (from [`PlanState::encode`] on a state of the same plan),
    /// touching only the places marked before and after; returns what follows the key.
    pub(crate) fn decode<'k>(&mut self, key: &'k [u32]) -> &'k [u32] {
        for &p in &self.marked {
            self.tokens[p as usize] = 0;
        }
        self.marked.clear();
        // Which executable failed does not matter to the analysis, only that one did.
        self.failed = (key[0] & FAILED_BIT != 0).then_some(0);
        let n = (key[0] & !FAILED_BIT) as usize;
        for pair in key[1..1 + 2 * n].chunks_exact(2) {
            self.tokens[pair[0] as usize] = pair[1];
            self.marked.push(pair[0]);
        }
        // Keys list places in order (`encode`); one from elsewhere may not.
        if !self.marked.is_sorted() {
            self.marked.sort_unstable();
            self.marked.dedup();
        }
        let mut rest = &key[1 + 2 * n..];
        for &e in &self.sub_execs {
            if let Some(sub) = &mut self.subs[e] {
                rest = sub.decode(rest);
            }
        }
        rest
    }

    /// Stops looking for unhandled failures, here and in sub-plans (see `ignore_unhandled`).
    pub(crate) fn for_analysis(mut self) -> Self {
        self.ignore_unhandled = true;
        for sub in self.subs.iter_mut().flatten() {
            let s = std::mem::replace(sub.as_mut(), PlanState::empty());
            **sub = s.for_analysis();
        }
        self
    }

    fn empty() -> PlanState {
        PlanState {
            tokens: Vec::new(),
            marked: Vec::new(),
            subs: Vec::new(),
            sub_execs: Vec::new(),
            failed: None,
            ignore_unhandled: false,
            reported: HashSet::new(),
            scratch: Scratch::default(),
        }
    }

    /// Whether some transition has the tokens it needs (guards aside).
    pub(crate) fn token_enabled(&self, plan: &Plan) -> bool {
        let hot = plan.hot();
        self.marked.iter().any(|&p| {
            plan.output_transitions(p as usize)
                .iter()
                .any(|&t| has_tokens(self, hot.trans[t as usize].inputs(&hot.arcs)))
        })
    }
}

/// Set in the first word of a key ([`PlanState::encode`]) when an unhandled failure failed the plan.
pub(crate) const FAILED_BIT: u32 = 1 << 31;

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

/// Performs one step of `plan` (see the module docs) and returns what it did.
pub fn step(plan: &Plan, state: &mut PlanState, env: &mut dyn Environment) -> StepReport {
    let mut report = StepReport::default();
    step_into(plan, state, env, &mut report, true);
    report
}

/// Like [`step`], into `report` (cleared first): a caller stepping often (a mission's rounds)
/// reuses one report's buffers instead of allocating them at every step.
pub fn step_with(
    plan: &Plan,
    state: &mut PlanState,
    env: &mut dyn Environment,
    report: &mut StepReport,
) {
    report.fired.clear();
    report.calls.clear();
    report.unknown_conditions.clear();
    report.unhandled_failure = None;
    step_into(plan, state, env, report, true);
}

fn step_into(
    plan: &Plan,
    state: &mut PlanState,
    env: &mut dyn Environment,
    report: &mut StepReport,
    top: bool,
) {
    if state.status(plan) != PlanStatus::Running {
        return;
    }
    // The step's buffers, taken out of the state while it is borrowed, and put back after.
    // Taken field by field: moving the whole struct out and back cost a stall on the copy.
    let mut running = std::mem::take(&mut state.scratch.running);
    let mut candidates = std::mem::take(&mut state.scratch.candidates);
    let mut enabled = std::mem::take(&mut state.scratch.enabled);
    state.running_into(plan, &mut running);
    for &e in &running {
        let exe = &plan.executables()[e];
        match (&exe.subplan, state.subs[e].as_deref_mut()) {
            (Some(sp), Some(sub)) => step_into(sp, sub, env, report, false),
            _ => env.step_action(&exe.name),
        }
    }
    // A failure no transition asks about would leave its action running for ever: it fails
    // the plan instead (before any transition fires, so a recovery cannot race it).
    let hot = plan.hot();
    let unhandled = match state.ignore_unhandled {
        true => None,
        false => unhandled_failure(plan, state, env, hot),
    };
    if let Some(e) = unhandled {
        state.failed = Some(e as u32);
        if report.unhandled_failure.is_none() {
            report.unhandled_failure = state.unhandled_failure(plan);
        }
        state.scratch.put_back(running, candidates, enabled);
        return;
    }
    candidates.clear();
    for &p in &state.marked {
        candidates.extend_from_slice(plan.output_transitions(p as usize));
    }
    if candidates.len() > 1 {
        candidates.sort_unstable();
        candidates.dedup();
    }
    enabled.clear();
    for &ti in &candidates {
        let h = hot.trans[ti as usize];
        if has_tokens(state, h.inputs(&hot.arcs))
            && (h.plain || guard(plan, state, env, report, ti as usize))
        {
            enabled.push(ti as usize);
        }
    }
    for &ti in &enabled {
        let h = hot.trans[ti];
        if !has_tokens(state, h.inputs(&hot.arcs)) {
            continue; // an earlier firing of this step took the tokens
        }
        for e in h.inputs(&hot.arcs) {
            state.take(e.place, e.weight);
        }
        for e in h.outputs(&hot.arcs) {
            state.add(e.place, e.weight);
        }
        if top {
            report.fired.push(ti);
        }
        if !h.plain {
            for c in &plan.transitions()[ti].calls {
                make_call(plan, state, c.exec, c.kind, env, report);
            }
        }
    }
    state.scratch.put_back(running, candidates, enabled);
}

/// The first running executable (in place order) that failed where no transition handles it.
fn unhandled_failure(
    plan: &Plan,
    state: &PlanState,
    env: &mut dyn Environment,
    hot: &Hot,
) -> Option<usize> {
    state
        .marked
        .iter()
        .filter(|&&p| hot.unhandled_fail[p as usize])
        .map(|&p| hot.place_exec[p as usize] as usize)
        .find(|&e| {
            let exe = &plan.executables()[e];
            match (&exe.subplan, state.subs[e].as_deref()) {
                (Some(sp), Some(sub)) => sub.status(sp) == PlanStatus::Fail,
                _ => env.action_failed_at(plan, e),
            }
        })
}

fn has_tokens(state: &PlanState, inputs: &[crate::model::Edge]) -> bool {
    inputs.iter().all(|e| state.tokens[e.place] >= e.weight)
}

fn guard(
    plan: &Plan,
    state: &mut PlanState,
    env: &mut dyn Environment,
    report: &mut StepReport,
    t: usize,
) -> bool {
    plan.transitions()[t].guard.eval(&mut |a: &Atom| match *a {
        Atom::Finished(e) | Atom::Failed(e) => {
            let exe = &plan.executables()[e];
            let want = if matches!(a, Atom::Finished(_)) {
                PlanStatus::Goal
            } else {
                PlanStatus::Fail
            };
            match (&exe.subplan, state.subs[e].as_deref()) {
                (Some(sp), Some(sub)) => sub.status(sp) == want,
                _ if want == PlanStatus::Goal => env.action_finished_at(plan, e),
                _ => env.action_failed_at(plan, e),
            }
        }
        Atom::External(c) => env.condition_at(plan, c).unwrap_or_else(|| {
            let name = &plan.conditions()[c];
            if state.reported.insert(name.clone()) {
                report.unknown_conditions.push(name.clone());
            }
            false
        }),
    })
}

fn make_call(
    plan: &Plan,
    state: &mut PlanState,
    e: usize,
    kind: CallKind,
    env: &mut dyn Environment,
    report: &mut StepReport,
) {
    let exe = &plan.executables()[e];
    report.calls.push(CallRecord {
        executable: plan.hot().exec_names[e].clone(),
        kind,
    });
    let (Some(sp), Some(sub)) = (&exe.subplan, state.subs[e].as_deref_mut()) else {
        env.call(&exe.name, kind);
        return;
    };
    if kind == CallKind::Start {
        *sub = PlanState::new(sp);
    } else {
        // end / interrupt / fail (and resume, symmetrically) pass on to the
        // sub-plan's running executables.
        for inner in sub.running(sp) {
            make_call(sp, sub, inner, kind, env, report);
        }
    }
}
