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

impl<V: Clone + PartialEq> SavedEffect<V> {
    /// Whether this is `applied` on `target` already.
    pub(super) fn is(&self, target: &Arc<str>, applied: &Applied<V>) -> bool {
        same_name(&self.target, target)
            && same_name(&self.context, &applied.context)
            && self.sticky == applied.sticky
            && self.value == applied.value
    }

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
        let active = self.active.iter().map(|&i| &self.rules[i]);
        fill_in_place(
            &mut memory.active,
            active,
            |(name, _), rule| same_name(name, &rule.name),
            |slot, rule| slot.1 = rule.since.map_or(0.0, Clock::secs_of),
            |rule| (rule.name.clone(), rule.since.map_or(0.0, Clock::secs_of)),
        );
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

/// Whether two names are equal, by pointer first: they are usually the same `Arc`, and
/// `Arc<str>`'s `==` compares the text (the standard library's pointer shortcut needs a
/// sized type).
#[inline]
pub(crate) fn same_name(a: &Arc<str>, b: &Arc<str>) -> bool {
    Arc::ptr_eq(a, b) || a == b
}

/// Makes `out` hold one entry per item, in order, changing only what differs: an entry that
/// is `same` as its item is kept (and `refresh`ed), any other is made anew, the rest dropped.
///
/// A manager saves its memory after every switch into the buffer it published two saves
/// ago, which usually holds the very same names: kept, they cost no reference counting,
/// which cost more than the rest of a save.
#[inline]
pub(crate) fn fill_in_place<T, S>(
    out: &mut Vec<T>,
    items: impl IntoIterator<Item = S>,
    same: impl Fn(&T, &S) -> bool,
    refresh: impl Fn(&mut T, &S),
    make: impl Fn(S) -> T,
) {
    let mut n = 0;
    for item in items {
        match out.get_mut(n) {
            Some(slot) if same(slot, &item) => refresh(slot, &item),
            Some(slot) => *slot = make(item),
            None => out.push(make(item)),
        }
        n += 1;
    }
    out.truncate(n);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn filling_in_place_keeps_what_is_the_same_and_remakes_the_rest() {
        let (a, b, c): (Arc<str>, Arc<str>, Arc<str>) = ("a".into(), "b".into(), "c".into());
        let mut out = vec![(a.clone(), 0), (c.clone(), 0), (c.clone(), 0)];
        let fill = |out: &mut Vec<(Arc<str>, i32)>, items: &[(Arc<str>, i32)]| {
            fill_in_place(
                out,
                items,
                |(name, _), (item, _)| same_name(name, item),
                |slot, (_, n)| slot.1 = *n,
                |(item, n)| (item.clone(), *n),
            )
        };
        fill(&mut out, &[(a.clone(), 1), (b.clone(), 2)]);
        assert_eq!(out, [(a.clone(), 1), (b.clone(), 2)]);
        // The kept entry is the same allocation; a name of the same text counts as the same.
        assert!(Arc::ptr_eq(&out[0].0, &a));
        fill(
            &mut out,
            &[(Arc::from("a"), 3), (b.clone(), 4), (c.clone(), 5)],
        );
        assert_eq!(out, [(a.clone(), 3), (b, 4), (c, 5)]);
        assert!(Arc::ptr_eq(&out[0].0, &a));
        fill(&mut out, &[]);
        assert!(out.is_empty());
    }
}
