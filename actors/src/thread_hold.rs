//! Which module holds its agent's thread, and for how long (`scheduler: agent_thread`).
//!
//! On an agent's thread every module shares one thread: a step that blocks or computes without
//! yielding holds up every other module of the agent, and the agent's own supervisor with
//! them. The step budget (`supervision/long_steps.rs`) moves a module whose steps are long on
//! average, but only after a window of steps; a module that blocks in its first step, or
//! blocks once for seconds after a thousand short steps, needs something that looks from
//! outside the thread. Each poll of a module's step on the agent's thread writes a word here
//! (which slot, which poll); a watcher on the shared runtime reads it a few times per
//! `held_ms` and, when the same poll is still running after `held_ms`, reports the module at
//! once (a `held` supervisor event, written from the watcher: the supervisor cannot run) and
//! asks the supervisor to move it to the shared runtime when its step returns.

#[cfg(test)]
use std::future::Future;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use ractor::ActorRef;

use crate::supervision::SupervisorEvent;
use crate::supervisor::SupervisorMsg;
use crate::QueueWriter;

/// The poll running on one agent's thread: `sequence << 32 | (slot + 1)`, 0 when none.
/// Only the agent's thread writes it (plain loads and stores, no read-modify-write).
#[derive(Debug, Default)]
pub(crate) struct ThreadHold {
    word: AtomicU64,
    polls: AtomicU64,
    names: parking_lot::Mutex<Vec<String>>,
}

impl ThreadHold {
    /// Notes that slot `slot` runs module `name` (the watcher names it from this).
    pub fn register(&self, slot: usize, name: &str) {
        let mut names = self.names.lock();
        if names.len() <= slot {
            names.resize(slot + 1, String::new());
        }
        names[slot] = name.to_string();
    }

    /// Runs `future` with each of its polls marked as slot `slot`'s.
    #[cfg(test)]
    pub async fn polls<F: Future>(&self, slot: usize, future: F) -> F::Output {
        let mut future = std::pin::pin!(future);
        std::future::poll_fn(|cx| self.marked(slot, || future.as_mut().poll(cx))).await
    }

    /// Runs `poll` (one poll of slot `slot`'s step) marked as that slot's.
    #[inline]
    pub fn marked<R>(&self, slot: usize, poll: impl FnOnce() -> R) -> R {
        let slot = slot as u64 + 1;
        let sequence = self.polls.load(Ordering::Relaxed).wrapping_add(1);
        self.polls.store(sequence, Ordering::Relaxed);
        self.word.store(sequence << 32 | slot, Ordering::Relaxed);
        let output = poll();
        self.word.store(0, Ordering::Relaxed);
        output
    }

    fn sample(&self) -> u64 {
        self.word.load(Ordering::Relaxed)
    }

    fn name(&self, slot: usize) -> String {
        self.names.lock().get(slot).cloned().unwrap_or_default()
    }
}

/// The pure rule: the same poll seen in `SAMPLES_PER_HOLD + 1` samples in a row (so
/// `held_ms` apart) is held; each held poll is reported once.
#[derive(Debug, Default)]
struct HoldWatch {
    last: u64,
    seen: u32,
    reported: u64,
}

/// Samples per `held_ms`: a poll is reported after between `held_ms` and 1.25 × `held_ms`.
const SAMPLES_PER_HOLD: u32 = 4;

impl HoldWatch {
    /// Notes a sample; returns the holding slot the first time its poll counts as held.
    fn observe(&mut self, word: u64) -> Option<usize> {
        if word == 0 || word != self.last {
            self.last = word;
            self.seen = u32::from(word != 0);
            return None;
        }
        self.seen += 1;
        if self.seen <= SAMPLES_PER_HOLD || self.reported == word {
            return None;
        }
        self.reported = word;
        Some((word & u64::from(u32::MAX)) as usize - 1)
    }
}

/// What the watcher of one agent's thread needs besides its supervisor.
pub(crate) struct HoldWatcher {
    pub hold: Arc<ThreadHold>,
    /// The agent's `step_budget.held_ms`.
    pub held: Duration,
    /// A writer of the agent's `_supervisor/events`, usable while its thread is held.
    pub events: QueueWriter<SupervisorEvent>,
    pub agent: Arc<str>,
}

/// Watches the agent's thread from the caller's runtime until the supervisor ends: a poll
/// that holds the thread for `held` gets a `held` event now, and a move off the thread once
/// it returns.
pub(crate) fn watch(watcher: HoldWatcher, supervisor: ActorRef<SupervisorMsg>) {
    let HoldWatcher {
        hold,
        held,
        events,
        agent,
    } = watcher;
    let started = Instant::now();
    tokio::spawn(async move {
        let mut ticks = tokio::time::interval(held / SAMPLES_PER_HOLD);
        ticks.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        let mut rule = HoldWatch::default();
        loop {
            ticks.tick().await;
            if !matches!(
                supervisor.get_status(),
                ractor::ActorStatus::Running | ractor::ActorStatus::Starting
            ) {
                return;
            }
            let Some(slot) = rule.observe(hold.sample()) else {
                continue;
            };
            let module = hold.name(slot);
            let reason = format!(
                "one of its steps has held the agent's thread for over {} ms without yielding (it blocks or computes in one go): no other module of `{agent}` steps until it returns; it will then be moved to the shared runtime, as `long_steps: true` would",
                held.as_millis()
            );
            tracing::warn!(agent = %agent, module = %module, "{reason}");
            events.push(SupervisorEvent {
                time_s: started.elapsed().as_secs_f64(),
                module,
                kind: "held".into(),
                reason,
                restarts: 0,
            });
            let _ = supervisor.send_message(SupervisorMsg::Held(slot, held));
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn word(sequence: u64, slot: u64) -> u64 {
        sequence << 32 | (slot + 1)
    }

    #[test]
    fn the_same_poll_in_enough_samples_in_a_row_is_held_once() {
        let mut rule = HoldWatch::default();
        let w = word(7, 2);
        let seen: Vec<_> = (0..12).map(|_| rule.observe(w)).collect();
        let first = seen.iter().position(Option::is_some).unwrap();
        assert_eq!(first as u32, SAMPLES_PER_HOLD, "{seen:?}");
        assert_eq!(seen[first], Some(2));
        assert_eq!(seen.iter().filter(|s| s.is_some()).count(), 1, "{seen:?}");
    }

    #[test]
    fn short_polls_idle_samples_and_new_polls_are_never_held() {
        let mut rule = HoldWatch::default();
        for sequence in 0..100 {
            // A new poll of the same slot at every sample, with idle samples between.
            assert_eq!(rule.observe(word(sequence, 0)), None);
            assert_eq!(rule.observe(0), None);
        }
        // The same poll, interrupted by an idle sample, starts counting again.
        for _ in 0..SAMPLES_PER_HOLD {
            assert_eq!(rule.observe(word(500, 1)), None);
        }
        assert_eq!(rule.observe(0), None);
        assert_eq!(rule.observe(word(501, 1)), None);
    }

    #[test]
    fn a_marked_future_marks_only_while_it_is_polled() {
        let hold = Arc::new(ThreadHold::default());
        let inside = hold.clone();
        let mut marked = Box::pin(hold.polls(3, async move {
            assert_eq!(
                inside.sample() & 0xffff_ffff,
                4,
                "slot 3 marked while polled"
            );
            tokio::task::yield_now().await;
        }));
        let mut cx = std::task::Context::from_waker(std::task::Waker::noop());
        assert!(marked.as_mut().poll(&mut cx).is_pending());
        assert_eq!(hold.sample(), 0, "not marked between polls");
        assert!(marked.as_mut().poll(&mut cx).is_ready());
        assert_eq!(hold.sample(), 0);
    }
}
