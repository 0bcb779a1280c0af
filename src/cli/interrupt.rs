//! Ctrl-C (and SIGTERM, as `run` takes it) for the commands that go on until it (`echo`, `hz`,
//! `events`, `top`, `console`): they end cleanly, exit code 0.
//!
//! `tokio::signal::ctrl_c()` made anew at each wait of a loop hears only signals that come
//! while that wait is polled: a Ctrl-C while the command printed or asked its agents (`top`
//! collects a table for a good part of each second) was lost, and the command went on. An
//! [`Interrupt`] listens from its creation on and keeps a signal for its next wait.

use tokio::signal::unix::{signal, Signal, SignalKind};

/// SIGINT and SIGTERM, heard from creation on.
pub(crate) struct Interrupt {
    /// `None` where a handler could not be installed: that signal then ends the process as it
    /// would without one.
    int: Option<Signal>,
    term: Option<Signal>,
}

impl Interrupt {
    /// Listens for SIGINT and SIGTERM from now on. Within a tokio runtime.
    pub(crate) fn new() -> Interrupt {
        Interrupt {
            int: signal(SignalKind::interrupt()).ok(),
            term: signal(SignalKind::terminate()).ok(),
        }
    }

    /// Resolves at the next signal, or at once for one that came since the last call.
    pub(crate) async fn recv(&mut self) {
        tokio::select! {
            _ = next(&mut self.int) => {}
            _ = next(&mut self.term) => {}
        }
    }
}

async fn next(signal: &mut Option<Signal>) {
    match signal {
        Some(s) => {
            s.recv().await;
        }
        None => std::future::pending().await,
    }
}
