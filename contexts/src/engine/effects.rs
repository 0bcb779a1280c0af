//! One kind of effect (values, links or running states) over its targets: what is applied to
//! each target, what the active contexts want, and the actions that take one to the other.
//!
//! Targets are numbered when the rules are built (in name order, so actions come out sorted by
//! target), and a step works on flat per-target slots: resolving the effects of a context switch
//! allocates nothing but the actions themselves.

use std::collections::HashMap;
use std::sync::Arc;

use super::memory::{fill_in_place, SavedEffect};
use super::Action;

/// An effect: the context responsible, the value, and whether it outlives its context.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Applied<V> {
    pub context: Arc<str>,
    pub value: V,
    pub sticky: bool,
}

/// How an effect kind turns into actions.
pub(super) struct Actions<V> {
    pub apply: fn(Arc<str>, &Applied<V>) -> Action,
    pub restore: fn(Arc<str>) -> Action,
    pub release: fn(Arc<str>) -> Action,
}

/// The targets of one effect kind and their applied and wanted effects, by target number.
pub(super) struct Effects<V> {
    targets: Vec<Arc<str>>,
    applied: Vec<Option<Applied<V>>>,
    /// Scratch for one resolution: what the active contexts want, per target.
    wanted: Vec<Option<Applied<V>>>,
}

impl<V: Clone + PartialEq> Effects<V> {
    /// A table over `targets` (sorted and deduplicated here); returns it with each name's number.
    pub fn new(mut targets: Vec<Arc<str>>) -> (Self, HashMap<Arc<str>, usize>) {
        targets.sort();
        targets.dedup();
        let numbers = targets
            .iter()
            .enumerate()
            .map(|(i, t)| (t.clone(), i))
            .collect();
        let n = targets.len();
        let table = Effects {
            targets,
            applied: vec![None; n],
            wanted: vec![None; n],
        };
        (table, numbers)
    }

    /// Writes what is applied, in target order, into `out`.
    pub fn save_into(&self, out: &mut Vec<SavedEffect<V>>) {
        let applied = (self.targets.iter().zip(&self.applied))
            .filter_map(|(name, applied)| Some((name, applied.as_ref()?)));
        fill_in_place(
            out,
            applied,
            |saved, (name, applied)| saved.is(name, applied),
            |_, _| {},
            |(name, applied)| SavedEffect::of(name, applied),
        );
    }

    /// Takes over what was applied (a reload or a restart); targets these rules do not
    /// mention are kept at the end so the next resolution restores them.
    pub fn resume(&mut self, saved: &[SavedEffect<V>]) {
        for effect in saved {
            let t = match self.targets.iter().position(|t| *t == effect.target) {
                Some(t) => t,
                None => {
                    self.targets.push(effect.target.clone());
                    self.applied.push(None);
                    self.wanted.push(None);
                    self.targets.len() - 1
                }
            };
            self.applied[t] = Some(effect.applied());
        }
    }

    /// Forgets what the last resolution wanted.
    pub fn clear_wanted(&mut self) {
        self.wanted.fill(None);
    }

    /// Context `context` wants `value` on target `t`; contexts are offered highest priority
    /// first, so the first one to want a target gets it.
    pub fn want(&mut self, t: usize, context: &Arc<str>, value: &V, sticky: bool) {
        let slot = &mut self.wanted[t];
        if slot.is_none() {
            *slot = Some(Applied {
                context: context.clone(),
                value: value.clone(),
                sticky,
            });
        }
    }

    /// Pushes the actions that take what is applied to what is wanted: first the targets no
    /// context wants any more (restored, or released if sticky), then the changed ones, each
    /// in target order.
    pub fn reconcile(&mut self, actions: &mut Vec<Action>, kind: &Actions<V>) {
        for t in 0..self.targets.len() {
            if self.wanted[t].is_none() {
                if let Some(was) = self.applied[t].take() {
                    let name = self.targets[t].clone();
                    actions.push(match was.sticky {
                        true => (kind.release)(name),
                        false => (kind.restore)(name),
                    });
                }
            }
        }
        for t in 0..self.targets.len() {
            if let Some(want) = self.wanted[t].take() {
                if self.applied[t].as_ref() != Some(&want) {
                    actions.push((kind.apply)(self.targets[t].clone(), &want));
                    self.applied[t] = Some(want);
                }
            }
        }
    }
}
