//! The exploration behind [`super::check`]: every marking reachable under the real step
//! function ([`crate::step`]), with the guard atoms left open.
//!
//! * A marking is a compact key ([`PlanState::encode`]: marked places only, sub-plans
//!   included), interned once in [`Markings`]; its id is its node in a petgraph [`Graph`] of
//!   the explored steps, so a marking touching a few places costs a few words, whatever the
//!   net size, and one step costs what is marked.
//! * Successors: the step runs once per combination of the atoms it asks, found lazily
//!   ([`Decisions`]): an atom asked for the first time answers false, and the runs backtrack
//!   over those answers, so only atoms that matter are combined. One atom answers the same
//!   for every transition asking it within a step, as at run time. Beyond [`MAX_ATOMS`] atoms
//!   in one step, each atom is tried alone, then all together.
//! * Markings are numbered in breadth-first order, so the first parent of each is on a
//!   shortest path from the initial marking: the witness of a livelock.

use std::collections::HashMap;
use std::hash::BuildHasher;

use petgraph::graph::{Graph, NodeIndex};

use crate::exec::{step_with, Environment, PlanState, PlanStatus, StepReport};
use crate::label::CallKind;
use crate::model::Plan;

/// A place holding more tokens than this is taken as unbounded.
pub(super) const MAX_TOKENS: u32 = 64;
/// Atoms tried in all combinations in one step; beyond, one at a time, then all together.
const MAX_ATOMS: usize = 10;

/// What a marking turned out to be when explored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    /// Expanded: its successors are in the graph.
    Running,
    Goal,
    Fail,
    /// No transition has its tokens.
    Deadlock,
    /// Not expanded: a place exceeds [`MAX_TOKENS`], or the budget ran out first.
    Open,
}

/// Interned marking keys: an arena of words, and a table of their ids hashed by key.
///
/// The table holds ids only (4 bytes and a control byte each), the keys staying in the arena:
/// a long plan's check looks a successor up at every step, and a table of 200,000 markings
/// then stays within a core's cache, where one holding keys or their hashes did not.
pub(super) struct Markings {
    words: Vec<u32>,
    start: Vec<usize>,
    table: hashbrown::HashTable<u32>,
    hasher: foldhash::fast::FixedState,
}

impl Markings {
    /// Room for `markings` keys of about one marked place each, so that a check reaching about
    /// that many does not copy its tables as they grow.
    fn with_capacity(markings: usize) -> Self {
        Markings {
            words: Vec::with_capacity(3 * markings),
            start: Vec::with_capacity(markings),
            table: hashbrown::HashTable::with_capacity(markings),
            hasher: Default::default(),
        }
    }

    pub fn len(&self) -> usize {
        self.start.len()
    }

    /// The words the keys take, together.
    pub fn words(&self) -> usize {
        self.words.len()
    }

    pub fn get(&self, id: u32) -> &[u32] {
        let from = self.start[id as usize];
        let to = self
            .start
            .get(id as usize + 1)
            .copied()
            .unwrap_or(self.words.len());
        &self.words[from..to]
    }

    fn hash(&self, key: &[u32]) -> u64 {
        self.hasher.hash_one(key)
    }

    pub fn find(&self, key: &[u32]) -> Option<u32> {
        let hash = self.hash(key);
        self.table.find(hash, |&id| self.get(id) == key).copied()
    }

    /// Adds a key not yet present; returns its id.
    pub fn add(&mut self, key: &[u32]) -> u32 {
        let id = self.len() as u32;
        let hash = self.hash(key);
        self.start.push(self.words.len());
        self.words.extend_from_slice(key);
        let Markings {
            words,
            start,
            table,
            hasher,
        } = self;
        let key_of = |id: &u32| {
            let from = start[*id as usize];
            let to = start.get(*id as usize + 1).copied().unwrap_or(words.len());
            hasher.hash_one(&words[from..to])
        };
        table.insert_unique(hash, id, key_of);
        id
    }
}

/// The top-level `(place, tokens)` pairs of a key.
pub(super) fn top_pairs(key: &[u32]) -> impl Iterator<Item = (usize, u32)> + '_ {
    key[1..1 + 2 * (key[0] & !crate::exec::FAILED_BIT) as usize]
        .chunks_exact(2)
        .map(|p| (p[0] as usize, p[1]))
}

/// How unanswered atoms are answered.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// False, and recorded as a decision to backtrack over.
    Record,
    /// True for this atom only.
    Only(u32),
    /// True.
    All,
}

/// What a sub-plan, checked on its own, can come to: whether it can reach its goal (its
/// action ends) and its fail marking (its action fails). A plan is explored with its sub-plans
/// as plain actions that can end or fail only as their own check found, so a plan shared by
/// many parents is explored once, not once per path to it.
pub(super) type Outcomes = HashMap<String, (bool, bool)>;

/// The [`Environment`] of the exploration: answers atoms from a list of decisions.
struct Decisions<'p> {
    plan: &'p Plan,
    /// Executable and condition names to numbers (a fast hasher: a long plan has a name per
    /// action, all hashed when its check starts).
    names: foldhash::HashMap<&'p str, u32>,
    /// The atoms of the plan's conditions and executables (kind 0), by position: the step asks
    /// by position, and a long plan's check looked a name up in a table of every name at
    /// every marking, which cost more in cache misses than the rest of its step.
    conditions: Vec<u32>,
    executables: Vec<u32>,
    /// Atoms that are always false: a sub-plan's end or fail it cannot come to.
    never: Vec<u32>,
    /// Atoms answered in this run, in the order asked (atom = name * 3 + kind).
    path: Vec<(u32, bool)>,
    /// Where each atom of the plan's names is in `path`, plus one (0: not asked in this run):
    /// a step over a plan of thousands of parallel branches asks thousands of atoms, and a
    /// search of `path` for each made one run quadratic.
    asked: Vec<u32>,
    mode: Mode,
}

impl<'p> Decisions<'p> {
    fn new(plan: &'p Plan, outcomes: &Outcomes) -> Self {
        let count = plan.conditions().len() + plan.executables().len();
        let mut names = foldhash::HashMap::with_capacity_and_hasher(
            count,
            foldhash::fast::RandomState::default(),
        );
        for name in plan
            .conditions()
            .iter()
            .chain(plan.executables().iter().map(|e| &e.name))
        {
            let n = names.len() as u32;
            names.entry(name.as_str()).or_insert(n);
        }
        let mut never = Vec::new();
        for (name, &(can_end, can_fail)) in outcomes {
            if let Some(&n) = names.get(name.as_str()) {
                never.extend((!can_end).then_some(n * 3 + 1));
                never.extend((!can_fail).then_some(n * 3 + 2));
            }
        }
        let names_count = names.len();
        let base = |name: &str| atom_base(&names, name);
        let conditions = plan.conditions().iter().map(|c| base(c)).collect();
        let executables = plan.executables().iter().map(|e| base(&e.name)).collect();
        Decisions {
            plan,
            names,
            conditions,
            executables,
            never,
            path: Vec::new(),
            asked: vec![0; 3 * names_count],
            mode: Mode::Record,
        }
    }

    fn answer(&mut self, name: &str, kind: u32) -> bool {
        self.answer_atom(atom_base(&self.names, name) + kind)
    }

    /// Answers `atom` (a name's base, plus 0 holds, 1 finished, 2 failed).
    fn answer_atom(&mut self, atom: u32) -> bool {
        if self.never.contains(&atom) {
            return false;
        }
        let asked = match self.asked.get(atom as usize) {
            Some(&at) => at.checked_sub(1).map(|i| self.path[i as usize]),
            // A name the plan does not have (rare): looked for in the path.
            None => self.path.iter().find(|(a, _)| *a == atom).copied(),
        };
        if let Some((_, v)) = asked {
            return v;
        }
        match self.mode {
            Mode::Record => {
                self.path.push((atom, false));
                if let Some(at) = self.asked.get_mut(atom as usize) {
                    *at = self.path.len() as u32;
                }
                false
            }
            Mode::Only(a) => a == atom,
            Mode::All => true,
        }
    }
}

/// The atoms of `name` are its base plus 0, 1 and 2; a name the plan does not have gets atoms
/// of its own, beyond every name's.
fn atom_base(names: &foldhash::HashMap<&str, u32>, name: &str) -> u32 {
    names.get(name).map_or(u32::MAX - 3, |n| n * 3)
}

impl Decisions<'_> {
    /// Forgets the last atom of the path.
    fn pop(&mut self) {
        if let Some((atom, _)) = self.path.pop() {
            if let Some(at) = self.asked.get_mut(atom as usize) {
                *at = 0;
            }
        }
    }

    /// Forgets the whole path, for a run afresh.
    fn clear(&mut self) {
        while !self.path.is_empty() {
            self.pop();
        }
    }
}

impl Environment for Decisions<'_> {
    fn condition(&mut self, name: &str) -> Option<bool> {
        Some(self.answer(name, 0))
    }
    fn step_action(&mut self, _: &str) {}
    fn action_finished(&mut self, name: &str) -> bool {
        self.answer(name, 1)
    }
    fn action_failed(&mut self, name: &str) -> bool {
        self.answer(name, 2)
    }
    fn call(&mut self, _: &str, _: CallKind) {}

    // By position when asked about the plan explored (a sub-plan's own step asks by name).
    fn condition_at(&mut self, plan: &Plan, c: usize) -> Option<bool> {
        match std::ptr::eq(plan, self.plan) {
            true => Some(self.answer_atom(self.conditions[c])),
            false => self.condition(&plan.conditions()[c]),
        }
    }
    fn action_finished_at(&mut self, plan: &Plan, e: usize) -> bool {
        match std::ptr::eq(plan, self.plan) {
            true => self.answer_atom(self.executables[e] + 1),
            false => self.action_finished(&plan.executables()[e].name),
        }
    }
    fn action_failed_at(&mut self, plan: &Plan, e: usize) -> bool {
        match std::ptr::eq(plan, self.plan) {
            true => self.answer_atom(self.executables[e] + 2),
            false => self.action_failed(&plan.executables()[e].name),
        }
    }
}

/// Runs the real step from given markings.
pub(super) struct Stepper<'p> {
    plan: &'p Plan,
    state: PlanState,
    env: Decisions<'p>,
    next: Vec<u32>,
    /// Reused from run to run: a check runs the step once per marking and answer.
    report: StepReport,
    /// The initial marking's key, encoded from `state` when it was made (a long plan's state
    /// is as long as the plan: made once).
    initial: Vec<u32>,
}

impl<'p> Stepper<'p> {
    pub fn new(plan: &'p Plan, outcomes: &Outcomes) -> Self {
        let state = PlanState::new(plan).for_analysis();
        let mut initial = Vec::new();
        state.encode(&mut initial);
        Stepper {
            plan,
            state,
            env: Decisions::new(plan, outcomes),
            next: Vec::new(),
            report: StepReport::default(),
            initial,
        }
    }

    /// The initial marking's key.
    pub fn initial(&self) -> &[u32] {
        &self.initial
    }

    /// What marking `key` is, before expanding it.
    pub fn kind(&mut self, key: &[u32]) -> Kind {
        self.state.decode(key);
        match self.state.status(self.plan) {
            PlanStatus::Goal => Kind::Goal,
            PlanStatus::Fail => Kind::Fail,
            PlanStatus::Running if top_pairs(key).any(|(_, k)| k > MAX_TOKENS) => Kind::Open,
            PlanStatus::Running if !self.state.token_enabled(self.plan) => Kind::Deadlock,
            PlanStatus::Running => Kind::Running,
        }
    }

    /// Calls `visit(successor key, transitions fired)` for every answer combination of the
    /// atoms a step from `key` asks (successors may repeat), until `visit` says to stop
    /// (returns false: the exploration's budget is spent).
    pub fn expand(&mut self, key: &[u32], visit: &mut dyn FnMut(&[u32], &[usize]) -> bool) {
        self.env.clear();
        self.env.mode = Mode::Record;
        loop {
            if !self.run(key, visit) {
                return;
            }
            if self.env.path.len() > MAX_ATOMS {
                break;
            }
            while self.env.path.last().is_some_and(|d| d.1) {
                self.env.pop();
            }
            match self.env.path.last_mut() {
                Some(last) => last.1 = true,
                None => return,
            }
        }
        // Too many atoms to combine: each alone, then all true.
        let mut atoms: Vec<u32> = self.env.path.iter().map(|d| d.0).collect();
        atoms.sort_unstable();
        atoms.dedup();
        for a in atoms {
            self.env.clear();
            self.env.mode = Mode::Only(a);
            if !self.run(key, visit) {
                return;
            }
        }
        self.env.clear();
        self.env.mode = Mode::All;
        self.run(key, visit);
    }

    fn run(&mut self, key: &[u32], visit: &mut dyn FnMut(&[u32], &[usize]) -> bool) -> bool {
        self.state.decode(key);
        step_with(self.plan, &mut self.state, &mut self.env, &mut self.report);
        self.next.clear();
        self.state.encode(&mut self.next);
        visit(&self.next, &self.report.fired)
    }
}

/// The explored reachability graph.
pub(super) struct Explored {
    pub markings: Markings,
    /// Node `i` is marking `i`; an edge is a step changing the marking.
    pub graph: Graph<(), (), petgraph::Directed, u32>,
    /// Per marking expanded (or classified), in id order: all of them unless the budget ran
    /// out.
    pub kinds: Vec<Kind>,
    /// The marking each was first reached from (`u32::MAX` for the initial one).
    pub parent: Vec<u32>,
    /// Top-level transitions fired in some step.
    pub fired: Vec<bool>,
    /// Whether the budget stopped the exploration.
    pub budget_hit: bool,
    /// Whether it was the markings' memory ([`MAX_MARKING_WORDS`]) rather than their number.
    pub memory_hit: bool,
}

/// The most words (4 bytes each) the kept markings may take together: 256 MiB. The number of
/// markings alone did not bound a check's memory: a marking of a plan of 1,000 parallel
/// branches holds a token per branch, and 500,000 of them took 4 GB.
pub(super) const MAX_MARKING_WORDS: usize = 64 << 20;

/// Explores `plan` breadth-first, interning at most `max_states` markings, together at most
/// [`MAX_MARKING_WORDS`] long; stops at the first marking beyond.
pub(super) fn explore(plan: &Plan, outcomes: &Outcomes, max_states: usize) -> Explored {
    explore_within(plan, outcomes, max_states, MAX_MARKING_WORDS)
}

/// [`explore`] with the markings' words at most `max_words`.
fn explore_within(
    plan: &Plan,
    outcomes: &Outcomes,
    max_states: usize,
    max_words: usize,
) -> Explored {
    let mut stepper = Stepper::new(plan, outcomes);
    // A plan usually reaches about as many markings as it has places (a sequence of actions:
    // two places and two markings each); room for that many, within the budget, spares the
    // copies of tables growing while a long plan is checked (and their peak memory).
    let expected = plan.places().len().min(max_states);
    let mut parent = Vec::with_capacity(expected);
    parent.push(u32::MAX);
    let mut ex = Explored {
        markings: Markings::with_capacity(expected),
        graph: Graph::with_capacity(expected, expected),
        kinds: Vec::with_capacity(expected),
        parent,
        fired: vec![false; plan.transitions().len()],
        budget_hit: false,
        memory_hit: false,
    };
    ex.markings.add(stepper.initial());
    ex.graph.add_node(());
    let (mut key, mut succ) = (Vec::new(), Vec::new());
    let mut id = 0u32;
    while (id as usize) < ex.markings.len() {
        key.clear();
        key.extend_from_slice(ex.markings.get(id));
        let kind = stepper.kind(&key);
        ex.kinds.push(kind);
        if kind == Kind::Running {
            succ.clear();
            stepper.expand(&key, &mut |next, fired| {
                fired.iter().for_each(|&t| ex.fired[t] = true);
                let n = match ex.markings.find(next) {
                    Some(n) => n,
                    None if ex.markings.words() + next.len() > max_words => {
                        ex.budget_hit = true;
                        ex.memory_hit = true;
                        return false;
                    }
                    None if ex.markings.len() < max_states => {
                        ex.graph.add_node(());
                        ex.parent.push(id);
                        ex.markings.add(next)
                    }
                    None => {
                        ex.budget_hit = true;
                        return false;
                    }
                };
                if n != id {
                    succ.push(n);
                }
                true
            });
            // Deduplicated once: a marking of a choice among thousands of branches has
            // thousands of successors, and a search of the list for each was quadratic.
            succ.sort_unstable();
            succ.dedup();
            for &n in &succ {
                ex.graph
                    .add_edge(NodeIndex::new(id as usize), NodeIndex::new(n as usize), ());
            }
        }
        if ex.budget_hit {
            // The rest could only be expanded into markings that are not kept.
            break;
        }
        id += 1;
    }
    ex
}

/// The transitions fired by each step of the shortest path from the initial marking to
/// `to`, replayed with the real step.
pub(super) fn witness(plan: &Plan, outcomes: &Outcomes, ex: &Explored, to: u32) -> Vec<Vec<usize>> {
    let mut path = vec![to];
    while let Some(&p) = path.last().and_then(|&n| ex.parent.get(n as usize)) {
        if p == u32::MAX {
            break;
        }
        path.push(p);
    }
    path.reverse();
    let mut stepper = Stepper::new(plan, outcomes);
    path.windows(2)
        .map(|w| {
            let (from, target) = (ex.markings.get(w[0]), ex.markings.get(w[1]));
            let mut found = Vec::new();
            stepper.expand(from, &mut |next, fired| {
                if found.is_empty() && next == target {
                    found = fired.to_vec();
                }
                found.is_empty()
            });
            found
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The markings' memory bounds a check as their number does: a marking of a wide parallel
    /// plan holds a token per branch.
    #[test]
    fn the_markings_memory_stops_the_exploration_and_says_so() {
        let branches: Vec<String> = (0..12).map(|i| format!("{{ a{i} }}")).collect();
        let plan = crate::compile_text(&branches.join(" || "), "t.plan", "t", None).unwrap();
        let whole = explore_within(&plan, &Outcomes::new(), 1_000_000, usize::MAX);
        assert!(!whole.budget_hit && !whole.memory_hit);
        let words = whole.markings.words();
        let cut = explore_within(&plan, &Outcomes::new(), 1_000_000, words / 4);
        assert!(cut.budget_hit && cut.memory_hit);
        assert!(cut.markings.words() <= words / 4);
        assert!(cut.markings.len() < whole.markings.len());
        // A spent budget stops a marking's expansion at once: a step of a plan of 100,000
        // branches asks each branch's atom, and running the step once per atom to the end
        // took minutes after the budget was spent.
        let mut stepper = Stepper::new(&plan, &Outcomes::new());
        let initial = stepper.initial().to_vec();
        // The first successors, up to a marking where every action runs (each asks whether
        // it ended).
        let (mut marking, mut answers) = (initial, 0);
        for _ in 0..5 {
            let mut first = None;
            answers = 0;
            stepper.expand(&marking, &mut |next, _| {
                first.get_or_insert_with(|| next.to_vec());
                answers += 1;
                true
            });
            if answers > 12 {
                break;
            }
            marking = first.unwrap();
        }
        let mut calls = 0;
        // The budget spent at the second successor (the first taking each atom alone).
        stepper.expand(&marking, &mut |_, _| {
            calls += 1;
            calls < 2
        });
        assert!(answers > 12, "{answers}");
        assert_eq!(calls, 2);
        // The number of markings, when it comes first, is not the memory.
        let few = explore_within(&plan, &Outcomes::new(), 10, usize::MAX);
        assert!(few.budget_hit && !few.memory_hit);
    }
}
