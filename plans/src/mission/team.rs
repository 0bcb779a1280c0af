//! A mission in a team: the shell around [`crate::remote`].
//!
//! In `run` mode (the default) the mission runs its plan and sends other robots' actions
//! (`robot#action`) to the executor module on their agents, reading their conditions
//! (`robot#cond`) from them; in `serve` mode it runs no plan and carries out this agent's
//! actions (`me#action`) for whoever runs the team plan. Messages go through the mission's
//! `out/outbox` and `in/inbox` (delivered in order by the team transport); who is in the team
//! comes from `_team/members`, so a robot whose agent dies is seen leaving and fails its
//! running actions.

use petrel_actors::team::{Message, TeamMembers};
use petrel_actors::{AnyHandle, Context, QueueReader, QueueWriter};

use crate::remote::{Dispatch, Outgoing, Serve, TeamMsg};

/// `params/mode` values.
pub(crate) const RUN: &str = "run";
pub(crate) const SERVE: &str = "serve";

/// Whether `params/mode` says `serve`; an error naming the expected values otherwise.
pub(crate) fn is_serve(mode: &str) -> Result<bool, String> {
    match mode {
        RUN => Ok(false),
        SERVE => Ok(true),
        other => Err(format!(
            "expected `{RUN}` (run the plan) or `{SERVE}` (carry out this agent's own `agent#action`s for a plan run elsewhere), got `{other}`"
        )),
    }
}

/// Why a mission needs a team that agent `agent` does not have.
pub(crate) fn needs_team(dispatch: &Dispatch, serve: bool, agent: &str) -> String {
    let robots: Vec<&str> = dispatch.robots().collect();
    let why = match serve {
        true => "params/mode is `serve`".to_string(),
        false => format!("the plan names other robots ({})", robots.join(", ")),
    };
    format!("{why}, which needs a team: agent `{agent}` has no `team:` section")
}

/// The mission's side of the team: dispatch (run mode) or serve state, and membership.
pub(crate) struct TeamIo {
    pub agent: String,
    pub dispatch: Dispatch,
    /// `params/mode` is `serve`: no plan runs here.
    pub serve_mode: bool,
    /// What other agents' plans ask of this one: actions (serve mode) and conditions.
    pub serve: Serve,
    /// Serve mode: starts (full name, call) waiting for a running action that switches the
    /// same modules to end: a robot does one thing with its explorer at a time.
    pub pending: Vec<(String, crate::label::CallKind)>,
    /// `_team/members`, when the agent is in a team and the mission needs it.
    pub members: Option<AnyHandle>,
    members_seen: Option<u64>,
    /// The plan waits for these robots' conditions (logged when it changes).
    waiting: Vec<String>,
}

impl TeamIo {
    /// Connects to the team when the plan names other robots (or in serve mode); an agent
    /// without a `team:` section cannot.
    pub async fn connect(ctx: &Context, dispatch: Dispatch, serve: bool) -> anyhow::Result<Self> {
        let members = if dispatch.is_empty() && !serve {
            None
        } else {
            let h = ctx.blackboard().any_handle("_team/members").await.ok();
            if h.is_none() {
                // No restart will give the agent a team.
                let message = needs_team(&dispatch, serve, ctx.agent());
                return Err(petrel_actors::Unrecoverable(message).into());
            }
            h
        };
        Ok(TeamIo {
            agent: ctx.agent().to_string(),
            dispatch,
            serve_mode: serve,
            serve: Serve::new(),
            pending: Vec::new(),
            members,
            members_seen: None,
            waiting: Vec::new(),
        })
    }

    /// The agents in the team now, if that changed since the last call.
    pub fn members_changed(&mut self) -> Option<Vec<String>> {
        let h = self.members.as_ref()?;
        let version = h.version();
        if self.members_seen == Some(version) {
            return None;
        }
        self.members_seen = Some(version);
        let members = h.get::<TeamMembers>()?;
        Some(members.0.iter().map(|m| m.agent.clone()).collect())
    }

    /// Run mode, before the plan steps: answers and conditions from robots (when `items` says
    /// the inbox may hold some), robots that joined or left. Returns whether the plan may step
    /// (it waits for robots' conditions).
    pub fn take_news(&mut self, inbox: &QueueReader<Message>, items: bool) -> bool {
        let news = match items {
            true => inbox.drain(),
            false => Vec::new(),
        };
        for item in news {
            let result = match TeamMsg::decode(&item.body) {
                // Another agent's plan watching this one's conditions (distributed plans).
                Ok(TeamMsg::Watch { .. } | TeamMsg::Call { .. }) => {
                    match self.serve.receive(&item.from, &item.body) {
                        Ok(Some((action, call))) => Err(format!(
                            "`{action}.{call}`: this mission runs its own plan; only a mission in serve mode carries out calls (answered as failed)"
                        )),
                        other => other.map(|_| ()),
                    }
                }
                Ok(_) => self.dispatch.receive(&item.from, &item.body),
                Err(e) => Err(e),
            };
            if let Err(e) = result {
                tracing::warn!(from = %item.from, "message ignored: {e}");
            }
        }
        if let Some(present) = self.members_changed() {
            self.serve.members(present.iter().map(String::as_str));
            for gone in self.dispatch.members(present.iter().map(String::as_str)) {
                tracing::warn!(
                    robot = %gone.robot,
                    failed = ?gone.failed,
                    "a robot left the team: its running actions fail"
                );
            }
        }
        let waiting: Vec<String> = self
            .dispatch
            .waiting_for()
            .iter()
            .map(|r| r.to_string())
            .collect();
        if waiting != self.waiting {
            if !waiting.is_empty() {
                tracing::info!(robots = ?waiting, "the plan waits for these robots' conditions");
            }
            self.waiting = waiting;
        }
        self.waiting.is_empty()
    }

    /// Pushes the messages the plan (or the executor) made.
    pub fn send(&mut self, outbox: &QueueWriter<Message>) {
        let mut out = self.dispatch.take_outgoing();
        out.extend(self.serve.take_outgoing());
        for Outgoing { to, body } in out {
            outbox.push(Message {
                to,
                from: String::new(),
                body,
            });
        }
    }
}
