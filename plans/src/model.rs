//! The immutable net model: places, transitions, executables, guards.
//!
//! A [`Plan`] is built once (from PNML or from a text plan) and never changes;
//! the run-time state lives in [`crate::PlanState`]. Building resolves labels
//! into calls and guards, so a label or guard error is reported at load time.

use std::collections::HashMap;
use std::sync::Arc;

use crate::condition::{parse_condition, Cond};
use crate::error::PlanError;
use crate::label::{parse_place_label, parse_transition_label, CallKind, CallTarget};

/// An editor position in pixels (JARP's `graphics/position`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Position {
    /// Horizontal, growing to the right.
    pub x: f64,
    /// Vertical, growing downwards.
    pub y: f64,
}

/// An atom of a resolved guard.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Atom {
    /// `A.finished`, with `A` an index into [`Plan::executables`].
    Finished(usize),
    /// `A.failed`, with `A` an index into [`Plan::executables`].
    Failed(usize),
    /// An external condition, an index into [`Plan::conditions`].
    External(usize),
}

/// A resolved guard.
pub type Condition = Cond<Atom>;

/// A place.
#[derive(Debug, Clone)]
pub struct Place {
    /// The node id in the file.
    pub id: String,
    /// The label as written.
    pub label: String,
    /// Initial tokens.
    pub initial: u32,
    /// The executable whose execution place this is (index into [`Plan::executables`]).
    pub exec: Option<usize>,
    /// The goal marking (0 = not a goal place).
    pub goal: u32,
    /// The fail marking (0 = not a fail place).
    pub fail: u32,
    /// Editor position, if known.
    pub position: Option<Position>,
}

/// One side of an arc, seen from its transition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    /// Index into [`Plan::places`].
    pub place: usize,
    /// Tokens moved.
    pub weight: u32,
}

/// A call made when a transition fires.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Call {
    /// Index into [`Plan::executables`].
    pub exec: usize,
    /// What is called.
    pub kind: CallKind,
}

/// A transition.
#[derive(Debug, Clone)]
pub struct Transition {
    /// The node id in the file.
    pub id: String,
    /// The label as written.
    pub label: String,
    /// Input places with arc weights, in arc document order.
    pub inputs: Vec<Edge>,
    /// Output places with arc weights, in arc document order.
    pub outputs: Vec<Edge>,
    /// The guard: the explicit one, or the default one (`A.finished` for
    /// `A.end`, `A.failed` for `A.fail`, their conjunction if several), or true.
    pub guard: Condition,
    /// Whether the guard was written in the label.
    pub explicit_guard: bool,
    /// Calls, in label order (bare calls expanded in place order).
    pub calls: Vec<Call>,
    /// Editor position, if known.
    pub position: Option<Position>,
}

/// An executable: an action run by the [`crate::Environment`], or a sub-plan.
#[derive(Debug, Clone)]
pub struct Executable {
    /// The name (text before the last dot), e.g. `gotopose_6_2_0`.
    pub name: String,
    /// The sub-plan, when a plan file of that name sits next to the parent.
    pub subplan: Option<Arc<Plan>>,
}

/// A free-text comment of the editor (kept so a written file looks the same).
#[derive(Debug, Clone, PartialEq)]
pub struct Comment {
    /// The text.
    pub text: String,
    /// Editor position, if known.
    pub position: Option<Position>,
}

/// An immutable Petri Net Plan.
#[derive(Debug, Clone)]
pub struct Plan {
    name: String,
    places: Vec<Place>,
    transitions: Vec<Transition>,
    executables: Vec<Executable>,
    conditions: Vec<String>,
    hot: Hot,
    goal: Vec<(usize, u32)>,
    fail: Vec<(usize, u32)>,
    comments: Vec<Comment>,
}

impl Plan {
    /// The plan name (JARP comment `PLAN NAME: x`, or the file name up to its first dot).
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Places in document order.
    pub fn places(&self) -> &[Place] {
        &self.places
    }
    /// Transitions in document order (the firing order).
    pub fn transitions(&self) -> &[Transition] {
        &self.transitions
    }
    /// Executables, in order of first mention.
    pub fn executables(&self) -> &[Executable] {
        &self.executables
    }
    /// External condition names used by guards, in order of first mention.
    pub fn conditions(&self) -> &[String] {
        &self.conditions
    }
    /// Transitions having `place` as an input, in document order.
    pub fn output_transitions(&self, place: usize) -> &[u32] {
        let h = &self.hot;
        &h.out_list[h.out_start[place] as usize..h.out_start[place + 1] as usize]
    }

    pub(crate) fn hot(&self) -> &Hot {
        &self.hot
    }
    /// Goal places with their goal marking.
    pub fn goal_places(&self) -> &[(usize, u32)] {
        &self.goal
    }
    /// Fail places with their fail marking.
    pub fn fail_places(&self) -> &[(usize, u32)] {
        &self.fail
    }
    /// Editor comments.
    pub fn comments(&self) -> &[Comment] {
        &self.comments
    }
    /// The first place with this exact label.
    pub fn place_by_label(&self, label: &str) -> Option<usize> {
        self.places.iter().position(|p| p.label == label)
    }
    /// The executable of this name.
    pub fn executable(&self, name: &str) -> Option<usize> {
        self.executables.iter().position(|e| e.name == name)
    }

    pub(crate) fn set_subplan(&mut self, exec: usize, plan: Arc<Plan>) {
        self.executables[exec].subplan = Some(plan);
    }

    /// Builds and validates a plan from raw nodes; `file` names the source in errors.
    pub(crate) fn build(raw: RawNet, file: &str) -> Result<Plan, PlanError> {
        Builder {
            file,
            exec_ix: HashMap::new(),
            cond_ix: HashMap::new(),
            executables: vec![],
            conditions: vec![],
        }
        .build(raw)
    }
}

/// The step's working set, laid out flat so that a step touches a few
/// small arrays per marked place, whatever the net size.
#[derive(Debug, Clone)]
pub(crate) struct Hot {
    /// Per place, its executable or [`Hot::NO_EXEC`].
    pub place_exec: Vec<u32>,
    /// `out_list[out_start[p]..out_start[p + 1]]`: transitions fed by place `p`.
    pub out_start: Vec<u32>,
    pub out_list: Vec<u32>,
    /// Per transition, where its arcs start in `arcs` and how many there are.
    pub trans: Vec<HotTransition>,
    /// Input arcs then output arcs of each transition, back to back.
    pub arcs: Vec<Edge>,
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

    fn new(places: &[Place], transitions: &[Transition]) -> Hot {
        let place_exec = places
            .iter()
            .map(|p| p.exec.map_or(Hot::NO_EXEC, |e| e as u32))
            .collect();
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
            out_start,
            out_list,
            trans,
            arcs,
        }
    }
}

/// Nodes as read from a file or produced by the text compiler.
#[derive(Debug, Clone, Default)]
pub(crate) struct RawNet {
    pub name: String,
    pub places: Vec<RawPlace>,
    pub transitions: Vec<RawTransition>,
    pub arcs: Vec<RawArc>,
    pub comments: Vec<Comment>,
}

#[derive(Debug, Clone)]
pub(crate) struct RawPlace {
    pub id: String,
    pub label: String,
    pub initial: u32,
    pub position: Option<Position>,
}

#[derive(Debug, Clone)]
pub(crate) struct RawTransition {
    pub id: String,
    pub label: String,
    pub position: Option<Position>,
}

#[derive(Debug, Clone)]
pub(crate) struct RawArc {
    pub id: String,
    pub source: String,
    pub target: String,
    pub weight: u32,
}

struct Builder<'a> {
    file: &'a str,
    exec_ix: HashMap<String, usize>,
    cond_ix: HashMap<String, usize>,
    executables: Vec<Executable>,
    conditions: Vec<String>,
}

enum Node {
    Place(usize),
    Transition(usize),
}

impl Builder<'_> {
    fn exec(&mut self, name: &str) -> usize {
        if let Some(&i) = self.exec_ix.get(name) {
            return i;
        }
        self.executables.push(Executable {
            name: name.to_string(),
            subplan: None,
        });
        self.exec_ix
            .insert(name.to_string(), self.executables.len() - 1);
        self.executables.len() - 1
    }

    fn atom(&mut self, text: &str) -> Atom {
        match text.rsplit_once('.') {
            Some((name, "finished")) if !name.is_empty() => Atom::Finished(self.exec(name)),
            Some((name, "failed")) if !name.is_empty() => Atom::Failed(self.exec(name)),
            _ => {
                let n = self.conditions.len();
                let i = *self.cond_ix.entry(text.to_string()).or_insert(n);
                if i == n {
                    self.conditions.push(text.to_string());
                }
                Atom::External(i)
            }
        }
    }

    fn pnml_err(&self, element: String, message: String) -> PlanError {
        PlanError::Pnml {
            file: self.file.to_string(),
            element,
            message,
        }
    }

    fn build(mut self, raw: RawNet) -> Result<Plan, PlanError> {
        let mut ids: HashMap<&str, Node> = HashMap::new();
        let mut places = Vec::with_capacity(raw.places.len());
        for (i, p) in raw.places.iter().enumerate() {
            if ids.insert(&p.id, Node::Place(i)).is_some() {
                return Err(self.pnml_err(format!("place '{}'", p.id), "duplicate node id".into()));
            }
            let l = parse_place_label(&p.label).map_err(|message| PlanError::Label {
                file: self.file.to_string(),
                kind: "place",
                id: p.id.clone(),
                label: p.label.clone(),
                message,
            })?;
            let exec = l.exec.map(|n| self.exec(&n));
            places.push(Place {
                id: p.id.clone(),
                label: p.label.clone(),
                initial: p.initial,
                exec,
                goal: l.goal,
                fail: l.fail,
                position: p.position,
            });
        }
        let mut transitions = Vec::with_capacity(raw.transitions.len());
        for (i, t) in raw.transitions.iter().enumerate() {
            if ids.insert(&t.id, Node::Transition(i)).is_some() {
                return Err(
                    self.pnml_err(format!("transition '{}'", t.id), "duplicate node id".into())
                );
            }
            transitions.push(Transition {
                id: t.id.clone(),
                label: t.label.clone(),
                inputs: vec![],
                outputs: vec![],
                guard: Cond::True,
                explicit_guard: false,
                calls: vec![],
                position: t.position,
            });
        }
        for a in &raw.arcs {
            let find = |id: &str, end: &str| {
                ids.get(id).ok_or_else(|| {
                    self.pnml_err(
                        format!("arc '{}'", a.id),
                        format!("{end} '{id}' is not a place or transition id"),
                    )
                })
            };
            let (s, t) = (find(&a.source, "source")?, find(&a.target, "target")?);
            let (tr, edge, input) = match (s, t) {
                (Node::Place(p), Node::Transition(t)) => (*t, Edge { place: *p, weight: a.weight }, true),
                (Node::Transition(t), Node::Place(p)) => (*t, Edge { place: *p, weight: a.weight }, false),
                (Node::Place(_), Node::Place(_)) => {
                    return Err(self.pnml_err(
                        format!("arc '{}'", a.id),
                        format!("joins two places ('{}' -> '{}'); an arc must join a place and a transition", a.source, a.target),
                    ))
                }
                (Node::Transition(_), Node::Transition(_)) => {
                    return Err(self.pnml_err(
                        format!("arc '{}'", a.id),
                        format!(
                            "joins two transitions ('{}' -> '{}'); an arc must join a place and a transition",
                            a.source, a.target
                        ),
                    ))
                }
            };
            let side = if input {
                &mut transitions[tr].inputs
            } else {
                &mut transitions[tr].outputs
            };
            // Parallel arcs between the same pair add up, as in a multiset.
            match side.iter_mut().find(|e| e.place == edge.place) {
                Some(e) => e.weight += edge.weight,
                None => side.push(edge),
            }
        }
        for t in &mut transitions {
            self.resolve_label(t, &places)?;
        }
        let hot = Hot::new(&places, &transitions);
        let goal = places
            .iter()
            .enumerate()
            .filter(|(_, p)| p.goal > 0)
            .map(|(i, p)| (i, p.goal))
            .collect();
        let fail = places
            .iter()
            .enumerate()
            .filter(|(_, p)| p.fail > 0)
            .map(|(i, p)| (i, p.fail))
            .collect();
        Ok(Plan {
            name: raw.name,
            places,
            transitions,
            executables: self.executables,
            conditions: self.conditions,
            hot,
            goal,
            fail,
            comments: raw.comments,
        })
    }

    fn resolve_label(&mut self, t: &mut Transition, places: &[Place]) -> Result<(), PlanError> {
        let l = parse_transition_label(&t.label).map_err(|message| PlanError::Label {
            file: self.file.to_string(),
            kind: "transition",
            id: t.id.clone(),
            label: t.label.clone(),
            message,
        })?;
        for (target, kind) in l.calls {
            match target {
                CallTarget::Named(n) => {
                    let exec = self.exec(&n);
                    t.calls.push(Call { exec, kind });
                }
                CallTarget::Bare => {
                    let side = if kind.bare_uses_outputs() {
                        &t.outputs
                    } else {
                        &t.inputs
                    };
                    for e in side {
                        if let Some(exec) = places[e.place].exec {
                            if !t.calls.contains(&Call { exec, kind }) {
                                t.calls.push(Call { exec, kind });
                            }
                        }
                    }
                }
            }
        }
        if let Some(g) = l.guard {
            let parsed = parse_condition(&g).map_err(|e| PlanError::Guard {
                file: self.file.to_string(),
                id: t.id.clone(),
                label: t.label.clone(),
                message: e.to_string(),
            })?;
            t.guard = parsed
                .try_map::<_, ()>(&mut |a| Ok(self.atom(a)))
                .expect("atom resolution cannot fail");
            t.explicit_guard = true;
        } else {
            let mut atoms: Vec<Condition> = Vec::new();
            for c in &t.calls {
                let a = match c.kind {
                    CallKind::End => Atom::Finished(c.exec),
                    CallKind::Fail => Atom::Failed(c.exec),
                    _ => continue,
                };
                if !atoms.contains(&Cond::Atom(a)) {
                    atoms.push(Cond::Atom(a));
                }
            }
            t.guard = match atoms.len() {
                0 => Cond::True,
                1 => atoms.pop().expect("one atom"),
                _ => Cond::And(atoms),
            };
        }
        Ok(())
    }
}
