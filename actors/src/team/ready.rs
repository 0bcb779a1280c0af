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

use super::remote::{QueueTap, Tap, ValueTap};
use crate::cell::{cause, Signal};

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

impl ValueTap {
    /// See [`Tap::wake_through`].
    pub fn wake_through(&mut self, ready: &TapReady, id: usize) {
        let signal = Arc::new(Signal::marking(ready.clone(), id));
        self.ep.subscribe(&signal);
        self.ep.unsubscribe(&self.signal, cause::CHANGE);
        self.signal = signal;
        self.signal.raise(cause::CHANGE);
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
