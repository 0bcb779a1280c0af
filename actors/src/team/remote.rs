//! What a team transport needs from an agent, without the core knowing any transport:
//! the remote links to feed ([`RemoteLinks`]), the agent's properties to publish ([`Tap`]),
//! and the `_team/...` properties that show membership (their types are in `types.rs`).
//!
//! A remote link feeds the input's *own* cell (or, for a queue input, its private queue): an
//! input linked to another agent reads a local copy, exactly as it reads an unlinked input,
//! so modules cannot tell local from remote.

use std::collections::BTreeMap;
use std::marker::PhantomData;
use std::sync::Arc;

use parking_lot::Mutex;
use tokio::sync::watch;
use tokio::time::Instant;

use super::config::Qos;
use super::types::{LinkStatus, OutboxStatus};
use crate::cell::{cause, Endpoint, Signal};
use crate::queue::{QueueCore, QueueItem, ReaderEndpoint};
use crate::url::PropertyUrl;
use crate::value::{AnyValue, TypeInfo};

/// Carries writes to other agents' properties; the team transport installs one in the
/// agent's [`Blackboard`](crate::Blackboard) (see `Blackboard::set_remote_writer`), so modules,
/// contexts and tools write `petrel://other/...` with the ordinary `Blackboard::set`.
pub trait RemoteWriter: Send + Sync {
    /// Sets `url` (another agent's `params/` or `control/` property) to the JSON `value`;
    /// the error says why the owner refused, or that nobody answered.
    fn set_json(
        &self,
        url: PropertyUrl,
        json: Vec<u8>,
    ) -> std::pin::Pin<Box<dyn std::future::Future<Output = Result<(), String>> + Send>>;
}

/// The module of the runtime's team properties.
pub const TEAM_MODULE: &str = "_team";

/// Where received values of a remote link go.
#[derive(Clone)]
pub enum RemoteFeed {
    /// A value input's own cell.
    Value(RemoteValue),
    /// A queue input's private queue.
    Queue(RemoteQueue),
}

impl RemoteFeed {
    /// The input's type: what received samples must decode to.
    pub fn type_info(&self) -> TypeInfo {
        match self {
            RemoteFeed::Value(v) => v.ep.type_info(),
            RemoteFeed::Queue(q) => q.core.type_info,
        }
    }
}

/// The local copy of a remote value.
#[derive(Clone)]
pub struct RemoteValue {
    pub(crate) ep: Arc<Endpoint>,
}

impl RemoteValue {
    /// Stores a received value (of the input's type: decode it with the feed's [`TypeInfo`])
    /// and wakes the input's watchers.
    pub fn write(&self, value: AnyValue, stamp: Instant) {
        debug_assert!(self.ep.type_info().is_type_of(value.as_ref()));
        self.ep.own.write(value, stamp);
    }
}

/// The local end of a remote queue.
#[derive(Clone)]
pub struct RemoteQueue {
    pub(crate) core: Arc<QueueCore>,
}

impl RemoteQueue {
    /// Appends a received item for the input's reader (who counts what it lags behind).
    pub fn push(&self, value: AnyValue, stamp: Instant) {
        debug_assert!(self.core.type_info.is_type_of(value.as_ref()));
        self.core.push(value, stamp);
    }
}

/// Writes one status property owned by the team transport: a link's `stats/links/<input>`
/// ([`StatusWriter`]) or a module's `stats/outbox` ([`OutboxWriter`]).
pub struct StatWriter<T> {
    pub(crate) ep: Arc<Endpoint>,
    _status: PhantomData<fn(T)>,
}

impl<T> StatWriter<T> {
    pub(crate) fn new(ep: Arc<Endpoint>) -> Self {
        StatWriter {
            ep,
            _status: PhantomData,
        }
    }
}

// Derived `Clone` would ask `T: Clone` for nothing: only the endpoint is cloned.
impl<T> Clone for StatWriter<T> {
    fn clone(&self) -> Self {
        StatWriter::new(self.ep.clone())
    }
}

impl<T: Clone + Default + Send + Sync + 'static> StatWriter<T> {
    /// Publishes the status.
    pub fn set(&self, status: T) {
        self.ep.write(Arc::new(status));
    }

    /// The status as last published.
    pub fn get(&self) -> T {
        self.ep
            .value()
            .downcast_ref::<T>()
            .cloned()
            .unwrap_or_default()
    }
}

/// Writes one link's `stats/links/<input>`.
pub type StatusWriter = StatWriter<LinkStatus>;

/// Writes a module's `stats/outbox`.
pub type OutboxWriter = StatWriter<OutboxStatus>;

/// A module's outbox as the team transport sends it: the tap on its `out/outbox` (attached as
/// soon as the module is declared on an agent with a team, so nothing pushed before the
/// transport starts is missed) and the writer of its `stats/outbox`.
pub struct Outbox {
    /// The module.
    pub module: String,
    /// Its `stats/outbox`.
    pub status: OutboxWriter,
    /// Its `out/outbox` items.
    pub tap: QueueTap,
}

/// One input of this agent linked to another agent's property.
#[derive(Clone)]
pub struct RemoteLink {
    /// The input, `module/path`.
    pub input: String,
    /// The remote property, with its agent.
    pub source: PropertyUrl,
    /// How its values travel.
    pub qos: Qos,
    /// Where received values go.
    pub feed: RemoteFeed,
    /// The link's `stats/links/<input>`.
    pub status: StatusWriter,
}

/// The remote links of one agent, shared by its registry (which adds and removes them as
/// links change) and the team transport (which feeds them).
pub struct RemoteLinks {
    links: Mutex<BTreeMap<String, RemoteLink>>,
    generation: watch::Sender<u64>,
}

impl Default for RemoteLinks {
    fn default() -> Self {
        RemoteLinks {
            links: Mutex::default(),
            generation: watch::channel(0).0,
        }
    }
}

impl RemoteLinks {
    /// Every remote link, by input.
    pub fn links(&self) -> Vec<RemoteLink> {
        self.links.lock().values().cloned().collect()
    }

    /// How many remote links there are.
    pub fn len(&self) -> usize {
        self.links.lock().len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// A receiver that sees a new generation whenever links are added or removed.
    pub fn watch(&self) -> watch::Receiver<u64> {
        self.generation.subscribe()
    }

    pub(crate) fn insert(&self, link: RemoteLink) {
        self.links.lock().insert(link.input.clone(), link);
        self.generation.send_modify(|g| *g += 1);
    }

    pub(crate) fn remove(&self, input: &str) {
        if self.links.lock().remove(input).is_some() {
            self.generation.send_modify(|g| *g += 1);
        }
    }

    pub(crate) fn remove_module(&self, module: &str) {
        let prefix = format!("{module}/");
        let mut links = self.links.lock();
        let before = links.len();
        links.retain(|k, _| !k.starts_with(&prefix));
        if links.len() != before {
            self.generation.send_modify(|g| *g += 1);
        }
    }
}

/// A running agent's property, watched by a team transport that publishes it.
pub enum Tap {
    /// A value property: publish its changes.
    Value(ValueTap),
    /// An output queue: publish its items.
    Queue(QueueTap),
}

impl Tap {
    /// The property's value (or item) type.
    pub fn type_info(&self) -> TypeInfo {
        match self {
            Tap::Value(v) => v.ep.type_info(),
            Tap::Queue(q) => q.reader.type_info,
        }
    }
}

/// Watches a value property; unsubscribes when dropped.
pub struct ValueTap {
    pub(super) ep: Arc<Endpoint>,
    pub(super) signal: Arc<Signal>,
}

impl ValueTap {
    pub(crate) fn new(ep: Arc<Endpoint>) -> Self {
        let signal = Arc::new(Signal::default());
        ep.subscribe(&signal);
        ValueTap { ep, signal }
    }

    /// The current value, its version and write time.
    pub fn read(&self) -> (AnyValue, u64, Instant) {
        // Re-arms a tap woken through a `TapReady` before the read, so a later write queues it again.
        self.signal.take();
        let slot = self.ep.read();
        (slot.value, slot.version, slot.written)
    }

    /// The current version, without reading the value.
    pub fn version(&self) -> u64 {
        self.ep.version()
    }

    /// Waits for the next change (at once if it changed since the last call).
    pub async fn changed(&self) {
        self.signal.wait().await;
    }
}

impl Drop for ValueTap {
    fn drop(&mut self) {
        self.ep.unsubscribe(&self.signal, cause::CHANGE);
    }
}

/// Reads every item of an output queue as one more reader; detaches when dropped.
pub struct QueueTap {
    pub(super) reader: Arc<ReaderEndpoint>,
    pub(super) signal: Arc<Signal>,
    buffer: Vec<QueueItem>,
}

impl QueueTap {
    pub(crate) fn new(reader: Arc<ReaderEndpoint>) -> Self {
        let signal = Arc::new(Signal::default());
        reader.subscribe(&signal);
        QueueTap {
            reader,
            signal,
            buffer: Vec::new(),
        }
    }

    /// Takes up to `max` new items (sequence number, push time, value), oldest first; they
    /// count as consumed at once. `lost` says how many this tap missed by lagging so far.
    pub fn take(&mut self, max: usize) -> Vec<(u64, Instant, AnyValue)> {
        // Re-arms a tap woken through a `TapReady`, as in `ValueTap::read`.
        self.signal.take();
        self.buffer.clear();
        self.reader.take(max, &mut self.buffer);
        self.reader.ack();
        self.buffer
            .drain(..)
            .map(|i| (i.seq, i.stamp, i.value))
            .collect()
    }

    /// Items this tap lost by lagging more than the queue's capacity.
    pub fn lost(&self) -> i64 {
        *self
            .reader
            .dropped
            .value()
            .downcast_ref::<i64>()
            .unwrap_or(&0)
    }

    /// Waits until items arrive (at once if some arrived since the last call).
    pub async fn changed(&self) {
        self.signal.wait().await;
    }
}
