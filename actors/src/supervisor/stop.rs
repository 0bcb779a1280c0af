//! Stopping modules: one on request, several for a restart plan, all when the agent stops.

use std::time::Duration;

use super::{SlotState, SupervisorState};

impl SupervisorState {
    /// Stops slot `i` gracefully, killing it after its shutdown timeout.
    /// A module waiting for a restart is stopped too: the restart is forgotten.
    pub(super) async fn stop_slot(&mut self, i: usize, timeout: Option<Duration>) {
        self.slots[i].generation += 1;
        self.slots[i].state = SlotState::Stopped;
        self.stop_slots(&[i], timeout).await;
    }

    /// Stops the running modules among `order` (in that order), each killed after its
    /// shutdown timeout (or `timeout`). Every one is asked to leave its step loop at once, so
    /// busy modules do not keep stepping while the ones before them stop; then each cleans up
    /// in turn, so cleanup still runs in `order`.
    pub(super) async fn stop_slots(&mut self, order: &[usize], timeout: Option<Duration>) {
        let running: Vec<usize> = order
            .iter()
            .copied()
            .filter(|&i| self.slots[i].actor.is_some())
            .collect();
        for &i in &running {
            let slot = &mut self.slots[i];
            slot.generation += 1;
            slot.state = SlotState::Stopped;
            slot.stop.halt();
        }
        for i in running {
            let slot = &mut self.slots[i];
            slot.stop.allow_cleanup();
            let timeout = timeout.unwrap_or(slot.spec.shutdown_timeout);
            let actor = slot.actor.take();
            if let Some(join) = slot.join.take() {
                if tokio::time::timeout(timeout, join).await.is_err() {
                    tracing::warn!(agent = %self.agent, module = %slot.spec.name, ?timeout, "module did not stop in time: killed");
                    slot.killed = true;
                    if let Some(actor) = actor {
                        actor.kill();
                    }
                }
            }
        }
    }

    pub(super) async fn stop_all(&mut self, timeout: Option<Duration>) {
        self.stopping = true;
        for i in 0..self.slots.len() {
            let slot = &mut self.slots[i];
            if slot.actor.is_none() && slot.state == SlotState::Waiting {
                slot.state = SlotState::Stopped;
                // Its last word was a failure, and the restart it waited for will not come:
                // the summary says `failed`, not `restarting`.
                self.set_stat(i, "stats/status", crate::status::FAILED.to_string())
                    .await;
            }
        }
        let order: Vec<usize> = (0..self.slots.len()).rev().collect();
        self.stop_slots(&order, timeout).await;
    }
}
