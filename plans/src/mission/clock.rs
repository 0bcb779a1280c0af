//! The mission's clock: the agent's time, which is simulated time when a simulator drives the
//! agent (`in/clock` linked to its `out/simTime`), wall time otherwise.
//!
//! Expressions run on tokio [`Instant`]s; a clock reading in seconds maps to the instant
//! `base() + seconds`, so `held`, `age`, `elapsed` and deadlines all count clock seconds. Start
//! times are kept as clock seconds (numbers survive a restart and a snapshot; instants do not).

use std::sync::OnceLock;
use std::time::Duration;

use petrel_actors::AnyHandle;
use tokio::time::Instant;

/// The instant clock seconds count from: the first time any mission read a clock in this
/// process (wall-clock seconds are thus shared by every mission of the process, and by a
/// restarted mission module).
fn base() -> Instant {
    static BASE: OnceLock<Instant> = OnceLock::new();
    *BASE.get_or_init(Instant::now)
}

/// Where a mission reads the time.
pub(crate) enum Clock {
    /// Wall time (tokio's clock, so a paused test clock drives it).
    Wall,
    /// Seconds read from a number property, e.g. a simulator's `out/simTime`.
    Property(AnyHandle),
}

impl Clock {
    /// The time now, in clock seconds; `step_now` is the module step's time (wall clock).
    pub fn secs(&self, step_now: Instant) -> f64 {
        match self {
            Clock::Wall => step_now.saturating_duration_since(base()).as_secs_f64(),
            Clock::Property(h) => h.get::<f64>().map_or(0.0, |v| *v),
        }
    }

    /// The instant standing for clock seconds `secs`.
    pub fn instant(secs: f64) -> Instant {
        let secs = if secs.is_finite() { secs.max(0.0) } else { 0.0 };
        base() + Duration::from_secs_f64(secs)
    }

    /// Clock seconds of an instant made by [`Clock::instant`].
    pub fn secs_of(t: Instant) -> f64 {
        t.saturating_duration_since(base()).as_secs_f64()
    }

    /// Whether the clock is wall time, so that deadlines can be slept for.
    pub fn is_wall(&self) -> bool {
        matches!(self, Clock::Wall)
    }

    /// The property read, if any (so the mission steps when it changes).
    pub fn handle(&self) -> Option<&AnyHandle> {
        match self {
            Clock::Wall => None,
            Clock::Property(h) => Some(h),
        }
    }
}
