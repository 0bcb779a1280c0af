//! The pure rule engine: which contexts hold (with hysteresis and dwell), what their effects
//! should be (resolved by priority), and the actions that take the blackboard from what is
//! applied to what is desired. No I/O and no clock of its own: values and times are passed in.

use std::sync::Arc;
use std::time::Duration;

use petrel_actors::expr::{ExprId, ExprSet, PropId, Value};
use petrel_actors::{AnyValue, TypeInfo};
use tokio::time::Instant;

mod build;
mod effects;
mod memory;
mod whole;

pub(crate) use memory::{fill_in_place, same_name};
pub use memory::{EngineMemory, SavedEffect};

use effects::{Actions, Effects};

/// What the engine needs to know about the agent's properties to check rules.
pub trait Schema {
    /// The type and a sample value (default or current) of the property at `path`.
    fn property(&self, path: &str) -> Option<(TypeInfo, AnyValue)>;

    /// Why the property at `path` would refuse `value` (of its type), if it would: a kind
    /// nobody sets from outside (`stats/...`, queues) or a parameter out of its range.
    fn refuses(&self, path: &str, value: &AnyValue) -> Option<String>;

    /// Why `input` could not be linked to `source`, if it could not: not an input or
    /// parameter, a value and a queue, other types, or a link cycle with the links there are.
    /// Known to a schema that holds the links (`petrel check`'s registry); others say nothing
    /// and the link is checked when made.
    fn refuses_link(&self, _input: &str, _source: &str) -> Option<String> {
        None
    }
}

/// One step of the engine's output, in the order to carry out. Fields are named by what they
/// hold: the property or module changed, the new value or source, the context responsible.
/// Names are shared with the engine (`Arc<str>`): producing an action does not copy them.
#[derive(Debug, Clone, PartialEq)]
#[allow(missing_docs)]
pub enum Action {
    /// A context started to hold.
    Activated(Arc<str>),
    /// A context stopped holding.
    Deactivated(Arc<str>),
    /// Write `value` to `target` (save the original first, if not saved yet).
    Set {
        target: Arc<str>,
        value: Value,
        context: Arc<str>,
    },
    /// Put `target` back to its saved original.
    Restore(Arc<str>),
    /// Forget `target`'s saved original and leave its value (a sticky context ended).
    Release(Arc<str>),
    /// Link `input` to `source` (save the original link first, if not saved yet).
    Link {
        input: Arc<str>,
        source: Arc<str>,
        context: Arc<str>,
    },
    /// Put `input`'s original link back.
    RestoreLink(Arc<str>),
    /// Forget `input`'s original link (sticky).
    ReleaseLink(Arc<str>),
    /// Start (`true`) or stop (`false`) a module instance (save whether it ran, if not saved).
    Run {
        module: Arc<str>,
        start: bool,
        context: Arc<str>,
    },
    /// Put a module back in the running state it had.
    RestoreRun(Arc<str>),
    /// Forget a module's original running state (sticky).
    ReleaseRun(Arc<str>),
}

struct Rule {
    name: Arc<str>,
    when: ExprId,
    until: Option<ExprId>,
    min_dwell: Duration,
    priority: i64,
    sets: Vec<Effect<ExprId>>,
    relinks: Vec<Effect<Arc<str>>>,
    runs: Vec<Effect<bool>>,
    sticky: bool,
    active: bool,
    since: Option<Instant>,
}

/// One effect of a rule: its target (by name and by number in its [`Effects`] table) and what
/// the rule puts there (an expression, a link source, a running state).
struct Effect<X> {
    target: Arc<str>,
    number: usize,
    what: X,
}

/// What setting a value, relinking and starting or stopping a module turn into.
const SET: Actions<Value> = Actions {
    apply: |target, a| Action::Set {
        target,
        value: a.value.clone(),
        context: a.context.clone(),
    },
    restore: Action::Restore,
    release: Action::Release,
};
const LINK: Actions<Arc<str>> = Actions {
    apply: |input, a| Action::Link {
        input,
        source: a.value.clone(),
        context: a.context.clone(),
    },
    restore: Action::RestoreLink,
    release: Action::ReleaseLink,
};
const RUN: Actions<bool> = Actions {
    apply: |module, a| Action::Run {
        module,
        start: a.value,
        context: a.context.clone(),
    },
    restore: Action::RestoreRun,
    release: Action::ReleaseRun,
};

/// Context rules running over a set of expressions.
pub struct Engine {
    exprs: ExprSet,
    rules: Vec<Rule>,
    values: Effects<Value>,
    links: Effects<Arc<str>>,
    runs: Effects<bool>,
    /// The rule whose `when` or `until` each expression is (by expression number), so a step
    /// looks only at rules whose conditions changed.
    condition_of: Vec<Option<usize>>,
    /// Rules whose switch waits for their `min_dwell` to pass.
    waiting: Vec<usize>,
    /// Active rules, highest priority first, then declaration order: effects and the active
    /// list cost what is active, not the number of rules.
    active: Vec<usize>,
    /// Actions owed before the next step's own (contexts a reload removed).
    pending: Vec<Action>,
    /// Effects must be resolved at the next step even if nothing switches (after a reload).
    resolve: bool,
    /// Scratch buffers, kept to avoid allocating in every step.
    changed: Vec<ExprId>,
    candidates: Vec<usize>,
}

impl Engine {
    /// The properties the rules read (feed their values with [`update`](Engine::update) or
    /// [`update_prop`](Engine::update_prop)).
    pub fn properties(&self) -> impl Iterator<Item = (PropId, &str)> {
        self.exprs.properties()
    }

    /// A property the rules read has a new value.
    pub fn update(&mut self, path: &str, info: TypeInfo, value: &AnyValue, written: Instant) {
        if let Some(id) = self.exprs.property(path) {
            self.exprs.update(id, info, value, written);
        }
    }

    /// Like [`update`](Engine::update), for a property known by its id in
    /// [`properties`](Engine::properties).
    pub fn update_prop(&mut self, id: PropId, info: TypeInfo, value: &AnyValue, written: Instant) {
        self.exprs.update(id, info, value, written);
    }

    /// Takes over from `old` (a reload), so that only the difference is applied (see
    /// [`resume`](Engine::resume)).
    pub fn adopt(&mut self, old: Engine) {
        let mut memory = EngineMemory::default();
        old.save_into(&mut memory);
        self.resume(&memory);
    }

    /// The contexts that hold now, by descending priority.
    pub fn active(&self) -> impl ExactSizeIterator<Item = &str> {
        self.active.iter().map(|&i| &*self.rules[i].name)
    }

    /// The properties context `name`'s conditions (`when`, `until`) read, without repeats:
    /// what to show as the trigger of a switch.
    pub fn condition_reads(&self, name: &str) -> Vec<(PropId, &str)> {
        let mut reads = Vec::new();
        if let Some(rule) = self.rules.iter().find(|r| &*r.name == name) {
            for id in std::iter::once(rule.when).chain(rule.until) {
                for read in self.exprs.reads(id) {
                    if !reads.contains(&read) {
                        reads.push(read);
                    }
                }
            }
        }
        reads
    }

    /// Whether time alone can switch a context (`held`, `age`, `min_dwell_ms`), so the engine
    /// must be stepped periodically as well as on changes.
    pub fn uses_time(&self) -> bool {
        self.exprs.has_timed() || self.rules.iter().any(|r| !r.min_dwell.is_zero())
    }

    /// Expression evaluations so far (evaluation is incremental).
    pub fn evaluations(&self) -> u64 {
        self.exprs.total_evaluations()
    }

    fn condition(&self, id: ExprId) -> Option<usize> {
        self.condition_of.get(id.0).copied().flatten()
    }

    fn sort_active(&mut self) {
        let rules = &self.rules;
        self.active
            .sort_by_key(|&i| (std::cmp::Reverse(rules[i].priority), i));
    }

    /// Evaluates what changed at `now`, switches contexts, and returns the actions to apply.
    pub fn step(&mut self, now: Instant) -> Vec<Action> {
        let mut actions = Vec::new();
        self.step_into(now, &mut actions);
        actions
    }

    /// Like [`step`](Engine::step), into `actions` (cleared first): a caller stepping at every
    /// change reuses one buffer.
    pub fn step_into(&mut self, now: Instant, actions: &mut Vec<Action>) {
        actions.clear();
        actions.append(&mut self.pending);
        let mut changed = std::mem::take(&mut self.changed);
        self.exprs.evaluate_into(now, &mut changed);
        let mut candidates = std::mem::take(&mut self.candidates);
        candidates.clear();
        candidates.append(&mut self.waiting);
        candidates.extend(changed.iter().filter_map(|&id| self.condition(id)));
        candidates.sort_unstable();
        candidates.dedup();
        let mut switched = false;
        for &i in &candidates {
            let rule = &mut self.rules[i];
            let holds = self.exprs.bool(rule.when) == Some(true);
            let ends = match rule.until {
                Some(until) => self.exprs.bool(until) == Some(true),
                None => self.exprs.bool(rule.when) == Some(false),
            };
            let wants_switch = if rule.active { ends } else { holds };
            if !wants_switch {
                continue;
            }
            if !rule.min_dwell.is_zero()
                && rule
                    .since
                    .is_some_and(|t| now.duration_since(t) < rule.min_dwell)
            {
                self.waiting.push(i);
                continue;
            }
            rule.active = !rule.active;
            rule.since = Some(now);
            let name = rule.name.clone();
            if rule.active {
                self.active.push(i);
                actions.push(Action::Activated(name));
            } else {
                self.active.retain(|&a| a != i);
                actions.push(Action::Deactivated(name));
            }
            switched = true;
        }
        if switched {
            self.sort_active();
        }
        // Effects change only when a context switched or a value expression (any expression
        // that is not a condition) changed; otherwise there is nothing to resolve.
        let values_changed = changed.iter().any(|&id| self.condition(id).is_none());
        if switched || values_changed || std::mem::take(&mut self.resolve) {
            self.resolve_effects(actions);
        }
        self.changed = changed;
        self.candidates = candidates;
    }

    /// Offers the active contexts' effects, highest priority first, and pushes the actions
    /// that bring the applied effects in line.
    fn resolve_effects(&mut self, actions: &mut Vec<Action>) {
        self.values.clear_wanted();
        self.links.clear_wanted();
        self.runs.clear_wanted();
        for &i in &self.active {
            let rule = &self.rules[i];
            for e in &rule.sets {
                if let Some(Ok(v)) = self.exprs.value(e.what) {
                    self.values.want(e.number, &rule.name, v, rule.sticky);
                }
            }
            for e in &rule.relinks {
                self.links.want(e.number, &rule.name, &e.what, rule.sticky);
            }
            for e in &rule.runs {
                self.runs.want(e.number, &rule.name, &e.what, rule.sticky);
            }
        }
        self.values.reconcile(actions, &SET);
        self.links.reconcile(actions, &LINK);
        self.runs.reconcile(actions, &RUN);
    }
}

/// Converts an expression value into a value of property type `info`.
pub fn to_property(value: &Value, info: TypeInfo) -> Result<AnyValue, String> {
    match value {
        Value::Bool(b) if info.is::<bool>() => Ok(Arc::new(*b)),
        Value::Num(n) if info.is::<f64>() => Ok(Arc::new(*n)),
        // Whole numbers an i64 holds exactly: `as` would saturate larger ones silently.
        Value::Num(n) if info.is::<i64>() && n.fract() == 0.0 && n.abs() < 9.0e15 => {
            Ok(Arc::new(*n as i64))
        }
        Value::Num(n) if info.is::<i64>() => Err(format!(
            "cannot store {} in an i64 property: it takes whole numbers (up to 9e15)",
            petrel_actors::short_number(*n)
        )),
        Value::Str(s) if info.is::<String>() => Ok(Arc::new(s.to_string())),
        other => Err(format!(
            "cannot store {other} in a {} property",
            info.name()
        )),
    }
}
