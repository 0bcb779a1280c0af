//! Shared property storage: the cells the blackboard owns and modules read and write directly.
//!
//! The blackboard actor owns the *structure* (which cells exist, what links to what); values
//! move through these cells without any actor round trip. A write replaces the cell's value
//! under a short lock and raises the [`Signal`] of every module watching the cell.

use std::sync::atomic::{AtomicPtr, AtomicU64, Ordering};
use std::sync::Arc;

use arc_swap::ArcSwap;
use parking_lot::{Mutex, RwLock};
use tokio::time::Instant;

use crate::value::{AnyValue, TypeInfo};

mod history;
mod signal;
pub(crate) use history::History;
pub(crate) use signal::{cause, Signal};

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
        let (old, watchers) = {
            let mut slot = self.slot.write();
            slot.version += 1;
            self.version.store(slot.version, Ordering::Release);
            slot.written = written;
            // The watchers are read under the lock, and a history is given the write there:
            // it keeps concurrent writes in version order, and a watcher added meanwhile
            // (see `add_watcher`) either has this write or the value it left.
            let watchers = self.watchers.load();
            for history in watchers.iter().filter_map(|(w, _)| w.history()) {
                history.push(&value, slot.version, written);
            }
            (std::mem::replace(&mut slot.value, value), watchers)
        };
        for (watcher, cause) in watchers.iter() {
            watcher.raise(*cause);
        }
        old
    }

    fn add_watcher(&self, signal: &Arc<Signal>, cause: u8) {
        // A history starts with the value it finds, taken where no write can come between
        // (writers take the lock for writing): it then holds what the property read at each
        // moment since, once each, across relinks too (each adds the new cell's value).
        let slot = signal.history().map(|_| self.slot.read());
        self.watchers.rcu(|w| {
            let mut w = Vec::clone(w);
            w.push((signal.clone(), cause));
            w
        });
        if let (Some(history), Some(slot)) = (signal.history(), slot) {
            history.push(&slot.value, slot.version, slot.written);
        }
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
