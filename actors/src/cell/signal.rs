//! A module's wake-up: why it woke (`cause`), and the [`Signal`] that its watched cells,
//! queues, timers and stop requests raise.

use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, AtomicU8, Ordering};
use std::sync::Arc;
use std::task::Poll;

use atomic_waker::AtomicWaker;

use super::History;
use crate::loop_watch::Hop;
use crate::team::TapReady;

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
    /// Set while a module's step loop waits on this signal (see [`Signal::busy`]): the
    /// signals of modules not running (stopped, replaced, never started) are raised too, and
    /// their causes are never taken.
    live: AtomicBool,
    /// The longest chain of steps that led to the data raised since the last step, and whose
    /// write ended it: a packed [`Hop`] (see [`loop_watch`](crate::loop_watch)).
    hops: AtomicU64,
    /// Names this signal in a [`Hop`].
    id: u32,
    /// Set for a tap drained with many others: a raise queues this id on the shared list
    /// instead of waking a waiter of its own.
    ready: Option<(TapReady, usize)>,
    /// Set for a tap that must see every write (a recorder's): the cells it watches keep each
    /// write here, which a later read of the latest value would miss.
    history: Option<Arc<History>>,
}

impl Default for Signal {
    fn default() -> Self {
        static NEXT_ID: AtomicU32 = AtomicU32::new(1);
        Signal {
            notified: AtomicBool::new(false),
            waker: AtomicWaker::new(),
            causes: AtomicU8::new(0),
            quiet: AtomicBool::new(false),
            live: AtomicBool::new(false),
            hops: AtomicU64::new(0),
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            ready: None,
            history: None,
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

    /// Like [`marking`](Self::marking), with the writes of the cells it watches kept in a
    /// [`History`] of `capacity`.
    pub fn recording(ready: TapReady, id: usize, capacity: usize) -> Self {
        Signal {
            ready: Some((ready, id)),
            history: Some(Arc::new(History::new(capacity))),
            ..Signal::default()
        }
    }

    /// The history writes are kept in, for a recording signal.
    #[inline]
    pub fn history(&self) -> Option<&History> {
        self.history.as_deref()
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

    /// Marks the signal's module as running (its step loop takes the causes) or not.
    pub fn set_live(&self, live: bool) {
        self.live.store(live, Ordering::Release);
    }

    /// Whether a running, enabled module has a step waiting: raised for data it watches and
    /// not yet woken to take it (see [`Context::settle_agent`](crate::Context::settle_agent)).
    pub fn busy(&self) -> bool {
        self.live.load(Ordering::Acquire)
            && !self.quiet.load(Ordering::Acquire)
            && self.causes.load(Ordering::Acquire) & (cause::CHANGE | cause::ITEMS) != 0
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
