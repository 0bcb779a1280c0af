//! Team plans (`robot#action`, `robot#condition`), the pure part: what a coordinator and the
//! robots' executors say to each other and what each of them keeps.
//!
//! * [`protocol`]: the messages ([`TeamMsg`]), carried as message bodies between modules
//!   (`out/outbox` → `in/inbox`), in order and at least once;
//! * [`Dispatch`]: the coordinator's side: the plan's calls on other robots' actions become
//!   messages; their answers and conditions come back; a robot that leaves the team fails its
//!   running actions;
//! * [`Serve`]: a robot's side: calls to carry out, answers to send once, conditions to send
//!   to whoever watches them when they change.
//!
//! No clocks, no network, no blackboard: the `mission.pnp` module is the shell.

mod dispatch;
pub mod protocol;
mod serve;

pub use dispatch::{Departure, Dispatch, DispatchMemory};
pub use protocol::{Outgoing, TeamMsg};
pub use serve::Serve;

/// Splits `robot#name` into the robot and the name; `None` without a robot prefix.
pub fn robot_of(full: &str) -> Option<(&str, &str)> {
    full.split_once('#')
}

#[cfg(test)]
mod tests;
