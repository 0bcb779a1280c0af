//! One step of a plan (see the parent module's docs): the pure step function.

use super::{CallRecord, Environment, PlanState, PlanStatus, StepReport};
use crate::hot::Hot;
use crate::label::CallKind;
use crate::model::{Atom, Plan};

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
    report.sub_fired = 0;
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
        match top {
            true => report.fired.push(ti),
            false => report.sub_fired += 1,
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

pub(super) fn has_tokens(state: &PlanState, inputs: &[crate::model::Edge]) -> bool {
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
