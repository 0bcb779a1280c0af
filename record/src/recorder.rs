//! The recorder shell: taps on an agent's blackboard feed a bounded channel that a writer
//! thread drains into a [`Sink`]. Modules never wait for it: a tap that finds the channel full
//! drops the value and counts it (per channel, written in the file's summary), and a queue tap
//! that lags behind its queue's capacity loses the oldest items, counted the same way.

use parking_lot::{Condvar, Mutex};
use std::io;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use petrel_actors::team::{QueueTap, Tap, ValueTap};
use petrel_actors::{AnyValue, Blackboard, BlackboardError, PropertyKind, TypeInfo};
use tokio::time::Instant;

use crate::encode::LogRecord;
use crate::select::RecordOptions;
use crate::sink::{ChannelSpec, Entry, Sink, SinkReport};

/// How often the writer closes its chunk, so a killed run loses at most this much.
pub const FLUSH_EVERY: Duration = Duration::from_secs(1);
/// Items a queue tap takes per wake-up.
const BATCH: usize = 256;

enum Msg {
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
struct Backlog(Arc<Queue>);

impl Backlog {
    fn new(limit: usize) -> Self {
        Backlog(Arc::new(Queue {
            msgs: Mutex::new(Vec::new()),
            ready: Condvar::new(),
            limit: limit.max(1),
        }))
    }

    /// Queues a value unless `limit` already wait; says whether it did.
    fn try_send(&self, msg: Msg) -> bool {
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

    /// Queues a control message (a channel, the stop), whatever the backlog, and wakes the writer.
    fn send(&self, msg: Msg) {
        self.0.msgs.lock().push(msg);
        self.0.ready.notify_one();
    }

    /// Takes what is queued into `out` (emptied first), waiting up to [`LATENCY`] for some.
    fn take(&self, out: &mut Vec<Msg>) {
        out.clear();
        let mut msgs = self.0.msgs.lock();
        if msgs.len() < WAKE_AT {
            self.0.ready.wait_for(&mut msgs, LATENCY);
        }
        std::mem::swap(&mut *msgs, out);
    }
}

/// Sends values to the writer thread without ever waiting.
#[derive(Clone)]
struct Out {
    tx: Backlog,
    clock: StampClock,
    channel: usize,
    dropped: Arc<AtomicU64>,
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

/// Records the tracing log: the root's tracing layer hands it each event.
#[derive(Clone)]
pub struct LogSink {
    out: Out,
    sequence: Arc<AtomicU64>,
}

impl LogSink {
    /// Records one log line (dropped and counted if the recorder is behind).
    pub fn record(&self, rec: LogRecord) {
        let seq = self.sequence.fetch_add(1, Ordering::Relaxed);
        let entry = Entry {
            channel: self.out.channel,
            publish_ns: rec.stamp_ns,
            log_ns: rec.stamp_ns,
            value: Arc::new(rec),
            sequence: seq,
        };
        if !self.out.tx.try_send(Msg::Entry(entry)) {
            self.out.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// A running recording.
pub struct Recorder {
    tx: Backlog,
    clock: StampClock,
    options: RecordOptions,
    channels: usize,
    dropped: Vec<Arc<AtomicU64>>,
    tasks: Vec<tokio::task::JoinHandle<()>>,
    thread: Option<JoinHandle<io::Result<SinkReport>>>,
}

impl Recorder {
    /// Creates the first file and starts the writer thread.
    pub fn start(options: RecordOptions) -> io::Result<Recorder> {
        let mut sink = Sink::create(&options.path, options.format, options.split)?;
        let path = options.path.clone();
        let tx = Backlog::new(options.backlog);
        let rx = tx.clone();
        let thread = std::thread::Builder::new()
            .name("petrel-record".into())
            .spawn(move || {
                let mut counters: Vec<(Arc<AtomicU64>, u64)> = Vec::new();
                let mut last_flush = std::time::Instant::now();
                let mut on_disk = false;
                let mut written = 0_u64;
                let sync = |sink: &mut Sink, counters: &mut Vec<(Arc<AtomicU64>, u64)>| {
                    for (i, (counter, seen)) in counters.iter_mut().enumerate() {
                        let now = counter.load(Ordering::Relaxed);
                        sink.dropped(i, now - *seen);
                        *seen = now;
                    }
                };
                let mut batch = Vec::new();
                let mut stop = false;
                while !stop {
                    rx.take(&mut batch);
                    for msg in batch.drain(..) {
                        match msg {
                            Msg::Channel(spec, dropped) => {
                                sink.channel(spec);
                                counters.push((dropped, 0));
                            }
                            Msg::Entry(entry) => {
                                sink.write(&entry)?;
                                written += 1;
                            }
                            // What was queued before the stop is written; nothing after.
                            Msg::Stop => stop = true,
                        }
                    }
                    if last_flush.elapsed() >= FLUSH_EVERY {
                        sync(&mut sink, &mut counters);
                        sink.flush()?;
                        last_flush = std::time::Instant::now();
                        if !on_disk && written > 0 {
                            on_disk = true;
                            tracing::info!(file = %path.display(), messages = written, "recording: first chunks on disk (a killed run leaves a file that opens)");
                        }
                    }
                }
                sync(&mut sink, &mut counters);
                sink.finish()
            })?;
        Ok(Recorder {
            tx,
            clock: StampClock::now(),
            options,
            channels: 0,
            dropped: Vec::new(),
            tasks: Vec::new(),
            thread: Some(thread),
        })
    }

    /// The options it records with.
    pub fn options(&self) -> &RecordOptions {
        &self.options
    }

    fn add_channel(&mut self, spec: ChannelSpec) -> Out {
        let dropped = Arc::new(AtomicU64::new(0));
        self.tx.send(Msg::Channel(spec, dropped.clone()));
        let out = Out {
            tx: self.tx.clone(),
            clock: self.clock,
            channel: self.channels,
            dropped: dropped.clone(),
        };
        self.channels += 1;
        self.dropped.push(dropped);
        out
    }

    /// The log channel (`/rosout` in ROS 2 files, `/log` otherwise).
    pub fn log_sink(&mut self) -> LogSink {
        let topic = match self.options.format {
            crate::Format::Ros2 => "/rosout",
            crate::Format::Foxglove => "/log",
        };
        let out = self.add_channel(ChannelSpec {
            topic: topic.into(),
            url: String::new(),
            type_info: TypeInfo::of::<LogRecord>(),
            queue: true,
        });
        LogSink {
            out,
            sequence: Arc::default(),
        }
    }

    /// Taps every property of the agent the selection wants (linked inputs are recorded at
    /// their source; input queues are their source's items); returns how many.
    pub async fn attach(
        &mut self,
        agent: &str,
        blackboard: &Blackboard,
    ) -> Result<usize, BlackboardError> {
        let listing = blackboard.listing().await?;
        let queue_in = PropertyKind::QueueIn.to_string();
        let mut tapped = 0;
        for p in listing.properties {
            if p.link.is_some()
                || p.kind == queue_in
                || !self.options.selection.wants(agent, &p.key)
            {
                continue;
            }
            let tap = blackboard.tap(&p.key).await?;
            let spec = ChannelSpec {
                topic: crate::select::topic(agent, &p.key),
                url: format!("petrel://{agent}/{}", p.key),
                type_info: tap.type_info(),
                queue: matches!(tap, Tap::Queue(_)),
            };
            let out = self.add_channel(spec);
            let task = match tap {
                Tap::Value(tap) => tokio::spawn(record_value(tap, out)),
                Tap::Queue(tap) => tokio::spawn(record_queue(tap, out)),
            };
            self.tasks.push(task);
            tapped += 1;
        }
        Ok(tapped)
    }

    /// Values dropped so far because the writer could not keep up.
    pub fn dropped(&self) -> u64 {
        self.dropped.iter().map(|d| d.load(Ordering::Relaxed)).sum()
    }

    /// Stops the taps, writes what is queued, finishes the file (summary, indexes, drop
    /// counts) and says what was recorded.
    pub async fn finish(mut self) -> io::Result<SinkReport> {
        for task in self.tasks.drain(..) {
            task.abort();
        }
        self.tx.send(Msg::Stop);
        let thread = self.thread.take().expect("finished once");
        tokio::task::spawn_blocking(move || thread.join())
            .await
            .map_err(io::Error::other)?
            .map_err(|_| io::Error::other("the recording thread panicked"))?
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        for task in &self.tasks {
            task.abort();
        }
        self.tx.send(Msg::Stop);
    }
}

async fn record_value(tap: ValueTap, out: Out) {
    let mut last = None;
    loop {
        let (value, version, written) = tap.read();
        if last != Some(version) {
            last = Some(version);
            out.send(value, version, written);
        }
        tap.changed().await;
    }
}

async fn record_queue(mut tap: QueueTap, out: Out) {
    let mut lost = 0;
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
        if !full {
            tap.changed().await;
        }
    }
}
