//! Static analysis (`petrel plan check`).
//!
//! Structural checks, plus a bounded exploration of the markings reachable
//! under the real step semantics with every guard atom left open: in each
//! step, every combination of truth values of the atoms asked by the
//! token-enabled transitions is tried (`A.finished` is one atom however many
//! transitions ask it, so joined branches of one executable end together, as
//! at run time). The result over-approximates what the plan can do, so
//! "never fires" and "never reaches goal" are sure when the exploration is
//! complete, and "can hold more than one token" means "may".
//!
//! The exploration (`explore.rs`) interns sparse markings and keeps the explored steps in a
//! petgraph graph, so a linear plan costs linear time and memory; `livelock.rs` finds traps
//! (markings from which neither goal nor fail can be reached) as bottom strongly connected
//! components, with a witness path. At most [`CheckOptions::max_states`] markings are kept;
//! beyond, the report is incomplete and says how to raise the limit.

mod explore;
mod livelock;

use std::fmt;

use crate::model::Plan;
use explore::{explore, top_pairs, Kind, Outcomes, MAX_TOKENS};
use std::collections::HashMap;
use std::rc::Rc;
use std::sync::Arc;

/// The markings [`check`] explores at most, and the default of `petrel plan check
/// --max-states`: a linear plan of 100,000 actions has about 200,000 markings.
pub const DEFAULT_MAX_STATES: usize = 500_000;

/// How [`check_with`] explores.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CheckOptions {
    /// Markings explored at most; beyond, the report says so and is incomplete.
    pub max_states: usize,
}

impl Default for CheckOptions {
    fn default() -> Self {
        CheckOptions {
            max_states: DEFAULT_MAX_STATES,
        }
    }
}

/// One problem found by [`check`].
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Finding {
    /// A stable short code, e.g. `dead-transition`.
    pub code: &'static str,
    /// A sentence for a person.
    pub message: String,
}

/// The result of [`check`]. Errors mean the plan cannot work (non-zero
/// exit); warnings deserve a look. Serialisable, for a `--json` output.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct CheckReport {
    /// The plan name.
    pub plan: String,
    /// Problems that make the plan unusable.
    pub errors: Vec<Finding>,
    /// Suspicious things.
    pub warnings: Vec<Finding>,
    /// Action names (executables that are not sub-plans).
    pub actions: Vec<String>,
    /// Sub-plan names.
    pub subplans: Vec<String>,
    /// External conditions used by guards.
    pub conditions: Vec<String>,
    /// Markings explored.
    pub states: usize,
    /// Whether the exploration covered every reachable marking.
    pub complete: bool,
}

impl CheckReport {
    /// No errors.
    pub fn is_ok(&self) -> bool {
        self.errors.is_empty()
    }
}

impl fmt::Display for CheckReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = |n: usize| if n == 1 { "" } else { "s" };
        writeln!(
            f,
            "plan '{}': {} error{}, {} warning{} ({} marking{} explored{})",
            self.plan,
            self.errors.len(),
            s(self.errors.len()),
            self.warnings.len(),
            s(self.warnings.len()),
            self.states,
            s(self.states),
            if self.complete { "" } else { ", incomplete" }
        )?;
        for e in &self.errors {
            writeln!(f, "error[{}]: {}", e.code, e.message)?;
        }
        for w in &self.warnings {
            writeln!(f, "warning[{}]: {}", w.code, w.message)?;
        }
        let list = |v: &[String]| {
            if v.is_empty() {
                "(none)".to_string()
            } else {
                v.join(", ")
            }
        };
        writeln!(f, "actions: {}", list(&self.actions))?;
        if !self.subplans.is_empty() {
            writeln!(f, "sub-plans: {}", list(&self.subplans))?;
        }
        writeln!(f, "conditions: {}", list(&self.conditions))
    }
}

fn finding(code: &'static str, message: String) -> Finding {
    Finding { code, message }
}

fn place_name(plan: &Plan, p: usize) -> String {
    let pl = &plan.places()[p];
    match plan.is_text_plan() {
        // A text plan's ids are made up: its labels are what `plan dot` and `simulate` show.
        true => format!("place '{}'", pl.label),
        false => format!("place '{}' ('{}')", pl.id, pl.label),
    }
}

/// Checks a plan and its sub-plans (their findings are prefixed with
/// `sub-plan NAME:`), exploring at most [`DEFAULT_MAX_STATES`] markings.
pub fn check(plan: &Plan) -> CheckReport {
    check_with(plan, &CheckOptions::default())
}

/// [`check`] with explicit options.
pub fn check_with(plan: &Plan, options: &CheckOptions) -> CheckReport {
    let checked = check_once(plan, options, &mut HashMap::new());
    // The top plan's report is held only here (sub-plans' are in `done`, dropped by now), so
    // it is taken rather than copied: a long plan's lists every action.
    match Rc::try_unwrap(checked) {
        Ok(checked) => checked.report,
        Err(shared) => shared.report.clone(),
    }
}

/// A plan's report, and what its parents may assume of it as a sub-plan.
struct Checked {
    report: CheckReport,
    can_end: bool,
    can_fail: bool,
}

/// Checks `plan`, each distinct sub-plan once (`done`, by address): a sub-plan shared by
/// many plans of a deep hierarchy costs one check, and its parents are explored with it as an
/// action that ends or fails only if its own check says it can.
fn check_once(
    plan: &Plan,
    options: &CheckOptions,
    done: &mut HashMap<*const Plan, Rc<Checked>>,
) -> Rc<Checked> {
    let mut r = CheckReport {
        plan: plan.name().to_string(),
        ..CheckReport::default()
    };
    let mut outcomes = Outcomes::new();
    for e in plan.executables() {
        match &e.subplan {
            Some(sp) => {
                r.subplans.push(e.name.clone());
                let key = Arc::as_ptr(sp);
                let sub = match done.get(&key) {
                    Some(sub) => sub.clone(),
                    None => {
                        let sub = check_once(sp, options, done);
                        done.insert(key, sub.clone());
                        sub
                    }
                };
                outcomes.insert(e.name.clone(), (sub.can_end, sub.can_fail));
                let pre =
                    |f: &Finding| finding(f.code, format!("sub-plan {}: {}", e.name, f.message));
                r.errors.extend(sub.report.errors.iter().map(pre));
                r.warnings.extend(sub.report.warnings.iter().map(pre));
            }
            None => r.actions.push(e.name.clone()),
        }
    }
    r.conditions = plan.conditions().to_vec();
    structural(plan, &mut r);
    let (can_end, can_fail) = behaviour(
        &plan.without_subplans(),
        &outcomes,
        options.max_states,
        &mut r,
    );
    Rc::new(Checked {
        report: r,
        can_end,
        can_fail,
    })
}

fn structural(plan: &Plan, r: &mut CheckReport) {
    if plan.goal_places().is_empty() {
        r.errors.push(finding(
            "no-goal",
            "the plan has no goal place, so it can never succeed".into(),
        ));
    }
    if plan.places().iter().all(|p| p.initial == 0) {
        r.errors.push(finding(
            "no-initial-marking",
            "no place holds a token initially, so nothing can happen".into(),
        ));
    }
    for t in plan.transitions() {
        if t.inputs.is_empty() {
            r.errors.push(finding(
                "source-transition",
                format!(
                    "transition '{}' ('{}') has no input place, so it fires at every step",
                    t.id, t.label
                ),
            ));
        }
    }
    for e in plan.executables().iter().filter(|e| e.subplan.is_none()) {
        let local = crate::remote::robot_of(&e.name).map_or(e.name.as_str(), |(_, l)| l);
        if let Some(why) = crate::mission::builtin::not_a_wait(local) {
            r.warnings.push(finding(
                "not-a-wait",
                format!("{why}; as written it is an ordinary action, which a mission must bind"),
            ));
        }
    }
    for (i, p) in plan.places().iter().enumerate() {
        if p.goal == 0 && p.fail == 0 && plan.output_transitions(i).is_empty() {
            r.warnings.push(finding(
                "dead-end-place",
                format!(
                    "{} is neither a goal nor a fail place and has no outgoing transition",
                    place_name(plan, i)
                ),
            ));
        }
    }
}

/// `{'label': tokens, ...}` for the top-level places of a marking key.
fn show_marking(plan: &Plan, key: &[u32]) -> String {
    let marked: Vec<String> = top_pairs(key)
        .map(|(p, k)| format!("'{}': {k}", plan.places()[p].label))
        .collect();
    format!("{{{}}}", marked.join(", "))
}

/// The findings of the exploration.
/// Explores `plan` (sub-plans as actions with `outcomes`) and reports what it finds; returns
/// whether the goal and the fail marking can be reached (either, when unsure).
fn behaviour(
    plan: &Plan,
    outcomes: &Outcomes,
    max_states: usize,
    r: &mut CheckReport,
) -> (bool, bool) {
    let ex = explore(plan, outcomes, max_states);
    let mut max_tokens = vec![0u32; plan.places().len()];
    for id in 0..ex.markings.len() as u32 {
        for (p, k) in top_pairs(ex.markings.get(id)) {
            max_tokens[p] = max_tokens[p].max(k);
        }
    }
    let has = |kind: Kind| ex.kinds.contains(&kind);
    let unbounded = ex.kinds.iter().zip(0..).any(|(k, id)| {
        *k == Kind::Open && top_pairs(ex.markings.get(id)).any(|(_, k)| k > MAX_TOKENS)
    });
    r.states = ex.markings.len();
    r.complete = !ex.budget_hit && !unbounded;
    if ex.memory_hit {
        r.warnings.push(finding(
            "incomplete",
            format!(
                "stopped after exploring {} markings: they filled the {} MiB a check may keep (a plan with many parallel branches has many interleavings); the findings below may be partial",
                ex.markings.len(),
                (explore::MAX_MARKING_WORDS * 4) >> 20
            ),
        ));
    } else if ex.budget_hit {
        r.warnings.push(finding(
            "incomplete",
            format!(
                "stopped after exploring {} markings (the limit); raise --max-states to explore further; the findings below may be partial",
                ex.markings.len()
            ),
        ));
    }
    if unbounded {
        r.warnings.push(finding(
            "unbounded",
            format!("some place can hold more than {MAX_TOKENS} tokens"),
        ));
    }
    if let Some(id) = ex.kinds.iter().position(|k| *k == Kind::Deadlock) {
        r.warnings.push(finding(
            "deadlock",
            format!(
                "the plan can get stuck in a marking that is neither goal nor fail: {}; no transition has the tokens it needs there: check that each join waits only for branches that all end, and give each place a way on (`petrel plan simulate` shows how it gets there)",
                show_marking(plan, ex.markings.get(id as u32))
            ),
        ));
    }
    for (i, &mx) in max_tokens.iter().enumerate() {
        if mx > 1 {
            r.warnings.push(finding(
                "multiple-tokens",
                format!("{} can hold {mx} tokens", place_name(plan, i)),
            ));
        }
    }
    let reached = (has(Kind::Goal), has(Kind::Fail));
    if !r.complete {
        // Unsure: a parent must not conclude this plan never ends or never fails.
        return (true, true);
    }
    // A rule that never applies leaves all its transitions dead: say it once.
    let mut told = std::collections::HashSet::new();
    for ti in 0..plan.transitions().len() {
        if !ex.fired[ti] && plan.origin(ti).is_none_or(|o| told.insert(o)) {
            r.warnings.push(finding(
                "dead-transition",
                dead_transition(plan, &ex.fired, ti),
            ));
        }
    }
    if let Some(f) = livelock::find(plan, outcomes, &ex) {
        r.warnings.push(f);
    }
    if !has(Kind::Goal) && !plan.goal_places().is_empty() {
        let over: Vec<String> = plan
            .goal_places()
            .iter()
            .filter(|&&(p, k)| max_tokens[p] > k)
            .map(|&(p, k)| {
                format!(
                    "{} gets {} tokens but its goal marking is {k}",
                    place_name(plan, p),
                    max_tokens[p]
                )
            })
            .collect();
        let why = if over.is_empty() {
            String::new()
        } else {
            format!(": {}", over.join("; "))
        };
        r.warnings.push(finding(
            "goal-unreachable",
            format!("the goal marking can never be reached exactly{why}"),
        ));
    }
    reached
}

/// Why transition `ti` never fires, in the terms the user wrote: the rule or action it comes
/// from, and an earlier transition that takes the same tokens on the same guard (a rule
/// shadowed by another).
fn dead_transition(plan: &Plan, fired: &[bool], ti: usize) -> String {
    let ts = plan.transitions();
    let t = &ts[ti];
    let Some(origin) = plan.origin(ti) else {
        return format!("transition '{}' ('{}') can never fire", t.id, t.label);
    };
    let shadow = ts[..ti].iter().enumerate().find(|(ei, e)| {
        fired[*ei] && e.guard == t.guard && e.inputs.iter().any(|i| t.inputs.contains(i))
    });
    let why = match shadow {
        Some((ei, e)) => match plan.origin(ei) {
            Some(o) => format!(": {o} already handles it"),
            None => format!(": `{}` takes the same tokens first", e.label),
        },
        None => String::new(),
    };
    if origin.starts_with("action") {
        return format!("{origin}: `{}` can never fire{why}", t.label);
    }
    format!("{origin} never applies (`{}` can never fire){why}", t.label)
}
