//! Stopping one module instance from outside its step loop.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use tokio::sync::Notify;

use crate::cell::{cause, Signal};

/// A request to stop one module instance, shared by its supervisor and its actor. Stopping
/// raises the module's signal, so the request is seen at once, even by a waiting module.
///
/// Stopping has two halves: leaving the step loop (`halt`) and running cleanup (`allow_cleanup`).
/// An agent's stop halts every module at once, so busy modules stop stepping together instead
/// of taking turns on the workers while the supervisor waits for them one by one, and then lets
/// them clean up one at a time in reverse start order.
#[derive(Default)]
pub(crate) struct StopRequest {
    requested: AtomicBool,
    signal: parking_lot::Mutex<Option<Arc<Signal>>>,
    cleanup_allowed: AtomicBool,
    cleanup_turn: Notify,
    /// The instance stops only to be started again at once (a restart or a move), which its
    /// cleanup can tell ([`crate::Context::restarting`]).
    restart: AtomicBool,
}

impl StopRequest {
    /// Asks the module to leave its step loop; its cleanup waits for [`Self::allow_cleanup`].
    pub fn halt(&self) {
        let signal = self.signal.lock();
        self.requested.store(true, Ordering::SeqCst);
        if let Some(signal) = signal.as_ref() {
            signal.raise(cause::STOP);
        }
    }

    /// Marks this stop as one after which the module is started again at once; call before
    /// [`Self::halt`].
    pub fn for_restart(&self) {
        self.restart.store(true, Ordering::SeqCst);
    }

    /// Whether the module is started again right after this stop.
    pub(super) fn is_restart(&self) -> bool {
        self.restart.load(Ordering::SeqCst)
    }

    /// Lets a halted module run its cleanup.
    pub fn allow_cleanup(&self) {
        self.cleanup_allowed.store(true, Ordering::SeqCst);
        // `notify_one` keeps a permit if the module is not waiting yet.
        self.cleanup_turn.notify_one();
    }

    /// Waits until the module may run its cleanup.
    pub(super) async fn cleanup_turn(&self) {
        while !self.cleanup_allowed.load(Ordering::SeqCst) {
            self.cleanup_turn.notified().await;
        }
    }

    pub(super) fn attach(&self, signal: &Arc<Signal>) {
        let mut slot = self.signal.lock();
        *slot = Some(signal.clone());
        if self.requested.load(Ordering::SeqCst) {
            signal.raise(cause::STOP);
        }
    }

    pub(super) fn is_requested(&self) -> bool {
        self.requested.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn a_halted_module_cleans_up_only_when_allowed() {
        let stop = Arc::new(StopRequest::default());
        stop.halt();
        assert!(stop.is_requested());
        let waiting = tokio::spawn({
            let stop = stop.clone();
            async move { stop.cleanup_turn().await }
        });
        tokio::task::yield_now().await;
        assert!(!waiting.is_finished(), "cleanup waits for its turn");
        stop.allow_cleanup();
        waiting.await.unwrap();
    }

    #[tokio::test]
    async fn cleanup_allowed_before_the_halt_is_not_lost() {
        let stop = StopRequest::default();
        stop.allow_cleanup();
        stop.halt();
        assert!(stop.is_requested());
        stop.cleanup_turn().await;
    }
}
