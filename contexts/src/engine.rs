//! The pure rule engine: which contexts hold (with hysteresis and dwell), what their effects
//! should be (resolved by priority), and the actions that take the blackboard from what is
//! applied to what is desired. No I/O and no clock of its own: values and times are passed in.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::time::Duration;

use petrel_actors::expr::{parse, properties, ExprId, ExprSet, Ty, TypeEnv, Value};
use petrel_actors::{AnyValue, TypeInfo};
use tokio::time::Instant;

use crate::rules::{LoadedRules, RuleError};

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
}

impl Engine {
    /// Checks `loaded` against `schema` and builds an engine; returns every problem found.
    pub fn build(loaded: &LoadedRules, schema: &dyn Schema) -> Result<Engine, Vec<RuleError>> {
        let mut errors = Vec::new();
        let mut engine = Engine {
            exprs: ExprSet::new(),
            rules: Vec::new(),
            values: BTreeMap::new(),
            links: BTreeMap::new(),
            runs: BTreeMap::new(),
            targets: HashMap::new(),
            by_condition: HashMap::new(),
            waiting: BTreeSet::new(),
        };
        let mut names = Vec::new();
        for rule in &loaded.rules.contexts {
            let err = |needle: Option<&str>, offset, message| {
                loaded.error(&rule.name, needle, offset, message)
            };
            if names.contains(&rule.name) {
                errors.push(err(
                    None,
                    None,
                    format!("duplicate context name `{}`", rule.name),
                ));
                continue;
            }
            names.push(rule.name.clone());
            let mut add = |src: &str, want: &Ty, errors: &mut Vec<RuleError>| -> Option<ExprId> {
                let env = env_for(src, schema);
                match engine.exprs.add(src, &env, Some(want)) {
                    Ok(id) => Some(id),
                    Err(e) => {
                        let message = format!("context `{}`: in `{src}`: {}", rule.name, e.message);
                        errors.push(err(Some(src), Some((e.line, e.column)), message));
                        None
                    }
                }
            };
            let when = add(&rule.when, &Ty::Bool, &mut errors);
            let until = rule.until.as_ref().map(|u| add(u, &Ty::Bool, &mut errors));
            let mut sets = Vec::new();
            // `enable`/`disable` are sets of `<module>/enabled`; errors point at the module name.
            let toggles = rule
                .enable
                .iter()
                .map(|m| (m, "true"))
                .chain(rule.disable.iter().map(|m| (m, "false")));
            let toggles = toggles.map(|(m, v)| (format!("{m}/enabled"), v.to_string(), m.clone()));
            let plain = rule
                .set
                .iter()
                .map(|(t, s)| (t.clone(), s.clone(), t.clone()));
            for (target, src, needle) in plain.chain(toggles) {
                let Some((info, _)) = schema.property(&target) else {
                    errors.push(err(
                        Some(&needle),
                        None,
                        format!("context `{}`: unknown property `{target}`", rule.name),
                    ));
                    continue;
                };
                let Some(want) = settable_ty(info) else {
                    let message = format!("context `{}`: `{target}` is a {}; `set` takes bool, number or string properties", rule.name, info.name());
                    errors.push(err(Some(&needle), None, message));
                    continue;
                };
                engine.targets.insert(target.clone(), info);
                if let Some(id) = add(&src, &want, &mut errors) {
                    sets.push((target, id));
                }
            }
            for (input, source) in &rule.relink {
                match (schema.property(input), schema.property(source)) {
                    (Some((a, _)), Some((b, _))) if a != b => errors.push(err(
                        Some(source),
                        None,
                        format!("context `{}`: cannot relink `{input}` ({}) to `{source}` ({}): the types differ", rule.name, a.name(), b.name()),
                    )),
                    (Some(_), Some(_)) => {}
                    (None, _) => errors.push(err(Some(input), None, format!("context `{}`: unknown property `{input}`", rule.name))),
                    (_, None) => errors.push(err(Some(source), None, format!("context `{}`: unknown property `{source}`", rule.name))),
                }
            }
            let runs: Vec<(String, bool)> = rule
                .start
                .iter()
                .map(|m| (m.clone(), true))
                .chain(rule.stop.iter().map(|m| (m.clone(), false)))
                .collect();
            for (module, _) in &runs {
                if schema.property(&format!("{module}/enabled")).is_none() {
                    errors.push(err(
                        Some(module),
                        None,
                        format!("context `{}`: unknown module `{module}`", rule.name),
                    ));
                }
            }
            let (Some(when), Some(until)) = (when, until.unwrap_or(Some(ExprId(usize::MAX))))
            else {
                continue;
            };
            engine.rules.push(Rule {
                name: rule.name.clone(),
                when,
                until: (until.0 != usize::MAX).then_some(until),
                min_dwell: Duration::from_millis(rule.min_dwell_ms),
                priority: rule.priority,
                sets,
                relinks: rule
                    .relink
                    .iter()
                    .map(|(a, b)| (a.clone(), b.clone()))
                    .collect(),
                runs,
                sticky: rule.sticky,
                active: false,
                since: None,
            });
        }
        for (i, rule) in engine.rules.iter().enumerate() {
            engine.by_condition.insert(rule.when, i);
            if let Some(until) = rule.until {
                engine.by_condition.insert(until, i);
            }
        }
        // Every rule is looked at once, on the first step.
        engine.waiting = (0..engine.rules.len()).collect();
        errors.extend(engine.conflicts(loaded));
        errors.extend(engine.never_hold(loaded));
        match errors.is_empty() {
            true => Ok(engine),
            false => Err(errors),
        }
    }

    /// Equal priorities on a shared target cannot be resolved deterministically.
    fn conflicts(&self, loaded: &LoadedRules) -> Vec<RuleError> {
        let mut errors = Vec::new();
        let mut owners: BTreeMap<(String, i64), &str> = BTreeMap::new();
        for rule in &self.rules {
            let targets = rule
                .sets
                .iter()
                .map(|(t, _)| t.clone())
                .chain(rule.relinks.iter().map(|(i, _)| format!("link of {i}")))
                .chain(
                    rule.runs
                        .iter()
                        .map(|(m, _)| format!("running state of {m}")),
                );
            for target in targets {
                if let Some(other) = owners.insert((target.clone(), rule.priority), &rule.name) {
                    errors.push(loaded.error(&rule.name, None, None, format!(
                        "contexts `{other}` and `{}` both change the {target} with priority {}: give them different priorities",
                        rule.name, rule.priority
                    )));
                }
            }
        }
        errors
    }

    /// A `when` that reads no property and is false can never hold.
    fn never_hold(&mut self, loaded: &LoadedRules) -> Vec<RuleError> {
        self.exprs.evaluate(Instant::now());
        self.rules
            .iter()
            .filter(|r| self.exprs.bool(r.when) == Some(false))
            .map(|r| {
                loaded.error(
                    &r.name,
                    None,
                    None,
                    format!(
                        "context `{}` can never hold: its `when` is always false",
                        r.name
                    ),
                )
            })
            .collect()
    }

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
        let mut active: Vec<&Rule> = self.rules.iter().filter(|r| r.active).collect();
        active.sort_by_key(|r| std::cmp::Reverse(r.priority));
        active.into_iter().map(|r| r.name.as_str()).collect()
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
            let name = rule.name.clone();
            actions.push(if rule.active {
                Action::Activated(name)
            } else {
                Action::Deactivated(name)
            });
        }
        self.diff(&mut actions);
        actions
    }

    /// Effects the active contexts want, the highest priority first, then declaration order.
    fn desired(&self) -> Effects {
        let mut order: Vec<&Rule> = self.rules.iter().filter(|r| r.active).collect();
        order.sort_by_key(|r| std::cmp::Reverse(r.priority));
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

/// The expression type a property of type `info` can be set from.
fn settable_ty(info: TypeInfo) -> Option<Ty> {
    if info.is::<bool>() {
        Some(Ty::Bool)
    } else if info.is::<f64>() || info.is::<i64>() {
        Some(Ty::Num)
    } else if info.is::<String>() {
        Some(Ty::Str)
    } else {
        None
    }
}

/// Types for the properties `src` reads (unknown ones are left out: the checker reports them
/// with their position).
fn env_for(src: &str, schema: &dyn Schema) -> TypeEnv {
    let mut env = TypeEnv::new();
    if let Ok(ast) = parse(src) {
        for path in properties(&ast) {
            if let Some((info, sample)) = schema.property(&path) {
                env.insert_property(&path, info, &sample);
            }
        }
    }
    env
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
