//! Typed handles a module uses to read and write its properties and queues.
//!
//! Handles point straight at the blackboard's shared cells: reading or writing costs a short
//! lock, never a message to the blackboard actor. A handle stays valid across relinks: an
//! input reads whatever its link points to at the time of the read.

use std::marker::PhantomData;
use std::ops::Deref;
use std::sync::Arc;

use tokio::time::Instant;

use crate::cell::{Endpoint, Signal};
use crate::queue::{QueueCore, QueueItem, ReaderEndpoint};
use crate::step_clock::StepClock;
use crate::types::PropertyType;
use crate::value::AnyValue;

fn downcast<T: PropertyType>(value: AnyValue) -> Arc<T> {
    // Ports and links are type-checked when declared and linked, so a cell behind a
    // `T` handle always holds a `T`.
    value
        .downcast::<T>()
        .unwrap_or_else(|_| unreachable!("property holds a {}", T::TYPE_NAME))
}

/// Reads `ep` as a typed sample.
fn sample<T: PropertyType>(ep: &Endpoint) -> Sample<T> {
    let slot = ep.read();
    Sample {
        value: downcast(slot.value),
        version: slot.version,
        written: slot.written,
    }
}

/// A value read from a property, with its version and write time.
#[derive(Debug, Clone)]
pub struct Sample<T: ?Sized> {
    /// The value, shared with the blackboard.
    pub value: Arc<T>,
    /// Number of writes to the cell read since it was declared.
    pub version: u64,
    /// When the value was written.
    pub written: Instant,
}

impl<T: ?Sized> Deref for Sample<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.value
    }
}

/// The read methods every typed value handle has, over its endpoint `ep`.
macro_rules! read_methods {
    ($handle:ident) => {
        impl<T: PropertyType> $handle<T> {
            /// The current value (of the link target, if linked). Copies no data, only a pointer.
            #[inline]
            pub fn get(&self) -> Arc<T> {
                downcast(self.ep.value())
            }

            /// The current value with its version and write time.
            pub fn read(&self) -> Sample<T> {
                sample(&self.ep)
            }

            /// The property's `module/path`.
            pub fn key(&self) -> &str {
                &self.ep.key
            }

            /// How many times the value seen through this handle was written, read without a
            /// lock: a cheap "did it change?" check before reading it.
            #[inline]
            pub fn version(&self) -> u64 {
                self.ep.version()
            }
        }

        impl<T: PropertyType + Copy> $handle<T> {
            /// The current value, copied out (for small `Copy` values such as `f64`).
            #[inline]
            pub fn value(&self) -> T {
                self.ep.with_value(|v| match v.downcast_ref::<T>() {
                    Some(v) => *v,
                    None => unreachable!("property holds a {}", T::TYPE_NAME),
                })
            }
        }
    };
}

/// Read access to an input (`in/...`) or parameter (`params/...`).
pub struct Input<T> {
    pub(crate) ep: Arc<Endpoint>,
    _t: PhantomData<fn() -> T>,
}

/// A parameter handle: read-only for the module, set by config, links, tools or contexts.
pub type Param<T> = Input<T>;

impl<T: PropertyType> Input<T> {
    pub(crate) fn new(ep: Arc<Endpoint>) -> Self {
        Input {
            ep,
            _t: PhantomData,
        }
    }
}

read_methods!(Input);

/// Read and write access to an output (`out/...`) or state (`state/...`).
pub struct Output<T> {
    pub(crate) ep: Arc<Endpoint>,
    clock: Arc<StepClock>,
    _t: PhantomData<fn() -> T>,
}

/// A state handle: like an output, but meant for what the module must find again after a restart.
pub type State<T> = Output<T>;

impl<T: PropertyType> Output<T> {
    pub(crate) fn new(ep: Arc<Endpoint>, clock: Arc<StepClock>) -> Self {
        Output {
            ep,
            clock,
            _t: PhantomData,
        }
    }

    /// Publishes a new value and wakes every module watching it. The value is stamped with the
    /// module's step time ([`Context::now`](crate::Context::now)) during a step, else with the
    /// current time.
    #[inline]
    pub fn set(&self, value: T) {
        self.trace_write(&value);
        self.ep.write_at(Arc::new(value), self.clock.now())
    }

    /// Publishes a value that describes the world at `stamp`, earlier than the step's time:
    /// a result computed from a queue item keeps the item's [`stamp`](Item::stamp), as a ROS
    /// node copies its input's header stamp, so that readers can pair it with what held then
    /// (where the robot was when the camera took the frame). A `stamp` later than the step's
    /// time is written as the step's time: nothing is measured after it is published.
    pub fn set_at(&self, value: T, stamp: Instant) {
        self.trace_write(&value);
        self.ep
            .write_at(Arc::new(value), stamp.min(self.clock.now()))
    }

    #[inline]
    fn trace_write(&self, value: &T) {
        if tracing::enabled!(tracing::Level::TRACE) {
            let shown = self
                .ep
                .type_info()
                .short(&(Arc::new(value.clone()) as AnyValue));
            tracing::trace!(property = %self.ep.key, value = %shown, "write");
        }
    }

    /// Publishes an already shared value like [`set`](Self::set) and returns the value it
    /// replaced. A writer that publishes a large value often can keep the returned one and,
    /// once no reader holds it ([`Arc::get_mut`]), fill it in place for its next write
    /// instead of allocating a new value (copy-on-write with two buffers).
    pub fn swap(&self, value: Arc<T>) -> Arc<T> {
        if tracing::enabled!(tracing::Level::TRACE) {
            let shown = self.ep.type_info().short(&(value.clone() as AnyValue));
            tracing::trace!(property = %self.ep.key, value = %shown, "write");
        }
        downcast(self.ep.replace_at(value, self.clock.now()))
    }
}

impl<T: PropertyType + PartialEq> Output<T> {
    /// Publishes `value` like [`set`](Self::set) unless the output holds an equal value
    /// already; returns whether it wrote. For an output computed at every step that changes
    /// seldom (a flag, a quality, a count): its watchers are woken, and a recording grows, only
    /// when there is news. A NaN is never equal to what it replaces, so it is always written.
    #[inline]
    pub fn set_if_changed(&self, value: T) -> bool {
        let same = self
            .ep
            .with_value(|v| v.downcast_ref::<T>() == Some(&value));
        if !same {
            self.set(value);
        }
        !same
    }
}

read_methods!(Output);

/// A handle to any value property of a running agent, from outside its modules (tools, tests,
/// benchmarks); see [`Blackboard::handle`](crate::Blackboard::handle).
pub struct PropertyHandle<T> {
    ep: Arc<Endpoint>,
    signal: Arc<Signal>,
    _t: PhantomData<fn() -> T>,
}

impl<T: PropertyType> PropertyHandle<T> {
    pub(crate) fn new(ep: Arc<Endpoint>) -> Self {
        let signal = Arc::new(Signal::default());
        ep.subscribe(&signal);
        PropertyHandle {
            ep,
            signal,
            _t: PhantomData,
        }
    }

    /// Writes a value (to the link target, if linked) and wakes its watchers.
    #[inline]
    pub fn set(&self, value: T) {
        self.ep.write(Arc::new(value))
    }

    /// Waits until the value seen through this handle changes (returns at once if it changed
    /// since the last call).
    pub async fn changed(&self) {
        self.signal.wait().await;
    }
}

read_methods!(PropertyHandle);

/// An untyped handle to a value property, for code that learns property types at run time
/// (expression evaluation, context rules, plan bindings); see
/// [`Blackboard::any_handle`](crate::Blackboard::any_handle). A module can wait on it with
/// [`Schedule::on_change`](crate::Schedule::on_change).
#[derive(Clone)]
pub struct AnyHandle {
    pub(crate) ep: Arc<Endpoint>,
    pub(crate) rule: Arc<WriteRule>,
    /// The rule asks nothing beyond the type (settable, no range): the usual write, on the
    /// reaction path of missions and contexts, checks one flag instead of reading the rule.
    pub(crate) plain: bool,
}

/// What a write through an [`AnyHandle`] must respect, from the property's declaration: the
/// same checks as a config value or `petrel set` (see [`Registry::set`](crate::Registry)), so
/// that a plan binding or a context rule cannot write what a person could not.
pub(crate) struct WriteRule {
    pub kind: crate::PropertyKind,
    pub range: Option<crate::range::RangeCheck>,
    /// The property's one-line description, for the out-of-range message.
    pub doc: String,
    /// Its module reads it only when it starts: every write through a handle is refused
    /// (handles write while the agent runs; configs and snapshots go through the registry).
    pub read_at_start: bool,
    /// Its rule on whole values, if any.
    pub shape: Option<crate::ports::Shape>,
}

impl WriteRule {
    /// What a property of `kind` with `range` refuses of `value` (its type already checked):
    /// the one check of [`AnyHandle::check`] and [`Registry::check_set`](crate::Registry).
    pub fn check(
        key: &str,
        kind: crate::PropertyKind,
        range: Option<&crate::range::RangeCheck>,
        shape: Option<&crate::ports::Shape>,
        doc: &str,
        value: &AnyValue,
    ) -> Result<(), crate::BlackboardError> {
        if !kind.settable() {
            let key = key.to_string();
            return Err(crate::BlackboardError::NotSettable { key, kind });
        }
        if let Some((shape, refused)) = shape.and_then(|s| Some((s, (s.refuses)(value)?))) {
            return Err(crate::BlackboardError::OutOfRange {
                key: key.to_string(),
                value: refused,
                range: shape.expected.to_string(),
                doc: doc.to_string(),
            });
        }
        match range.and_then(|check| Some((check, check.refuses(value)?))) {
            Some((check, refused)) => Err(crate::BlackboardError::OutOfRange {
                key: key.to_string(),
                value: refused,
                range: check.expected(),
                doc: doc.to_string(),
            }),
            None => Ok(()),
        }
    }
}

impl AnyHandle {
    /// The property's value type.
    pub fn type_info(&self) -> crate::TypeInfo {
        self.ep.type_info()
    }

    /// The current value (of the link target, if linked).
    pub fn value(&self) -> AnyValue {
        self.ep.value()
    }

    /// The current value with its version and write time.
    pub fn read(&self) -> Sample<dyn std::any::Any + Send + Sync> {
        let slot = self.ep.read();
        Sample {
            value: slot.value,
            version: slot.version,
            written: slot.written,
        }
    }

    /// The version of the current value (writes so far), read without locking the value:
    /// a cheap "did it change?" check before [`read`](Self::read).
    pub fn version(&self) -> u64 {
        self.ep.version()
    }

    /// The current value, if it is a `T`.
    pub fn get<T: PropertyType>(&self) -> Option<Arc<T>> {
        self.ep.value().downcast::<T>().ok()
    }

    /// Writes a value, which must have the property's type.
    pub fn set(&self, value: AnyValue) -> Result<(), crate::BlackboardError> {
        self.set_at(value, Instant::now())
    }

    /// Like [`set`](Self::set), with the value stamped `written` rather than with a clock read:
    /// for a module that writes through untyped handles during a step, so that those writes
    /// carry the step's time ([`Context::now`](crate::Context::now)) like its typed outputs'.
    pub fn set_at(&self, value: AnyValue, written: Instant) -> Result<(), crate::BlackboardError> {
        if !(self.plain && self.ep.type_info().is_type_of(value.as_ref())) {
            self.check(&value)?;
        }
        self.ep.write_at(value, written);
        Ok(())
    }

    /// Whether [`set`](Self::set) would take `value`: its type, the property's kind
    /// (`stats/...` and queues are written only by the runtime and their module) and a
    /// parameter's range (a finite number at least, for every `f64` parameter).
    pub fn check(&self, value: &AnyValue) -> Result<(), crate::BlackboardError> {
        let key = || self.ep.key.to_string();
        if !self.ep.type_info().is_type_of(value.as_ref()) {
            return Err(crate::BlackboardError::BadValue {
                key: key(),
                expected: self.ep.type_info().name(),
                reason: "got a value of another type".into(),
            });
        }
        let rule = &*self.rule;
        if rule.read_at_start {
            return Err(crate::BlackboardError::ReadAtStart { key: key() });
        }
        WriteRule::check(
            &self.ep.key,
            rule.kind,
            rule.range.as_ref(),
            rule.shape.as_ref(),
            &rule.doc,
            value,
        )
    }

    /// The property's `module/path`.
    pub fn key(&self) -> &str {
        &self.ep.key
    }
}

/// One queue item: the value, shared by every reader, with its sequence number and push time.
#[derive(Debug, Clone)]
pub struct Item<T> {
    /// Position in the queue's stream, from 0; gaps mean items this reader lost.
    pub seq: u64,
    /// When the item was pushed.
    pub stamp: Instant,
    /// The payload, shared (never copied) between readers.
    pub value: Arc<T>,
}

impl<T> Deref for Item<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.value
    }
}

/// The producing side of an `out/...` queue.
pub struct QueueWriter<T> {
    pub(crate) core: Arc<QueueCore>,
    clock: Arc<StepClock>,
    _t: PhantomData<fn(T)>,
}

impl<T: PropertyType> QueueWriter<T> {
    pub(crate) fn new(core: Arc<QueueCore>, clock: Arc<StepClock>) -> Self {
        QueueWriter {
            core,
            clock,
            _t: PhantomData,
        }
    }

    /// Appends an item and wakes every subscribed reader. Like a value, the item is stamped
    /// with the module's step time during a step, else with the current time.
    #[inline]
    pub fn push(&self, value: T) {
        self.push_shared(Arc::new(value))
    }

    /// Appends an already shared item without copying it.
    pub fn push_shared(&self, value: Arc<T>) {
        self.core.push(value, self.clock.now())
    }

    /// Appends the item `make` builds, only if the queue has a reader (a module linked to it,
    /// a recorder's or a console's tap, an expression): items nobody reads are dropped, so
    /// they need not be built.
    pub fn push_with(&self, make: impl FnOnce() -> T) {
        self.core
            .push_with(|| Arc::new(make()) as AnyValue, self.clock.now())
    }

    /// Items held for readers that have not consumed them yet.
    pub fn len(&self) -> usize {
        self.core.len()
    }

    /// Whether every reader has consumed every item.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The queue's `module/path`.
    pub fn key(&self) -> &str {
        &self.core.key
    }
}

/// The consuming side of an `in/...` queue input: sees every item of the queue it is linked to,
/// once, in order, from the moment it was linked (again after a module failure, for items not
/// yet acknowledged: see [`ack`](QueueReader::ack)).
pub struct QueueReader<T> {
    pub(crate) reader: Arc<ReaderEndpoint>,
    _t: PhantomData<fn() -> T>,
}

impl<T: PropertyType> QueueReader<T> {
    pub(crate) fn new(reader: Arc<ReaderEndpoint>) -> Self {
        QueueReader {
            reader,
            _t: PhantomData,
        }
    }

    /// The next unread item, if any.
    pub fn try_next(&self) -> Option<Item<T>> {
        let mut out = Vec::with_capacity(1);
        self.reader.take(1, &mut out);
        out.pop().map(convert)
    }

    /// Every unread item, oldest first.
    pub fn drain(&self) -> Vec<Item<T>> {
        self.drain_at_most(usize::MAX)
    }

    /// Up to `max` unread items, oldest first.
    pub fn drain_at_most(&self, max: usize) -> Vec<Item<T>> {
        let mut out = Vec::new();
        self.reader.take(max, &mut out);
        out.into_iter().map(convert).collect()
    }

    /// How many items wait to be read.
    pub fn pending(&self) -> usize {
        self.reader.pending()
    }

    /// Acknowledges every item taken so far, now.
    ///
    /// The runtime acknowledges what a step took when the step returns `Ok`, and a restarted
    /// module is given again what its failed instance took but had not acknowledged (at least
    /// once). A module that records in its state which items it has processed (e.g. the last
    /// sequence number) and acknowledges right after recording them processes each item
    /// exactly once across failures.
    pub fn ack(&self) {
        self.reader.ack()
    }

    /// How many items this reader lost because it lagged more than the queue's capacity.
    pub fn dropped(&self) -> i64 {
        *downcast::<i64>(self.reader.dropped.value())
    }

    /// The input's `module/path`.
    pub fn key(&self) -> &str {
        &self.reader.key
    }
}

fn convert<T: PropertyType>(item: QueueItem) -> Item<T> {
    Item {
        seq: item.seq,
        stamp: item.stamp,
        value: downcast(item.value),
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;
    use crate::TypeInfo;

    #[tokio::test(start_paused = true)]
    async fn a_value_written_at_an_earlier_time_keeps_it_and_a_later_one_gets_the_steps() {
        let ep = Endpoint::new("m/out/x", TypeInfo::of::<f64>(), Arc::new(0.0));
        let clock = Arc::new(StepClock::default());
        let out = Output::<f64>::new(ep, clock.clone());
        let taken = Instant::now();
        tokio::time::advance(Duration::from_millis(70)).await;
        clock.begin();
        let step = clock.now();
        out.set_at(1.0, taken);
        assert_eq!((*out.read().value, out.read().written), (1.0, taken));
        out.set_at(2.0, step + Duration::from_millis(5));
        assert_eq!(out.read().written, step, "not after the step's time");
        out.set(3.0);
        assert_eq!(out.read().written, step);
        clock.end();
    }

    #[test]
    fn set_if_changed_writes_news_only() {
        let ep = Endpoint::new("m/out/x", TypeInfo::of::<f64>(), Arc::new(0.0));
        let out = Output::<f64>::new(ep, Arc::new(StepClock::default()));
        let writes: Vec<bool> = [0.0, 1.0, 1.0, 2.0, f64::NAN, f64::NAN, 2.0]
            .into_iter()
            .map(|v| out.set_if_changed(v))
            .collect();
        assert_eq!(writes, [false, true, false, true, true, true, true]);
        assert_eq!(out.version(), 5, "a write for every `true`");
        assert_eq!(out.value(), 2.0);
    }
}
