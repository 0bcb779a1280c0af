//! A short spin of an agent's thread before it parks, while work comes back quickly.
//!
//! Why: on a VM an idle vCPU that a wake-up reaches from another thread (a tool's request, a
//! team's import, a benchmark's driver) takes tens of µs to run again. An agent answering
//! requests that come back within microseconds would park and be woken for each; spinning a
//! few µs first catches the next request awake, for half the cost of a message sent into the
//! agent (BENCHMARKS.md, session 21).
//!
//! The CPU a spin may take is bounded twice:
//! - [`SpinPolicy`], a pure function of what the last parks did: a thread that slept long last
//!   time (an idle agent, a periodic module) parks at once, and a spin that caught nothing
//!   makes the thread skip spinning for twice as many parks as the one before (up to
//!   [`MAX_SKIP`]), so work that comes back just too late to be caught costs a spin in every
//!   65 parks at most;
//! - the spin yields the CPU at each turn and ends as soon as another thread took it: on a
//!   loaded machine (many processes on few cores) it gives way instead of taking time from
//!   them, and counts as a miss. (Under `realtime_priority` a yield gives way only to threads
//!   of the same priority; the backoff still bounds the spin.)
//!
//! A timer of the agent's own runtime that falls due during a spin fires when it ends, at most
//! [`SPIN`] late; periodic modules tick from the fine timer's thread, whose wake-ups a spin
//! catches at once.

use std::cell::{Cell, RefCell};
use std::time::{Duration, Instant};

/// How long the thread looks for work before it parks.
const SPIN: Duration = Duration::from_micros(30);
/// A park shorter than this counts as a quick wake-up: the next park may spin first.
const QUICK: Duration = Duration::from_micros(200);
/// A turn of the spin longer than this means another thread had the CPU: the spin ends.
const CONTENDED: Duration = Duration::from_micros(10);
/// The most parks skipped without spinning after spins that caught nothing.
const MAX_SKIP: u32 = 64;

/// Whether to spin before the next park, from what the last ones did (the functional core;
/// the hooks below are its shell).
#[derive(Debug, Default, Clone)]
pub(crate) struct SpinPolicy {
    /// The last wake-up came quickly, or the last spin caught work.
    quick: bool,
    /// Parks left to skip before the next spin.
    skip: u32,
    /// Parks skipped after the last spin that caught nothing: doubled at each miss.
    backoff: u32,
}

impl SpinPolicy {
    /// Whether this park should spin first (a skipped park counts down the backoff).
    pub fn should_spin(&mut self) -> bool {
        if !self.quick {
            return false;
        }
        if self.skip > 0 {
            self.skip -= 1;
            return false;
        }
        true
    }

    /// The outcome of a spin: `caught` when work came before it ended.
    pub fn spun(&mut self, caught: bool) {
        if caught {
            self.backoff = 0;
        } else {
            self.backoff = (self.backoff * 2).clamp(1, MAX_SKIP);
            self.skip = self.backoff;
        }
        self.quick = caught;
    }

    /// The thread parked for `parked` (after any spin) and was woken.
    pub fn woke(&mut self, parked: Duration) {
        self.quick = parked < QUICK;
    }
}

thread_local! {
    static POLICY: RefCell<SpinPolicy> = RefCell::new(SpinPolicy::default());
    static PARKED_AT: Cell<Option<Instant>> = const { Cell::new(None) };
}

/// The runtime's `on_thread_park` hook: spins while the policy says so and no task was woken
/// from another thread; a spin that caught work leaves the thread awake (tokio's park then
/// returns at once, as the waker's unpark is already pending).
pub(crate) fn before_park() {
    if POLICY.with_borrow_mut(SpinPolicy::should_spin) {
        let caught = spin();
        POLICY.with_borrow_mut(|p| p.spun(caught));
        if caught {
            return;
        }
    }
    PARKED_AT.set(Some(Instant::now()));
}

/// Looks for a task woken from another thread for up to [`SPIN`]; true when one came.
///
/// Each turn yields the CPU: on an idle CPU the yield returns at once, and on a loaded one it
/// lets another thread run, after which the spin ends (its time would come out of other work,
/// and a parked thread is woken sooner than a yielded one is run again).
fn spin() -> bool {
    // tokio runs the hook inside the runtime's context; without one there is nothing to watch.
    let Ok(handle) = tokio::runtime::Handle::try_current() else {
        return false;
    };
    let metrics = handle.metrics();
    let start = Instant::now();
    let mut last = start;
    loop {
        if metrics.global_queue_depth() > 0 {
            return true;
        }
        let now = Instant::now();
        if now - start >= SPIN || now - last >= CONTENDED {
            return false;
        }
        last = now;
        std::thread::yield_now();
    }
}

/// The runtime's `on_thread_unpark` hook: tells the policy how long the thread slept.
pub(crate) fn after_unpark() {
    if let Some(at) = PARKED_AT.take() {
        let parked = at.elapsed();
        POLICY.with_borrow_mut(|p| p.woke(parked));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quick() -> SpinPolicy {
        let mut p = SpinPolicy::default();
        p.woke(Duration::from_micros(10));
        p
    }

    #[test]
    fn a_thread_that_slept_long_parks_at_once() {
        let mut p = SpinPolicy::default();
        assert!(!p.should_spin(), "a fresh thread has no quick wake-up yet");
        p.woke(QUICK);
        assert!(!p.should_spin());
        p.woke(QUICK - Duration::from_micros(1));
        assert!(p.should_spin());
    }

    #[test]
    fn spins_go_on_while_they_catch_work() {
        let mut p = quick();
        for _ in 0..1000 {
            assert!(p.should_spin());
            p.spun(true);
        }
    }

    #[test]
    fn misses_double_the_parks_skipped_up_to_the_bound() {
        let mut p = quick();
        let mut skipped = Vec::new();
        let mut spins = 0;
        // Work always comes back just after the spin ends: every spin misses, every park is
        // quick. Count the parks skipped between spins.
        let mut run = 0;
        for _ in 0..2000 {
            if p.should_spin() {
                spins += 1;
                skipped.push(run);
                run = 0;
                p.spun(false);
            } else {
                run += 1;
            }
            p.woke(Duration::from_micros(20));
        }
        assert_eq!(&skipped[..9], &[0, 1, 2, 4, 8, 16, 32, 64, 64]);
        // Bounded: one spin in every MAX_SKIP + 1 parks once backed off.
        assert!(spins <= 2000 / (MAX_SKIP as usize + 1) + 8, "{spins} spins");
    }

    #[test]
    fn a_catch_after_misses_resets_the_backoff() {
        let mut p = quick();
        for _ in 0..5 {
            while !p.should_spin() {
                p.woke(Duration::from_micros(20));
            }
            p.spun(false);
        }
        while !p.should_spin() {
            p.woke(Duration::from_micros(20));
        }
        p.spun(true);
        assert!(p.should_spin(), "no skip after a catch");
        p.spun(false);
        p.woke(Duration::from_micros(20));
        assert!(
            !p.should_spin(),
            "the first miss after a catch skips one park"
        );
        p.woke(Duration::from_micros(20));
        assert!(p.should_spin());
    }

    #[test]
    fn a_long_sleep_stops_spinning_even_when_spins_caught_work() {
        let mut p = quick();
        assert!(p.should_spin());
        p.spun(false);
        p.woke(Duration::from_millis(5));
        for _ in 0..10 {
            assert!(!p.should_spin());
        }
    }
}
