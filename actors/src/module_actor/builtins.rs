//! What the runtime keeps about every module: its `enabled`, `control/fault` and `stats/...`
//! properties and the status values.

use crate::handle::Output;
use crate::ports::{Ports, PropertyKind};

/// Module status values, as published in `stats/status`.
pub mod status {
    /// Declared, running `init`.
    pub const INITIALIZING: &str = "initializing";
    /// Waiting for events and stepping.
    pub const RUNNING: &str = "running";
    /// `enabled` is false: not stepping.
    pub const DISABLED: &str = "disabled";
    /// Ended by a panic, an error or a hang.
    pub const FAILED: &str = "failed";
    /// Failed, waiting for the supervisor to start it again.
    pub const RESTARTING: &str = "restarting";
    /// Stopped on request.
    pub const STOPPED: &str = "stopped";
    /// Did not stop within its stop timeout: killed (a step that never yields keeps its
    /// thread until the process ends).
    pub const KILLED: &str = "killed";
}

/// The runtime-owned properties every module has.
pub(crate) struct Builtins {
    pub enabled: Output<bool>,
    pub fault: Output<String>,
    pub status: Output<String>,
    pub steps: Output<i64>,
    pub last_step_us: Output<f64>,
    pub mean_step_us: Output<f64>,
    pub mean_interval_ms: Output<f64>,
}

/// What `control/fault` takes ("" once the fault is taken).
pub(crate) const FAULTS: &[&str] = &["", "panic", "error", "hang", "spin", "block"];

pub(crate) fn declare_builtins(ports: &mut Ports) -> Builtins {
    use PropertyKind::{Enabled, Stats};
    // Written by the supervisor, declared here so that every module has it.
    ports.builtin(
        Stats,
        "stats/restarts",
        0_i64,
        "times the supervisor restarted this module",
    );
    ports.builtin(
        Stats,
        "stats/failures",
        0_i64,
        "failures (panics, errors, hangs) of this module",
    );
    Builtins {
        enabled: ports.builtin(Enabled, "enabled", true, "whether the module steps"),
        fault: {
            let fault = ports.builtin(
                PropertyKind::Control,
                "control/fault",
                String::new(),
                "write panic, error or hang to make the next step fail, spin or block to make it never return (fault injection)",
            );
            // Anything else was ignored with a warning in the agent's log, the writer told ok.
            ports.check_last(crate::range::RangeCheck::one_of(FAULTS));
            fault
        },
        status: ports.builtin(
            Stats,
            "stats/status",
            status::INITIALIZING.to_string(),
            "initializing, running, disabled, failed or stopped",
        ),
        steps: ports.builtin(
            Stats,
            "stats/steps",
            0_i64,
            "steps run since the agent started",
        ),
        last_step_us: ports.builtin(
            Stats,
            "stats/last_step_us",
            0.0,
            "duration of the last step, µs",
        ),
        mean_step_us: ports.builtin(Stats, "stats/mean_step_us", 0.0, "mean step duration, µs"),
        mean_interval_ms: ports.builtin(
            Stats,
            "stats/mean_interval_ms",
            0.0,
            "mean time between step starts, ms",
        ),
    }
}
