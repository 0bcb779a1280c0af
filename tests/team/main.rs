//! Teams over real zenoh sessions on loopback: agents in one process, each with its own
//! session and its own free port. Waits are on property changes with deadlines, never sleeps.

#[path = "../common/bounded.rs"]
mod bounded;
mod cli;
mod links;
mod mail;
mod membership;
mod partition;
mod plans;
#[path = "../common/ports.rs"]
mod ports;
mod processes;
mod python;
mod rescue_team;
mod rogue;
mod router;
mod scale;
mod scaling_plot;
mod support;
mod team_scaling;
mod tools;
mod writes;
