//! The binding types set in configs (`params/actions`, `params/conditions`, `in/conditions`),
//! and the pure rules that match action names to bindings.

use std::collections::BTreeMap;

use petrel_actors::PropertyType;
use serde::{Deserialize, Serialize};

/// How one action (or family of parameterized actions) drives modules.
///
/// Every field is optional. `$1`, `$2`, ... in `set` values and in `finished` / `failed`
/// stand for the action's parameters (`gotopose_6_2_0` bound as `gotopose`: `$1` = 6, ...).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ActionBinding {
    /// Modules set `enabled = true` on start / resume and `false` on end / interrupt / fail.
    pub enable: Vec<String>,
    /// Properties set on start / resume (`module/path` → value). A value that is exactly
    /// `"$N"` becomes the parameter read as RON (a number stays a number).
    pub set: BTreeMap<String, ron::Value>,
    /// Inputs relinked on start / resume (`module/in/x` → `other/out/y`): the action points a
    /// module at a source it chooses while it runs (the planner's target at a victim).
    pub link: BTreeMap<String, String>,
    /// Whether end / interrupt / fail put back the values `set` replaced and the links `link`
    /// changed (default true).
    pub restore: bool,
    /// Boolean expression: the action finished (empty: only an interrupt ends it).
    pub finished: String,
    /// Boolean expression: the action failed (empty: it never fails).
    pub failed: String,
}

impl ActionBinding {
    /// A binding with every field left out (`restore` is true).
    pub fn defaults() -> Self {
        ActionBinding {
            restore: true,
            ..Default::default()
        }
    }
}

/// `params/actions`: action binding by action name or name prefix (see [`match_action`]).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
#[serde(transparent)]
pub struct ActionBindings(pub BTreeMap<String, ActionBinding>);

impl<'de> Deserialize<'de> for ActionBindings {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        // `restore` defaults to true, which `#[serde(default)]` (false) cannot say: read each
        // binding as a map over the defaults.
        let raw = BTreeMap::<String, BTreeMap<String, ron::Value>>::deserialize(d)?;
        let mut out = BTreeMap::new();
        for (name, fields) in raw {
            let mut b = ActionBinding::defaults();
            for (field, value) in fields {
                let bad = |e: ron::Error| {
                    serde::de::Error::custom(format!("action `{name}`, field `{field}`: {e}"))
                };
                match field.as_str() {
                    "enable" => b.enable = value.into_rust().map_err(bad)?,
                    "set" => b.set = value.into_rust().map_err(bad)?,
                    "link" => b.link = value.into_rust().map_err(bad)?,
                    "restore" => b.restore = value.into_rust().map_err(bad)?,
                    "finished" => b.finished = value.into_rust().map_err(bad)?,
                    "failed" => b.failed = value.into_rust().map_err(bad)?,
                    other => {
                        return Err(serde::de::Error::custom(format!(
                            "action `{name}`: unknown field `{other}`; expected enable, set, link, restore, finished or failed"
                        )))
                    }
                }
            }
            out.insert(name, b);
        }
        Ok(ActionBindings(out))
    }
}

impl PropertyType for ActionBindings {
    const TYPE_NAME: &'static str = "pnp.actions";
}

/// `params/conditions`: condition atom → boolean expression over properties.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct ConditionBindings(pub BTreeMap<String, String>);

impl PropertyType for ConditionBindings {
    const TYPE_NAME: &'static str = "pnp.conditions";
}

/// `params/places`: named values that action parameters may name (`goto_kitchen` with
/// `kitchen: (x: 2.0, y: 1.0)`): a `set` value `"$1"` becomes the place's value, `$1.x` in an
/// expression its field.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Places(pub BTreeMap<String, ron::Value>);

impl PropertyType for Places {
    const TYPE_NAME: &'static str = "pnp.places";
}

/// `in/conditions`: values of the condition atoms no expression binds.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Flags(pub BTreeMap<String, bool>);

impl PropertyType for Flags {
    const TYPE_NAME: &'static str = "pnp.flags";
}

/// An action name split into its parts: `robot1#gotopose_6_2_0`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ActionName {
    /// The robot prefix (`robot1`), kept for multi-robot plans (not sent anywhere yet).
    pub robot: Option<String>,
    /// The name without the robot prefix (`gotopose_6_2_0`).
    pub local: String,
}

impl ActionName {
    /// Splits `robot#name`.
    pub fn parse(full: &str) -> ActionName {
        match full.split_once('#') {
            Some((r, l)) => ActionName {
                robot: Some(r.to_string()),
                local: l.to_string(),
            },
            None => ActionName {
                robot: None,
                local: full.to_string(),
            },
        }
    }
}

/// The binding key for action `local` and its parameters: the key equal to the name, or else
/// the longest key `K` such that the name is `K_p1_p2...` (parameters split on `_`).
pub fn match_action<'a>(
    keys: impl Iterator<Item = &'a str>,
    local: &str,
) -> Option<(&'a str, Vec<String>)> {
    let mut best: Option<(&str, Vec<String>)> = None;
    for k in keys {
        if k == local {
            return Some((k, Vec::new()));
        }
        if let Some(rest) = local.strip_prefix(k).and_then(|r| r.strip_prefix('_')) {
            if best.as_ref().is_none_or(|(b, _)| k.len() > b.len()) {
                best = Some((k, rest.split('_').map(str::to_string).collect()));
            }
        }
    }
    best
}

/// Replaces `$1`, `$2`, ... in expression text by parameters: a parameter naming a place
/// gives its value (a number or string), and `$N.field` a field of a place (`$1.x`).
/// Errors name what cannot be substituted.
pub fn substitute(text: &str, params: &[String], places: &Places) -> Result<String, String> {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(i) = rest.find('$') {
        out.push_str(&rest[..i]);
        let after = &rest[i + 1..];
        let digits = after.len() - after.trim_start_matches(|c: char| c.is_ascii_digit()).len();
        let Ok(n) = after[..digits].parse::<usize>() else {
            out.push('$');
            rest = after;
            continue;
        };
        let Some(param) = n.checked_sub(1).and_then(|k| params.get(k)) else {
            return Err(format!(
                "`${n}`: the action has {} parameter{}",
                params.len(),
                plural(params.len())
            ));
        };
        rest = &after[digits..];
        let field_len = rest
            .strip_prefix('.')
            .filter(|f| f.starts_with(|c: char| c.is_alphabetic() || c == '_'))
            .map(|f| {
                1 + f.len()
                    - f.trim_start_matches(|c: char| c.is_alphanumeric() || c == '_')
                        .len()
            });
        match (places.0.get(param), field_len) {
            (Some(value), Some(len)) => {
                let field = &rest[1..len];
                let Some(v) = field_of(value, field) else {
                    return Err(format!("`${n}.{field}`: place `{param}` has no field `{field}`"));
                };
                out.push_str(&expr_literal(v).ok_or_else(|| format!("`${n}.{field}` of place `{param}` is not a number, string or boolean"))?);
                rest = &rest[len..];
            }
            (Some(value), None) => out.push_str(&expr_literal(value).ok_or_else(|| {
                format!("`${n}` is place `{param}`, a structured value: name one of its fields, as `${n}.x`")
            })?),
            (None, Some(len)) => {
                let known: Vec<&str> = places.0.keys().map(String::as_str).collect();
                return Err(format!(
                    "`${n}{}`: `{param}` is not a place in params/places (places: {})",
                    &rest[..len],
                    if known.is_empty() { "none".to_string() } else { known.join(", ") }
                ));
            }
            (None, None) => out.push_str(&param_literal(param)),
        }
    }
    out.push_str(rest);
    Ok(out)
}

/// A parameter as a value in an expression: a number or `true`/`false` as it is, anything
/// else as a string. Never as code: a PNML action `check_a/out/x` must not read a property.
fn param_literal(param: &str) -> String {
    let number = param.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '.')
        && param.parse::<f64>().is_ok_and(f64::is_finite);
    match number || param == "true" || param == "false" {
        true => param.to_string(),
        false => format!("{param:?}"),
    }
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

fn field_of<'a>(v: &'a ron::Value, field: &str) -> Option<&'a ron::Value> {
    match v {
        ron::Value::Map(m) => m.get(&ron::Value::String(field.to_string())),
        _ => None,
    }
}

/// A scalar as expression text.
fn expr_literal(v: &ron::Value) -> Option<String> {
    Some(match v {
        ron::Value::Number(n) => n.into_f64().to_string(),
        ron::Value::Bool(b) => b.to_string(),
        ron::Value::String(s) => format!("{s:?}"),
        _ => return None,
    })
}

/// A `set` value with parameters substituted: `"$N"` alone becomes the place the parameter
/// names (`"$N.field"` its field), or else the parameter read as RON (so `6` is a number); `$N` inside a longer string
/// is replaced in the text.
pub fn substitute_value(v: &ron::Value, params: &[String], places: &Places) -> ron::Value {
    match v {
        ron::Value::String(s) => {
            // `"$1.x"`: a field of the place the parameter names.
            let (head, field) = s.split_once('.').unwrap_or((s, ""));
            let whole = head
                .strip_prefix('$')
                .and_then(|n| n.parse::<usize>().ok())
                .and_then(|n| params.get(n.wrapping_sub(1)));
            if let Some(place) = whole.and_then(|p| places.0.get(p)) {
                if field.is_empty() {
                    return place.clone();
                }
                if let Some(v) = field_of(place, field) {
                    return v.clone();
                }
            }
            let whole = if field.is_empty() { whole } else { None };
            // A bare word (`kitchen`) reads as RON's unit: keep it as the text it is.
            match whole.and_then(|p| ron::from_str::<ron::Value>(p).ok()) {
                Some(ron::Value::Unit) | None => ron::Value::String(replace_params(s, params)),
                Some(parsed) => parsed,
            }
        }
        ron::Value::Seq(xs) => ron::Value::Seq(
            xs.iter()
                .map(|x| substitute_value(x, params, places))
                .collect(),
        ),
        ron::Value::Map(m) => ron::Value::Map(
            m.iter()
                .map(|(k, x)| (k.clone(), substitute_value(x, params, places)))
                .collect(),
        ),
        other => other.clone(),
    }
}

/// `$N` replaced by the parameter text (highest first, so `$12` is not read as `$1`).
fn replace_params(text: &str, params: &[String]) -> String {
    let mut out = text.to_string();
    for (i, p) in params.iter().enumerate().rev() {
        out = out.replace(&format!("${}", i + 1), p);
    }
    out
}

/// The highest `$N` a binding uses (0: none), in its `set` values and expressions.
pub fn max_param(b: &ActionBinding) -> usize {
    fn text(s: &str) -> usize {
        let mut best = 0;
        let mut rest = s;
        while let Some(i) = rest.find('$') {
            rest = &rest[i + 1..];
            let digits = rest.len() - rest.trim_start_matches(|c: char| c.is_ascii_digit()).len();
            best = best.max(rest[..digits].parse().unwrap_or(0));
        }
        best
    }
    fn value(v: &ron::Value) -> usize {
        match v {
            ron::Value::String(s) => text(s),
            ron::Value::Seq(xs) => xs.iter().map(value).max().unwrap_or(0),
            ron::Value::Map(m) => m.values().map(value).max().unwrap_or(0),
            _ => 0,
        }
    }
    let set = b.set.values().map(value).max().unwrap_or(0);
    set.max(text(&b.finished)).max(text(&b.failed))
}

pub use petrel_actors::config_form;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_match_exactly_or_by_longest_prefix_with_parameters() {
        let keys = ["goto", "gotopose", "say"];
        let m = |n| match_action(keys.iter().copied(), n);
        assert_eq!(m("say"), Some(("say", vec![])));
        assert_eq!(
            m("gotopose_6_2_0"),
            Some(("gotopose", vec!["6".into(), "2".into(), "0".into()]))
        );
        assert_eq!(m("goto_kitchen"), Some(("goto", vec!["kitchen".into()])));
        assert_eq!(m("gotox"), None);
        assert_eq!(
            ActionName::parse("r1#goto_a"),
            ActionName {
                robot: Some("r1".into()),
                local: "goto_a".into()
            }
        );
    }

    #[test]
    fn parameters_substitute_in_text_and_values() {
        let p: Vec<String> = ["6", "2", "x"].iter().map(|s| s.to_string()).collect();
        let none = Places::default();
        assert_eq!(
            substitute("a/out/x > $1 + $2", &p, &none).unwrap(),
            "a/out/x > 6 + 2"
        );
        let n = substitute_value(&ron::Value::String("$1".into()), &p, &none);
        assert!(matches!(n, ron::Value::Number(n) if n.into_f64() == 6.0));
        assert_eq!(
            substitute_value(&ron::Value::String("to $3".into()), &p, &none),
            ron::Value::String("to x".into())
        );
        assert!(substitute("$4 > 1", &p, &none)
            .unwrap_err()
            .contains("3 parameters"));
        // A parameter is a value, never code: a word is a string, a path is not read.
        let words: Vec<String> = ["x", "a/out/x", "true", "-1.5", "inf", "1)or(1"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        assert_eq!(
            substitute("[$1, $2, $3, $4, $5, $6]", &words, &none).unwrap(),
            r#"["x", "a/out/x", true, -1.5, "inf", "1)or(1"]"#
        );
    }

    #[test]
    fn parameters_naming_places_give_their_values_and_fields() {
        let places: Places = ron::from_str("{\"kitchen\": (x: 2.5, y: -1.0)}").unwrap();
        let p = vec!["kitchen".to_string()];
        let v = substitute_value(&ron::Value::String("$1".into()), &p, &places);
        assert_eq!(config_form(&v), "(x: 2.5, y: -1.0)");
        assert_eq!(
            substitute("abs(r/out/pose.x - $1.x) < 0.2", &p, &places).unwrap(),
            "abs(r/out/pose.x - 2.5) < 0.2"
        );
        let whole = substitute("r/out/pose == $1", &p, &places).unwrap_err();
        assert!(whole.contains("`$1.x`"), "{whole}");
        let missing = substitute("$1.z > 0", &p, &places).unwrap_err();
        assert!(missing.contains("no field `z`"), "{missing}");
        let other = vec!["garage".to_string()];
        let not_a_place = substitute("$1.x > 0", &other, &places).unwrap_err();
        assert_eq!(
            not_a_place,
            "`$1.x`: `garage` is not a place in params/places (places: kitchen)"
        );
        assert_eq!(
            substitute_value(&ron::Value::String("$1".into()), &other, &places),
            ron::Value::String("garage".into()),
            "a bare word stays a word"
        );
    }

    #[test]
    fn bindings_read_from_config_values_with_restore_defaulting_to_true() {
        let v: ron::Value = ron::from_str(
            r#"{"go": (enable: ["nav"], set: {"nav/params/x": "$1"}, finished: "nav/out/done")}"#,
        )
        .unwrap();
        let b: ActionBindings = v.into_rust().unwrap();
        let go = &b.0["go"];
        assert!(go.restore && go.enable == ["nav"] && go.finished == "nav/out/done");
        let bad: ron::Value = ron::from_str(r#"{"go": (finish: "x")}"#).unwrap();
        let err = bad.into_rust::<ActionBindings>().unwrap_err().to_string();
        assert!(err.contains("action `go`: unknown field `finish`"), "{err}");
    }
}
