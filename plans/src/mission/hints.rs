//! What binding tells a user beyond errors: hints about places, bindings that no action uses,
//! and the nearest name to a misspelt one.

use std::collections::BTreeSet;

use super::bind::BindingProblem;
use super::config::{match_action, ActionBindings, ActionName, Places};

/// For a `"$N"` value whose parameter names no place: say which places there are.
pub(crate) fn place_hint(value: &ron::Value, params: &[String], places: &Places) -> String {
    let ron::Value::String(s) = value else {
        return String::new();
    };
    let Some(param) = s
        .strip_prefix('$')
        .and_then(|n| n.parse::<usize>().ok())
        .and_then(|n| params.get(n.wrapping_sub(1)))
    else {
        return String::new();
    };
    if places.0.contains_key(param) || param.parse::<f64>().is_ok() {
        return String::new();
    }
    let known: Vec<&str> = places.0.keys().map(String::as_str).collect();
    format!(
        "; `{param}` is not a place in params/places (places: {})",
        if known.is_empty() {
            "none".to_string()
        } else {
            known.join(", ")
        }
    )
}

/// Bindings no plan action uses (a typo such as `reprot_dock`), each with the nearest name.
pub(crate) fn unused_bindings(
    module: &str,
    bindings: &ActionBindings,
    actions: &BTreeSet<String>,
) -> Vec<BindingProblem> {
    let locals: Vec<String> = actions.iter().map(|a| ActionName::parse(a).local).collect();
    bindings
        .0
        .keys()
        .filter(|key| {
            !locals
                .iter()
                .any(|l| match_action(std::iter::once(key.as_str()), l).is_some())
        })
        .map(|key| BindingProblem {
            needle: key.clone(),
            message: format!(
                "{module}/params/actions[\"{key}\"]: the plan has no action `{key}` (nor `{key}_...`){}",
                nearest(key, locals.iter().map(String::as_str))
            ),
        })
        .collect()
}

/// ` (is the binding `x` it, misspelt?)` for an action no binding matches, when a binding's
/// name is close to the action's name or to one of its prefixes before a `_` (the binding
/// `cuont` of `count_5`).
pub(crate) fn misspelt_binding(action: &str, bindings: &[&str]) -> String {
    let local = ActionName::parse(crate::remote::robot_of(action).map_or(action, |(_, l)| l)).local;
    let prefixes = local
        .match_indices('_')
        .map(|(i, _)| &local[..i])
        .chain(std::iter::once(local.as_str()));
    prefixes
        .flat_map(|name| {
            bindings
                .iter()
                .filter_map(move |b| close(name, b).map(|d| (d, *b)))
        })
        .min()
        .map_or(String::new(), |(_, b)| {
            format!(" (is the binding `{b}` it, misspelt?)")
        })
}

/// The edit distance of `name` and `candidate` when they are close: at most a third of the
/// longer, or 2 (a swap of two letters) for short names. Half the length offered `goto_dock`
/// for `reprot_dock`.
fn close(name: &str, candidate: &str) -> Option<usize> {
    let d = edit_distance(name, candidate);
    (d > 0 && d <= (name.len().max(candidate.len()) / 3).max(2)).then_some(d)
}

/// `; did you mean `x`?` for the candidate nearest to `name`, if one is close.
pub(crate) fn nearest<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> String {
    candidates
        .filter_map(|c| close(name, c).map(|d| (d, c)))
        .min()
        .map_or(String::new(), |(_, c)| format!("; did you mean `{c}`?"))
}

/// Levenshtein distance over characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != *cb)).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_close_names_are_offered() {
        let offered = |name, c: &[&str]| nearest(name, c.iter().copied());
        assert_eq!(
            offered("reprot_dock", &["goto_dock", "report_dock"]),
            "; did you mean `report_dock`?"
        );
        assert_eq!(offered("reprot_dock", &["goto_dock"]), "");
        assert_eq!(offered("stop", &["goto"]), "");
        assert_eq!(
            misspelt_binding("count_5", &["cuont", "check"]),
            " (is the binding `cuont` it, misspelt?)"
        );
        assert_eq!(
            misspelt_binding("warmup", &["wramup"]),
            " (is the binding `wramup` it, misspelt?)"
        );
        assert_eq!(misspelt_binding("goto_dock", &["stop"]), "");
    }
}
