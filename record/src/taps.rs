//! The recorder's taps: one drain task per recorded agent reads the properties whose taps
//! were marked ready ([`TapReady`]) and sends their changes (or queue items) to the writer
//! thread without ever waiting; and the table of channels they feed, shared by the drains and
//! the log.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use parking_lot::Mutex;
use petrel_actors::team::{QueueTap, Tap, TapReady, ValueTap};
use petrel_actors::{Blackboard, WatchedTap};
use tokio::sync::{mpsc, watch};
use tokio::task::JoinHandle;
use tokio::time::Instant;

use crate::backlog::{Backlog, Msg, StampClock};
use crate::sink::{ChannelSpec, Entry};

/// Items a queue tap takes at a time.
const BATCH: usize = 256;
/// Writes of one value property kept for the drain between two of its passes: a drain runs
/// beside the modules, after each step that wrote, so it finds a few; a simulator catching up
/// with the wall clock writes one per simulated step. Past this many, the oldest are lost and
/// counted as dropped.
const KEPT_WRITES: usize = 1024;

/// Where one channel's values go: the writer's backlog, and the channel's drop counter.
#[derive(Clone)]
pub(crate) struct Out {
    pub tx: Backlog,
    pub channel: usize,
    pub dropped: Arc<AtomicU64>,
}

/// The channels of a recording and the drain tasks feeding them.
pub(crate) struct Channels {
    tx: Backlog,
    clock: StampClock,
    /// By topic: a module removed and added again under its name feeds the same channel.
    by_topic: HashMap<String, Out>,
    /// Drop counters, by channel index.
    pub dropped: Vec<Arc<AtomicU64>>,
    drains: Vec<JoinHandle<()>>,
    /// Raised when the recording finishes: each drain sends what is left, then ends.
    stop: watch::Sender<bool>,
    /// Set when the recording finishes: a drain started later taps nothing.
    closed: bool,
}

impl Channels {
    pub fn new(tx: Backlog, clock: StampClock) -> Self {
        Channels {
            tx,
            clock,
            by_topic: HashMap::new(),
            dropped: Vec::new(),
            drains: Vec::new(),
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
            channel: self.dropped.len(),
            dropped: dropped.clone(),
        };
        self.by_topic.insert(spec.topic.clone(), out.clone());
        self.tx.send(Msg::Channel(spec, dropped.clone()));
        self.dropped.push(dropped);
        out
    }

    /// Starts recording `agent` in one task: the taps `taps` holds now are added before this
    /// returns (their channels announced in order), those it receives later as they come.
    /// Returns how many were added now.
    ///
    /// The task runs beside the agent's modules ([`Blackboard::spawn_beside`]): their writes
    /// wake it on their own thread, and the values it hands the writer were allocated there,
    /// where it also frees them (see `Backlog::give_back`).
    pub fn drain(
        shared: &Arc<Mutex<Channels>>,
        agent: &str,
        mut taps: mpsc::UnboundedReceiver<WatchedTap>,
        blackboard: &Blackboard,
    ) -> usize {
        let mut channels = shared.lock();
        if channels.closed {
            return 0;
        }
        let mut drain = Drain::new(agent, channels.tx.clone(), channels.clock);
        while let Ok(tapped) = taps.try_recv() {
            drain.add(&mut channels, tapped);
        }
        let added = drain.taps.len();
        let stop = channels.stop.subscribe();
        let task = blackboard.spawn_beside(drain.run(taps, shared.clone(), stop));
        channels.drains.push(task);
        added
    }

    /// Asks every drain to send what is left and end; returns the drains to wait for.
    pub fn close(&mut self) -> Vec<JoinHandle<()>> {
        self.closed = true;
        self.stop.send_replace(true);
        std::mem::take(&mut self.drains)
    }
}

/// What a drain reads of one tapped property.
enum Source {
    /// A value: its value when tapped, then every write (and how many writes the tap lost,
    /// already counted).
    Value { tap: ValueTap, lost: u64 },
    /// A queue: its items (and how many it lost by lagging, already counted).
    Queue { tap: QueueTap, lost: u64 },
}

struct Tapped {
    out: Out,
    source: Source,
}

/// One agent's taps, read by one task when they are marked ready.
///
/// Dropped, it reads every tap one last time: at the end of the recording, and also when its
/// task is cancelled because the agent's thread ended first (an agent shut down before the
/// recording finished), so that what the agent wrote last is recorded either way.
struct Drain {
    agent: String,
    ready: TapReady,
    /// By id (the index the tap marks).
    taps: Vec<Tapped>,
    tx: Backlog,
    clock: StampClock,
    /// Values read in one pass, with the id of their tap, sent under one lock.
    batch: Vec<(usize, Entry)>,
    /// Values the writer handed back, dropped at each pass (the buffer is kept).
    spent: Vec<petrel_actors::AnyValue>,
    /// The writes a value tap kept, taken in one read (the buffer is kept).
    writes: Vec<(petrel_actors::AnyValue, u64, Instant)>,
}

impl Drop for Drain {
    fn drop(&mut self) {
        let all: Vec<usize> = (0..self.taps.len()).collect();
        self.pass(&all);
    }
}

impl Drain {
    fn new(agent: &str, tx: Backlog, clock: StampClock) -> Self {
        Drain {
            agent: agent.to_string(),
            ready: TapReady::new(),
            taps: Vec::new(),
            tx,
            clock,
            batch: Vec::new(),
            spent: Vec::new(),
            writes: Vec::new(),
        }
    }

    /// Records what `tapped` writes from now on (its current value or unread items first).
    fn add(&mut self, channels: &mut Channels, tapped: WatchedTap) {
        let WatchedTap { key, mut tap } = tapped;
        let out = channels.channel(ChannelSpec {
            topic: crate::select::topic(&self.agent, &key),
            url: format!("petrel://{}/{key}", self.agent),
            type_info: tap.type_info(),
            queue: matches!(tap, Tap::Queue(_)),
        });
        tap.record_through(&self.ready, self.taps.len(), KEPT_WRITES);
        let source = match tap {
            Tap::Value(tap) => Source::Value { tap, lost: 0 },
            Tap::Queue(tap) => Source::Queue { tap, lost: 0 },
        };
        self.taps.push(Tapped { out, source });
    }

    /// Reads what the ready taps hold until `stop`, adding the taps declared meanwhile; then
    /// reads every tap one last time (as it is dropped).
    async fn run(
        mut self,
        mut declared: mpsc::UnboundedReceiver<WatchedTap>,
        channels: Arc<Mutex<Channels>>,
        mut stop: watch::Receiver<bool>,
    ) {
        let mut ids = Vec::new();
        let mut watching = true;
        let stopped = stop.wait_for(|&stop| stop);
        tokio::pin!(stopped);
        loop {
            tokio::select! {
                biased;
                _ = &mut stopped => break,
                tapped = declared.recv(), if watching => match tapped {
                    Some(tapped) => {
                        tracing::info!(agent = %self.agent, property = %tapped.key, "recording a property declared while running");
                        self.add(&mut channels.lock(), tapped);
                    }
                    None => watching = false,
                },
                _ = self.ready.wait(&mut ids) => self.pass(&ids),
            }
        }
        // The last pass is `Drop`'s.
    }

    /// Reads the taps `ids` and sends what they hold.
    fn pass(&mut self, ids: &[usize]) {
        // What the writer has written since the last pass is freed here, beside the modules
        // that allocated it: on the agent's own thread when it has one (`Backlog::give_back`).
        self.tx.take_spent(&mut self.spent);
        self.spent.clear();
        let log_ns = self.clock.unix_ns(Instant::now());
        for &id in ids {
            self.read(id, log_ns);
        }
        let taps = &self.taps;
        self.tx.try_send_all(self.batch.drain(..), |id| {
            taps[id].out.dropped.fetch_add(1, Ordering::Relaxed);
        });
    }

    /// Reads tap `id` into the batch: a value's writes since the last read, a queue's unread
    /// items.
    fn read(&mut self, id: usize, log_ns: u64) {
        let Tapped { out, source } = &mut self.taps[id];
        let writes = &mut self.writes;
        let clock = self.clock;
        let entry = |value, sequence, written| Entry {
            channel: out.channel,
            value,
            sequence,
            publish_ns: clock.unix_ns(written),
            log_ns,
        };
        match source {
            Source::Value { tap, lost } => {
                let now_lost = tap.take_writes(writes);
                for (value, version, written) in writes.drain(..) {
                    self.batch.push((id, entry(value, version, written)));
                }
                if now_lost > *lost {
                    out.dropped.fetch_add(now_lost - *lost, Ordering::Relaxed);
                    *lost = now_lost;
                }
            }
            Source::Queue { tap, lost } => {
                loop {
                    let items = tap.take(BATCH);
                    let full = items.len() == BATCH;
                    for (seq, stamp, value) in items {
                        self.batch.push((id, entry(value, seq, stamp)));
                    }
                    if !full {
                        break;
                    }
                }
                let now_lost = tap.lost().max(0) as u64;
                if now_lost > *lost {
                    out.dropped.fetch_add(now_lost - *lost, Ordering::Relaxed);
                    *lost = now_lost;
                }
            }
        }
    }
}
