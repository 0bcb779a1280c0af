//! The agent's clock for expressions: simulated time when a simulator drives the agent (an
//! `in/clock` input linked to its `out/simTime`), wall time otherwise. Missions and context
//! managers read it the same way, so their `held`, `age` and timeouts agree.
//!
//! Expressions run on tokio [`Instant`]s; a clock reading in seconds maps to the instant
//! `base() + seconds`, so `held`, `age`, `elapsed` and deadlines all count clock seconds. Start
//! times are kept as clock seconds (numbers survive a restart and a snapshot; instants do not).

use std::sync::OnceLock;
use std::time::Duration;

use crate::AnyHandle;
use tokio::time::Instant;

/// The instant clock seconds count from: the first time any clock was read in this process
/// (wall-clock seconds are thus shared by every module of the process, and by a restarted
/// module).
fn base() -> Instant {
    static BASE: OnceLock<Instant> = OnceLock::new();
    *BASE.get_or_init(Instant::now)
}

/// Where a module evaluating expressions reads the time.
pub enum Clock {
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

    /// The time now as an instant: the step's time on wall time (exactly), the instant of the
    /// clock's seconds otherwise.
    pub fn now(&self, step_now: Instant) -> Instant {
        match self {
            Clock::Wall => step_now,
            Clock::Property(_) => Clock::instant(self.secs(step_now)),
        }
    }

    /// The instant standing for clock seconds `secs`.
    pub fn instant(secs: f64) -> Instant {
        // An instant cannot hold any number: beyond some 30,000 years (a clock property gone
        // wild, `1e300`), time stands at that limit rather than overflowing.
        const MAX_SECS: f64 = 1e12;
        let secs = if secs.is_finite() {
            secs.clamp(0.0, MAX_SECS)
        } else {
            0.0
        };
        base() + Duration::from_secs_f64(secs)
    }

    /// Clock seconds of an instant made by [`Clock::instant`].
    pub fn secs_of(t: Instant) -> f64 {
        t.saturating_duration_since(base()).as_secs_f64()
    }

    /// The clock of module `module`: the property its `in/clock` input is linked to, or wall
    /// time when it is not linked.
    pub async fn of_module(bb: &crate::Blackboard, module: &str) -> Clock {
        let path = format!("{module}/in/clock");
        match bb.link_of(&path).await {
            Ok(Some(_)) => match bb.any_handle(&path).await {
                Ok(h) => Clock::Property(h),
                Err(_) => Clock::Wall,
            },
            _ => Clock::Wall,
        }
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
