//! The hand-off from the taps to the writer thread: a count-bounded batch the writer takes
//! whole, and the conversion of write stamps to Unix time.

use parking_lot::{Condvar, Mutex};
use std::sync::atomic::AtomicU64;
use std::sync::Arc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use tokio::time::Instant;

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

struct Queue {
    msgs: Mutex<Vec<Msg>>,
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
