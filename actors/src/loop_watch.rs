//! Finding modules that re-trigger themselves without progress.
//!
//! Every step carries a *hop count*: how many steps in a row led to it through writes, with no
//! tick, timeout or outside write in between. A write made by a step of hop count `h` wakes its
//! readers with `h + 1`; a step woken by time starts again at 0. A chain of modules reaches its
//! length and stops; a cycle (a module linked to its own output, two modules feeding each other,
//! a context rule whose change undoes its own condition, a plan firing in a circle) climbs
//! without end. Past [`LOOP_HOPS`] the module is reported, then again at most every
//! [`REPORT_EVERY`] while it goes on, so a runaway loop costs one log line, not one per step.
//!
//! The count travels in a thread-local set around each poll of a step (steps are async, and a
//! task may move between threads between polls) and in the module's
//! [`Signal`](crate::cell::Signal).

use std::cell::Cell;
use std::time::{Duration, Instant};

/// Hops after which a chain of steps counts as a loop. A real pipeline is tens of modules
/// long; a loop on the CPU passes this in a few milliseconds.
pub(crate) const LOOP_HOPS: u32 = 1_000;

/// The least time between two reports of the same module's loop.
pub(crate) const REPORT_EVERY: Duration = Duration::from_secs(10);

/// What a write passes on to the modules it wakes: the writing step's hop count and the id of
/// the writing module's signal, packed so that one atomic maximum keeps the longest chain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Hop {
    /// Steps in a row that led here.
    pub hops: u32,
    /// The [`Signal`](crate::cell::Signal) id of the module whose write it was.
    pub waker: u32,
}

impl Hop {
    /// Packs the hop, the count in the high half so that comparing packed values compares counts.
    pub fn pack(self) -> u64 {
        (u64::from(self.hops) << 32) | u64::from(self.waker)
    }

    pub fn unpack(packed: u64) -> Self {
        Hop {
            hops: (packed >> 32) as u32,
            waker: packed as u32,
        }
    }
}

thread_local! {
    /// The hop of the step being polled on this thread. A plain thread-local set around each
    /// poll rather than a task-local: the step is polled in place, so the two are the same,
    /// and a task-local's scope cost a few percent of a hand-over between modules.
    static STEP: Cell<Option<Hop>> = const { Cell::new(None) };
}

/// The hop the writes of the step being polled on this thread pass on, or `None` outside any
/// step.
pub(crate) fn current() -> Option<Hop> {
    STEP.with(Cell::get)
}

/// Runs `step` (of the module whose signal is `me`, `hops` steps down a chain) with that hop
/// current during each of its polls.
#[cfg(test)]
pub(crate) async fn in_step<F: std::future::Future>(hops: u32, me: u32, step: F) -> F::Output {
    let mut step = std::pin::pin!(step);
    std::future::poll_fn(|cx| in_poll(hops, me, || step.as_mut().poll(cx))).await
}

/// Runs `poll` (one poll of the step of the module whose signal is `me`, `hops` steps down a
/// chain) with that hop current: for a step future polled in place rather than wrapped. What
/// was current before comes back afterwards, also when `poll` panics.
#[inline]
pub(crate) fn in_poll<R>(hops: u32, me: u32, poll: impl FnOnce() -> R) -> R {
    struct Restore(Option<Hop>);
    impl Drop for Restore {
        #[inline]
        fn drop(&mut self) {
            STEP.with(|s| s.set(self.0));
        }
    }
    let _restore = Restore(STEP.with(|s| s.replace(Some(Hop { hops, waker: me }))));
    poll()
}

/// One module's loop state: when it was last reported, and how many looping steps since.
#[derive(Debug, Default)]
pub(crate) struct LoopWatch {
    /// When the next report may come (a deadline rather than the last report's time: a
    /// comparison at each looping step, not a subtraction).
    next_report: Option<Instant>,
    looping_steps: u64,
}

impl LoopWatch {
    /// Notes a step of `hops`; returns the number of looping steps to report, when a report is due.
    /// The clock (`now`) is read only for a step that may be looping: most are not, and a clock
    /// read costs a fair part of a hand-over between modules.
    pub fn observe(&mut self, hops: u32, now: impl FnOnce() -> Instant) -> Option<u64> {
        if hops < LOOP_HOPS {
            return None;
        }
        let now = now();
        self.looping_steps += 1;
        let due = self.next_report.is_none_or(|next| now >= next);
        due.then(|| {
            self.next_report = now.checked_add(REPORT_EVERY);
            std::mem::take(&mut self.looping_steps)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chain_shorter_than_the_limit_is_never_reported() {
        let mut watch = LoopWatch::default();
        let now = Instant::now();
        assert!((0..LOOP_HOPS).all(|h| watch.observe(h, || now).is_none()));
    }

    #[test]
    fn a_loop_is_reported_once_then_at_most_every_ten_seconds_with_the_steps_between() {
        let mut watch = LoopWatch::default();
        let t0 = Instant::now();
        assert_eq!(watch.observe(LOOP_HOPS, || t0), Some(1));
        for i in 1..=1000 {
            let at = t0 + Duration::from_millis(i);
            assert_eq!(watch.observe(LOOP_HOPS + i as u32, || at), None);
        }
        assert_eq!(watch.observe(u32::MAX, || t0 + REPORT_EVERY), Some(1001));
        assert_eq!(watch.observe(u32::MAX, || t0 + REPORT_EVERY), None);
    }

    #[tokio::test]
    async fn the_hop_is_seen_inside_its_step_only() {
        assert_eq!(current(), None);
        let inside = in_step(7, 3, async {
            tokio::task::yield_now().await;
            current()
        })
        .await;
        assert_eq!(inside, Some(Hop { hops: 7, waker: 3 }));
        assert_eq!(current(), None);
    }

    #[test]
    fn the_hop_before_a_poll_comes_back_after_it_even_when_it_panics() {
        let inner = in_poll(1, 2, || in_poll(5, 6, current));
        assert_eq!(inner, Some(Hop { hops: 5, waker: 6 }));
        let outer = in_poll(1, 2, || {
            let _ = std::panic::catch_unwind(|| in_poll(5, 6, || panic!("a step panics")));
            current()
        });
        assert_eq!(outer, Some(Hop { hops: 1, waker: 2 }));
        assert_eq!(current(), None);
    }

    #[test]
    fn packed_hops_compare_by_count_first() {
        let short = Hop {
            hops: 2,
            waker: u32::MAX,
        };
        let long = Hop { hops: 3, waker: 0 };
        assert!(long.pack() > short.pack());
        assert_eq!(Hop::unpack(short.pack()), short);
    }
}
