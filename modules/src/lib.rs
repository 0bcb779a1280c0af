//! Built-in petrel functional modules.
//!
//! [`sim`] and [`nav`] are the pure, deterministic cores of the simulator and the navigation
//! modules: plain structs with `step`-style methods, no actors and no async.

pub mod demo;
pub mod nav;
pub mod sim;
