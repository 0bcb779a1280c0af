//! What a mission keeps in its blackboard state (`state/memory`), so that a restarted mission
//! module, or an agent resumed from a snapshot, goes on where the plan was: the marking, the
//! actions running with their start times and what they replaced, the `held` windows they had
//! seen open, and what each action did so far (for the summary).

use std::collections::BTreeMap;
use std::sync::Arc;

use petrel_actors::PropertyType;
use serde::{Deserialize, Serialize};

/// `state/memory` of a `mission.pnp` module.
///
/// `clone_from` reuses the target's allocations (strings, vectors, map entries with the same
/// keys): the mission fills the value it published two saves ago in place (see `Run::save`).
#[derive(Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MissionMemory {
    /// The plan this memory is about (its name), empty before the first step.
    pub plan: String,
    /// The marking ([`crate::PlanState::save`]).
    pub marking: Vec<u32>,
    /// Actions started (or resumed) and not ended, interrupted or failed since.
    pub running: BTreeMap<String, RunningAction>,
    /// Per action, what it did so far.
    pub actions: BTreeMap<String, ActionStats>,
    /// The action whose unhandled failure failed the plan, if one did.
    pub failed_action: Option<String>,
    /// What other agents asked of this one (team runs to answer, conditions watched).
    pub serve: crate::remote::Serve,
    /// The runs this mission started on other agents' actions, and where they stand.
    pub dispatch: crate::remote::DispatchMemory,
}

impl PropertyType for MissionMemory {
    const TYPE_NAME: &'static str = "pnp.memory";
}

impl Clone for MissionMemory {
    fn clone(&self) -> Self {
        MissionMemory {
            plan: self.plan.clone(),
            marking: self.marking.clone(),
            running: self.running.clone(),
            actions: self.actions.clone(),
            failed_action: self.failed_action.clone(),
            serve: self.serve.clone(),
            dispatch: self.dispatch.clone(),
        }
    }

    fn clone_from(&mut self, source: &Self) {
        // Destructured so that a field added later cannot be forgotten here.
        let MissionMemory {
            plan,
            marking,
            running,
            actions,
            failed_action,
            serve,
            dispatch,
        } = source;
        self.plan.clone_from(plan);
        self.marking.clone_from(marking);
        clone_map_from(&mut self.running, running);
        clone_map_from(&mut self.actions, actions);
        self.failed_action.clone_from(failed_action);
        self.serve.clone_from(serve);
        self.dispatch.clone_from(dispatch);
    }
}

/// `dst = src.clone()`, keeping the entries (and their allocations) of keys both have.
fn clone_map_from<V: Clone>(dst: &mut BTreeMap<String, V>, src: &BTreeMap<String, V>) {
    dst.retain(|k, _| src.contains_key(k));
    for (k, v) in src {
        match dst.get_mut(k) {
            Some(d) => d.clone_from(v),
            None => {
                dst.insert(k.clone(), v.clone());
            }
        }
    }
}

/// One mission step's firings, as pushed to `out/firings`: what fired, in firing order, and the
/// marking it left (for consoles and recordings, which need not infer firings from markings).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PlanFiring {
    /// The mission's clock (s) when they fired.
    pub time_s: f64,
    /// The transitions fired, by label (by id for a jump without one), in order (shared with
    /// the mission: a firing copies no text).
    pub transitions: Vec<Arc<str>>,
    /// The marking after them, as `out/marking` shows it.
    pub marking: Arc<str>,
}

impl PropertyType for PlanFiring {
    const TYPE_NAME: &'static str = "pnp.firing";
}

/// An action in progress.
#[derive(Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RunningAction {
    /// When it started, in mission clock seconds.
    pub started_s: f64,
    /// The values its `set` replaced (config form), put back when it ends.
    pub saved: Option<Vec<ron::Value>>,
    /// Per condition expression (finished, failed), when each `held` has seen its condition
    /// true since, in clock seconds.
    pub held: Vec<Vec<Option<f64>>>,
}

impl Clone for RunningAction {
    fn clone(&self) -> Self {
        RunningAction {
            started_s: self.started_s,
            saved: self.saved.clone(),
            held: self.held.clone(),
        }
    }

    /// Reuses `self`'s vectors (see [`MissionMemory`]).
    fn clone_from(&mut self, source: &Self) {
        self.started_s = source.started_s;
        self.saved.clone_from(&source.saved);
        self.held.clone_from(&source.held);
    }
}

/// What one action did during the run.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ActionStats {
    /// Starts and resumes.
    pub starts: u32,
    /// Ends (its `finished` held).
    pub ends: u32,
    /// Failures (its `failed` held).
    pub failures: u32,
    /// Interrupts (an execution rule, a timeout).
    pub interrupts: u32,
    /// Time spent running, clock seconds (finished runs only).
    pub time_s: f64,
}

impl MissionMemory {
    /// `action` failed and no execution rule handled it (the plan failed with it): a failure
    /// in its record like a handled one, its run ended at `secs`. No plan transition fired for
    /// it, so the step did not count it.
    pub(crate) fn count_unhandled_failure(&mut self, action: &str, secs: f64) {
        let stats = self.actions.entry(action.to_string()).or_default();
        stats.failures += 1;
        if let Some(run) = self.running.remove(action) {
            stats.time_s += (secs - run.started_s).max(0.0);
        }
    }

    /// One line per action: `goto_A: 2 starts, 2 ends, 0 failures, 0 interrupts, 12.3 s`.
    pub fn report(&self) -> String {
        self.actions
            .iter()
            .map(|(name, a)| {
                format!(
                    "{name}: {} start{}, {} end{}, {} failure{}, {} interrupt{}, {:.1} s",
                    a.starts,
                    s(a.starts),
                    a.ends,
                    s(a.ends),
                    a.failures,
                    s(a.failures),
                    a.interrupts,
                    s(a.interrupts),
                    a.time_s
                )
            })
            .collect::<Vec<_>>()
            .join("\n")
    }
}

/// Why `memory` cannot be where `plan` goes on from, if it cannot: a marking that does not
/// fit the plan, a running action the plan does not have, a time that is no clock time. A
/// memory the mission wrote itself always fits; one from a snapshot may have been edited, or
/// taken with another plan of the same name. `None` too for a memory of another plan (or of
/// none), which a mission does not resume.
pub(crate) fn memory_problem(plan: &crate::Plan, memory: &MissionMemory) -> Option<String> {
    if memory.plan != plan.name() || memory.marking.is_empty() {
        return None;
    }
    if let Err(e) = crate::PlanState::new(plan).restore(plan, &memory.marking) {
        return Some(e);
    }
    let mut actions = Vec::new();
    action_names(plan, &mut actions);
    let clock_time = |t: f64| t.is_finite() && (0.0..=MAX_CLOCK_S).contains(&t);
    for (name, running) in &memory.running {
        if !actions.contains(&name.as_str()) {
            return Some(format!(
                "running action `{name}` is not an action of plan `{}`",
                plan.name()
            ));
        }
        let held = running.held.iter().flatten().flatten();
        if let Some(t) = std::iter::once(&running.started_s)
            .chain(held)
            .find(|t| !clock_time(**t))
        {
            return Some(format!(
                "running action `{name}`: {} is no mission clock time (seconds from 0 to 1e12)",
                petrel_actors::short_number(*t)
            ));
        }
    }
    None
}

/// The latest clock time a memory may hold, s: where the expression clock stops (some 30,000
/// years).
const MAX_CLOCK_S: f64 = 1e12;

/// The names of `plan`'s actions, sub-plans' included.
fn action_names<'p>(plan: &'p crate::Plan, into: &mut Vec<&'p str>) {
    for e in plan.executables() {
        match &e.subplan {
            Some(sub) => action_names(sub, into),
            None => into.push(&e.name),
        }
    }
}

fn s(n: u32) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn memory(running: &[&str], starts: u32) -> MissionMemory {
        let mut m = MissionMemory {
            plan: "p".into(),
            marking: vec![1, 2, starts],
            ..Default::default()
        };
        for name in running {
            let held = vec![vec![Some(1.5), None]];
            let ra = RunningAction {
                started_s: f64::from(starts),
                saved: None,
                held,
            };
            m.running.insert(name.to_string(), ra);
            let stats = ActionStats {
                starts,
                ..Default::default()
            };
            m.actions.insert(name.to_string(), stats);
        }
        m
    }

    #[test]
    fn clone_from_gives_an_equal_memory_whatever_was_there() {
        let sources = [
            memory(&["a"], 1),
            memory(&[], 2),
            memory(&["a", "b"], 3),
            memory(&["b"], 4),
        ];
        for from in &sources {
            for into in &sources {
                let mut target = into.clone();
                target.clone_from(from);
                assert_eq!(&target, from);
            }
        }
    }
}
