//! The step's working set: flat arrays built once per plan.

use std::sync::Arc;

use crate::condition::Cond;
use crate::model::{Atom, Edge, Executable, Place, Transition};

/// The step's working set, laid out flat so that a step touches a few
/// small arrays per marked place, whatever the net size.
#[derive(Debug, Clone)]
pub(crate) struct Hot {
    /// Per place, its executable or [`Hot::NO_EXEC`].
    pub place_exec: Vec<u32>,
    /// Per place: an execution place none of whose output transitions asks whether its
    /// executable failed. A failure there has nobody to handle it, so it fails the plan.
    pub unhandled_fail: Vec<bool>,
    /// `out_list[out_start[p]..out_start[p + 1]]`: transitions fed by place `p`.
    pub out_start: Vec<u32>,
    pub out_list: Vec<u32>,
    /// Per transition, where its arcs start in `arcs` and how many there are.
    pub trans: Vec<HotTransition>,
    /// Input arcs then output arcs of each transition, back to back.
    pub arcs: Vec<Edge>,
    /// Per executable, its name, shared by every [`crate::CallRecord`] of it.
    pub exec_names: Vec<Arc<str>>,
}

#[derive(Debug, Clone, Copy)]
pub(crate) struct HotTransition {
    pub start: u32,
    pub inputs: u32,
    pub outputs: u32,
    /// Guard is `true` and there are no calls: the transition itself need not be read.
    pub plain: bool,
}

impl HotTransition {
    pub fn inputs<'a>(&self, arcs: &'a [Edge]) -> &'a [Edge] {
        &arcs[self.start as usize..(self.start + self.inputs) as usize]
    }
    pub fn outputs<'a>(&self, arcs: &'a [Edge]) -> &'a [Edge] {
        let from = (self.start + self.inputs) as usize;
        &arcs[from..from + self.outputs as usize]
    }
}

impl Hot {
    pub const NO_EXEC: u32 = u32::MAX;

    pub(crate) fn new(places: &[Place], transitions: &[Transition], execs: &[Executable]) -> Hot {
        let place_exec = places
            .iter()
            .map(|p| p.exec.map_or(Hot::NO_EXEC, |e| e as u32))
            .collect();
        // One pass over the transitions: each input place of a transition that asks `A.failed`
        // is handled for `A` (so this costs the arcs, not places times transitions).
        let mut unhandled_fail: Vec<bool> = places.iter().map(|p| p.exec.is_some()).collect();
        for t in transitions {
            t.guard.for_each_atom(&mut |a| {
                if let Atom::Failed(e) = *a {
                    for i in &t.inputs {
                        if places[i.place].exec == Some(e) {
                            unhandled_fail[i.place] = false;
                        }
                    }
                }
            });
        }
        let mut count = vec![0u32; places.len() + 1];
        for t in transitions {
            for e in &t.inputs {
                count[e.place + 1] += 1;
            }
        }
        for i in 1..count.len() {
            count[i] += count[i - 1];
        }
        let out_start = count.clone();
        let mut out_list = vec![0u32; *count.last().unwrap_or(&0) as usize];
        let (mut trans, mut arcs) = (Vec::with_capacity(transitions.len()), Vec::new());
        for (ti, t) in transitions.iter().enumerate() {
            for e in &t.inputs {
                out_list[count[e.place] as usize] = ti as u32;
                count[e.place] += 1;
            }
            trans.push(HotTransition {
                start: arcs.len() as u32,
                inputs: t.inputs.len() as u32,
                outputs: t.outputs.len() as u32,
                plain: t.guard == Cond::True && t.calls.is_empty(),
            });
            arcs.extend_from_slice(&t.inputs);
            arcs.extend_from_slice(&t.outputs);
        }
        Hot {
            place_exec,
            unhandled_fail,
            out_start,
            out_list,
            trans,
            arcs,
            exec_names: execs.iter().map(|e| Arc::from(e.name.as_str())).collect(),
        }
    }
}
