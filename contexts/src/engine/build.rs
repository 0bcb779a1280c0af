//! Building an engine from a rules file: every check `petrel check` reports.

use std::collections::{BTreeMap, HashMap};
use std::time::Duration;

use petrel_actors::expr::{never_true, parse, properties, quoted, ExprId, ExprSet, Ty, TypeEnv};
use petrel_actors::TypeInfo;
use tokio::time::Instant;

use super::{Effect, Effects, Engine, Rule, Schema};
use crate::rules::{LoadedRules, RuleError};

/// The longest `min_dwell_ms` a rule may ask for, ms: a day.
const MAX_DWELL_MS: u64 = 86_400_000;

impl Engine {
    /// Checks `loaded` against `schema` and builds an engine; returns every problem found.
    pub fn build(loaded: &LoadedRules, schema: &dyn Schema) -> Result<Engine, Vec<RuleError>> {
        let mut errors = Vec::new();
        let mut engine = Engine {
            exprs: ExprSet::new(),
            rules: Vec::new(),
            values: Effects::new(Vec::new()).0,
            links: Effects::new(Vec::new()).0,
            runs: Effects::new(Vec::new()).0,
            condition_of: Vec::new(),
            waiting: Vec::new(),
            active: Vec::new(),
            pending: Vec::new(),
            resolve: false,
            changed: Vec::new(),
            candidates: Vec::new(),
        };
        // Each name with how many contexts had it so far, in a map: 100,000 contexts were
        // compared with each other (a minute of `petrel check`).
        let mut names = std::collections::HashMap::new();
        for rule in &loaded.rules.contexts {
            let seen = names.entry(rule.name.as_str()).or_insert(0usize);
            let nth = *seen;
            *seen += 1;
            let err = |needle: Option<&str>, offset, message| {
                loaded.error_nth(&rule.name, nth, needle, offset, message)
            };
            if rule.name.trim().is_empty() {
                let message = "a context without a name: its switches and errors could not say which it is; give it `name: \"...\"`";
                errors.push(err(Some("name: \"\""), None, message.into()));
                continue;
            }
            // Reported where the second is written; its body is still checked, so its own
            // mistakes show in the same run.
            if nth > 0 {
                errors.push(err(
                    None,
                    None,
                    format!("duplicate context name `{}`: a context of that name comes before; give this one another name", rule.name),
                ));
            }
            // A dwell is a wait: past a day it is a typo (and u64::MAX overflowed the clock).
            if rule.min_dwell_ms > MAX_DWELL_MS {
                errors.push(err(
                    None,
                    None,
                    format!(
                        "context `{}`: min_dwell_ms is {}; expected at most {MAX_DWELL_MS} (a day)",
                        rule.name, rule.min_dwell_ms
                    ),
                ));
            }
            let mut add = |src: &str, want: &Ty, errors: &mut Vec<RuleError>| -> Option<ExprId> {
                let env = env_for(src, schema);
                match engine.exprs.add(src, &env, Some(want)) {
                    Ok(id) => Some(id),
                    Err(e) => {
                        let message = format!(
                            "context `{}`: in `{}`: {}",
                            rule.name,
                            quoted(src),
                            e.message
                        );
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
                let Some((info, sample)) = schema.property(&target) else {
                    // An `enable`/`disable` entry names a module (its needle is the name).
                    let what = match needle == target {
                        true => format!("unknown property `{target}`"),
                        false => format!("unknown module `{needle}`"),
                    };
                    let message = format!("context `{}`: {what}", rule.name);
                    errors.push(err(Some(&needle), None, message));
                    continue;
                };
                let Some(want) = settable_ty(info) else {
                    let message = format!("context `{}`: `{target}` is a {}; `set` takes bool, number or string properties", rule.name, info.name());
                    errors.push(err(Some(&needle), None, message));
                    continue;
                };
                // The kind, checked with the current value (always one the property takes).
                if let Some(why) = schema.refuses(&target, &sample) {
                    let message = format!("context `{}`: {why}", rule.name);
                    errors.push(err(Some(&needle), None, message));
                    continue;
                }
                let Some(id) = add(&src, &want, &mut errors) else {
                    continue;
                };
                let fraction = match info.is::<i64>() {
                    true => super::whole::fraction_source(&src, schema).map(|why| {
                        format!(
                            "`{target}` takes whole numbers (an i64), but `{}` may give a fraction: {why}",
                            quoted(&src)
                        )
                    }),
                    false => None,
                };
                match constant_refused(&src, &want, info, &target, schema).or(fraction) {
                    Some(why) => {
                        let message = format!("context `{}`: {why}", rule.name);
                        errors.push(err(Some(&needle), None, message));
                    }
                    None => sets.push(effect(&target, id)),
                }
            }
            for (input, source) in &rule.relink {
                match (schema.property(input), schema.property(source)) {
                    (Some((a, _)), Some((b, _))) if a != b => errors.push(err(
                        Some(source),
                        None,
                        format!("context `{}`: cannot relink `{input}` ({}) to `{source}` ({}): the types differ", rule.name, a.name(), b.name()),
                    )),
                    (Some(_), Some(_)) => {
                        if let Some(why) = schema.refuses_link(input, source) {
                            errors.push(err(Some(source), None, format!("context `{}`: cannot relink `{input}` to `{source}`: {why}", rule.name)));
                        }
                    }
                    (None, _) => errors.push(err(Some(input), None, format!("context `{}`: unknown property `{input}`", rule.name))),
                    (_, None) => errors.push(err(Some(source), None, format!("context `{}`: unknown property `{source}`", rule.name))),
                }
            }
            let runs: Vec<Effect<bool>> = rule
                .start
                .iter()
                .map(|m| effect(m, true))
                .chain(rule.stop.iter().map(|m| effect(m, false)))
                .collect();
            for module in runs.iter().map(|e| &e.target) {
                if schema.property(&format!("{module}/enabled")).is_none() {
                    errors.push(err(
                        Some(module),
                        None,
                        format!("context `{}`: unknown module `{module}`", rule.name),
                    ));
                }
            }
            // `until` is optional; a given one that failed to check skips the rule like `when`.
            let (Some(when), Some(until)) = (when, until.map_or(Some(None), |u| u.map(Some)))
            else {
                continue;
            };
            engine.rules.push(Rule {
                name: rule.name.as_str().into(),
                when,
                until,
                min_dwell: Duration::from_millis(rule.min_dwell_ms),
                priority: rule.priority,
                sets,
                relinks: rule
                    .relink
                    .iter()
                    .map(|(input, source)| effect(input, source.as_str().into()))
                    .collect(),
                runs,
                sticky: rule.sticky,
                active: false,
                since: None,
            });
        }
        for (i, rule) in engine.rules.iter().enumerate() {
            for id in std::iter::once(rule.when).chain(rule.until) {
                if engine.condition_of.len() <= id.0 {
                    engine.condition_of.resize(id.0 + 1, None);
                }
                engine.condition_of[id.0] = Some(i);
            }
        }
        engine.number_targets();
        // Every rule is looked at once, on the first step.
        engine.waiting = (0..engine.rules.len()).collect();
        errors.extend(engine.conflicts(loaded));
        errors.extend(engine.never_hold(loaded));
        match errors.is_empty() {
            true => Ok(engine),
            false => Err(errors),
        }
    }

    /// Numbers the targets of each effect kind (in name order) and creates their tables.
    fn number_targets(&mut self) {
        fn table<X, V: Clone + PartialEq>(effects: Vec<&mut Effect<X>>) -> Effects<V> {
            let names = effects.iter().map(|e| e.target.clone()).collect();
            let (table, numbers) = Effects::new(names);
            for e in effects {
                e.number = numbers[&e.target];
            }
            table
        }
        let rules = &mut self.rules;
        self.values = table(rules.iter_mut().flat_map(|r| &mut r.sets).collect());
        self.links = table(rules.iter_mut().flat_map(|r| &mut r.relinks).collect());
        self.runs = table(rules.iter_mut().flat_map(|r| &mut r.runs).collect());
    }

    /// Equal priorities on a shared target cannot be resolved deterministically.
    fn conflicts(&self, loaded: &LoadedRules) -> Vec<RuleError> {
        let mut errors = Vec::new();
        let mut owners: BTreeMap<(String, i64), &str> = BTreeMap::new();
        for rule in &self.rules {
            let targets = rule
                .sets
                .iter()
                .map(|e| e.target.to_string())
                .chain(rule.relinks.iter().map(|e| format!("link of {}", e.target)))
                .chain(
                    rule.runs
                        .iter()
                        .map(|e| format!("running state of {}", e.target)),
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

    /// Contexts that can never hold: a `when` that reads no property and is false, or one
    /// whose comparisons contradict each other (`v > 5 and v < 3`).
    fn never_hold(&mut self, loaded: &LoadedRules) -> Vec<RuleError> {
        self.exprs.evaluate(Instant::now());
        let mut errors = Vec::new();
        // Rules that failed to build are not in `self.rules`: each is found by name (in a
        // table: a search per rule made 100,000 contexts take a minute).
        let mut written: HashMap<&str, &str> = HashMap::new();
        for c in &loaded.rules.contexts {
            // The first of a name given twice is the one built.
            written.entry(c.name.as_str()).or_insert(c.when.as_str());
        }
        for rule in &self.rules {
            let name = &rule.name;
            if self.exprs.bool(rule.when) == Some(false) {
                let message =
                    format!("context `{name}` can never hold: its `when` is always false");
                errors.push(loaded.error(name, None, None, message));
                continue;
            }
            let Some(&when) = written.get(&**name) else {
                continue;
            };
            let contradiction = parse(when).ok().and_then(|ast| never_true(when, &ast));
            if let Some(e) = contradiction {
                let message = format!("context `{name}` can never hold: {}", e.message);
                errors.push(loaded.error(name, Some(when), Some((e.line, e.column)), message));
            }
        }
        errors
    }
}

/// An effect on `target`, numbered later by [`Engine::number_targets`].
fn effect<X>(target: &str, what: X) -> Effect<X> {
    Effect {
        target: target.into(),
        number: usize::MAX,
        what,
    }
}

/// What `target` would refuse of `src` if `src` is a constant (it reads no property and no
/// clock), so that `petrel check` refuses it rather than the run logging it at every switch:
/// a value that cannot be evaluated (`1 / 0`), of another type (`2.5` for an `i64`) or out of
/// the parameter's range. Values computed from properties are checked when written.
fn constant_refused(
    src: &str,
    want: &Ty,
    info: TypeInfo,
    target: &str,
    schema: &dyn Schema,
) -> Option<String> {
    let mut one = ExprSet::new();
    let id = one.add(src, &TypeEnv::new(), Some(want)).ok()?;
    if one.has_timed() || one.properties().next().is_some() {
        return None;
    }
    one.evaluate(Instant::now());
    let value = match one.value(id)? {
        Ok(value) => value,
        Err(e) => {
            return Some(format!(
                "`{target}`: `{}` cannot be evaluated: {e}",
                quoted(src)
            ))
        }
    };
    match super::to_property(value, info) {
        Ok(value) => schema.refuses(target, &value),
        Err(e) => Some(format!("`{target}`: {e}")),
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
