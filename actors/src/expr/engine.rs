//! [`ExprSet`]: many expressions over shared properties, re-evaluated incrementally.

use std::collections::HashMap;

use tokio::time::Instant;

use super::check::{Checker, Node, Resolve};
use super::eval::{Eval, PropSlot};
use super::parse::parse;
use super::types::{Ty, TypeEnv};
use super::value::Value;
use super::ExprError;
use crate::value::{AnyValue, TypeInfo};

/// An expression in an [`ExprSet`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ExprId(pub usize);

/// A property read by expressions of an [`ExprSet`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PropId(pub usize);

struct Entry {
    node: Node,
    ty: Ty,
    /// Uses `held` or `age`: its value may change with time alone.
    timed: bool,
    dirty: bool,
    /// The properties it reads.
    reads: Vec<usize>,
    value: Option<Result<Value, String>>,
    deadline: Option<Instant>,
    evaluations: u64,
    /// Where its time counts from (`elapsed`, and the earliest start of `held` and `age`).
    origin: Option<Instant>,
    /// Its `held` state slots.
    held: std::ops::Range<usize>,
    /// When it was added: `elapsed` counts from here until an origin is set.
    added: Instant,
}

/// A set of checked expressions that knows which expressions read which properties: after
/// [`update`](ExprSet::update)s, [`evaluate`](ExprSet::evaluate) re-evaluates only the
/// expressions reading a changed property, plus the time-dependent ones (`held`, `age`).
///
/// The caller owns the properties: it reads them (blackboard handles, a test table...) and
/// passes new values in; time is passed in too, so a paused or fake clock works.
#[derive(Default)]
pub struct ExprSet {
    paths: Vec<String>,
    index: HashMap<String, usize>,
    props: Vec<PropSlot>,
    readers: Vec<Vec<usize>>,
    exprs: Vec<Entry>,
    held: Vec<Option<Instant>>,
    /// Expressions to evaluate next time (dirty ones and time-dependent ones), so that an
    /// evaluation costs what changed, not the size of the set.
    due: Vec<usize>,
    /// Evaluations of every expression so far.
    total: u64,
}

struct Resolver<'a> {
    env: &'a TypeEnv,
    index: &'a HashMap<String, usize>,
    known: usize,
    new: Vec<String>,
    deps: Vec<usize>,
    held: usize,
    timed: bool,
}

impl Resolve for Resolver<'_> {
    fn resolve(&mut self, path: &str) -> Result<(usize, Ty), String> {
        let ty = self
            .env
            .get(path)
            .ok_or_else(|| format!("unknown property `{path}`"))?;
        let i = match self.index.get(path) {
            Some(&i) => i,
            None => match self.new.iter().position(|p| p == path) {
                Some(k) => self.known + k,
                None => {
                    self.new.push(path.to_string());
                    self.known + self.new.len() - 1
                }
            },
        };
        if !self.deps.contains(&i) {
            self.deps.push(i);
        }
        Ok((i, ty.clone()))
    }

    fn timed(&mut self) {
        self.timed = true;
    }

    fn held_slot(&mut self) -> usize {
        self.timed = true;
        self.held += 1;
        self.held - 1
    }
}

fn uses_age(n: &Node) -> bool {
    match n {
        Node::Age(_) | Node::Elapsed => true,
        Node::Const(_) | Node::Prop(_) => false,
        Node::Field(x, _) | Node::Neg(x) | Node::Not(x) | Node::Abs(x) | Node::Held(x, _, _) => {
            uses_age(x)
        }
        Node::Bin(_, a, b) => uses_age(a) || uses_age(b),
        Node::MinMax(_, xs) => xs.iter().any(uses_age),
        Node::MinMaxList(_, x) | Node::Len(x) => uses_age(x),
        Node::Clamp(a, b, c) => uses_age(a) || uses_age(b) || uses_age(c),
    }
}

impl ExprSet {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Parses and checks `src` against `env`, requiring type `want` if given (e.g.
    /// [`Ty::Bool`] for a condition), and adds it. Errors carry the line and column in `src`.
    pub fn add(
        &mut self,
        src: &str,
        env: &TypeEnv,
        want: Option<&Ty>,
    ) -> Result<ExprId, ExprError> {
        let ast = parse(src)?;
        let mut r = Resolver {
            env,
            index: &self.index,
            known: self.paths.len(),
            new: Vec::new(),
            deps: Vec::new(),
            held: self.held.len(),
            timed: false,
        };
        let first_held = self.held.len();
        let (node, ty) = Checker {
            src,
            resolve: &mut r,
        }
        .check(&ast)?;
        if let Some(want) = want.filter(|w| **w != ty) {
            return Err(ExprError::at(
                src,
                ast.span.start,
                format!("the expression must be {want}, found {ty}"),
            ));
        }
        let (new, deps, held, timed) = (r.new, r.deps, r.held, r.timed);
        for p in new {
            self.index.insert(p.clone(), self.paths.len());
            self.paths.push(p);
            self.props.push(PropSlot {
                value: Err("not read yet".into()),
                written: Instant::now(),
            });
            self.readers.push(Vec::new());
        }
        self.held.resize(held, None);
        let id = self.exprs.len();
        for &d in &deps {
            self.readers[d].push(id);
        }
        let timed = timed || uses_age(&node);
        self.due.push(id);
        self.exprs.push(Entry {
            node,
            ty,
            timed,
            dirty: true,
            reads: deps,
            value: None,
            deadline: None,
            evaluations: 0,
            origin: None,
            held: first_held..held,
            added: Instant::now(),
        });
        Ok(ExprId(id))
    }

    /// The properties read so far, with their ids, in order of first use.
    pub fn properties(&self) -> impl Iterator<Item = (PropId, &str)> {
        self.paths
            .iter()
            .enumerate()
            .map(|(i, p)| (PropId(i), p.as_str()))
    }

    /// The properties expression `id` reads, in order of first use.
    pub fn reads(&self, id: ExprId) -> impl Iterator<Item = (PropId, &str)> {
        self.exprs[id.0]
            .reads
            .iter()
            .map(|&i| (PropId(i), self.paths[i].as_str()))
    }

    /// The id of property `path`, if an expression reads it.
    pub fn property(&self, path: &str) -> Option<PropId> {
        self.index.get(path).map(|&i| PropId(i))
    }

    /// Gives property `prop` a new value (of type `info`) written at `written`, and marks the
    /// expressions reading it for re-evaluation.
    pub fn update(&mut self, prop: PropId, info: TypeInfo, value: &AnyValue, written: Instant) {
        self.props[prop.0] = PropSlot {
            value: Value::of_property(info, value),
            written,
        };
        for &e in &self.readers[prop.0] {
            let entry = &mut self.exprs[e];
            if !entry.dirty && !entry.timed {
                self.due.push(e);
            }
            entry.dirty = true;
        }
    }

    /// Re-evaluates the expressions that need it at time `now`; returns those whose value changed.
    pub fn evaluate(&mut self, now: Instant) -> Vec<ExprId> {
        let mut changed = Vec::new();
        self.evaluate_into(now, &mut changed);
        changed
    }

    /// Like [`evaluate`](ExprSet::evaluate), into `changed` (cleared first), so a caller that
    /// evaluates often can reuse one buffer.
    pub fn evaluate_into(&mut self, now: Instant, changed: &mut Vec<ExprId>) {
        changed.clear();
        if self.due.is_empty() {
            return;
        }
        let mut due = std::mem::take(&mut self.due);
        // Evaluate in insertion order, as a full scan would.
        due.sort_unstable();
        for &i in &due {
            let e = &mut self.exprs[i];
            let mut ev = Eval {
                props: &self.props,
                held: &mut self.held,
                now,
                deadline: None,
                origin: e.origin,
                since: e.origin.unwrap_or(e.added),
            };
            let v = ev.eval(&e.node);
            e.deadline = ev.deadline;
            e.dirty = false;
            e.evaluations += 1;
            self.total += 1;
            if e.value.as_ref() != Some(&v) {
                e.value = Some(v);
                changed.push(ExprId(i));
            }
        }
        // Time-dependent expressions stay due.
        due.retain(|&i| self.exprs[i].timed);
        self.due = due;
    }

    /// Makes time in expression `id` count from `origin`: `elapsed()` is the time since
    /// `origin`, a `held` window starts at `origin` at the earliest (its state is forgotten),
    /// and `age` is at most the time since `origin`. A plan action sets this when it starts, so
    /// its conditions cannot hold because of what happened before it ran. `None` goes back
    /// to counting from when the expression was added, with no floor on `held` and `age`.
    pub fn set_origin(&mut self, id: ExprId, origin: Option<Instant>) {
        let e = &mut self.exprs[id.0];
        e.origin = origin;
        for slot in e.held.clone() {
            self.held[slot] = None;
        }
        if !e.dirty && !e.timed {
            self.due.push(id.0);
        }
        e.dirty = true;
    }

    /// When each `held` of expression `id` has seen its condition true since (`None`: false),
    /// to keep them across a restart of the module that owns the set.
    pub fn held_states(&self, id: ExprId) -> Vec<Option<Instant>> {
        self.exprs[id.0]
            .held
            .clone()
            .map(|s| self.held[s])
            .collect()
    }

    /// Puts back `held` states saved by [`held_states`](ExprSet::held_states) (extra or
    /// missing entries are ignored).
    pub fn restore_held_states(&mut self, id: ExprId, states: &[Option<Instant>]) {
        for (slot, state) in self.exprs[id.0].held.clone().zip(states) {
            self.held[slot] = *state;
        }
    }

    /// The last value of `id` (`None` before its first evaluation; `Some(Err)` if a property
    /// could not be read, e.g. was never updated).
    pub fn value(&self, id: ExprId) -> Option<&Result<Value, String>> {
        self.exprs[id.0].value.as_ref()
    }

    /// The last value of `id` as a boolean, if it is one.
    pub fn bool(&self, id: ExprId) -> Option<bool> {
        self.value(id)?.as_ref().ok()?.as_bool()
    }

    /// The checked type of `id`.
    pub fn ty(&self, id: ExprId) -> &Ty {
        &self.exprs[id.0].ty
    }

    /// How many times `id` was evaluated (to check that evaluation is incremental).
    pub fn evaluations(&self, id: ExprId) -> u64 {
        self.exprs[id.0].evaluations
    }

    /// Evaluations of every expression so far.
    pub fn total_evaluations(&self) -> u64 {
        self.total
    }

    /// The earliest time at which a time-dependent expression may change value by time
    /// alone (a `held` window closing, an `age` crossing a compared constant); evaluate again then.
    pub fn next_deadline(&self) -> Option<Instant> {
        // Only time-dependent expressions have deadlines, and they always stay due.
        self.due
            .iter()
            .filter_map(|&i| self.exprs[i].deadline)
            .min()
    }

    /// Whether some expression depends on time alone (`held`, `age`).
    pub fn has_timed(&self) -> bool {
        self.exprs.iter().any(|e| e.timed)
    }

    /// How many expressions the set holds.
    pub fn len(&self) -> usize {
        self.exprs.len()
    }

    /// Whether the set holds no expression.
    pub fn is_empty(&self) -> bool {
        self.exprs.is_empty()
    }
}
