//! The hand-off from the taps to the writer thread: a count-bounded batch the writer takes
//! whole, and the conversion of write stamps to Unix time.

use parking_lot::{Condvar, Mutex};
use std::sync::atomic::AtomicU64;
use std::sync::Arc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use tokio::time::Instant;

use petrel_actors::AnyValue;

use crate::sink::{ChannelSpec, Entry};

pub(crate) enum Msg {
    Channel(ChannelSpec, Arc<AtomicU64>),
    Entry(Entry),
    Stop,
}

/// Converts write stamps (tokio instants, paused in tests) to Unix nanoseconds.
#[derive(Clone, Copy)]
pub struct StampClock {
    instant: Instant,
    unix_ns: u64,
}

impl StampClock {
    /// A conversion taken now.
    pub fn now() -> Self {
        let unix = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .unwrap_or_default();
        StampClock {
            instant: Instant::now(),
            unix_ns: u64::try_from(unix.as_nanos()).unwrap_or(u64::MAX),
        }
    }

    /// `stamp` as Unix ns.
    pub fn unix_ns(&self, stamp: Instant) -> u64 {
        let ns = |d: Duration| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX);
        match self.instant.checked_duration_since(stamp) {
            Some(ago) => self.unix_ns.saturating_sub(ns(ago)),
            None => self.unix_ns.saturating_add(ns(stamp - self.instant)),
        }
    }
}

/// Values queued before the writer thread is woken: it takes them in batches, so a busy
/// agent costs one thread wake-up per batch, not one per value.
const WAKE_AT: usize = 256;
/// Longest a value waits for the writer when fewer than [`WAKE_AT`] are queued.
const LATENCY: Duration = Duration::from_millis(100);
/// Written values kept for the drains to drop (see [`Backlog::give_back`]): a few batches.
const SPENT_MAX: usize = 4 * WAKE_AT;

struct Queue {
    msgs: Mutex<Vec<Msg>>,
    /// Values the writer has written, handed back to be dropped by a drain on an agent's
    /// thread (see [`Backlog::give_back`]).
    spent: Mutex<Vec<AnyValue>>,
    ready: Condvar,
    limit: usize,
}

/// The hand-off to the writer thread: bounded by a count (a large backlog costs memory only
/// while used), never waited on by the taps.
#[derive(Clone)]
pub(crate) struct Backlog(Arc<Queue>);

impl Backlog {
    pub(crate) fn new(limit: usize) -> Self {
        Backlog(Arc::new(Queue {
            msgs: Mutex::new(Vec::new()),
            spent: Mutex::new(Vec::new()),
            ready: Condvar::new(),
            limit: limit.max(1),
        }))
    }

    /// Queues a value unless `limit` already wait; says whether it did.
    pub(crate) fn try_send(&self, msg: Msg) -> bool {
        let mut msgs = self.0.msgs.lock();
        if msgs.len() >= self.0.limit {
            return false;
        }
        msgs.push(msg);
        if msgs.len() == WAKE_AT {
            self.0.ready.notify_one();
        }
        true
    }

    /// Queues `entries` under one lock while fewer than `limit` wait; each one that does not
    /// fit is dropped and its tag handed to `dropped`.
    pub(crate) fn try_send_all<T>(
        &self,
        entries: impl Iterator<Item = (T, Entry)>,
        mut dropped: impl FnMut(T),
    ) {
        let mut msgs = self.0.msgs.lock();
        let before = msgs.len();
        for (tag, entry) in entries {
            if msgs.len() >= self.0.limit {
                dropped(tag);
            } else {
                msgs.push(Msg::Entry(entry));
            }
        }
        if before < WAKE_AT && msgs.len() >= WAKE_AT {
            self.0.ready.notify_one();
        }
    }

    /// Queues a control message (a channel, the stop), whatever the backlog, and wakes the writer.
    pub(crate) fn send(&self, msg: Msg) {
        self.0.msgs.lock().push(msg);
        self.0.ready.notify_one();
    }

    /// Hands the values the writer has written (`values`, emptied) back, for the next drain
    /// pass to drop on its agent's thread.
    ///
    /// A recorded value is usually last held by the recorder (the property has moved on), so
    /// the writer would free memory the agent's thread allocated: the allocator then moves
    /// those blocks between the threads' caches and arenas, which cost the agent's thread
    /// more than the frees themselves (`record_overhead`, BENCHMARKS.md). Values nobody
    /// takes (no drain has run for a while: only log records, or the agents stopped) are
    /// dropped here past [`SPENT_MAX`].
    pub(crate) fn give_back(&self, values: &mut Vec<AnyValue>) {
        let mut spent = self.0.spent.lock();
        if spent.len() >= SPENT_MAX {
            drop(spent);
            values.clear();
        } else if spent.is_empty() {
            std::mem::swap(&mut *spent, values);
        } else {
            spent.append(values);
        }
    }

    /// Takes the values the writer handed back into `out` (emptied first), unless the writer
    /// is handing some back right now (they are taken at a later pass).
    pub(crate) fn take_spent(&self, out: &mut Vec<AnyValue>) {
        out.clear();
        if let Some(mut spent) = self.0.spent.try_lock() {
            std::mem::swap(&mut *spent, out);
        }
    }

    /// Takes what is queued into `out` (emptied first), waiting up to [`LATENCY`] for some.
    pub(crate) fn take(&self, out: &mut Vec<Msg>) {
        out.clear();
        let mut msgs = self.0.msgs.lock();
        if msgs.len() < WAKE_AT {
            self.0.ready.wait_for(&mut msgs, LATENCY);
        }
        std::mem::swap(&mut *msgs, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn values(n: usize) -> Vec<AnyValue> {
        (0..n).map(|i| Arc::new(i) as AnyValue).collect()
    }

    #[test]
    fn written_values_go_back_to_the_drain_that_takes_them() {
        let backlog = Backlog::new(16);
        let kept = values(3);
        let mut written: Vec<AnyValue> = kept.clone();
        backlog.give_back(&mut written);
        assert!(written.is_empty());
        // Still held by the backlog until a drain takes them.
        assert!(kept.iter().all(|v| Arc::strong_count(v) == 2));
        let mut taken = vec![Arc::new(99_usize) as AnyValue];
        backlog.take_spent(&mut taken);
        assert_eq!(taken.len(), 3);
        drop(taken);
        assert!(kept.iter().all(|v| Arc::strong_count(v) == 1));
        // Nothing is taken twice.
        let mut again = Vec::new();
        backlog.take_spent(&mut again);
        assert!(again.is_empty());
    }

    #[test]
    fn values_no_drain_takes_are_dropped_by_the_writer_past_the_bound() {
        let backlog = Backlog::new(16);
        let mut first = values(SPENT_MAX);
        backlog.give_back(&mut first);
        let late = values(5);
        let mut written = late.clone();
        backlog.give_back(&mut written);
        assert!(written.is_empty());
        assert!(
            late.iter().all(|v| Arc::strong_count(v) == 1),
            "dropped at once"
        );
        let mut taken = Vec::new();
        backlog.take_spent(&mut taken);
        assert_eq!(taken.len(), SPENT_MAX);
    }
}
