//! Stopping one module instance from outside its step loop.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::cell::{cause, Signal};

/// A request to stop one module instance, shared by its supervisor and its actor. Stopping
/// raises the module's signal, so the request is seen at once, even by a waiting module.
#[derive(Default)]
pub(crate) struct StopRequest {
    requested: AtomicBool,
    signal: parking_lot::Mutex<Option<Arc<Signal>>>,
}

impl StopRequest {
    pub fn request(&self) {
        let signal = self.signal.lock();
        self.requested.store(true, Ordering::SeqCst);
        if let Some(signal) = signal.as_ref() {
            signal.raise(cause::STOP);
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
