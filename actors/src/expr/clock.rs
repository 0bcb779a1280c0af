//! The agent's clock for expressions: simulated time when a simulator drives the agent (an
//! `in/clock` input linked to its `out/simTime`), wall time otherwise. Missions and context
//! managers read it the same way, so their `held`, `age` and timeouts agree.
//!
//! Expressions run on tokio [`Instant`]s; a clock reading in seconds maps to the instant
//! `base() + seconds`, so `held`, `age`, `elapsed` and deadlines all count clock seconds. Start
//! times are kept as clock seconds (numbers survive a restart and a snapshot; instants do not).

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;
use std::time::Duration;

use crate::AnyHandle;
use tokio::time::Instant;

/// The instant clock seconds count from: when the first agent of this process was built, or
/// the first time any clock was read before that (wall-clock seconds are thus shared by every
/// module of the process, and by a restarted module).
fn base() -> Instant {
    static BASE: OnceLock<Instant> = OnceLock::new();
    *BASE.get_or_init(Instant::now)
}

/// Starts this process's wall clock, if nothing read it yet: called when an agent is built,
/// so that the clock counts from the first agent's start even when none of its modules reads
/// the time (a snapshot of such an agent said `clock_s: 0.0` after running for minutes).
pub(crate) fn start_wall_clock() {
    base();
}

/// The most seconds a clock reading stands for (some 30,000 years): beyond, a clock property
/// gone wild (`1e300`) stands at this limit rather than overflowing an instant.
pub const MAX_CLOCK_S: f64 = 1e12;

/// Seconds added to every wall-clock reading of this process (an `f64`'s bits; 0 at first):
/// what [`continue_from`] moved the wall clock forward by.
static OFFSET: AtomicU64 = AtomicU64::new(0);

fn offset() -> f64 {
    f64::from_bits(OFFSET.load(Ordering::Relaxed))
}

/// Moves this process's wall clock forward so that it reads at least `secs` now, never back.
///
/// An agent resumed from a snapshot taken when its clock read `secs` goes on from there: the
/// start times its modules' memories keep in clock seconds (a mission's running actions, a
/// context manager's active contexts) then count the time that passed before the snapshot,
/// where a new process's clock, starting again near 0, made a wait that had run 2 s of 6 wait
/// 6 s more, and a context whose dwell was spent hold on. Property clocks (a simulator's
/// `out/simTime`, kept in its state) are not affected.
pub fn continue_from(secs: f64) {
    let now = Clock::Wall.secs(Instant::now());
    if !(secs.is_finite() && secs > now) {
        return;
    }
    let add = secs - now;
    let _ = OFFSET.fetch_update(Ordering::Relaxed, Ordering::Relaxed, |bits| {
        Some((f64::from_bits(bits) + add).to_bits())
    });
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
            Clock::Wall => step_now.saturating_duration_since(base()).as_secs_f64() + offset(),
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
        let secs = if secs.is_finite() {
            secs.clamp(0.0, MAX_CLOCK_S)
        } else {
            0.0
        };
        // Seconds from before a resume (see `continue_from`) lie before this process's base;
        // an instant before the machine's boot cannot be made, and stands at the base.
        let since_base = secs - offset();
        match since_base >= 0.0 {
            true => base() + Duration::from_secs_f64(since_base),
            false => base()
                .checked_sub(Duration::from_secs_f64(-since_base))
                .unwrap_or_else(base),
        }
    }

    /// Clock seconds of an instant made by [`Clock::instant`].
    pub fn secs_of(t: Instant) -> f64 {
        let base = base();
        match t >= base {
            true => t.duration_since(base).as_secs_f64() + offset(),
            false => offset() - base.duration_since(t).as_secs_f64(),
        }
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
