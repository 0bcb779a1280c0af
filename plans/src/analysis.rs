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

use std::collections::{HashSet, VecDeque};
use std::fmt;

use crate::exec::{status_of, PlanStatus};
use crate::model::{Atom, Plan};

/// Markings explored at most.
const MAX_STATES: usize = 20_000;
/// A place holding more tokens than this is taken as unbounded.
const MAX_TOKENS: u32 = 64;
/// Atoms tried in all combinations in one step; beyond, transitions are
/// fired one at a time instead.
const MAX_ATOMS: usize = 10;

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
    format!("place '{}' ('{}')", pl.id, pl.label)
}

/// Checks a plan and its sub-plans (their findings are prefixed with
/// `sub-plan NAME:`).
pub fn check(plan: &Plan) -> CheckReport {
    let mut r = CheckReport {
        plan: plan.name().to_string(),
        ..CheckReport::default()
    };
    for e in plan.executables() {
        match &e.subplan {
            Some(sp) => {
                r.subplans.push(e.name.clone());
                let sub = check(sp);
                let pre =
                    |f: Finding| finding(f.code, format!("sub-plan {}: {}", e.name, f.message));
                r.errors.extend(sub.errors.into_iter().map(pre));
                r.warnings.extend(sub.warnings.into_iter().map(pre));
            }
            None => r.actions.push(e.name.clone()),
        }
    }
    r.conditions = plan.conditions().to_vec();
    structural(plan, &mut r);
    explore(plan, &mut r);
    r
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

/// Fires, in document order, every transition in `enabled` that still has
/// its tokens; returns the successor and whether anything fired.
fn fire_all(plan: &Plan, m: &[u32], enabled: &[usize], fired: &mut [bool]) -> Option<Vec<u32>> {
    let mut next = m.to_vec();
    let mut any = false;
    for &ti in enabled {
        let t = &plan.transitions()[ti];
        if t.inputs.iter().all(|e| next[e.place] >= e.weight) {
            t.inputs.iter().for_each(|e| next[e.place] -= e.weight);
            t.outputs
                .iter()
                .for_each(|e| next[e.place] = next[e.place].saturating_add(e.weight));
            fired[ti] = true;
            any = true;
        }
    }
    any.then_some(next)
}

fn explore(plan: &Plan, r: &mut CheckReport) {
    let n = plan.places().len();
    let initial: Vec<u32> = plan.places().iter().map(|p| p.initial).collect();
    let mut seen: HashSet<Vec<u32>> = HashSet::from([initial.clone()]);
    let mut queue = VecDeque::from([initial]);
    let mut fired = vec![false; plan.transitions().len()];
    let mut max_tokens = vec![0u32; n];
    let (mut goal_reached, mut unbounded, mut complete) = (false, false, true);
    let mut deadlock: Option<Vec<u32>> = None;
    while let Some(m) = queue.pop_front() {
        for (mx, &k) in max_tokens.iter_mut().zip(&m) {
            *mx = (*mx).max(k);
        }
        match status_of(plan, &m) {
            PlanStatus::Goal => {
                goal_reached = true;
                continue;
            }
            PlanStatus::Fail => continue,
            PlanStatus::Running => {}
        }
        if m.iter().any(|&k| k > MAX_TOKENS) {
            unbounded = true;
            continue;
        }
        let cands: Vec<usize> = (0..plan.transitions().len())
            .filter(|&ti| {
                plan.transitions()[ti]
                    .inputs
                    .iter()
                    .all(|e| m[e.place] >= e.weight)
            })
            .collect();
        if cands.is_empty() {
            deadlock.get_or_insert_with(|| m.clone());
            continue;
        }
        let mut atoms: Vec<Atom> = Vec::new();
        for &ti in &cands {
            plan.transitions()[ti].guard.for_each_atom(&mut |a| {
                if !atoms.contains(a) {
                    atoms.push(*a);
                }
            });
        }
        let mut succ = Vec::new();
        if atoms.len() <= MAX_ATOMS {
            for mask in 0u32..(1 << atoms.len()) {
                let value =
                    |a: &Atom| mask & (1 << atoms.iter().position(|x| x == a).unwrap_or(0)) != 0;
                let enabled: Vec<usize> = cands
                    .iter()
                    .copied()
                    .filter(|&ti| plan.transitions()[ti].guard.eval(&mut |a| value(a)))
                    .collect();
                succ.extend(fire_all(plan, &m, &enabled, &mut fired));
            }
        } else {
            for &ti in &cands {
                succ.extend(fire_all(plan, &m, &[ti], &mut fired));
            }
        }
        for s in succ {
            if seen.len() >= MAX_STATES {
                complete = false;
                break;
            }
            if seen.insert(s.clone()) {
                queue.push_back(s);
            }
        }
    }
    r.states = seen.len();
    r.complete = complete && !unbounded;
    if !complete {
        r.warnings.push(finding(
            "incomplete",
            format!(
                "stopped exploring after {MAX_STATES} markings; the findings below may be partial"
            ),
        ));
    }
    if unbounded {
        r.warnings.push(finding(
            "unbounded",
            format!("some place can hold more than {MAX_TOKENS} tokens"),
        ));
    }
    if let Some(m) = deadlock {
        let marked: Vec<String> = m
            .iter()
            .enumerate()
            .filter(|(_, k)| **k > 0)
            .map(|(p, k)| format!("'{}': {k}", plan.places()[p].label))
            .collect();
        r.warnings.push(finding(
            "deadlock",
            format!(
                "the plan can get stuck in a marking that is neither goal nor fail: {{{}}}",
                marked.join(", ")
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
    if r.complete {
        for (ti, t) in plan.transitions().iter().enumerate() {
            if !fired[ti] {
                r.warnings.push(finding(
                    "dead-transition",
                    format!("transition '{}' ('{}') can never fire", t.id, t.label),
                ));
            }
        }
        if !goal_reached && !plan.goal_places().is_empty() {
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
    }
}
