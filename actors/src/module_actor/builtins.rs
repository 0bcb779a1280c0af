//! What the runtime keeps about every module: its `enabled`, `control/fault` and `stats/...`
//! properties, the status values, and the step figures behind the stats.

use std::time::Duration;

use tokio::time::Instant;

use crate::handle::Output;
use crate::ports::{Ports, PropertyKind};

/// Stats are published at most this often (and at every status change), to keep steps cheap.
const STATS_INTERVAL: Duration = Duration::from_millis(100);

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
        fault: ports.builtin(
            PropertyKind::Control,
            "control/fault",
            String::new(),
            "write panic, error or hang to make the next step fail (fault injection)",
        ),
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

/// Running step-time and interval figures, kept locally and published now and then.
#[derive(Default)]
pub(crate) struct StepStats {
    count: u64,
    total: Duration,
    pub last: Duration,
    first_start: Option<Instant>,
    last_start: Option<Instant>,
    pub published: Option<Instant>,
}

impl StepStats {
    /// Records a step; true when the stats are due for publishing.
    pub fn record(&mut self, started: Instant, took: Duration) -> bool {
        self.count += 1;
        self.total += took;
        self.last = took;
        self.first_start.get_or_insert(started);
        self.last_start = Some(started);
        self.published
            .is_none_or(|p| started.duration_since(p) >= STATS_INTERVAL)
    }

    pub fn mean_step_us(&self) -> f64 {
        if self.count == 0 {
            return 0.0;
        }
        self.total.as_secs_f64() * 1e6 / self.count as f64
    }

    pub fn mean_interval_ms(&self) -> f64 {
        match (self.first_start, self.last_start) {
            (Some(a), Some(b)) if self.count > 1 => {
                b.duration_since(a).as_secs_f64() * 1e3 / (self.count - 1) as f64
            }
            _ => 0.0,
        }
    }
}
