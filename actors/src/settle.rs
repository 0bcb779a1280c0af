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
    /// The other modules' signals, looked up at the first [`Context::settle_agent`] and
    /// again after modules were added or removed, with the count of those changes then.
    pub others: Option<(Vec<Arc<Signal>>, u64)>,
    /// The last [`Context::settle_agent`] gave up with modules still busy: the next one only
    /// yields, so that a module that never goes quiet costs the millisecond waits once.
    pub gave_up: bool,
}

/// The most yields one [`Context::settle_agent`] makes: enough for chains of modules on the
/// agent's thread far longer than real pipelines.
const SETTLE_AGENT_YIELDS: usize = 256;

/// Then, for modules still busy (one moved off the agent's thread, whose step runs beside),
/// it checks again every millisecond for at most this long, so that a module that never goes
/// quiet (one woken by its own writes) holds it up for a bounded time; once it gave up, the
/// next call only yields until one goes quiet again.
const SETTLE_AGENT_WAIT: Duration = Duration::from_millis(20);

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

    /// Lets the agent's other modules run until none has a step waiting: those woken by what
    /// this step wrote, those woken by what they wrote in turn, and so on. Returns whether
    /// the agent went quiet (false after a bounded number of yields, or when this module is
    /// not bound to a signal).
    ///
    /// For a module that feeds an agent from outside at its own pace, a replay above all:
    /// published one recorded instant at a time with this in between, each instant reaches
    /// the modules downstream as it did live, however fast the replay goes. A simulator that
    /// catches up several steps with the wall clock hands them over the same way. Only steps woken
    /// by data are waited for (not periodic ticks or timeouts), and only on the agent's own
    /// thread is every such step sure to have run; modules added while the agent runs are
    /// waited for from the next call. The time spent is left out of the step's duration, as
    /// with [`settle`](Self::settle).
    pub async fn settle_agent(&mut self) -> bool {
        let Some(me) = self.settle.signal.clone() else {
            return false;
        };
        // Read before the lookup: a module added meanwhile is looked up at the next call.
        let changed = self.blackboard.modules_changed();
        if self
            .settle
            .others
            .as_ref()
            .is_none_or(|(_, at)| *at != changed)
        {
            let Ok(signals) = self.blackboard.signals().await else {
                return false;
            };
            let others = signals.into_iter().filter(|s| !Arc::ptr_eq(s, &me));
            self.settle.others = Some((others.collect(), changed));
        }
        let began = self.settle.timed.then(Instant::now);
        let others = self.settle.others.as_ref().map_or(&[][..], |(s, _)| s);
        let busy = || others.iter().any(|s| s.busy());
        let mut yields = 0;
        while busy() && yields < SETTLE_AGENT_YIELDS {
            YieldOnce(false).await;
            yields += 1;
        }
        let mut waited = match self.settle.gave_up {
            true => SETTLE_AGENT_WAIT,
            false => Duration::ZERO,
        };
        while busy() && waited < SETTLE_AGENT_WAIT {
            tokio::time::sleep(Duration::from_millis(1)).await;
            waited += Duration::from_millis(1);
        }
        let quiet = !busy();
        self.settle.gave_up = !quiet;
        if let Some(began) = began {
            self.settle.waited += began.elapsed();
        }
        quiet
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
