//! What an engine has switched on and applied, in a form that outlives it: a reloaded engine
//! takes over from the one it replaces, and a restarted manager's engine from the memory its
//! predecessor kept in `state/memory`, by the same path ([`Engine::resume`]).

use std::sync::Arc;

use petrel_actors::expr::{Clock, Value};
use serde::{Deserialize, Serialize};

use super::effects::Applied;
use super::{Action, Engine};

/// An engine's switches and applied effects. Times are in clock seconds
/// ([`Clock::secs_of`]), the clock the manager runs its conditions on.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct EngineMemory {
    /// The active contexts, highest priority first, each with when it switched on.
    pub active: Vec<(Arc<str>, f64)>,
    /// Values written, by target property.
    pub values: Vec<SavedEffect<Value>>,
    /// Inputs relinked, with their new source.
    pub links: Vec<SavedEffect<Arc<str>>>,
    /// Modules started (`true`) or stopped.
    pub runs: Vec<SavedEffect<bool>>,
}

/// One applied effect: on `target`, `value`, by `context`; `sticky` ones outlive it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[allow(missing_docs)]
pub struct SavedEffect<V> {
    pub target: Arc<str>,
    pub context: Arc<str>,
    pub value: V,
    pub sticky: bool,
}

impl<V: Clone> SavedEffect<V> {
    pub(super) fn of(target: &Arc<str>, applied: &Applied<V>) -> Self {
        SavedEffect {
            target: target.clone(),
            context: applied.context.clone(),
            value: applied.value.clone(),
            sticky: applied.sticky,
        }
    }

    pub(super) fn applied(&self) -> Applied<V> {
        Applied {
            context: self.context.clone(),
            value: self.value.clone(),
            sticky: self.sticky,
        }
    }
}

impl Engine {
    /// Writes what this engine has switched on and applied into `memory` (its vectors are
    /// reused).
    pub fn save_into(&self, memory: &mut EngineMemory) {
        memory.active.clear();
        memory.active.extend(self.active.iter().map(|&i| {
            let rule = &self.rules[i];
            (rule.name.clone(), rule.since.map_or(0.0, Clock::secs_of))
        }));
        self.values.save_into(&mut memory.values);
        self.links.save_into(&mut memory.links);
        self.runs.save_into(&mut memory.runs);
    }

    /// Takes over what `memory` says was switched on and applied (a restart, or a reload),
    /// so that only the difference is applied: contexts kept by name stay active (no second
    /// activation), contexts no longer in the rules are reported deactivated, and what was
    /// applied is resolved against these rules at the next step (restoring what removed rules
    /// changed, and what contexts that ended meanwhile changed).
    pub fn resume(&mut self, memory: &EngineMemory) {
        for (name, since) in &memory.active {
            match self.rules.iter_mut().find(|r| r.name == *name) {
                Some(rule) => {
                    rule.active = true;
                    rule.since = Some(Clock::instant(*since));
                }
                None => self.pending.push(Action::Deactivated(name.clone())),
            }
        }
        self.active = (0..self.rules.len())
            .filter(|&i| self.rules[i].active)
            .collect();
        self.sort_active();
        self.values.resume(&memory.values);
        self.links.resume(&memory.links);
        self.runs.resume(&memory.runs);
        self.resolve = true;
    }
}
