//! The pure rule engine: which contexts hold (with hysteresis and dwell), what their effects
//! should be (resolved by priority), and the actions that take the blackboard from what is
//! applied to what is desired. No I/O and no clock of its own: values and times are passed in.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::time::Duration;

use petrel_actors::expr::{ExprId, ExprSet, Value};
use petrel_actors::{AnyValue, TypeInfo};
use tokio::time::Instant;

mod build;

/// What the engine needs to know about the agent's properties to check rules.
pub trait Schema {
    /// The type and a sample value (default or current) of the property at `path`.
    fn property(&self, path: &str) -> Option<(TypeInfo, AnyValue)>;
}

/// One step of the engine's output, in the order to carry out. Fields are named by what they
/// hold: the property or module changed, the new value or source, the context responsible.
#[derive(Debug, Clone, PartialEq)]
#[allow(missing_docs)]
pub enum Action {
    /// A context started to hold.
    Activated(String),
    /// A context stopped holding.
    Deactivated(String),
    /// Write `value` to `target` (save the original first, if not saved yet).
    Set {
        target: String,
        value: Value,
        context: String,
    },
    /// Put `target` back to its saved original.
    Restore(String),
    /// Forget `target`'s saved original and leave its value (a sticky context ended).
    Release(String),
    /// Link `input` to `source` (save the original link first, if not saved yet).
    Link {
        input: String,
        source: String,
        context: String,
    },
    /// Put `input`'s original link back.
    RestoreLink(String),
    /// Forget `input`'s original link (sticky).
    ReleaseLink(String),
    /// Start (`true`) or stop (`false`) a module instance (save whether it ran, if not saved).
    Run {
        module: String,
        start: bool,
        context: String,
    },
    /// Put a module back in the running state it had.
    RestoreRun(String),
    /// Forget a module's original running state (sticky).
    ReleaseRun(String),
}

struct Rule {
    name: String,
    when: ExprId,
    until: Option<ExprId>,
    min_dwell: Duration,
    priority: i64,
    sets: Vec<(String, ExprId)>,
    relinks: Vec<(String, String)>,
    runs: Vec<(String, bool)>,
    sticky: bool,
    active: bool,
    since: Option<Instant>,
}

/// Effects by target: values, links, running states.
type Effects = (
    BTreeMap<String, Applied<Value>>,
    BTreeMap<String, Applied<String>>,
    BTreeMap<String, Applied<bool>>,
);

/// An effect currently applied: who applied it, what, and whether it outlives its context.
#[derive(Debug, Clone, PartialEq)]
struct Applied<V> {
    context: String,
    value: V,
    sticky: bool,
}

/// Context rules running over a set of expressions.
pub struct Engine {
    exprs: ExprSet,
    rules: Vec<Rule>,
    values: BTreeMap<String, Applied<Value>>,
    links: BTreeMap<String, Applied<String>>,
    runs: BTreeMap<String, Applied<bool>>,
    /// The expected type of each `set` target, to convert values.
    targets: HashMap<String, TypeInfo>,
    /// The rule whose `when` or `until` each condition is, so a step looks only at rules whose
    /// conditions changed.
    by_condition: HashMap<ExprId, usize>,
    /// Rules whose switch waits for their `min_dwell` to pass.
    waiting: BTreeSet<usize>,
    /// Active rules, highest priority first, then declaration order: effects and the active
    /// list cost what is active, not the number of rules.
    active: Vec<usize>,
}

impl Engine {
    /// The properties the rules read (feed their values with [`update`](Engine::update)).
    pub fn properties(&self) -> Vec<String> {
        self.exprs
            .properties()
            .map(|(_, p)| p.to_string())
            .collect()
    }

    /// The type of a `set` target.
    pub fn target_type(&self, target: &str) -> Option<TypeInfo> {
        self.targets.get(target).copied()
    }

    /// A property the rules read has a new value.
    pub fn update(&mut self, path: &str, info: TypeInfo, value: &AnyValue, written: Instant) {
        if let Some(id) = self.exprs.property(path) {
            self.exprs.update(id, info, value, written);
        }
    }

    /// Takes over what `old` had applied, so a reload only changes the difference.
    pub fn adopt(&mut self, old: Engine) {
        self.values = old.values;
        self.links = old.links;
        self.runs = old.runs;
    }

    /// The contexts that hold now, by descending priority.
    pub fn active(&self) -> Vec<&str> {
        self.active
            .iter()
            .map(|&i| self.rules[i].name.as_str())
            .collect()
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

    /// Evaluates what changed at `now`, switches contexts, and returns the actions to apply.
    pub fn step(&mut self, now: Instant) -> Vec<Action> {
        let changed = self.exprs.evaluate(now);
        let mut candidates = std::mem::take(&mut self.waiting);
        candidates.extend(changed.iter().filter_map(|id| self.by_condition.get(id)));
        let mut actions = Vec::new();
        for i in candidates {
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
            if rule
                .since
                .is_some_and(|t| now.duration_since(t) < rule.min_dwell)
            {
                self.waiting.insert(i);
                continue;
            }
            rule.active = !rule.active;
            rule.since = Some(now);
            match rule.active {
                true => self.active.push(i),
                false => self.active.retain(|&a| a != i),
            }
            let name = rule.name.clone();
            actions.push(if rule.active {
                Action::Activated(name)
            } else {
                Action::Deactivated(name)
            });
        }
        let rules = &self.rules;
        self.active
            .sort_by_key(|&i| (std::cmp::Reverse(rules[i].priority), i));
        // Effects change only when a context switched or a value expression (any expression
        // that is not a condition) changed; otherwise there is nothing to resolve.
        let values_changed = changed.iter().any(|id| !self.by_condition.contains_key(id));
        if !actions.is_empty() || values_changed {
            self.diff(&mut actions);
        }
        actions
    }

    /// Effects the active contexts want, the highest priority first, then declaration order.
    fn desired(&self) -> Effects {
        let order = self.active.iter().map(|&i| &self.rules[i]);
        let (mut values, mut links, mut runs) = (BTreeMap::new(), BTreeMap::new(), BTreeMap::new());
        for rule in order {
            let applied = |value| Applied {
                context: rule.name.clone(),
                value,
                sticky: rule.sticky,
            };
            for (target, id) in &rule.sets {
                if let Some(Ok(v)) = self.exprs.value(*id) {
                    values
                        .entry(target.clone())
                        .or_insert_with(|| applied(v.clone()));
                }
            }
            for (input, source) in &rule.relinks {
                links.entry(input.clone()).or_insert_with(|| Applied {
                    context: rule.name.clone(),
                    value: source.clone(),
                    sticky: rule.sticky,
                });
            }
            for (module, start) in &rule.runs {
                runs.entry(module.clone()).or_insert_with(|| Applied {
                    context: rule.name.clone(),
                    value: *start,
                    sticky: rule.sticky,
                });
            }
        }
        (values, links, runs)
    }

    fn diff(&mut self, actions: &mut Vec<Action>) {
        let (values, links, runs) = self.desired();
        reconcile(
            &mut self.values,
            values,
            actions,
            |target, a| Action::Set {
                target,
                value: a.value.clone(),
                context: a.context.clone(),
            },
            Action::Restore,
            Action::Release,
        );
        reconcile(
            &mut self.links,
            links,
            actions,
            |input, a| Action::Link {
                input,
                source: a.value.clone(),
                context: a.context.clone(),
            },
            Action::RestoreLink,
            Action::ReleaseLink,
        );
        reconcile(
            &mut self.runs,
            runs,
            actions,
            |module, a| Action::Run {
                module,
                start: a.value,
                context: a.context.clone(),
            },
            Action::RestoreRun,
            Action::ReleaseRun,
        );
    }
}

/// Turns `applied` into `desired`, pushing the actions that do it.
fn reconcile<V: PartialEq + Clone>(
    applied: &mut BTreeMap<String, Applied<V>>,
    desired: BTreeMap<String, Applied<V>>,
    actions: &mut Vec<Action>,
    apply: impl Fn(String, &Applied<V>) -> Action,
    restore: impl Fn(String) -> Action,
    release: impl Fn(String) -> Action,
) {
    let gone: Vec<String> = applied
        .keys()
        .filter(|k| !desired.contains_key(*k))
        .cloned()
        .collect();
    for key in gone {
        let was = applied.remove(&key).expect("listed above");
        actions.push(if was.sticky {
            release(key)
        } else {
            restore(key)
        });
    }
    for (key, want) in desired {
        if applied.get(&key) != Some(&want) {
            actions.push(apply(key.clone(), &want));
            applied.insert(key, want);
        }
    }
}

/// Converts an expression value into a value of property type `info`.
pub fn to_property(value: &Value, info: TypeInfo) -> Result<AnyValue, String> {
    use std::sync::Arc;
    match value {
        Value::Bool(b) if info.is::<bool>() => Ok(Arc::new(*b)),
        Value::Num(n) if info.is::<f64>() => Ok(Arc::new(*n)),
        Value::Num(n) if info.is::<i64>() && n.fract() == 0.0 => Ok(Arc::new(*n as i64)),
        Value::Str(s) if info.is::<String>() => Ok(Arc::new(s.to_string())),
        other => Err(format!(
            "cannot store {other:?} in a {} property",
            info.name()
        )),
    }
}
