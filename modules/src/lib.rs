//! Built-in petrel functional modules.
//!
//! [`sim`] and [`nav`] are the pure, deterministic cores of the simulator and the navigation
//! modules: plain structs with `step`-style methods, no actors and no async; [`robot`] wraps
//! them as runtime modules (`sim.world`, `nav.localizer`, ...); [`vision`] holds the victim
//! detector and mapper cores.
#![warn(missing_docs)]

pub mod demo;
pub mod nav;
pub mod robot;
pub mod seeded;
pub mod sim;
pub mod vision;

use petrel_actors::ModuleRegistry;

/// A registry holding every built-in module type.
pub fn builtin() -> ModuleRegistry {
    let mut registry = ModuleRegistry::new();
    register(&mut registry);
    registry
}

/// Adds every built-in module type to `registry`.
pub fn register(registry: &mut ModuleRegistry) {
    demo::register(registry);
    robot::register(registry);
}

/// Test helpers shared by the cores' unit tests.
#[cfg(test)]
mod test_support {
    /// `value` written as RON and read back through RON's dynamic values, as a snapshot (and
    /// a restarted module's `state/`) reads it.
    pub(crate) fn through_ron_values<T>(value: &T) -> T
    where
        T: serde::Serialize + serde::de::DeserializeOwned,
    {
        let text = ron::to_string(value).unwrap();
        ron::from_str::<ron::Value>(&text)
            .unwrap()
            .into_rust()
            .unwrap()
    }
}
