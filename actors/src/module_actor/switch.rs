//! A module's status, and switching it off without waking it.
//!
//! A plan action switches its modules on and off at every reaction. Waking a module only for it
//! to note that it is off cost a wake-up per reaction, as much as a hand-over. So while the
//! module waits, whoever writes `enabled = false` notes it in the module's place: the status
//! becomes `disabled` and the signal turns quiet (data no longer wakes it), with the same log
//! lines. Switching on still wakes the module: it has to step anyway. The status is written by
//! both the module and those writers, so its writes go one at a time, through [`Switch`].

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use parking_lot::Mutex;

use super::status;
use crate::cell::{Endpoint, QuietSwitch, Signal};

/// The status of one module instance, and its `enabled` as writers of it see it.
pub(crate) struct Switch {
    /// The step loop waits for its signal: not stepping, not in init or cleanup.
    idle: AtomicBool,
    enabled: Arc<Endpoint>,
    status: Arc<Endpoint>,
    /// Serialises status writes, so a writer switching the module off never overwrites a
    /// status the module wrote meanwhile (stopped, failed).
    writing: Mutex<()>,
    span: tracing::Span,
}

impl Switch {
    pub fn new(enabled: Arc<Endpoint>, status: Arc<Endpoint>, span: tracing::Span) -> Arc<Self> {
        Arc::new(Switch {
            idle: AtomicBool::new(false),
            enabled,
            status,
            writing: Mutex::new(()),
            span,
        })
    }

    /// Marks the step loop as waiting for its signal (true) or awake (false).
    pub fn set_idle(&self, idle: bool) {
        self.idle.store(idle, Ordering::SeqCst);
    }

    /// The module's `enabled`, as written last.
    pub fn enabled(&self) -> bool {
        self.enabled
            .with_value(|v| v.downcast_ref::<bool>().copied())
            .unwrap_or(true)
    }

    /// Publishes `new` as the module's status, if it is not shown already.
    pub fn show(&self, new: &str) {
        let _one_at_a_time = self.writing.lock();
        self.write(new);
    }

    /// Shows `running` or `disabled` after `enabled` changed, unless the module shows another
    /// status (it is starting, stopping or has failed).
    pub fn show_enabled(&self, enabled: bool) {
        let _one_at_a_time = self.writing.lock();
        let shown_enabled =
            self.status
                .with_value(|v| match v.downcast_ref::<String>().map(String::as_str) {
                    Some(status::RUNNING) => Some(true),
                    Some(status::DISABLED) => Some(false),
                    _ => None,
                });
        if shown_enabled.is_some_and(|shown| shown != enabled) {
            self.span
                .in_scope(|| tracing::info!(enabled, "enabled changed"));
            self.write(match enabled {
                true => status::RUNNING,
                false => status::DISABLED,
            });
        }
    }

    /// Writes `new` unless shown already (a write wakes every reader); the caller holds the lock.
    fn write(&self, new: &str) {
        let unchanged = self
            .status
            .with_value(|v| v.downcast_ref::<String>().is_some_and(|s| s == new));
        if unchanged {
            return;
        }
        self.status.write(Arc::new(new.to_string()));
        // The module actor's target, as before this code moved here: log filters name it.
        self.span.in_scope(|| match new {
            status::STOPPED | status::DISABLED => {
                tracing::info!(target: "petrel_actors::module_actor", status = new, "status")
            }
            _ => tracing::debug!(target: "petrel_actors::module_actor", status = new, "status"),
        });
    }
}

impl QuietSwitch for Switch {
    fn settle_off(&self, signal: &Signal) -> bool {
        // The `ENABLED` cause was recorded before this: either the module reads it after
        // marking itself awake, or this sees it idle (a store then a load on each side).
        std::sync::atomic::fence(Ordering::SeqCst);
        if !self.idle.load(Ordering::SeqCst) || self.enabled() {
            return false;
        }
        signal.set_quiet(true);
        self.show_enabled(false);
        if self.enabled() {
            // Switched on again meanwhile by another writer, whose wake-up the module may have
            // taken already: raise it again, so the module wakes and sees to it.
            signal.raise(crate::cell::cause::ENABLED);
        }
        true
    }
}
