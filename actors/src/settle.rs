//! [`Context::settle`]: a step lets the modules it woke answer before it goes on, so that a
//! module driving others (a mission enabling the module of an action) sees an answer given at
//! once within the same step, instead of being woken again for it.

use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;
use std::task::Poll;
use std::time::Duration;

use tokio::time::Instant;

use crate::cell::Signal;
use crate::module::Context;

/// What the module actor tells [`Context::settle`] about the module and its step.
#[derive(Default)]
pub(crate) struct Settle {
    /// The module's wake-up signal, once the actor has bound it.
    pub signal: Option<Arc<Signal>>,
    /// Whether the running step is timed (`stats.rs`): time spent settling is then measured.
    pub timed: bool,
    /// Time the running step spent settling, measured on a timed step only: left out of its
    /// duration, so that the modules it let run do not count against it (`step_budget`).
    pub waited: Duration,
}

impl Context {
    /// Lets the modules this step has woken so far run (a module its write enabled, a reader
    /// of what it wrote), then returns whether any property this module watches changed since
    /// the step began.
    ///
    /// Those changes are then this step's: they no longer make the module step again, so after
    /// a `true` the caller must read again everything it watches. A change written after
    /// `settle` returns wakes the module as usual, and queue items, ticks and timeouts are
    /// left to wake it. The step's time ([`now`](Self::now)) does not move, and the time spent
    /// waiting is not counted in the step's duration.
    ///
    /// The wait is one yield: on the agent's thread the modules woken run before this step
    /// goes on; on a multi-thread runtime another worker may take this step first, and an
    /// answer it missed wakes the module again afterwards, as without `settle`.
    pub async fn settle(&mut self) -> bool {
        let Some(signal) = self.settle.signal.clone() else {
            return false;
        };
        let began = self.settle.timed.then(Instant::now);
        YieldOnce(false).await;
        if let Some(began) = began {
            self.settle.waited += began.elapsed();
        }
        signal.take_changes()
    }

    /// Whether a property this module watches was written since its step began (or since
    /// [`settle`](Self::settle) last took such changes): such a write wakes the module again
    /// after the step. A step that reads what it watches several times (a mission's plan
    /// rounds) need not look at each property again while this is false. A single atomic
    /// load; false outside a step's module.
    pub fn changes_pending(&self) -> bool {
        self.settle
            .signal
            .as_ref()
            .is_some_and(|signal| signal.changes_pending())
    }
}

/// Pending once, having woken its task: the task goes to the back of its runtime's queue, so
/// every task woken before it runs first. Cheaper than `tokio::task::yield_now`, which on a
/// current-thread runtime waits for the I/O driver to be polled (a system call).
struct YieldOnce(bool);

impl Future for YieldOnce {
    type Output = ();

    fn poll(mut self: Pin<&mut Self>, cx: &mut std::task::Context<'_>) -> Poll<()> {
        if self.0 {
            return Poll::Ready(());
        }
        self.0 = true;
        cx.waker().wake_by_ref();
        Poll::Pending
    }
}
