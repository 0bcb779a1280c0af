//! The properties the contexts set, each with what the manager keeps about it: the value from
//! before (put back when its contexts end), that value's config form for `state/memory`, the
//! handle, and the last value a context set there.
//!
//! A context that switches on and off sets and restores the same targets again and again, so
//! they are kept for the whole run in one small vector in address order, found by the engine's
//! own name (a pointer compare) before any string is compared. Restoring a value keeps its
//! entry: the next switch then allocates nothing, converts nothing and looks nothing up.

use std::sync::Arc;

use petrel_actors::expr::Value;
use petrel_actors::{AnyHandle, AnyValue, TypeInfo};

use crate::engine::to_property;

/// One property the contexts set.
pub(super) struct Target {
    pub address: Arc<str>,
    /// Looked up at the first set; forgotten at a reload.
    pub handle: Option<AnyHandle>,
    /// The value from before the contexts, while one is applied.
    pub original: Option<AnyValue>,
    /// The config form of an original, with the value it was made from (made through RON
    /// text, which costs more than the rest of a save).
    shown: Option<(AnyValue, ron::Value)>,
    /// The last value a context set, as the expression gave it and as stored.
    set: Option<(Value, AnyValue)>,
}

impl Target {
    /// `value` converted for this property; the value set last time if it is the same.
    pub fn convert(&mut self, value: &Value, info: TypeInfo) -> Result<AnyValue, String> {
        if let Some((last, stored)) = &self.set {
            if last == value {
                return Ok(stored.clone());
            }
        }
        let stored = to_property(value, info)?;
        self.set = Some((value.clone(), stored.clone()));
        Ok(stored)
    }
}

/// The targets, in address order (the order `state/memory` lists them in).
#[derive(Default)]
pub(super) struct Targets {
    entries: Vec<Target>,
}

impl Targets {
    /// The entry of `address`, made if there is none.
    pub fn entry(&mut self, address: &Arc<str>) -> &mut Target {
        let at = match self.position(address) {
            Ok(at) => at,
            Err(at) => {
                self.entries.insert(
                    at,
                    Target {
                        address: address.clone(),
                        handle: None,
                        original: None,
                        shown: None,
                        set: None,
                    },
                );
                at
            }
        };
        &mut self.entries[at]
    }

    /// The entry of `address`, if there is one.
    pub fn get_mut(&mut self, address: &Arc<str>) -> Option<&mut Target> {
        let at = self.position(address).ok()?;
        Some(&mut self.entries[at])
    }

    fn position(&self, address: &Arc<str>) -> Result<usize, usize> {
        match self
            .entries
            .iter()
            .position(|e| Arc::ptr_eq(&e.address, address))
        {
            Some(at) => Ok(at),
            None => (self.entries).binary_search_by(|e| (*e.address).cmp(&**address)),
        }
    }

    /// Forgets every handle and the values converted for it (the rules were reloaded: the
    /// properties are looked up again, and may since belong to another module).
    pub fn forget_handles(&mut self) {
        for e in &mut self.entries {
            e.handle = None;
            e.set = None;
        }
    }

    /// Makes the config form of every original that lacks one (by `to_dynamic`); an
    /// original that cannot be converted has none, and is left out of the memory.
    pub fn show(&mut self, to_dynamic: impl Fn(&Arc<str>, &AnyValue) -> Option<ron::Value>) {
        for e in &mut self.entries {
            let Some(original) = &e.original else {
                continue;
            };
            if e.shown
                .as_ref()
                .is_some_and(|(s, _)| Arc::ptr_eq(s, original))
            {
                continue;
            }
            e.shown = to_dynamic(&e.address, original).map(|d| (original.clone(), d));
        }
    }

    /// The originals with their config form (see [`show`](Targets::show)), in address order.
    pub fn shown(&self) -> impl Iterator<Item = (&Arc<str>, &ron::Value)> {
        self.entries.iter().filter_map(|e| {
            let (shown, dynamic) = e.shown.as_ref()?;
            let original = e.original.as_ref()?;
            Arc::ptr_eq(shown, original).then_some((&e.address, dynamic))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_stay_in_address_order_and_are_found_by_any_copy_of_the_name() {
        let mut targets = Targets::default();
        for name in ["b/in/x", "a/in/x", "c/in/x"] {
            targets.entry(&Arc::from(name)).original = Some(Arc::new(1.0));
        }
        let order: Vec<&str> = targets.entries.iter().map(|e| &*e.address).collect();
        assert_eq!(order, ["a/in/x", "b/in/x", "c/in/x"]);
        // Another allocation of the same name finds the same entry.
        let copy: Arc<str> = Arc::from("b/in/x");
        assert!(targets.get_mut(&copy).is_some_and(|e| e.original.is_some()));
        assert!(targets.get_mut(&Arc::from("d/in/x")).is_none());
        targets.entry(&copy).original = None;
        assert_eq!(targets.entries.len(), 3);
    }

    #[test]
    fn an_original_without_a_config_form_is_left_out() {
        let mut targets = Targets::default();
        targets.entry(&Arc::from("a")).original = Some(Arc::new(1.0));
        targets.entry(&Arc::from("b")).original = Some(Arc::new(2.0));
        targets.entry(&Arc::from("c")).original = None;
        targets.show(|name, _| (&**name == "b").then_some(ron::Value::Bool(true)));
        let shown: Vec<&str> = targets.shown().map(|(name, _)| &**name).collect();
        assert_eq!(shown, ["b"]);
        // A new original is shown again, not taken for the old one.
        targets.entry(&Arc::from("b")).original = Some(Arc::new(3.0));
        assert_eq!(targets.shown().count(), 0);
    }
}
