//! The `mission.pnp` module driving demo modules, on tokio's paused clock; and the shipped
//! mission demo run by the real binary.

mod bindings;
#[path = "../common/bounded.rs"]
mod bounded;
mod cli;
mod execution;
mod guide;
mod patrol;
mod reaction;
mod resilience;
mod support;
mod time;
