//! The immutable net model: places, transitions, executables, guards.
//!
//! A [`Plan`] is built once (from PNML or from a text plan) and never changes;
//! the run-time state lives in [`crate::PlanState`]. Building resolves labels
//! into calls and guards, so a label or guard error is reported at load time.

use std::sync::Arc;

use crate::condition::Cond;
use crate::hot::Hot;
use crate::label::CallKind;

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
    pub(crate) name: String,
    pub(crate) places: Vec<Place>,
    pub(crate) transitions: Vec<Transition>,
    pub(crate) executables: Vec<Executable>,
    pub(crate) conditions: Vec<String>,
    pub(crate) hot: Hot,
    pub(crate) goal: Vec<(usize, u32)>,
    pub(crate) fail: Vec<(usize, u32)>,
    pub(crate) comments: Vec<Comment>,
    /// Where the plan's parts were written (text plans only).
    pub(crate) sources: Sources,
}

/// Where a text plan's actions and transitions come from, for messages in the user's terms.
#[derive(Debug, Clone, Default)]
pub(crate) struct Sources {
    /// The plan file.
    pub file: String,
    /// Line of each action's first occurrence in the plan file (the key is shared with
    /// [`Origin::Action`]: one copy of each name).
    pub action_lines: std::collections::HashMap<Arc<str>, u32>,
    /// What the user wrote that made each transition, by runs of consecutive transitions
    /// (first, past the last, origin), in increasing order: a map entry per transition would
    /// weigh more than the transition.
    pub origins: Vec<(u32, u32, Origin)>,
}

/// What the user wrote that made a run of transitions.
#[derive(Debug, Clone)]
pub(crate) enum Origin {
    /// Action `name` written at this line of the plan file.
    Action { name: Arc<str>, line: u32 },
    /// An execution rule, already said ("the rule at r.er:2 for `a`").
    Rule(Arc<str>),
}

impl Sources {
    /// Marks transitions `first..past` as made by `origin`; runs come in increasing order.
    pub fn mark(&mut self, first: usize, past: usize, origin: Origin) {
        debug_assert!(self.origins.last().is_none_or(|r| r.1 as usize <= first));
        if first < past {
            self.origins.push((first as u32, past as u32, origin));
        }
    }

    /// The origin of transition `t`, as a message says it.
    fn origin(&self, t: usize) -> Option<String> {
        let t = u32::try_from(t).ok()?;
        let i = self.origins.partition_point(|r| r.1 <= t);
        let (first, _, origin) = self.origins.get(i).filter(|r| r.0 <= t)?;
        debug_assert!(*first <= t);
        Some(match origin {
            Origin::Action { name, line } => format!("action `{name}` at {}:{line}", self.file),
            Origin::Rule(text) => text.to_string(),
        })
    }
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

    /// `file:line` where action `name` is first written, for text plans.
    pub fn action_line(&self, name: &str) -> Option<String> {
        let line = self.sources.action_lines.get(name)?;
        Some(format!("{}:{line}", self.sources.file))
    }

    /// Whether the plan was compiled from the text language (its node ids are made up, so
    /// messages name labels, actions and rules instead).
    pub(crate) fn is_text_plan(&self) -> bool {
        !self.sources.file.is_empty()
    }

    /// What the user wrote that made transition `t` (text plans): "the rule at r.er:2 (...)".
    pub fn origin(&self, t: usize) -> Option<String> {
        self.sources.origin(t)
    }

    pub(crate) fn set_subplan(&mut self, exec: usize, plan: Arc<Plan>) {
        self.executables[exec].subplan = Some(plan);
    }

    /// This plan with its sub-plans turned into plain actions (for checking it on its own):
    /// itself, not a copy, when it has none (a copy of a 100,000-action plan is 100 MB).
    pub(crate) fn without_subplans(&self) -> std::borrow::Cow<'_, Plan> {
        if self.executables.iter().all(|e| e.subplan.is_none()) {
            return std::borrow::Cow::Borrowed(self);
        }
        let mut plan = self.clone();
        for e in &mut plan.executables {
            e.subplan = None;
        }
        std::borrow::Cow::Owned(plan)
    }
}
