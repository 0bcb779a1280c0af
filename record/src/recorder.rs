//! The recorder shell: taps on an agent's blackboard, read by one drain task per agent when
//! they are marked ready, feed a bounded channel that a writer thread drains into a [`Sink`]. Modules never wait for it: a tap that finds the channel full
//! drops the value and counts it (per channel, written in the file's summary), and a queue tap
//! that lags behind its queue's capacity loses the oldest items, counted the same way.

use std::io;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use parking_lot::Mutex;
use petrel_actors::{Blackboard, BlackboardError, TypeInfo};

use crate::backlog::{Backlog, Msg, StampClock};
use crate::encode::LogRecord;
use crate::select::RecordOptions;
use crate::sink::{ChannelSpec, Entry, Sink, SinkReport};
use crate::taps::{Channels, Out};

/// How often the writer closes its chunk, so a killed run loses at most this much.
pub const FLUSH_EVERY: Duration = Duration::from_secs(1);

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
    options: RecordOptions,
    channels: Arc<Mutex<Channels>>,
    thread: Option<JoinHandle<io::Result<SinkReport>>>,
}

impl Recorder {
    /// Creates the first file and starts the writer thread.
    pub fn start(options: RecordOptions) -> io::Result<Recorder> {
        let mut sink = Sink::create_compressed(
            &options.path,
            options.format,
            options.compression,
            options.split,
        )?;
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
                let mut spent = Vec::new();
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
                                // Freed on an agent's thread (see `Backlog::give_back`).
                                spent.push(entry.value);
                            }
                            // What was queued before the stop is written; nothing after.
                            Msg::Stop => stop = true,
                        }
                    }
                    rx.give_back(&mut spent);
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
            channels: Arc::new(Mutex::new(Channels::new(tx.clone(), StampClock::now()))),
            tx,
            options,
            thread: Some(thread),
        })
    }

    /// The options it records with.
    pub fn options(&self) -> &RecordOptions {
        &self.options
    }

    /// The log channel (`/rosout` in ROS 2 files, `/log` otherwise).
    pub fn log_sink(&mut self) -> LogSink {
        let topic = crate::select::log_topic(self.options.format);
        let out: Out = self.channels.lock().channel(ChannelSpec {
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

    /// Records every property of the agent the selection wants (linked inputs are recorded at
    /// their source; input queues are their source's items), and those of modules added
    /// while it runs; returns how many are recorded now. Attached before the agent's modules
    /// start ([`petrel_actors::Agent::prepare`]), it misses none of their writes.
    pub async fn attach(
        &mut self,
        agent: &str,
        blackboard: &Blackboard,
    ) -> Result<usize, BlackboardError> {
        let selection = self.options.selection.clone();
        let name = agent.to_string();
        let taps = blackboard
            .watch_taps(move |key| selection.wants(&name, key))
            .await?;
        // What the agent holds now is tapped by the time `watch_taps` answers.
        let tapped = Channels::drain(&self.channels, agent, taps, blackboard);
        Ok(tapped)
    }

    /// Values dropped so far because the writer could not keep up.
    pub fn dropped(&self) -> u64 {
        let channels = self.channels.lock();
        channels
            .dropped
            .iter()
            .map(|d| d.load(Ordering::Relaxed))
            .sum()
    }

    /// Stops the taps (each drain sends what was written up to now first), writes what is queued,
    /// finishes the file (summary, indexes, drop counts) and says what was recorded. The agents
    /// may be stopped first ([`Agent::stop`](petrel_actors::Agent::stop)): a drain whose agent's
    /// thread ended has sent what the agent wrote last as it ended.
    pub async fn finish(mut self) -> io::Result<SinkReport> {
        let drains = self.channels.lock().close();
        for drain in drains {
            // Each sends what is left and ends; a drain that panicked has nothing more to send.
            let _ = drain.await;
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
        for drain in self.channels.lock().close() {
            drain.abort();
        }
        self.tx.send(Msg::Stop);
    }
}
