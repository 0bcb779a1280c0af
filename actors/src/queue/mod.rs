//! Queues: producer/consumer streams with many readers, for sensor data.
//!
//! A queue is passive (no task): a push appends an `Arc`-shared, timestamped item and raises
//! the signal of every subscribed reader; each reader has its own cursor and sees every item
//! once, in order. A queue holds at most `capacity` items: a reader that lags further loses the
//! oldest ones, and the loss is added to its drop counter, which is published as the property
//! `stats/dropped/<input path>`.
//!
//! Each reader also has an *acknowledged* position: the module actor acknowledges what a step
//! took once the step returns, and a restarted module rewinds to it. An item is freed once
//! every reader has acknowledged it. So delivery across a module failure is **at least once**:
//! the items of the step that failed are delivered again (unless evicted by capacity).

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use arc_swap::ArcSwap;
use parking_lot::Mutex;
use tokio::time::Instant;

use crate::cell::{cause, Endpoint, Signal};
use crate::value::{AnyValue, TypeInfo};

/// Default number of items a queue keeps for its slowest reader.
pub const DEFAULT_CAPACITY: usize = 64;

#[derive(Clone)]
pub(crate) struct QueueItem {
    pub seq: u64,
    pub stamp: Instant,
    pub value: AnyValue,
}

struct ReaderEntry {
    id: u64,
    /// Next item to deliver.
    cursor: u64,
    /// First item not yet acknowledged (`acked <= cursor`).
    acked: u64,
    signal: Option<Arc<Signal>>,
    dropped: Arc<Endpoint>,
    lag: LagReport,
}

/// When a lagging reader's drops are logged: at most once a second, with the count since the
/// last line. A reader that lags for good drops at every push, and a line per push flooded the
/// log (thousands in seconds); `stats/dropped/...` counts every one.
#[derive(Debug, Default)]
struct LagReport {
    warned_at: Option<Instant>,
    unreported: u64,
}

impl LagReport {
    const EVERY: std::time::Duration = std::time::Duration::from_secs(1);

    /// Notes `lost` items dropped at `now`; the number to log now, if a line is due.
    fn note(&mut self, lost: u64, now: Instant) -> Option<u64> {
        self.unreported += lost;
        let due = (self.warned_at).is_none_or(|t| now.saturating_duration_since(t) >= Self::EVERY);
        if !due {
            return None;
        }
        self.warned_at = Some(now);
        Some(std::mem::take(&mut self.unreported))
    }
}

struct Inner {
    capacity: usize,
    items: VecDeque<QueueItem>,
    /// Sequence number the next pushed item gets.
    next_seq: u64,
    readers: Vec<ReaderEntry>,
}

impl Inner {
    fn head_seq(&self) -> u64 {
        self.next_seq - self.items.len() as u64
    }

    /// Frees the items every reader has acknowledged.
    fn trim(&mut self) {
        let min = self
            .readers
            .iter()
            .map(|r| r.acked)
            .min()
            .unwrap_or(self.next_seq);
        while self.items.front().is_some_and(|i| i.seq < min) {
            self.items.pop_front();
        }
    }
}

/// The shared state of one queue (an `out/...` queue property).
pub(crate) struct QueueCore {
    pub key: Arc<str>,
    pub type_info: TypeInfo,
    inner: Mutex<Inner>,
    /// The latest item as a value property, made when something first reads the queue as a
    /// value (an expression: `min(robot/out/laserScan.ranges) < 0.6`); until then a push
    /// costs nothing more.
    latest: std::sync::OnceLock<Arc<crate::cell::Endpoint>>,
    /// Whether the queue has a reader, readable without the lock (`push_with`); set and
    /// cleared under it.
    read: AtomicBool,
}

impl QueueCore {
    pub fn new(key: &str, type_info: TypeInfo, capacity: usize) -> Arc<Self> {
        Arc::new(QueueCore {
            key: key.into(),
            type_info,
            inner: Mutex::new(Inner {
                capacity: capacity.max(1),
                items: VecDeque::new(),
                next_seq: 0,
                readers: Vec::new(),
            }),
            latest: std::sync::OnceLock::new(),
            read: AtomicBool::new(false),
        })
    }

    /// The latest item as a value endpoint (written at every push from now on, with the push
    /// time), starting from the newest item held, else from `sample`; `None` when there is
    /// neither (a type without a known sample, nothing pushed yet).
    pub fn latest(&self, sample: Option<AnyValue>) -> Option<Arc<crate::cell::Endpoint>> {
        if let Some(ep) = self.latest.get() {
            return Some(ep.clone());
        }
        let newest = self.inner.lock().items.back().map(|i| i.value.clone());
        let first = newest.or(sample)?;
        Some(
            self.latest
                .get_or_init(|| crate::cell::Endpoint::new(&self.key, self.type_info, first))
                .clone(),
        )
    }

    pub fn set_capacity(&self, capacity: usize) {
        self.inner.lock().capacity = capacity.max(1);
    }

    pub fn capacity(&self) -> usize {
        self.inner.lock().capacity
    }

    /// Items currently held (not yet consumed by every reader).
    pub fn len(&self) -> usize {
        self.inner.lock().items.len()
    }

    /// Like [`push`](Self::push), making the item only if someone will see it: a queue with
    /// no reader (and no expression reading its latest item) drops what is pushed, so a
    /// writer whose items cost something to build need not build them.
    pub fn push_with(&self, make: impl FnOnce() -> AnyValue, stamp: Instant) {
        // No lock: a reader attaching meanwhile starts after this push, which it would not
        // have seen anyway (a push with no reader keeps nothing; its sequence number is not
        // taken, which no one can tell).
        if self.latest.get().is_none() && !self.read.load(Ordering::Acquire) {
            return;
        }
        self.push(make(), stamp)
    }

    pub fn push(&self, value: AnyValue, stamp: Instant) {
        if let Some(latest) = self.latest.get() {
            latest.write_at(value.clone(), stamp);
        }
        let mut lagging = Vec::new();
        {
            let mut inner = self.inner.lock();
            let seq = inner.next_seq;
            inner.next_seq += 1;
            if inner.readers.is_empty() {
                return;
            }
            inner.items.push_back(QueueItem { seq, stamp, value });
            if inner.items.len() > inner.capacity {
                inner.items.pop_front();
                let head = inner.head_seq();
                for r in inner.readers.iter_mut() {
                    // Delivered but unacknowledged items can no longer be redelivered.
                    r.acked = r.acked.max(head);
                    if r.cursor < head {
                        let lost = head - r.cursor;
                        r.cursor = head;
                        let reported = r.lag.note(lost, stamp);
                        lagging.push((r.dropped.clone(), lost, reported));
                    }
                }
            }
            for r in &inner.readers {
                if let Some(s) = &r.signal {
                    s.raise(cause::ITEMS);
                }
            }
        }
        for (dropped, lost, reported) in lagging {
            let total = *dropped.value().downcast_ref::<i64>().unwrap_or(&0) + lost as i64;
            dropped.write(Arc::new(total));
            if let Some(lost) = reported {
                tracing::warn!(queue = %self.key, reader = %dropped.key, lost, total, "queue reader lagged: oldest items dropped (logged at most once a second; stats/dropped counts every one)");
            }
        }
    }

    fn attach(&self, id: u64, signal: Option<Arc<Signal>>, dropped: Arc<Endpoint>) {
        let mut inner = self.inner.lock();
        let cursor = inner.next_seq;
        self.read.store(true, Ordering::Release);
        inner.readers.push(ReaderEntry {
            id,
            cursor,
            acked: cursor,
            signal,
            dropped,
            lag: LagReport::default(),
        });
    }

    fn detach(&self, id: u64) {
        let mut inner = self.inner.lock();
        inner.readers.retain(|r| r.id != id);
        self.read
            .store(!inner.readers.is_empty(), Ordering::Release);
        inner.trim();
    }

    fn set_signal(&self, id: u64, signal: &Arc<Signal>) {
        let mut inner = self.inner.lock();
        if let Some(r) = inner.readers.iter_mut().find(|r| r.id == id) {
            r.signal = Some(signal.clone());
            if r.cursor < inner.next_seq {
                signal.raise(cause::ITEMS);
            }
        }
    }

    /// Takes up to `max` unread items for reader `id`, advancing its cursor.
    fn take(&self, id: u64, max: usize, out: &mut Vec<QueueItem>) {
        let mut inner = self.inner.lock();
        let head = inner.head_seq();
        let Some(r) = inner.readers.iter_mut().find(|r| r.id == id) else {
            return;
        };
        let start = (r.cursor - head) as usize;
        let end = inner.items.len().min(start.saturating_add(max));
        if start >= end {
            return;
        }
        out.extend(inner.items.range(start..end).cloned());
        let Some(r) = inner.readers.iter_mut().find(|r| r.id == id) else {
            return;
        };
        r.cursor = head + end as u64;
        inner.trim();
    }

    /// Acknowledges everything reader `id` took so far.
    fn ack(&self, id: u64) {
        let mut inner = self.inner.lock();
        if let Some(r) = inner.readers.iter_mut().find(|r| r.id == id) {
            if r.acked != r.cursor {
                r.acked = r.cursor;
                inner.trim();
            }
        }
    }

    /// Delivers again everything reader `id` took but did not acknowledge.
    fn rewind(&self, id: u64) {
        let mut inner = self.inner.lock();
        let head = inner.head_seq();
        if let Some(r) = inner.readers.iter_mut().find(|r| r.id == id) {
            r.cursor = r.acked.max(head);
        }
    }

    fn pending(&self, id: u64) -> usize {
        let inner = self.inner.lock();
        inner
            .readers
            .iter()
            .find(|r| r.id == id)
            .map_or(0, |r| (inner.next_seq - r.cursor) as usize)
    }
}

/// The path of the property that counts what the queue input at `path` lost.
pub(crate) fn dropped_path(path: &str) -> String {
    format!("stats/dropped/{path}")
}

/// The reading side of one `in/...` queue input; it follows relinks to other queues.
pub(crate) struct ReaderEndpoint {
    pub id: u64,
    pub key: Arc<str>,
    pub type_info: TypeInfo,
    source: ArcSwap<QueueCore>,
    signal: Mutex<Option<Arc<Signal>>>,
    pub dropped: Arc<Endpoint>,
    /// Items were taken since the last acknowledgement: without, an acknowledgement (after
    /// every step of the module) has nothing to do and takes no lock.
    unacked: AtomicBool,
}

impl ReaderEndpoint {
    /// A reader of `source`, starting at its current tail.
    pub fn new(id: u64, key: &str, type_info: TypeInfo, source: Arc<QueueCore>) -> Arc<Self> {
        let (module, path) = key.split_once('/').unwrap_or(("", key));
        let dropped = Endpoint::new(
            &format!("{module}/{}", dropped_path(path)),
            TypeInfo::of::<i64>(),
            Arc::new(0_i64),
        );
        source.attach(id, None, dropped.clone());
        Arc::new(ReaderEndpoint {
            id,
            key: key.into(),
            type_info,
            source: ArcSwap::new(source),
            signal: Mutex::new(None),
            dropped,
            unacked: AtomicBool::new(false),
        })
    }

    pub fn source(&self) -> Arc<QueueCore> {
        self.source.load_full()
    }

    pub fn subscribe(&self, signal: &Arc<Signal>) {
        let mut s = self.signal.lock();
        *s = Some(signal.clone());
        self.source.load().set_signal(self.id, signal);
    }

    /// Reads from `target` from now on, starting at its tail.
    pub fn retarget(&self, target: Arc<QueueCore>) {
        let signal = self.signal.lock();
        let old = self.source.swap(target.clone());
        if Arc::ptr_eq(&old, &target) {
            return;
        }
        old.detach(self.id);
        target.attach(self.id, signal.clone(), self.dropped.clone());
    }

    pub fn take(&self, max: usize, out: &mut Vec<QueueItem>) {
        let before = out.len();
        self.source.load().take(self.id, max, out);
        if out.len() > before {
            self.unacked.store(true, Ordering::Release);
        }
    }

    pub fn pending(&self) -> usize {
        self.source.load().pending(self.id)
    }

    pub fn ack(&self) {
        // Only taking moves the delivery cursor past the acknowledged one (an eviction moves
        // both), so with nothing taken there is nothing to acknowledge.
        if self.unacked.swap(false, Ordering::AcqRel) {
            self.source.load().ack(self.id)
        }
    }

    pub fn rewind(&self) {
        self.source.load().rewind(self.id)
    }
}

impl Drop for ReaderEndpoint {
    fn drop(&mut self) {
        self.source.load().detach(self.id);
    }
}

#[cfg(test)]
mod tests;
