//! The mission's deadlines (`held` windows, `age` conditions, `wait_N`): a task that bumps
//! `state/wake` when the next one passes, so the mission steps then without a period.

use std::sync::Arc;

use petrel_actors::AnyHandle;
use tokio::sync::watch;
use tokio::time::Instant;

/// The sender to the task that bumps `state/wake` when the next deadline passes, with the
/// deadline it was told last.
pub(super) struct Timer {
    tx: watch::Sender<Option<Instant>>,
    told: Option<Instant>,
}

impl Timer {
    /// Starts the task that bumps `wake` (the mission's `state/wake`) at each deadline.
    pub fn start(wake: AnyHandle) -> Timer {
        let (tx, rx) = watch::channel(None);
        tokio::spawn(deadline_timer(rx, wake));
        Timer { tx, told: None }
    }

    /// Tells the timer task about a new deadline. Only a change wakes it: a wake-up per mission
    /// step would put a second task on the run queue at every reaction, and tokio then brings
    /// in another worker thread to steal it, which costs more than the reaction itself. The
    /// deadline told last is kept here, so an unchanged one costs no lock of the channel.
    pub fn set(&mut self, deadline: Option<Instant>) {
        if deadline == self.told {
            return;
        }
        self.told = deadline;
        self.tx.send_if_modified(|d| {
            let changed = *d != deadline;
            *d = deadline;
            changed
        });
    }
}

/// Bumps `state/wake` when the latest deadline passes; ends when the mission drops its sender.
async fn deadline_timer(mut rx: watch::Receiver<Option<Instant>>, wake: AnyHandle) {
    loop {
        let deadline = *rx.borrow_and_update();
        let sleep = async {
            match deadline {
                Some(t) => tokio::time::sleep_until(t).await,
                None => std::future::pending().await,
            }
        };
        tokio::select! {
            changed = rx.changed() => if changed.is_err() { return },
            _ = sleep => {
                let n = wake.get::<i64>().map_or(0, |v| *v);
                let _ = wake.set(Arc::new(n + 1));
                // Wait for the next deadline the mission computes.
                if rx.changed().await.is_err() { return }
            }
        }
    }
}
