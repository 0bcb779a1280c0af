//! The agent's supervisor actor: starts module actors in config order, records their failures,
//! and stops them in reverse order.
//!
//! Policy for now: a failed module is reported (trace, `stats/status = failed`,
//! `stats/failures`) and stays stopped; it never takes the agent or the process down.

use std::sync::Arc;
use std::time::Duration;

use ractor::{Actor, ActorCell, ActorProcessingErr, ActorRef, RpcReplyPort, SupervisionEvent};
use tokio::sync::watch;
use tokio::task::JoinHandle;

use crate::agent::AgentControl;
use crate::blackboard::Blackboard;
use crate::module_actor::{status, ModuleArgs};
use crate::module_types::ModuleType;
use crate::summary::ModuleReport;

struct Slot {
    name: String,
    module_type: ModuleType,
    actor: Option<ActorCell>,
    join: Option<JoinHandle<()>>,
    stop: watch::Sender<bool>,
    failures: u64,
    last_error: Option<String>,
}

pub(crate) struct SupervisorArgs {
    pub agent: Arc<str>,
    pub blackboard: Blackboard,
    pub control: AgentControl,
    pub modules: Vec<(String, ModuleType)>,
}

pub(crate) struct SupervisorState {
    agent: Arc<str>,
    blackboard: Blackboard,
    control: AgentControl,
    slots: Vec<Slot>,
}

pub(crate) enum SupervisorMsg {
    /// Stops every module in reverse start order, each within the timeout, then reports.
    StopAll(Duration, RpcReplyPort<Vec<ModuleReport>>),
    /// Reports every module's status so far.
    Report(RpcReplyPort<Vec<ModuleReport>>),
}

pub(crate) struct AgentSupervisor;

impl Actor for AgentSupervisor {
    type Msg = SupervisorMsg;
    type State = SupervisorState;
    type Arguments = SupervisorArgs;

    async fn pre_start(
        &self,
        me: ActorRef<SupervisorMsg>,
        args: SupervisorArgs,
    ) -> Result<SupervisorState, ActorProcessingErr> {
        let mut state = SupervisorState {
            agent: args.agent,
            blackboard: args.blackboard,
            control: args.control,
            slots: Vec::new(),
        };
        for (name, module_type) in args.modules {
            let (stop, _) = watch::channel(false);
            state.slots.push(Slot {
                name,
                module_type,
                actor: None,
                join: None,
                stop,
                failures: 0,
                last_error: None,
            });
            let index = state.slots.len() - 1;
            state.start(index, me.get_cell()).await;
        }
        tracing::info!(agent = %state.agent, modules = state.slots.len(), "agent started");
        Ok(state)
    }

    async fn handle(
        &self,
        _me: ActorRef<SupervisorMsg>,
        msg: SupervisorMsg,
        state: &mut SupervisorState,
    ) -> Result<(), ActorProcessingErr> {
        match msg {
            SupervisorMsg::StopAll(timeout, reply) => {
                state.stop_all(timeout).await;
                let _ = reply.send(state.report().await);
            }
            SupervisorMsg::Report(reply) => {
                let _ = reply.send(state.report().await);
            }
        }
        Ok(())
    }

    async fn handle_supervisor_evt(
        &self,
        _me: ActorRef<SupervisorMsg>,
        event: SupervisionEvent,
        state: &mut SupervisorState,
    ) -> Result<(), ActorProcessingErr> {
        match event {
            SupervisionEvent::ActorFailed(cell, error) => {
                if let Some(i) = state.slot_of(&cell) {
                    state.slots[i].actor = None;
                    state.failed(i, error.to_string()).await;
                }
            }
            SupervisionEvent::ActorTerminated(cell, _, _) => {
                if let Some(i) = state.slot_of(&cell) {
                    state.slots[i].actor = None;
                }
            }
            _ => {}
        }
        Ok(())
    }
}

impl SupervisorState {
    fn slot_of(&self, cell: &ActorCell) -> Option<usize> {
        self.slots.iter().position(|s| {
            s.actor
                .as_ref()
                .is_some_and(|a| a.get_id() == cell.get_id())
        })
    }

    async fn start(&mut self, index: usize, supervisor: ActorCell) {
        let slot = &mut self.slots[index];
        let (stop, stop_rx) = watch::channel(false);
        slot.stop = stop;
        let args = ModuleArgs {
            agent: self.agent.clone(),
            name: slot.name.clone(),
            blackboard: self.blackboard.clone(),
            control: self.control.clone(),
            stop: stop_rx,
        };
        match slot.module_type.spawn(args, supervisor).await {
            Ok((actor, join)) => {
                slot.actor = Some(actor);
                slot.join = Some(join);
            }
            Err(reason) => {
                self.failed(index, format!("could not start: {reason}"))
                    .await
            }
        }
    }

    async fn failed(&mut self, index: usize, error: String) {
        let slot = &mut self.slots[index];
        slot.failures += 1;
        tracing::error!(agent = %self.agent, module = %slot.name, failures = slot.failures, %error, "module failed; it stays stopped");
        slot.last_error = Some(error);
        let name = slot.name.clone();
        let failures = slot.failures as i64;
        // The blackboard outlives the modules; if it is gone the agent is stopping anyway.
        let _ = self
            .blackboard
            .set_runtime(&format!("{name}/stats/failures"), failures)
            .await;
        let _ = self
            .blackboard
            .set_runtime(&format!("{name}/stats/status"), status::FAILED.to_string())
            .await;
    }

    async fn stop_all(&mut self, timeout: Duration) {
        for slot in self.slots.iter_mut().rev() {
            let _ = slot.stop.send(true);
            let Some(join) = slot.join.take() else {
                continue;
            };
            if tokio::time::timeout(timeout, join).await.is_err() {
                tracing::warn!(agent = %self.agent, module = %slot.name, ?timeout, "module did not stop in time: killed");
                if let Some(actor) = slot.actor.take() {
                    actor.kill();
                }
            }
        }
    }

    async fn report(&self) -> Vec<ModuleReport> {
        let mut reports = Vec::with_capacity(self.slots.len());
        for slot in &self.slots {
            let get = |path: &str| format!("{}/{}", slot.name, path);
            reports.push(ModuleReport {
                name: slot.name.clone(),
                module_type: slot.module_type.name().to_string(),
                status: self
                    .blackboard
                    .get::<String>(&get("stats/status"))
                    .await
                    .map(|s| s.to_string())
                    .unwrap_or_default(),
                steps: self
                    .blackboard
                    .get::<i64>(&get("stats/steps"))
                    .await
                    .map(|s| *s)
                    .unwrap_or_default() as u64,
                failures: slot.failures,
                last_error: slot.last_error.clone(),
            });
        }
        reports
    }
}
