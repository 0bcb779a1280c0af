//! The recorder's taps: one task per recorded property, sending each change (or queue item)
//! to the writer thread without ever waiting, and the table of channels they feed, shared
//! with the watches that tap properties declared while the agent runs.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use petrel_actors::team::{QueueTap, Tap, ValueTap};
use petrel_actors::{AnyValue, WatchedTap};
use tokio::sync::watch;
use tokio::task::JoinHandle;
use tokio::time::Instant;

use crate::backlog::{Backlog, Msg, StampClock};
use crate::sink::{ChannelSpec, Entry};

/// Items a queue tap takes per wake-up.
const BATCH: usize = 256;

/// Sends values of one channel to the writer thread without ever waiting.
#[derive(Clone)]
pub(crate) struct Out {
    pub tx: Backlog,
    pub clock: StampClock,
    pub channel: usize,
    pub dropped: Arc<AtomicU64>,
}

impl Out {
    fn send(&self, value: AnyValue, sequence: u64, written: Instant) {
        let entry = Entry {
            channel: self.channel,
            value,
            sequence,
            publish_ns: self.clock.unix_ns(written),
            log_ns: self.clock.unix_ns(Instant::now()),
        };
        if !self.tx.try_send(Msg::Entry(entry)) {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// The channels of a recording and the tasks feeding them.
pub(crate) struct Channels {
    tx: Backlog,
    clock: StampClock,
    /// By topic: a module removed and added again under its name feeds the same channel.
    by_topic: HashMap<String, Out>,
    /// Drop counters, by channel index.
    pub dropped: Vec<Arc<AtomicU64>>,
    tasks: Vec<JoinHandle<()>>,
    /// The watches tapping properties declared later.
    watches: Vec<JoinHandle<()>>,
    /// Raised when the recording finishes: each tap sends what is left, then ends.
    stop: watch::Sender<bool>,
    /// Set when the recording finishes: a watch that was mid-way taps nothing more.
    closed: bool,
}

impl Channels {
    pub fn new(tx: Backlog, clock: StampClock) -> Self {
        Channels {
            tx,
            clock,
            by_topic: HashMap::new(),
            dropped: Vec::new(),
            tasks: Vec::new(),
            watches: Vec::new(),
            stop: watch::channel(false).0,
            closed: false,
        }
    }

    /// The sender of `spec.topic`'s channel, added (and announced to the writer) if new.
    pub fn channel(&mut self, spec: ChannelSpec) -> Out {
        if let Some(out) = self.by_topic.get(&spec.topic) {
            return out.clone();
        }
        let dropped = Arc::new(AtomicU64::new(0));
        let out = Out {
            tx: self.tx.clone(),
            clock: self.clock,
            channel: self.dropped.len(),
            dropped: dropped.clone(),
        };
        self.by_topic.insert(spec.topic.clone(), out.clone());
        self.tx.send(Msg::Channel(spec, dropped.clone()));
        self.dropped.push(dropped);
        out
    }

    /// Records what `tapped` (a property of `agent`) writes from now on.
    pub fn record(&mut self, agent: &str, tapped: WatchedTap) {
        if self.closed {
            return;
        }
        let spec = ChannelSpec {
            topic: crate::select::topic(agent, &tapped.key),
            url: format!("petrel://{agent}/{}", tapped.key),
            type_info: tapped.tap.type_info(),
            queue: matches!(tapped.tap, Tap::Queue(_)),
        };
        let out = self.channel(spec);
        let stop = self.stop.subscribe();
        let task = match tapped.tap {
            Tap::Value(tap) => tokio::spawn(record_value(tap, out, stop)),
            Tap::Queue(tap) => tokio::spawn(record_queue(tap, out, stop)),
        };
        self.tasks.push(task);
    }

    /// Keeps `task` (a watch) to stop it with the taps.
    pub fn keep(&mut self, task: JoinHandle<()>) {
        match self.closed {
            true => task.abort(),
            false => self.watches.push(task),
        }
    }

    /// Stops the watches and asks every tap to send what is left and end; returns the taps
    /// to wait for.
    pub fn close(&mut self) -> Vec<JoinHandle<()>> {
        self.closed = true;
        for watch in self.watches.drain(..) {
            watch.abort();
        }
        self.stop.send_replace(true);
        std::mem::take(&mut self.tasks)
    }
}

/// Records a value's changes until `stop`, then its last change if not yet sent.
async fn record_value(tap: ValueTap, out: Out, mut stop: watch::Receiver<bool>) {
    let mut last = None;
    // Made once, not per wake-up: a fresh `wait_for` registers with the stop channel and
    // unregisters again on every change, a cost the agent's thread paid per recorded value.
    let stopped = stop.wait_for(|&stop| stop);
    tokio::pin!(stopped);
    loop {
        let (value, version, written) = tap.read();
        if last != Some(version) {
            last = Some(version);
            out.send(value, version, written);
        }
        tokio::select! {
            biased;
            _ = &mut stopped => break,
            _ = tap.changed() => {}
        }
    }
    let (value, version, written) = tap.read();
    if last != Some(version) {
        out.send(value, version, written);
    }
}

/// Records a queue's items until `stop`, then those still unread.
async fn record_queue(mut tap: QueueTap, out: Out, mut stop: watch::Receiver<bool>) {
    let mut lost = 0;
    let mut stopping = false;
    // Made once, as in `record_value`.
    let stopped = stop.wait_for(|&stop| stop);
    tokio::pin!(stopped);
    loop {
        let items = tap.take(BATCH);
        let full = items.len() == BATCH;
        for (seq, stamp, value) in items {
            out.send(value, seq, stamp);
        }
        let now_lost = tap.lost().max(0) as u64;
        if now_lost > lost {
            out.dropped.fetch_add(now_lost - lost, Ordering::Relaxed);
            lost = now_lost;
        }
        if full {
            continue;
        }
        if stopping {
            return;
        }
        tokio::select! {
            biased;
            _ = &mut stopped, if !stopping => stopping = true,
            _ = tap.changed() => {}
        }
    }
}
