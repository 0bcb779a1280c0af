//! A module's step time: read from the clock at most once per step and shared by everything
//! the step does — [`Context::now`](crate::Context::now) and the time stamps of the values and
//! queue items it writes.
//!
//! Why: a clock read costs tens of nanoseconds, as much as a third of a module-to-module hop
//! (`property_wake`); and one time per step makes stamps deterministic for a given schedule
//! (a replay does not depend on how long computing took). Outside a step (in `init`, in tasks a
//! module spawns) every call reads the clock.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;
use std::time::Duration;

use tokio::time::Instant;

/// Not in a step: every read is a clock read.
const IDLE: u64 = 0;
/// In a step whose time has not been read yet.
const UNREAD: u64 = 1;
/// Cached times are stored as nanoseconds since [`base`] plus this.
const OFFSET: u64 = 2;

/// The reference cached times are counted from: the first time any step clock was used.
fn base() -> Instant {
    static BASE: OnceLock<Instant> = OnceLock::new();
    *BASE.get_or_init(Instant::now)
}

/// The step time of one module, shared by its context and its output handles.
#[derive(Debug, Default)]
pub(crate) struct StepClock {
    state: AtomicU64,
}

impl StepClock {
    /// A step begins; its time is read when first needed.
    pub fn begin(&self) {
        self.state.store(UNREAD, Ordering::Relaxed);
    }

    /// A step begins at `now` (already read by the caller).
    pub fn begin_at(&self, now: Instant) {
        self.state.store(encode(now), Ordering::Relaxed);
    }

    /// The step is over: reads go to the clock again.
    pub fn end(&self) {
        self.state.store(IDLE, Ordering::Relaxed);
    }

    /// The current step's time (read now if it was not yet), or the clock outside steps.
    #[inline]
    pub fn now(&self) -> Instant {
        match self.state.load(Ordering::Relaxed) {
            IDLE => Instant::now(),
            UNREAD => {
                let now = Instant::now();
                // A step that ended meanwhile (its handle used from another task) stays ended.
                let _ = self.state.compare_exchange(
                    UNREAD,
                    encode(now),
                    Ordering::Relaxed,
                    Ordering::Relaxed,
                );
                now
            }
            cached => base() + Duration::from_nanos(cached - OFFSET),
        }
    }
}

/// `now` as a cached state; a time before the base (possible with paused test clocks in several
/// runtimes) or beyond 584 years after it is not cached.
fn encode(now: Instant) -> u64 {
    now.checked_duration_since(base())
        .and_then(|d| u64::try_from(d.as_nanos()).ok())
        .and_then(|n| n.checked_add(OFFSET))
        .unwrap_or(UNREAD)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test(start_paused = true)]
    async fn a_step_reads_the_clock_once_and_idle_reads_follow_it() {
        let clock = StepClock::default();
        clock.begin();
        let first = clock.now();
        tokio::time::advance(Duration::from_millis(5)).await;
        assert_eq!(clock.now(), first, "the step's time is read once");
        clock.end();
        assert_eq!(
            clock.now(),
            first + Duration::from_millis(5),
            "idle: the clock"
        );
        let at = Instant::now();
        clock.begin_at(at);
        tokio::time::advance(Duration::from_millis(5)).await;
        assert_eq!(clock.now(), at);
    }
}
