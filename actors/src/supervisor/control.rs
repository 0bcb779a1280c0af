//! Runtime control of modules through the supervisor: stop, start, restart, add, remove.

use std::time::Duration;

use super::{ControlRequest, ModuleSpec, Slot, SlotState, SupervisorState};
use crate::config::{ModuleConfig, Scheduler};

impl SupervisorState {
    pub(super) async fn control_request(&mut self, request: ControlRequest) -> Result<(), String> {
        if self.stopping {
            return Err("the agent is stopping".into());
        }
        tracing::info!(agent = %self.agent, ?request, "control request");
        match request {
            ControlRequest::Stop(name) => {
                let i = self.find(&name)?;
                self.stop_slot(i, None).await;
                self.event(&name, "stopped", "on request", self.slots[i].restarts);
            }
            ControlRequest::Start(name) => {
                let i = self.find(&name)?;
                if self.slots[i].actor.is_some() {
                    return Err(format!("module `{name}` is already running"));
                }
                self.slots[i].generation += 1;
                self.spawn(i).await;
            }
            ControlRequest::Restart(name) => {
                let i = self.find(&name)?;
                self.slots[i].stop.for_restart();
                self.stop_slot(i, None).await;
                self.slots[i].restarts += 1;
                let restarts = self.slots[i].restarts;
                self.set_stat(i, "stats/restarts", restarts as i64).await;
                self.event(&name, "restarted", "on request", restarts);
                self.spawn(i).await;
            }
            ControlRequest::Add(config) => self.add(*config).await?,
            ControlRequest::Remove(name) => {
                let i = self.find(&name)?;
                self.blackboard
                    .remove_module(&name)
                    .await
                    .map_err(|e| e.to_string())?;
                self.stop_slot(i, None).await;
                self.slots[i].state = SlotState::Removed;
                self.event(&name, "removed", "on request", self.slots[i].restarts);
            }
        }
        Ok(())
    }

    /// Moves the module instance `actor` off the agent's thread, as `long_steps: true` would:
    /// stopped at its next step boundary and started again on the shared runtime (its state
    /// lives in the blackboard), reported as a `moved` event. An instance that ended
    /// meanwhile, or one already moved, is left alone.
    pub(super) async fn move_to_shared(&mut self, actor: ractor::ActorId, mean: Duration) {
        let Some(i) = self.slots.iter().position(|s| {
            s.state == SlotState::Running && s.actor.as_ref().is_some_and(|a| a.get_id() == actor)
        }) else {
            return;
        };
        let reason = format!(
            "its steps took {:.2} ms on average over {} steps, above the agent's step_budget of {} µs: moved off the agent's thread to where `long_steps: true` modules run",
            mean.as_secs_f64() * 1e3,
            self.step_budget.steps,
            self.step_budget.mean_us
        );
        self.move_slot(i, reason).await;
    }

    /// Moves slot `i`'s module off the agent's thread after one of its steps held the thread
    /// for over `held` (the step has returned: this runs on that thread).
    pub(super) async fn move_held(&mut self, i: usize, held: Duration) {
        if self
            .slots
            .get(i)
            .is_none_or(|s| s.state != SlotState::Running)
        {
            return;
        }
        let reason = format!(
            "one of its steps held the agent's thread for over {} ms without yielding (the agent's step_budget allows {} ms): moved off the agent's thread to where `long_steps: true` modules run",
            held.as_millis(),
            self.step_budget.held_ms
        );
        self.move_slot(i, reason).await;
    }

    async fn move_slot(&mut self, i: usize, reason: String) {
        let on_agent_thread = self.shared.is_some();
        if self.stopping || !on_agent_thread || self.slots[i].spec.long_steps {
            return;
        }
        let name = self.slots[i].spec.name.clone();
        tracing::warn!(agent = %self.agent, module = %name, "{reason}");
        self.slots[i].stop.for_restart();
        self.stop_slot(i, None).await;
        self.slots[i].spec.long_steps = true;
        self.slots[i].moves += 1;
        self.event(&name, "moved", &reason, self.slots[i].restarts);
        self.spawn(i).await;
    }

    /// Adds a module instance while running: declared in the blackboard, then started.
    async fn add(&mut self, config: ModuleConfig) -> Result<(), String> {
        if self.find(&config.name).is_ok() {
            return Err(format!("a module `{}` already exists", config.name));
        }
        let Some(module_type) = self.types.get(&config.type_name).copied() else {
            let near = self.types.nearest(&config.type_name).join(", ");
            return Err(format!(
                "unknown module type `{}` (nearest: {near})",
                config.type_name
            ));
        };
        if config.long_steps && self.scheduler != Scheduler::AgentThread {
            return Err(format!(
                "module `{}`: `long_steps: true` needs `scheduler: agent_thread` (this agent's scheduler is `{}`)",
                config.name,
                self.scheduler.name()
            ));
        }
        let group = match &config.group {
            None => None,
            Some(g) => Some(
                self.groups
                    .iter()
                    .position(|x| &x.name == g)
                    .ok_or_else(|| format!("unknown group `{g}`"))?,
            ),
        };
        let spec = ModuleSpec {
            name: config.name.clone(),
            module_type,
            group,
            policy: config.restart,
            watchdog: config.watchdog_ms.map(Duration::from_millis),
            shutdown_timeout: Duration::from_millis(
                config
                    .shutdown_timeout_ms
                    .unwrap_or(self.config.shutdown_timeout_ms),
            ),
            long_steps: config.long_steps,
        };
        self.blackboard.add_module(config, module_type).await?;
        self.slots.push(Slot::new(spec, self.config.backoff));
        let i = self.slots.len() - 1;
        self.event(&self.slots[i].spec.name, "added", "on request", 0);
        self.spawn(i).await;
        Ok(())
    }
}
