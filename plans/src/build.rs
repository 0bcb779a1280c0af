//! Building a [`Plan`] from raw nodes: ids, labels, guards and calls are
//! resolved and checked here, so every label or guard error shows at load time.

use std::collections::HashMap;

use crate::condition::{parse_condition, Cond};
use crate::error::PlanError;
use crate::hot::Hot;
use crate::label::{parse_place_label, parse_transition_label, CallKind, CallTarget};
use crate::model::{
    Atom, Call, Comment, Condition, Edge, Executable, Place, Plan, Position, Transition,
};

impl Plan {
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

/// Nodes as read from a file or produced by the text compiler.
#[derive(Debug, Clone, Default)]
pub(crate) struct RawNet {
    pub name: String,
    pub places: Vec<RawPlace>,
    pub transitions: Vec<RawTransition>,
    pub arcs: Vec<RawArc>,
    pub comments: Vec<Comment>,
    /// The ids arcs name ([`ArcEnd::Named`], [`RawArc::id`]): a file's arcs refer to nodes by
    /// id; the text compiler's arcs number them and leave this empty.
    pub names: Vec<Box<str>>,
}

impl RawNet {
    /// Keeps `id` for an arc to name; its number in [`RawNet::names`].
    pub fn name(&mut self, id: &str) -> u32 {
        self.names.push(id.into());
        (self.names.len() - 1) as u32
    }
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

/// One end of an arc: a node id as a file names it (its number in [`RawNet::names`]), or a
/// node by number (the nets the text compiler makes: no id strings to format and look up,
/// which a 100,000-action plan feels). Eight bytes, so an arc is 28: a long plan has twice
/// as many arcs as nodes.
#[derive(Debug, Clone, Copy)]
pub(crate) enum ArcEnd {
    Named(u32),
    Place(u32),
    Transition(u32),
}

impl ArcEnd {
    /// The end as a message names it.
    fn text(self, names: &[Box<str>]) -> String {
        match self {
            ArcEnd::Named(n) => names[n as usize].to_string(),
            ArcEnd::Place(i) => format!("place #{i}"),
            ArcEnd::Transition(i) => format!("transition #{i}"),
        }
    }
}

#[derive(Debug, Clone)]
pub(crate) struct RawArc {
    /// The file's id for the arc (its number in [`RawNet::names`], for messages); nets made
    /// in memory leave it out.
    pub id: Option<u32>,
    pub source: ArcEnd,
    pub target: ArcEnd,
    pub weight: u32,
}

struct Builder<'a> {
    file: &'a str,
    exec_ix: HashMap<String, usize>,
    cond_ix: HashMap<String, usize>,
    executables: Vec<Executable>,
    conditions: Vec<String>,
}

/// An arc with its ends resolved: 16 bytes, as a long plan has many.
struct Link {
    transition: u32,
    place: u32,
    weight: u32,
    /// From the place into the transition.
    input: bool,
}

#[derive(Clone, Copy)]
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
            line: 0,
            column: 0,
            element,
            message,
        }
    }

    fn build(mut self, raw: RawNet) -> Result<Plan, PlanError> {
        let RawNet {
            name,
            places: raw_places,
            transitions: raw_transitions,
            arcs,
            comments,
            names,
        } = raw;
        // Ids and labels move into the plan: a copy of each would double a big plan's strings.
        let mut places = Vec::with_capacity(raw_places.len());
        for p in raw_places {
            let l = parse_place_label(&p.label).map_err(|message| PlanError::Label {
                file: self.file.to_string(),
                line: 0,
                column: 0,
                kind: "place",
                id: p.id.clone(),
                label: p.label.clone(),
                message,
            })?;
            let exec = l.exec.map(|n| self.exec(&n));
            places.push(Place {
                id: p.id,
                label: p.label,
                initial: p.initial,
                exec,
                goal: l.goal,
                fail: l.fail,
                position: p.position,
            });
        }
        let mut transitions: Vec<Transition> = raw_transitions
            .into_iter()
            .map(|t| Transition {
                id: t.id,
                label: t.label,
                inputs: vec![],
                outputs: vec![],
                guard: Cond::True,
                explicit_guard: false,
                calls: vec![],
                position: t.position,
            })
            .collect();
        let edges = self.edges(&places, &transitions, &arcs, &names)?;
        drop(arcs);
        drop(names);
        // Each side sized before it is filled: growing and shrinking half a million small
        // lists leaves the allocator holding the holes.
        let mut sides = vec![(0u32, 0u32); transitions.len()];
        for l in &edges {
            let side = &mut sides[l.transition as usize];
            match l.input {
                true => side.0 += 1,
                false => side.1 += 1,
            }
        }
        for (t, (ins, outs)) in transitions.iter_mut().zip(sides) {
            t.inputs.reserve_exact(ins as usize);
            t.outputs.reserve_exact(outs as usize);
        }
        for l in edges {
            let t = &mut transitions[l.transition as usize];
            let side = if l.input {
                &mut t.inputs
            } else {
                &mut t.outputs
            };
            let edge = Edge {
                place: l.place as usize,
                weight: l.weight,
            };
            // Parallel arcs between the same pair add up, as in a multiset.
            match side.iter_mut().find(|e| e.place == edge.place) {
                Some(e) => e.weight = e.weight.saturating_add(edge.weight),
                None => side.push(edge),
            }
        }
        for t in &mut transitions {
            self.resolve_label(t, &places)?;
        }
        let hot = Hot::new(&places, &transitions, &self.executables);
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
            name,
            places,
            transitions,
            executables: self.executables,
            conditions: self.conditions,
            hot,
            goal,
            fail,
            comments,
            sources: Default::default(),
        })
    }

    /// Each arc as a [`Link`], with its ends checked: ids unique and known, one end a place
    /// and the other a transition.
    fn edges(
        &self,
        places: &[Place],
        transitions: &[Transition],
        arcs: &[RawArc],
        names: &[Box<str>],
    ) -> Result<Vec<Link>, PlanError> {
        let mut ids: HashMap<&str, Node> = HashMap::new();
        // A net made in memory numbers its arcs' ends and its ids are unique by construction:
        // a map of half a million ids would be the biggest thing in a long plan's check.
        let named = |e: &ArcEnd| matches!(e, ArcEnd::Named(_));
        let numbered =
            !arcs.is_empty() && !arcs.iter().any(|a| named(&a.source) || named(&a.target));
        let (places_named, transitions_named) = match numbered {
            true => (&places[..0], &transitions[..0]),
            false => (places, transitions),
        };
        for (i, p) in places_named.iter().enumerate() {
            if ids.insert(&p.id, Node::Place(i)).is_some() {
                return Err(self.pnml_err(format!("place '{}'", p.id), "duplicate node id".into()));
            }
        }
        for (i, t) in transitions_named.iter().enumerate() {
            if ids.insert(&t.id, Node::Transition(i)).is_some() {
                return Err(
                    self.pnml_err(format!("transition '{}'", t.id), "duplicate node id".into())
                );
            }
        }
        let mut edges = Vec::with_capacity(arcs.len());
        for (k, a) in arcs.iter().enumerate() {
            let arc = || match a.id {
                Some(id) => format!("arc '{}'", names[id as usize]),
                None => format!("arc #{k}"),
            };
            let find = |end: ArcEnd, which: &str| -> Result<Node, PlanError> {
                let node = match end {
                    ArcEnd::Named(n) => ids.get(&*names[n as usize]).copied(),
                    ArcEnd::Place(i) => {
                        let i = i as usize;
                        (i < places.len()).then_some(Node::Place(i))
                    }
                    ArcEnd::Transition(i) => {
                        let i = i as usize;
                        (i < transitions.len()).then_some(Node::Transition(i))
                    }
                };
                node.ok_or_else(|| {
                    self.pnml_err(
                        arc(),
                        format!(
                            "{which} '{}' is not a place or transition id",
                            end.text(names)
                        ),
                    )
                })
            };
            let (s, t) = (find(a.source, "source")?, find(a.target, "target")?);
            let link = |transition: usize, place: usize, input: bool| Link {
                transition: transition as u32,
                place: place as u32,
                weight: a.weight,
                input,
            };
            edges.push(match (s, t) {
                (Node::Place(p), Node::Transition(t)) => link(t, p, true),
                (Node::Transition(t), Node::Place(p)) => link(t, p, false),
                (Node::Place(_), Node::Place(_)) => {
                    return Err(self.pnml_err(
                        arc(),
                        format!("joins two places ('{}' -> '{}'); an arc must join a place and a transition", a.source.text(names), a.target.text(names)),
                    ))
                }
                (Node::Transition(_), Node::Transition(_)) => {
                    return Err(self.pnml_err(
                        arc(),
                        format!(
                            "joins two transitions ('{}' -> '{}'); an arc must join a place and a transition",
                            a.source.text(names),
                            a.target.text(names)
                        ),
                    ))
                }
            });
        }
        Ok(edges)
    }

    fn resolve_label(&mut self, t: &mut Transition, places: &[Place]) -> Result<(), PlanError> {
        let l = parse_transition_label(&t.label).map_err(|message| PlanError::Label {
            file: self.file.to_string(),
            line: 0,
            column: 0,
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
                line: 0,
                column: 0,
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
