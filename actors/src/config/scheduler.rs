//! Where an agent's module actors run: the `scheduler:` field of an agent config and each
//! module's `long_steps:` (see ARCHITECTURE.md, "Scheduler").

use serde::{Deserialize, Serialize};

use super::{ConfigError, ConfigFile};

/// Where an agent's module actors run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Scheduler {
    /// Every module is a task of the process's shared multi-thread runtime (`--workers`).
    #[default]
    Shared,
    /// The agent gets an OS thread of its own with a current-thread runtime, where its
    /// blackboard, supervisor and modules run, so a hand-over between two of its modules is a
    /// same-thread task wake; modules declared `long_steps: true` run on the shared runtime.
    /// On a current-thread runtime (one worker, paused-clock tests) the agent runs in place.
    AgentThread,
}

impl Scheduler {
    /// The name configs use.
    pub fn name(self) -> &'static str {
        match self {
            Scheduler::Shared => "shared",
            Scheduler::AgentThread => "agent_thread",
        }
    }
}

impl ConfigFile {
    /// `long_steps: true` asks for the shared runtime, where a `shared` agent runs every
    /// module already: refused there, so that a config never says something that does nothing.
    pub(super) fn check_scheduler(&self) -> Vec<ConfigError> {
        if self.config.scheduler == Scheduler::AgentThread {
            return Vec::new();
        }
        self.config
            .modules
            .iter()
            .filter(|m| m.long_steps)
            .map(|m| {
                self.error(
                    &m.name,
                    Some("long_steps"),
                    format!(
                        "module `{}`: `long_steps: true` moves a module off its agent's thread onto the shared runtime, which only `scheduler: agent_thread` gives agents; this agent's scheduler is `{}` (every module is on the shared runtime already): remove `long_steps` or add `scheduler: agent_thread`",
                        m.name,
                        self.config.scheduler.name()
                    ),
                )
            })
            .collect()
    }
}
