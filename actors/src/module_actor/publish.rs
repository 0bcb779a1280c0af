//! What a module actor publishes about itself besides its step: its status and stats, and the
//! request to leave its agent's thread when its steps exceed the agent's `step_budget`.

use std::sync::Arc;
use std::time::Duration;

use tokio::time::Instant;

use super::{status, Running};
use crate::module::Module;
use crate::run_queue::RunQueueMark;

impl<M: Module> Running<M> {
    /// On the agent's own thread, asks the supervisor to move the module to the shared runtime
    /// once its steps exceed the agent's `step_budget`; the move stops it at a step boundary.
    /// `queue_mark`: the run-queue wait when the step began, if the watch asked for it.
    pub(super) fn watch_step_budget(&mut self, took: Duration, queue_mark: Option<RunQueueMark>) {
        let Some(watch) = self.long_steps.as_mut() else {
            return;
        };
        let waited = queue_mark.and_then(|mark| mark.elapsed());
        let Some(mean) = watch.observe(took, waited) else {
            return;
        };
        let msg = crate::supervisor::SupervisorMsg::Move(self.me, mean);
        // A supervisor that is gone is stopping the agent: nothing left to move.
        let _ = self.supervisor.cast(msg);
    }

    /// The run-queue wait so far, when the step budget's watch asks for it for the next step.
    pub(super) fn run_queue_mark(&self) -> Option<RunQueueMark> {
        let watch = self.long_steps.as_ref()?;
        watch.wants_run_queue_wait().then(RunQueueMark::now)?
    }

    /// Publishes `status`, and the stats with it when the module is leaving its step loop
    /// (steps publish them at most every 100 ms). An action that enables and disables a module
    /// at every plan reaction changes its status twice a reaction: writing four stats (and
    /// reading the clock for each) cost more than the reaction's own hand-overs. For the same
    /// reason the status is compared with what this instance wrote last (unless someone wrote
    /// since) rather than read back, and written as a value kept per status rather than a new
    /// string.
    pub(super) fn publish(&mut self, status: &'static str) {
        // `stats/...` cannot be linked: its own cell is the one written.
        let cell = &self.builtins.status.ep.own;
        let shown = match self.status_shown {
            Some((shown, version)) if version == cell.version() => shown == status,
            _ => *self.builtins.status.get() == status,
        };
        if !shown {
            let value = self.status_values.get(status);
            drop(self.builtins.status.swap(value));
            self.status_shown = Some((status, cell.version()));
            // The module actor's target, as before this code moved here: log filters name it.
            self.span.in_scope(|| match status {
                status::STOPPED | status::DISABLED => {
                    tracing::info!(target: "petrel_actors::module_actor", status, "status")
                }
                _ => tracing::debug!(target: "petrel_actors::module_actor", status, "status"),
            });
        }
        if matches!(status, status::STOPPED | status::FAILED) {
            self.publish_stats();
        }
    }

    pub(super) fn publish_stats(&mut self) {
        let s = &mut self.stats;
        s.published = Some(Instant::now());
        self.builtins
            .steps
            .set((self.steps_before + self.ctx.steps) as i64);
        self.builtins.last_step_us.set(s.last.as_secs_f64() * 1e6);
        self.builtins.mean_step_us.set(s.mean_step_us());
        self.builtins.mean_interval_ms.set(s.mean_interval_ms());
    }
}

/// The `stats/status` values a module actor has written, each made once: a status change
/// writes a shared value instead of allocating a string.
#[derive(Default)]
pub(super) struct StatusValues(Vec<(&'static str, Arc<String>)>);

impl StatusValues {
    fn get(&mut self, status: &'static str) -> Arc<String> {
        if let Some((_, value)) = self.0.iter().find(|(s, _)| *s == status) {
            return value.clone();
        }
        let value = Arc::new(status.to_string());
        self.0.push((status, value.clone()));
        value
    }
}
