//! Livelocks: reachable markings from which the plan can reach neither its goal nor its fail
//! marking, though it can still step (a deadlock is reported on its own).
//!
//! On a complete exploration these are exactly the bottom strongly connected components of
//! the reachability graph (no step leaves them) holding no goal, fail or deadlocked marking:
//! whatever the environment answers, the plan stays inside forever. Whether there is one is
//! found first by walking the steps backwards from the other markings (one pass); only then
//! are the components computed, with petgraph's Kosaraju (iterative: a 200,000-marking chain
//! must not recurse). The witness is the shortest path from the initial marking to the trap,
//! replayed with the real step.

use petgraph::algo::kosaraju_scc;
use petgraph::graph::NodeIndex;
use petgraph::Direction;

use super::explore::{witness, Explored, Kind, Outcomes};
use super::{finding, show_marking, Finding};
use crate::model::Plan;

/// Steps of a witness shown at each end; the middle of a longer one is elided.
const SHOWN_STEPS: usize = 6;

/// The livelock whose trap is reached first (breadth-first), with a witness, if any.
pub(super) fn find(plan: &Plan, outcomes: &Outcomes, ex: &Explored) -> Option<Finding> {
    if plan.goal_places().is_empty() {
        return None; // no goal to miss: the plan is reported unusable already
    }
    if !has_trap(ex) {
        return None;
    }
    let sccs = kosaraju_scc(&ex.graph);
    let mut component = vec![0usize; ex.markings.len()];
    for (c, scc) in sccs.iter().enumerate() {
        for n in scc {
            component[n.index()] = c;
        }
    }
    let traps: Vec<&Vec<_>> = sccs
        .iter()
        .enumerate()
        .filter(|(c, scc)| {
            let bottom = scc
                .iter()
                .all(|&n| ex.graph.neighbors(n).all(|m| component[m.index()] == *c));
            bottom && scc.iter().all(|n| ex.kinds[n.index()] == Kind::Running)
        })
        .map(|(_, scc)| scc)
        .collect();
    let trap = traps
        .iter()
        .min_by_key(|scc| scc.iter().map(|n| n.index()).min())?;
    let entry = trap.iter().map(|n| n.index() as u32).min()?;
    let steps = witness(plan, outcomes, ex, entry);
    let others = match traps.len() - 1 {
        0 => String::new(),
        1 => " (and 1 other such trap)".to_string(),
        n => format!(" (and {n} other such traps)"),
    };
    let size = match trap.len() {
        1 => "in this marking".to_string(),
        n => format!("among {n} markings"),
    };
    Some(finding(
        "livelock",
        format!(
            "from {} the plan can never reach its goal or fail: it stays {size} forever{others}; reached by {}",
            show_marking(plan, ex.markings.get(entry)),
            show_steps(plan, &steps)
        ),
    ))
}

/// Whether some marking can reach no goal, fail, deadlocked or unexpanded one: exactly when a
/// trap exists (all that such a marking reaches is running, so it reaches a bottom component
/// of running markings). Found walking the steps backwards from those markings, which costs a
/// pass over the graph; the components, which cost several and an allocation each, are only
/// computed for a plan that has a trap to report.
fn has_trap(ex: &Explored) -> bool {
    // Markings never classified (none on a complete exploration) are not traps either.
    let mut reaches_an_end: Vec<bool> = (0..ex.markings.len())
        .map(|id| ex.kinds.get(id).is_none_or(|k| *k != Kind::Running))
        .collect();
    let mut queue: Vec<NodeIndex<u32>> = (reaches_an_end.iter().enumerate())
        .filter(|(_, end)| **end)
        .map(|(id, _)| NodeIndex::new(id))
        .collect();
    while let Some(n) = queue.pop() {
        for m in ex.graph.neighbors_directed(n, Direction::Incoming) {
            if !std::mem::replace(&mut reaches_an_end[m.index()], true) {
                queue.push(m);
            }
        }
    }
    reaches_an_end.contains(&false)
}

/// `step 1: t0 ('a.start'); step 2: ...`, the middle elided when long.
fn show_steps(plan: &Plan, steps: &[Vec<usize>]) -> String {
    if steps.is_empty() {
        return "starting there".into();
    }
    let show = |(i, fired): (usize, &Vec<usize>)| {
        let ts: Vec<String> = fired
            .iter()
            .map(|&t| {
                let t = &plan.transitions()[t];
                match plan.is_text_plan() {
                    true => format!("'{}'", t.label),
                    false => format!("{} ('{}')", t.id, t.label),
                }
            })
            .collect();
        let ts = if ts.is_empty() {
            "sub-plans only".to_string()
        } else {
            ts.join(" + ")
        };
        format!("step {}: {ts}", i + 1)
    };
    let all: Vec<(usize, &Vec<usize>)> = steps.iter().enumerate().collect();
    if all.len() <= 2 * SHOWN_STEPS {
        return all.into_iter().map(show).collect::<Vec<_>>().join("; ");
    }
    let head: Vec<String> = all[..SHOWN_STEPS].iter().copied().map(show).collect();
    let tail: Vec<String> = all[all.len() - SHOWN_STEPS..]
        .iter()
        .copied()
        .map(show)
        .collect();
    format!(
        "{}; ... {} more steps ...; {}",
        head.join("; "),
        all.len() - 2 * SHOWN_STEPS,
        tail.join("; ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::explore::explore;

    /// The explored graph of text plan `src`, its sub-plans left out.
    fn explored(src: &str) -> Explored {
        let plan = crate::compile_text(src, "t.plan", "t", None).unwrap();
        explore(&plan, &Outcomes::new(), 10_000)
    }

    #[test]
    fn a_trap_is_found_exactly_where_some_marking_can_reach_no_end() {
        // The y branch loops on b forever.
        assert!(has_trap(&explored(
            "a; <x ? c : y ? LABEL_l; b; GOTO_LABEL_l>"
        )));
        // A loop with a way out is no trap; nor is a plain sequence.
        assert!(!has_trap(&explored(
            "LABEL_l; a; <x ? GOTO_LABEL_l : y ? b>"
        )));
        assert!(!has_trap(&explored("a; <x ? c : y ? b>")));
    }
}
