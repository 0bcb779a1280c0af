//! What `petrel check` asks of a rules file without running it, and the addresses a rules
//! file mentions (which the manager looks up when it starts).

use std::path::Path;

use petrel_actors::expr::{parse, properties};
use petrel_actors::{AnyValue, Registry, TypeInfo};

use crate::engine::{Engine, Schema};
use crate::rules::{LoadedRules, RuleError};

impl Schema for Registry {
    fn property(&self, path: &str) -> Option<(TypeInfo, AnyValue)> {
        self.get_or_latest(path).ok()
    }

    fn refuses(&self, path: &str, value: &AnyValue) -> Option<String> {
        self.check_live_set(path, value)
            .err()
            .map(|e| e.to_string())
    }

    fn refuses_link(&self, input: &str, source: &str) -> Option<String> {
        self.check_link(input, source).err().map(|e| e.to_string())
    }
}

/// Every property address a rules file mentions (expressions, targets, links, modules).
pub(super) fn mentioned(loaded: &LoadedRules) -> Vec<String> {
    let mut paths = Vec::new();
    for r in &loaded.rules.contexts {
        let sources = std::iter::once(&r.when)
            .chain(&r.until)
            .chain(r.set.values());
        for src in sources {
            if let Ok(ast) = parse(src) {
                paths.extend(properties(&ast));
            }
        }
        paths.extend(r.set.keys().cloned());
        paths.extend(r.relink.iter().flat_map(|(a, b)| [a.clone(), b.clone()]));
        let modules = r
            .enable
            .iter()
            .chain(&r.disable)
            .chain(&r.start)
            .chain(&r.stop);
        paths.extend(modules.map(|m| format!("{m}/enabled")));
    }
    paths.sort();
    paths.dedup();
    paths
}

/// Checks a rules file against an agent's registry for the context manager `manager` (what
/// `petrel check` does): the errors `run` would refuse it for, or the warnings (contexts whose
/// changes reach their own condition), each at its place in the file.
pub fn check_rules(
    path: &Path,
    registry: &Registry,
    manager: &str,
) -> Result<Vec<RuleError>, Vec<RuleError>> {
    let loaded = LoadedRules::load(path)?;
    let mut errors = crate::lint::stops_its_manager(&loaded, manager);
    if let Err(more) = Engine::build(&loaded, registry) {
        errors.extend(more);
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    // Not for a context that says it reads its own changes on purpose (the runtime still
    // names one that does loop, with this same finding).
    let on_purpose = |name: &str| {
        let rules = &loaded.rules.contexts;
        rules.iter().any(|r| r.name == name && r.reads_own_changes)
    };
    Ok(crate::lint::self_undoing(&loaded.rules.contexts)
        .into_iter()
        .filter(|s| !on_purpose(&s.context))
        .map(|s| loaded.error(&s.context, Some(&s.target), None, s.message()))
        .collect())
}
