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
    /// Whether end / interrupt / fail put back the values `set` replaced (default true).
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
                    "restore" => b.restore = value.into_rust().map_err(bad)?,
                    "finished" => b.finished = value.into_rust().map_err(bad)?,
                    "failed" => b.failed = value.into_rust().map_err(bad)?,
                    other => {
                        return Err(serde::de::Error::custom(format!(
                            "action `{name}`: unknown field `{other}`; expected enable, set, restore, finished or failed"
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

/// Replaces `$1`, `$2`, ... (highest first, so `$12` is not read as `$1`) by parameters.
pub fn substitute(text: &str, params: &[String]) -> String {
    let mut out = text.to_string();
    for (i, p) in params.iter().enumerate().rev() {
        out = out.replace(&format!("${}", i + 1), p);
    }
    out
}

/// A `set` value with parameters substituted: `"$N"` alone becomes the parameter read as RON
/// (so `6` is a number); `$N` inside a longer string is replaced in the text.
pub fn substitute_value(v: &ron::Value, params: &[String]) -> ron::Value {
    match v {
        ron::Value::String(s) => {
            let whole = s
                .strip_prefix('$')
                .and_then(|n| n.parse::<usize>().ok())
                .and_then(|n| params.get(n.wrapping_sub(1)));
            match whole.and_then(|p| ron::from_str::<ron::Value>(p).ok()) {
                Some(parsed) => parsed,
                None => ron::Value::String(substitute(s, params)),
            }
        }
        ron::Value::Seq(xs) => {
            ron::Value::Seq(xs.iter().map(|x| substitute_value(x, params)).collect())
        }
        other => other.clone(),
    }
}

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
        assert_eq!(substitute("a/out/x > $1 + $2", &p), "a/out/x > 6 + 2");
        let n = substitute_value(&ron::Value::String("$1".into()), &p);
        assert!(matches!(n, ron::Value::Number(n) if n.into_f64() == 6.0));
        assert_eq!(
            substitute_value(&ron::Value::String("to $3".into()), &p),
            ron::Value::String("to x".into())
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
