//! The context subsystem: rules that watch properties, decide which contexts hold, and adapt
//! other modules' parameters, links and running state — while those modules know nothing of it.
//!
//! * [`rules`]: the RON rules file and its locations;
//! * [`engine`]: the pure engine (hysteresis, dwell, priorities, restore on exit, sticky);
//! * [`ContextManager`]: the `context.manager` module that runs an engine in an agent.
#![warn(missing_docs)]

pub mod engine;
pub mod lint;
mod manager;
pub mod rules;

pub use engine::{Action, Engine, EngineMemory, SavedEffect, Schema};
pub use manager::{check_rules, ContextChange, ContextManager, ContextMemory};
pub use rules::{ContextRule, LoadedRules, RuleError, RulesFile};

/// Registers the `context.manager` module type.
pub fn register(registry: &mut petrel_actors::ModuleRegistry) {
    registry.register::<ContextManager>();
}
