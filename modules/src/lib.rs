//! Built-in petrel functional modules.
#![warn(missing_docs)]

pub mod demo;

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
}
