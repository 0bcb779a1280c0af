//! Rules that fight themselves: found from the rules alone, before anything runs.
//!
//! - A context whose `set` or `relink` changes a property its own `when` or `until` reads may
//!   end itself as soon as it starts: it restores the value, its condition holds again, and it
//!   starts again, as fast as the CPU allows. That is a warning (some such rules settle).
//! - A context that disables or stops the context manager running it can never be undone: no
//!   rule is evaluated any more. That is an error.

use petrel_actors::expr::{parse, properties};

use crate::rules::{ContextRule, LoadedRules, RuleError};

/// A context that changes a property its own condition reads.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SelfUndoing {
    /// The context.
    pub context: String,
    /// The property (or relinked input) it changes.
    pub target: String,
    /// `when` or `until`: the condition that reads it.
    pub condition: &'static str,
}

impl SelfUndoing {
    /// Says what may happen, in the user's terms.
    pub fn message(&self) -> String {
        format!(
            "context `{}` changes `{}`, which its own `{}` reads: the change may end the context that made it, which then restores the value and starts again, a loop",
            self.context, self.target, self.condition
        )
    }
}

/// Every context whose own changes reach its condition. A condition that does not parse is
/// left to the engine's errors.
pub fn self_undoing(rules: &[ContextRule]) -> Vec<SelfUndoing> {
    let mut found = Vec::new();
    for rule in rules {
        let conditions = std::iter::once(("when", Some(&rule.when)))
            .chain(std::iter::once(("until", rule.until.as_ref())));
        for (condition, source) in conditions {
            let Some(reads) = source.and_then(|s| parse(s).ok()).map(|a| properties(&a)) else {
                continue;
            };
            let changed = rule.set.keys().chain(rule.relink.keys());
            for target in changed.filter(|t| reads.iter().any(|r| r == *t)) {
                found.push(SelfUndoing {
                    context: rule.name.clone(),
                    target: target.clone(),
                    condition,
                });
            }
        }
    }
    found
}

/// Errors for contexts that disable or stop `manager`, the module running these rules.
pub fn stops_its_manager(loaded: &LoadedRules, manager: &str) -> Vec<RuleError> {
    let mut errors = Vec::new();
    for rule in &loaded.rules.contexts {
        for (field, list) in [("disable", &rule.disable), ("stop", &rule.stop)] {
            if list.iter().any(|m| m == manager) {
                errors.push(loaded.error(
                    &rule.name,
                    Some(manager),
                    None,
                    format!(
                        "context `{}`: `{field}` names `{manager}`, the context manager running these rules: once it is off, no rule is evaluated and nothing could switch it on again",
                        rule.name
                    ),
                ));
            }
        }
    }
    errors
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn rules(text: &str) -> LoadedRules {
        LoadedRules::parse(Path::new("t.rules.ron"), text).unwrap()
    }

    #[test]
    fn a_context_setting_what_its_condition_reads_is_found_and_others_are_not() {
        let loaded = rules(
            r#"Contexts(contexts: [
    (name: "undo", when: "m/params/factor > 0.5", set: {"m/params/factor": "0.0"}),
    (name: "fine", when: "speed/out/value > 0.6", set: {"vision/params/deblur": "true"}),
    (name: "swap", when: "a/out/x > 1", until: "m/in/v < 0", relink: {"m/in/v": "b/out/v"}),
])"#,
        );
        let found = self_undoing(&loaded.rules.contexts);
        assert_eq!(
            found,
            vec![
                SelfUndoing {
                    context: "undo".into(),
                    target: "m/params/factor".into(),
                    condition: "when",
                },
                SelfUndoing {
                    context: "swap".into(),
                    target: "m/in/v".into(),
                    condition: "until",
                },
            ]
        );
        assert!(found[0].message().contains("its own `when` reads"));
    }

    #[test]
    fn disabling_or_stopping_the_manager_itself_is_an_error_at_its_line() {
        let loaded = rules(
            "Contexts(contexts: [\n    (name: \"quiet\", when: \"true\",\n     disable: [\"contexts\", \"vision\"]),\n])",
        );
        let errors = stops_its_manager(&loaded, "contexts");
        assert_eq!(errors.len(), 1, "{errors:?}");
        assert_eq!((errors[0].line, errors[0].column), (3, 17));
        assert!(errors[0].to_string().contains("`disable` names `contexts`"));
        assert!(stops_its_manager(&loaded, "other").is_empty());
    }
}
