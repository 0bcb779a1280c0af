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
