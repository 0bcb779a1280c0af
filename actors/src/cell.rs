//! Shared property storage: the cells the blackboard owns and modules read and write directly.
//!
//! The blackboard actor owns the *structure* (which cells exist, what links to what); values
//! move through these cells without any actor round trip. A write replaces the cell's value
//! under a short lock and raises the [`Signal`] of every module watching the cell.

use std::sync::atomic::{AtomicBool, AtomicPtr, AtomicU32, AtomicU64, AtomicU8, Ordering};
use std::sync::Arc;
use std::task::Poll;

use arc_swap::ArcSwap;
use atomic_waker::AtomicWaker;
use parking_lot::{Mutex, RwLock};
use tokio::time::Instant;

use crate::loop_watch::Hop;
use crate::team::TapReady;
use crate::value::{AnyValue, TypeInfo};

/// Why a module woke up; a set of these is reported to the module's step.
pub(crate) mod cause {
    pub const PERIOD: u8 = 1;
    pub const CHANGE: u8 = 2;
    pub const ITEMS: u8 = 4;
    pub const TIMEOUT: u8 = 8;
    /// The module's `enabled` changed.
    pub const ENABLED: u8 = 16;
    /// The module is asked to stop.
    pub const STOP: u8 = 32;
    /// Causes that make a module step.
    pub const STEPS: u8 = PERIOD | CHANGE | ITEMS | TIMEOUT;
}

/// The wake-up signal of one module: one per module name, kept across restarts.
///
/// Raising it never blocks and is never lost: if the module is busy, the next wait returns at once.
pub(crate) struct Signal {
    /// Raised since the waiter last woke: its next wait returns at once (a permit, like
    /// `Notify`'s).
    notified: AtomicBool,
    /// The one task waiting on this signal. A signal has a single waiter (its module's step
    /// loop, or one handle's `changed`), so a waker slot does what `tokio::sync::Notify` did
    /// without its waiter list and the mutex around it (two locks per hand-over; BENCHMARKS.md,
    /// "`caterpillar_ring`, where a hand-over goes").
    waker: AtomicWaker,
    causes: AtomicU8,
    /// Step causes are recorded without waking the module (it is disabled): a write then
    /// wakes only the modules that will step, and the recorded causes make the module step
    /// when it is enabled again.
    quiet: AtomicBool,
    /// The longest chain of steps that led to the data raised since the last step, and whose
    /// write ended it: a packed [`Hop`] (see [`loop_watch`](crate::loop_watch)).
    hops: AtomicU64,
    /// Names this signal in a [`Hop`].
    id: u32,
    /// Set for a tap drained with many others: a raise queues this id on the shared list
    /// instead of waking a waiter of its own.
    ready: Option<(TapReady, usize)>,
}

impl Default for Signal {
    fn default() -> Self {
        static NEXT_ID: AtomicU32 = AtomicU32::new(1);
        Signal {
            notified: AtomicBool::new(false),
            waker: AtomicWaker::new(),
            causes: AtomicU8::new(0),
            quiet: AtomicBool::new(false),
            hops: AtomicU64::new(0),
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            ready: None,
        }
    }
}

impl Signal {
    /// A tap's signal that queues `id` on `ready` (see [`TapReady`]).
    pub fn marking(ready: TapReady, id: usize) -> Self {
        Signal {
            ready: Some((ready, id)),
            ..Signal::default()
        }
    }

    pub fn raise(&self, cause: u8) {
        if let Some((ready, id)) = &self.ready {
            // Only the first raise since the consumer took the causes (read the tap) queues it.
            if self.causes.fetch_or(cause, Ordering::AcqRel) == 0 {
                ready.mark(*id);
            }
            return;
        }
        if cause & (cause::CHANGE | cause::ITEMS) != 0 {
            if let Some(step) = crate::loop_watch::current() {
                let hop = Hop {
                    hops: step.hops.saturating_add(1),
                    waker: step.waker,
                };
                self.hops.fetch_max(hop.pack(), Ordering::Relaxed);
            }
        }
        self.causes.fetch_or(cause, Ordering::Release);
        if cause & !cause::STEPS == 0 && self.quiet.load(Ordering::Acquire) {
            return;
        }
        self.notified.store(true, Ordering::Release);
        self.waker.wake();
    }

    /// Whether step causes should wait, recorded, instead of waking the module.
    pub fn set_quiet(&self, quiet: bool) {
        self.quiet.store(quiet, Ordering::Release);
    }

    /// Waits for the next raise and returns the causes gathered since the last call.
    pub async fn wait(&self) -> u8 {
        std::future::poll_fn(|cx| {
            if self.take_notified() {
                return Poll::Ready(());
            }
            // Registered before the second look: a raise in between wakes this waker.
            self.waker.register(cx.waker());
            match self.take_notified() {
                true => Poll::Ready(()),
                false => Poll::Pending,
            }
        })
        .await;
        self.take()
    }

    /// Takes the permit a raise left, if any.
    fn take_notified(&self) -> bool {
        self.notified.load(Ordering::Relaxed) && self.notified.swap(false, Ordering::Acquire)
    }

    pub fn take(&self) -> u8 {
        self.causes.swap(0, Ordering::Acquire)
    }

    /// Takes the property changes raised since the last take, leaving every other cause;
    /// whether there were any (see [`Context::settle`](crate::Context::settle)).
    pub fn take_changes(&self) -> bool {
        self.causes.fetch_and(!cause::CHANGE, Ordering::AcqRel) & cause::CHANGE != 0
    }

    /// Whether property changes were raised since the causes were last taken.
    pub fn changes_pending(&self) -> bool {
        self.causes.load(Ordering::Acquire) & cause::CHANGE != 0
    }

    /// Whether step causes wait to be taken: the module will step again at once.
    pub fn pending(&self) -> bool {
        self.causes.load(Ordering::Acquire) & cause::STEPS != 0
    }

    /// The longest chain that led to the data raised since the last call (`hops` 0 when no
    /// step wrote it), and starts again.
    pub fn take_hop(&self) -> Hop {
        Hop::unpack(self.hops.swap(0, Ordering::Relaxed))
    }

    /// Names this signal (and the module it wakes) in a [`Hop`].
    pub fn id(&self) -> u32 {
        self.id
    }
}

/// A value with its version (writes since declaration) and write time.
#[derive(Clone)]
pub(crate) struct Slot {
    pub value: AnyValue,
    pub version: u64,
    pub written: Instant,
}

/// The storage of one property.
pub(crate) struct Cell {
    pub type_info: TypeInfo,
    slot: RwLock<Slot>,
    /// The slot's version, readable without the lock (for cheap "did it change?" checks).
    version: AtomicU64,
    /// Signals to raise on a write, each with the cause its subscriber asked for.
    watchers: ArcSwap<Vec<(Arc<Signal>, u8)>>,
}

impl Cell {
    pub fn new(type_info: TypeInfo, value: AnyValue) -> Arc<Self> {
        Arc::new(Cell {
            type_info,
            version: AtomicU64::new(0),
            slot: RwLock::new(Slot {
                value,
                version: 0,
                written: Instant::now(),
            }),
            watchers: ArcSwap::from_pointee(Vec::new()),
        })
    }

    pub fn read(&self) -> Slot {
        self.slot.read().clone()
    }

    pub fn value(&self) -> AnyValue {
        self.slot.read().value.clone()
    }

    /// Calls `f` on the value under the read lock, without taking a reference to it: no
    /// reference count changes hands between the writer's and the readers' cores.
    #[inline]
    pub fn with_value<R>(&self, f: impl FnOnce(&AnyValue) -> R) -> R {
        f(&self.slot.read().value)
    }

    pub fn version(&self) -> u64 {
        self.version.load(Ordering::Acquire)
    }

    pub fn write(&self, value: AnyValue, written: Instant) {
        // The previous value (maybe a large image) is freed outside the lock.
        drop(self.replace(value, written));
    }

    /// Like [`write`](Self::write), returning the value it replaced (for a writer that reuses
    /// it once no reader holds it).
    pub fn replace(&self, value: AnyValue, written: Instant) -> AnyValue {
        let old = {
            let mut slot = self.slot.write();
            slot.version += 1;
            self.version.store(slot.version, Ordering::Release);
            slot.written = written;
            std::mem::replace(&mut slot.value, value)
        };
        for (watcher, cause) in self.watchers.load().iter() {
            watcher.raise(*cause);
        }
        old
    }

    fn add_watcher(&self, signal: &Arc<Signal>, cause: u8) {
        self.watchers.rcu(|w| {
            let mut w = Vec::clone(w);
            w.push((signal.clone(), cause));
            w
        });
    }

    fn remove_watcher(&self, signal: &Arc<Signal>, cause: u8) {
        self.watchers.rcu(|w| {
            let mut w = Vec::clone(w);
            if let Some(i) = w
                .iter()
                .position(|(s, c)| Arc::ptr_eq(s, signal) && *c == cause)
            {
                w.swap_remove(i);
            }
            w
        });
    }
}

/// A declared (non-queue) property: its own cell, and the cell reads and writes go to,
/// which differs from its own when the property is linked (symlink semantics).
pub(crate) struct Endpoint {
    /// `module/path`, for traces and errors.
    pub key: Arc<str>,
    pub own: Arc<Cell>,
    /// The cell reads and writes go to: one of `targets`, so it lives as long as the endpoint.
    /// Every read and write of a property loads it, so it is a plain atomic pointer: an
    /// `ArcSwap` load (a hazard slot taken and given back, two locked instructions) cost as
    /// much as the cell's lock.
    resolved: AtomicPtr<Cell>,
    /// Every cell this endpoint has resolved to, kept while it lives. Relinks are rare and
    /// go back and forth between a few cells, so this stays as short as the cells linked.
    targets: Mutex<Vec<Arc<Cell>>>,
    subscribers: Mutex<Vec<(Arc<Signal>, u8)>>,
}

impl Endpoint {
    pub fn new(key: &str, type_info: TypeInfo, default: AnyValue) -> Arc<Self> {
        let own = Cell::new(type_info, default);
        Arc::new(Endpoint {
            key: key.into(),
            resolved: AtomicPtr::new(Arc::as_ptr(&own).cast_mut()),
            targets: Mutex::new(vec![own.clone()]),
            own,
            subscribers: Mutex::new(Vec::new()),
        })
    }

    /// The cell reads and writes go to now.
    #[inline]
    fn target(&self) -> &Cell {
        // SAFETY: `resolved` only ever holds a pointer to a cell in `targets`, which holds a
        // reference to every such cell until the endpoint is dropped, and `&self` outlives
        // the borrow returned.
        unsafe { &*self.resolved.load(Ordering::Acquire) }
    }

    pub fn type_info(&self) -> TypeInfo {
        self.own.type_info
    }

    #[inline]
    pub fn read(&self) -> Slot {
        self.target().read()
    }

    #[inline]
    pub fn value(&self) -> AnyValue {
        self.target().value()
    }

    /// See [`Cell::with_value`].
    #[inline]
    pub fn with_value<R>(&self, f: impl FnOnce(&AnyValue) -> R) -> R {
        self.target().with_value(f)
    }

    #[inline]
    pub fn write(&self, value: AnyValue) {
        self.write_at(value, Instant::now())
    }

    /// Writes a value stamped `written` (a module's step time).
    #[inline]
    pub fn write_at(&self, value: AnyValue, written: Instant) {
        self.target().write(value, written)
    }

    /// Writes a value stamped `written` and returns the value it replaced.
    #[inline]
    pub fn replace_at(&self, value: AnyValue, written: Instant) -> AnyValue {
        self.target().replace(value, written)
    }

    /// The version of the value seen through this endpoint, without locking it.
    #[inline]
    pub fn version(&self) -> u64 {
        self.target().version()
    }

    /// Wakes `signal` whenever the value seen through this endpoint changes, including after a relink.
    pub fn subscribe(&self, signal: &Arc<Signal>) {
        self.subscribe_with(signal, cause::CHANGE)
    }

    /// Like [`subscribe`](Self::subscribe), raising `cause` (one module signal serves all events).
    pub fn subscribe_with(&self, signal: &Arc<Signal>, cause: u8) {
        let mut subs = self.subscribers.lock();
        if !subs
            .iter()
            .any(|(s, c)| Arc::ptr_eq(s, signal) && *c == cause)
        {
            subs.push((signal.clone(), cause));
            self.target().add_watcher(signal, cause);
        }
    }

    /// Stops waking `signal` for `cause` (what [`subscribe_with`](Self::subscribe_with) started).
    pub fn unsubscribe(&self, signal: &Arc<Signal>, cause: u8) {
        let mut subs = self.subscribers.lock();
        if let Some(i) = subs
            .iter()
            .position(|(s, c)| Arc::ptr_eq(s, signal) && *c == cause)
        {
            subs.swap_remove(i);
            self.target().remove_watcher(signal, cause);
        }
    }

    /// Points the endpoint at another cell; subscribers follow, and are woken if the value they see changed.
    pub fn retarget(&self, target: Arc<Cell>) {
        let subs = self.subscribers.lock();
        let old = {
            let mut targets = self.targets.lock();
            if !targets.iter().any(|t| Arc::ptr_eq(t, &target)) {
                targets.push(target.clone());
            }
            let old = self
                .resolved
                .swap(Arc::as_ptr(&target).cast_mut(), Ordering::AcqRel);
            // Always found: every cell `resolved` pointed to is in `targets`.
            targets
                .iter()
                .find(|t| std::ptr::eq(Arc::as_ptr(t), old))
                .cloned()
        };
        let Some(old) = old.filter(|old| !Arc::ptr_eq(old, &target)) else {
            return;
        };
        for (s, c) in subs.iter() {
            old.remove_watcher(s, *c);
            target.add_watcher(s, *c);
        }
        if !Arc::ptr_eq(&old.value(), &target.value()) {
            for (s, c) in subs.iter() {
                s.raise(*c);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f64_endpoint(key: &str, v: f64) -> Arc<Endpoint> {
        Endpoint::new(key, TypeInfo::of::<f64>(), Arc::new(v))
    }

    fn read_f64(e: &Endpoint) -> f64 {
        *e.value().downcast_ref::<f64>().unwrap()
    }

    #[test]
    fn write_bumps_version_and_wakes_subscribers() {
        let e = f64_endpoint("a/out/x", 1.0);
        let s = Arc::new(Signal::default());
        e.subscribe(&s);
        e.subscribe(&s); // idempotent
        e.write(Arc::new(2.0));
        assert_eq!(e.read().version, 1);
        assert_eq!(read_f64(&e), 2.0);
        assert_eq!(s.take(), cause::CHANGE);
    }

    #[test]
    fn retarget_moves_subscribers_and_wakes_on_different_value() {
        let input = f64_endpoint("b/in/x", 0.0);
        let source = f64_endpoint("a/out/x", 5.0);
        let s = Arc::new(Signal::default());
        input.subscribe(&s);
        input.retarget(source.own.clone());
        assert_eq!(
            s.take(),
            cause::CHANGE,
            "reader sees a new value after relink"
        );
        assert_eq!(read_f64(&input), 5.0);
        input.own.write(Arc::new(9.0), Instant::now());
        assert_eq!(s.take(), 0, "the input's own cell is no longer watched");
        source.write(Arc::new(6.0));
        assert_eq!(s.take(), cause::CHANGE);
        assert_eq!(read_f64(&input), 6.0);
    }

    #[test]
    fn relinks_back_and_forth_keep_reads_and_wakes_right_and_the_cells_few() {
        let input = f64_endpoint("b/in/x", 0.0);
        let (one, two) = (f64_endpoint("a/out/x", 1.0), f64_endpoint("c/out/x", 2.0));
        let s = Arc::new(Signal::default());
        input.subscribe(&s);
        for _ in 0..10 {
            input.retarget(one.own.clone());
            assert_eq!(read_f64(&input), 1.0);
            input.retarget(two.own.clone());
            assert_eq!(read_f64(&input), 2.0);
        }
        s.take();
        one.write(Arc::new(5.0));
        assert_eq!(s.take(), 0, "no longer linked to `one`");
        two.write(Arc::new(6.0));
        assert_eq!(s.take(), cause::CHANGE);
        assert_eq!(read_f64(&input), 6.0);
        assert_eq!(input.version(), two.version());
        // Its own cell and the two it was linked to, however many relinks.
        assert_eq!(input.targets.lock().len(), 3);
    }

    #[test]
    fn changes_pending_says_a_change_came_without_taking_it() {
        let e = f64_endpoint("a/out/x", 1.0);
        let s = Arc::new(Signal::default());
        e.subscribe(&s);
        assert!(!s.changes_pending());
        e.write(Arc::new(2.0));
        assert!(s.changes_pending());
        assert!(s.changes_pending(), "still pending: not taken");
        assert_eq!(s.take(), cause::CHANGE);
        assert!(!s.changes_pending());
    }
}
