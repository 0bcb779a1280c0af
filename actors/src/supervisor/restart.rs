//! What happens when a module instance ends: failure bookkeeping, the restart plan of its
//! supervisor (strategy, policy, intensity, escalation), backoff, and giving up.

use tokio::time::Instant;

use super::{SlotState, SupervisorMsg, SupervisorState, EXIT_GAVE_UP};
use crate::module_actor::status;
use crate::supervision::{plan_restart, GiveUp, Member, RestartPlan};

impl SupervisorState {
    /// A module instance ended: record it and restart what its supervisor's policy says.
    pub(super) async fn on_exit(&mut self, i: usize, failure: bool, reason: String) {
        let slot = &mut self.slots[i];
        slot.actor = None;
        slot.join = None;
        if self.stopping {
            return;
        }
        let (name, restarts) = (slot.spec.name.clone(), slot.restarts);
        if failure {
            self.record_failure(i, &reason).await;
        }
        let members: Vec<Member> = self
            .slots
            .iter()
            .map(|s| Member {
                group: s.spec.group,
                policy: s.spec.policy,
            })
            .collect();
        let group = self.slots[i].spec.group;
        let strategy = group.map_or(self.config.strategy, |g| self.groups[g].strategy);
        let RestartPlan::Restart { stop, restart } =
            plan_restart(&members, i, failure, strategy, false)
        else {
            self.slots[i].state = if failure {
                SlotState::Failed
            } else {
                SlotState::Stopped
            };
            tracing::info!(agent = %self.agent, module = %name, policy = ?self.slots[i].spec.policy, "not restarted");
            return;
        };
        let now = Instant::now();
        let allowed = match group {
            Some(g) => self.groups[g].intensity.allow(now),
            None => self.top.allow(now),
        };
        if allowed {
            return self.execute(i, stop, restart).await;
        }
        let Some(g) = group else {
            return self.give_up(i).await;
        };
        let why = format!(
            "group `{}` exceeded its restart intensity; it fails to the agent",
            self.groups[g].name
        );
        tracing::warn!(agent = %self.agent, group = %self.groups[g].name, module = %name, "{why}");
        self.event(&self.groups[g].name, "escalated", &why, restarts);
        if !self.top.allow(now) {
            return self.give_up(i).await;
        }
        if let RestartPlan::Restart { stop, restart } =
            plan_restart(&members, i, true, self.config.strategy, true)
        {
            self.execute(i, stop, restart).await;
        }
    }

    /// A module could not start for a reason a restart cannot fix: reported once, left failed,
    /// and nothing else restarted for it.
    pub(super) async fn on_unrecoverable(&mut self, i: usize, reason: String) {
        if self.stopping {
            return;
        }
        self.record_failure(i, &reason).await;
        self.slots[i].state = SlotState::Failed;
        tracing::error!(agent = %self.agent, module = %self.slots[i].spec.name, "not restarted: a restart cannot fix this; fix the cause and start the module again");
    }

    async fn record_failure(&mut self, i: usize, reason: &str) {
        let slot = &mut self.slots[i];
        let (name, restarts) = (slot.spec.name.clone(), slot.restarts);
        slot.failures += 1;
        slot.last_error = Some(reason.to_string());
        let failures = slot.failures as i64;
        tracing::error!(agent = %self.agent, module = %name, failures, restarts, error = %reason, "module failed");
        self.event(&name, "failed", reason, restarts);
        self.set_stat(i, "stats/failures", failures).await;
        self.set_stat(i, "stats/status", status::FAILED.to_string())
            .await;
    }

    async fn give_up(&mut self, i: usize) {
        let slot = &mut self.slots[i];
        slot.state = SlotState::Failed;
        let name = slot.spec.name.clone();
        let (failures, last) = (slot.failures, slot.last_error.clone());
        // The limit is the agent's (or a group's, escalated to the agent): name it and every
        // module that used it, not only the one whose failure crossed it.
        let used: Vec<String> = self
            .slots
            .iter()
            .filter(|s| s.restarts > 0)
            .map(|s| format!("`{}` {}", s.spec.name, s.restarts))
            .collect();
        let reason = format!(
            "the agent-wide restart limit (supervision max_restarts: {} within_s: {}) was reached; restarts so far: {}; the last failure was module `{name}` (failure {failures}): {}",
            self.config.max_restarts,
            self.config.within_s,
            if used.is_empty() { "none".to_string() } else { used.join(", ") },
            last.as_deref().unwrap_or("no error message")
        );
        tracing::error!(agent = %self.agent, module = %name, on_give_up = ?self.config.on_give_up, "supervisor gave up: {reason}");
        self.event(&name, "gave_up", &reason, self.slots[i].restarts);
        match self.config.on_give_up {
            GiveUp::StopAgent => self
                .control
                .stop(EXIT_GAVE_UP, format!("supervisor gave up: {reason}")),
            GiveUp::DisableModule => {
                self.set_stat(i, "stats/status", status::FAILED.to_string())
                    .await
            }
        }
    }

    /// Stops `stop` (reverse order), then restarts `restart` after the failed module's backoff.
    async fn execute(&mut self, failed: usize, stop: Vec<usize>, restart: Vec<usize>) {
        for &j in &restart {
            self.slots[j].stop.for_restart();
        }
        self.stop_slots(&stop, None).await;
        let unit = self.unit();
        let delay = self.slots[failed].backoff.next_delay(Instant::now(), unit);
        let mut due = Vec::with_capacity(restart.len());
        for j in restart {
            let slot = &mut self.slots[j];
            if slot.state == SlotState::Removed {
                continue; // its slot stays (indices stay valid), the module never comes back
            }
            slot.generation += 1;
            slot.state = SlotState::Waiting;
            due.push((j, slot.generation));
            self.set_stat(j, "stats/status", status::RESTARTING.to_string())
                .await;
        }
        if delay.is_zero() {
            return self.restart_now(due).await;
        }
        let me = self.me.clone();
        tokio::spawn(async move {
            tokio::time::sleep(delay).await;
            let _ = me.cast(SupervisorMsg::Restart(due));
        });
    }

    pub(super) async fn restart_now(&mut self, due: Vec<(usize, u64)>) {
        for (j, generation) in due {
            let slot = &mut self.slots[j];
            if self.stopping || slot.generation != generation || slot.state != SlotState::Waiting {
                continue;
            }
            slot.restarts += 1;
            let (name, restarts) = (slot.spec.name.clone(), slot.restarts);
            tracing::warn!(agent = %self.agent, module = %name, restarts, "restarting module");
            self.event(&name, "restarted", "", restarts);
            self.set_stat(j, "stats/restarts", restarts as i64).await;
            self.spawn(j).await;
        }
    }
}
