//! One task draining many taps: a ready list the taps' writers mark, so a recorder (or any
//! tap consumer) wakes once for a burst of changes on many properties and reads only those
//! that changed, instead of running one task per tapped property.
//!
//! A tap routed through a [`TapReady`] ([`Tap::wake_through`]) no longer wakes its own
//! waiter: a write raises the tap's signal, whose first raise since the consumer last read
//! the tap queues the tap's id; later writes find it queued and cost one atomic operation.
//! Reading the tap ([`ValueTap::read`], [`QueueTap::take`]) re-arms it, so a write that
//! races the read queues the id again and no change is missed.

use std::sync::Arc;

use parking_lot::Mutex;
use tokio::sync::Notify;
use tokio::time::Instant;

use super::remote::{QueueTap, Tap, ValueTap};
use crate::cell::{cause, Signal};
use crate::value::AnyValue;

/// The ready list many taps share: which of them have news, and one waiter to wake.
#[derive(Clone, Default)]
pub struct TapReady(Arc<ReadyList>);

#[derive(Default)]
struct ReadyList {
    ids: Mutex<Vec<usize>>,
    notify: Notify,
}

impl TapReady {
    /// An empty list.
    pub fn new() -> Self {
        TapReady::default()
    }

    /// Queues `id`; wakes the waiter when the list was empty (it takes the whole list).
    pub(crate) fn mark(&self, id: usize) {
        let first = {
            let mut ids = self.0.ids.lock();
            ids.push(id);
            ids.len() == 1
        };
        if first {
            self.0.notify.notify_one();
        }
    }

    /// Takes the ids queued so far into `out` (emptied first), without waiting. Each id is
    /// queued once per read of its tap, however many writes it saw.
    pub fn take(&self, out: &mut Vec<usize>) {
        out.clear();
        std::mem::swap(&mut *self.0.ids.lock(), out);
    }

    /// Like [`take`](Self::take), waiting until at least one id is queued.
    pub async fn wait(&self, out: &mut Vec<usize>) {
        loop {
            self.take(out);
            if !out.is_empty() {
                return;
            }
            // A mark between the take and this wait leaves a permit: no wake-up is lost.
            self.0.notify.notified().await;
        }
    }
}

impl Tap {
    /// Routes this tap's wake-ups to `ready` under `id` (see [`TapReady`]); the tap is queued
    /// at once, so the consumer reads its current value (or pending items) first. Its own
    /// `changed()` no longer completes.
    pub fn wake_through(&mut self, ready: &TapReady, id: usize) {
        match self {
            Tap::Value(tap) => tap.wake_through(ready, id),
            Tap::Queue(tap) => tap.wake_through(ready, id),
        }
    }
}

impl Tap {
    /// Like [`wake_through`](Self::wake_through), and a value tap keeps its value now and every
    /// write from now on ([`ValueTap::take_writes`]), up to `capacity` not yet taken: for a
    /// consumer that must see each change (a recorder), where a read finds only the latest. A
    /// queue tap reads every item already.
    pub fn record_through(&mut self, ready: &TapReady, id: usize, capacity: usize) {
        match self {
            Tap::Value(tap) => tap.route(Signal::recording(ready.clone(), id, capacity)),
            Tap::Queue(tap) => tap.wake_through(ready, id),
        }
    }
}

impl ValueTap {
    /// See [`Tap::wake_through`].
    pub fn wake_through(&mut self, ready: &TapReady, id: usize) {
        self.route(Signal::marking(ready.clone(), id));
    }

    fn route(&mut self, signal: Signal) {
        let signal = Arc::new(signal);
        self.ep.subscribe(&signal);
        self.ep.unsubscribe(&self.signal, cause::CHANGE);
        self.signal = signal;
        self.signal.raise(cause::CHANGE);
    }

    /// Moves the writes kept since the last call (see [`Tap::record_through`]) into `out`,
    /// oldest first, as (value, version, write time): the first call begins with the value
    /// the tap found, and a relink adds the value the property reads then. Returns how many
    /// the tap lost so far to its capacity. Keeps nothing for a tap not routed by
    /// `record_through`.
    ///
    /// Re-arms the tap first, as [`read`](Self::read) does: a write after it queues the tap
    /// again, and one before it is among the writes taken.
    pub fn take_writes(&self, out: &mut Vec<(AnyValue, u64, Instant)>) -> u64 {
        self.signal.take();
        self.signal.history().map_or(0, |h| h.take(out))
    }
}

impl QueueTap {
    /// See [`Tap::wake_through`].
    pub fn wake_through(&mut self, ready: &TapReady, id: usize) {
        let signal = Arc::new(Signal::marking(ready.clone(), id));
        self.reader.subscribe(&signal);
        self.signal = signal;
        self.signal.raise(cause::ITEMS);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cell::Endpoint;
    use crate::value::TypeInfo;

    fn taken(ready: &TapReady) -> Vec<usize> {
        let mut out = vec![99];
        ready.take(&mut out);
        out
    }

    #[test]
    fn a_signal_queues_its_id_once_until_taken() {
        let ready = TapReady::new();
        let a = Signal::marking(ready.clone(), 3);
        let b = Signal::marking(ready.clone(), 7);
        a.raise(cause::CHANGE);
        a.raise(cause::CHANGE);
        b.raise(cause::ITEMS);
        a.raise(cause::CHANGE);
        assert_eq!(taken(&ready), vec![3, 7]);
        assert_eq!(taken(&ready), Vec::<usize>::new());
        // Not re-armed (its causes not taken): a raise finds it queued already.
        a.raise(cause::CHANGE);
        assert_eq!(taken(&ready), Vec::<usize>::new());
        assert_eq!(a.take(), cause::CHANGE);
        a.raise(cause::CHANGE);
        assert_eq!(taken(&ready), vec![3]);
    }

    #[test]
    fn a_recording_tap_keeps_the_value_it_found_every_write_and_each_relink() {
        let ep = Endpoint::new("m/in/x", TypeInfo::of::<i64>(), Arc::new(7_i64));
        let ready = TapReady::new();
        let mut tap = Tap::Value(ValueTap::new(ep.clone()));
        tap.record_through(&ready, 2, 3);
        let Tap::Value(tap) = tap else { unreachable!() };
        let kept = |tap: &ValueTap| {
            let mut out = Vec::new();
            let lost = tap.take_writes(&mut out);
            let values: Vec<i64> = out
                .iter()
                .map(|(v, _, _)| *v.downcast_ref::<i64>().unwrap())
                .collect();
            (values, lost)
        };
        assert_eq!(taken(&ready), vec![2], "queued at once");
        ep.write(Arc::new(8_i64));
        ep.write(Arc::new(9_i64));
        assert_eq!(kept(&tap), (vec![7, 8, 9], 0), "found, then both writes");
        // Linked elsewhere: the value it reads now, then that cell's writes.
        let source = Endpoint::new("s/out/x", TypeInfo::of::<i64>(), Arc::new(40_i64));
        ep.retarget(source.own.clone());
        source.write(Arc::new(41_i64));
        assert_eq!(taken(&ready), vec![2], "the relink queues it, once");
        assert_eq!(kept(&tap), (vec![40, 41], 0));
        for v in 0..5_i64 {
            source.write(Arc::new(v));
        }
        assert_eq!(
            kept(&tap),
            (vec![2, 3, 4], 2),
            "the capacity's newest, two lost"
        );
        assert_eq!(
            taken(&ready),
            vec![2],
            "the writes after the re-arm queue it, once"
        );
    }

    #[test]
    fn value_taps_are_queued_at_once_and_on_every_write_after_a_read() {
        let ep = Endpoint::new("m/out/x", TypeInfo::of::<i64>(), Arc::new(0_i64));
        let ready = TapReady::new();
        let mut tap = ValueTap::new(ep.clone());
        tap.wake_through(&ready, 5);
        assert_eq!(taken(&ready), vec![5], "queued at once");
        ep.write(Arc::new(1_i64));
        assert_eq!(taken(&ready), Vec::<usize>::new(), "not read yet");
        assert_eq!(tap.read().1, 1);
        ep.write(Arc::new(2_i64));
        ep.write(Arc::new(3_i64));
        assert_eq!(taken(&ready), vec![5]);
        let (value, version, _) = tap.read();
        assert_eq!((*value.downcast_ref::<i64>().unwrap(), version), (3, 3));
        drop(tap);
        ep.write(Arc::new(4_i64));
        assert_eq!(
            taken(&ready),
            Vec::<usize>::new(),
            "unsubscribed when dropped"
        );
    }

    #[tokio::test(start_paused = true)]
    async fn wait_returns_when_a_tap_is_marked() {
        let ready = TapReady::new();
        let signal = Signal::marking(ready.clone(), 1);
        let waiter = {
            let ready = ready.clone();
            tokio::spawn(async move {
                let mut out = Vec::new();
                ready.wait(&mut out).await;
                out
            })
        };
        tokio::task::yield_now().await;
        signal.raise(cause::CHANGE);
        // Bounded: on the paused clock a missed wake-up ends in the timeout at once.
        let woken = tokio::time::timeout(std::time::Duration::from_secs(60), waiter).await;
        assert_eq!(woken.expect("woken").unwrap(), vec![1]);
    }
}
