//! Ctrl-C for the commands that follow values until it (`echo`, `hz`, `events`, `top`).
//!
//! `tokio::signal::ctrl_c()` made anew at each wait of a loop hears only signals that come
//! while that wait is polled: a Ctrl-C while the command printed or asked its agents (`top`
//! collects a table for a good part of each second) was lost, and the command went on. An
//! [`Interrupt`] listens from its creation on and keeps a signal for its next wait.

use tokio::signal::unix::{signal, Signal, SignalKind};

/// SIGINT, heard from creation on.
pub(crate) struct Interrupt {
    /// `None` when the handler could not be installed: Ctrl-C then ends the process as it
    /// would without one.
    signal: Option<Signal>,
}

impl Interrupt {
    /// Listens for SIGINT from now on. Within a tokio runtime.
    pub(crate) fn new() -> Interrupt {
        Interrupt {
            signal: signal(SignalKind::interrupt()).ok(),
        }
    }

    /// Resolves at the next SIGINT, or at once for one that came since the last call.
    pub(crate) async fn recv(&mut self) {
        match &mut self.signal {
            Some(s) => {
                s.recv().await;
            }
            None => std::future::pending().await,
        }
    }
}
