//! Where an agent's module actors run: the `scheduler:` field of an agent config, its
//! `step_budget:`, its `realtime_priority:` and `long_steps_nice:`, and each module's
//! `long_steps:` (see
//! ARCHITECTURE.md, "Scheduler").

use serde::{Deserialize, Serialize};

use super::{ConfigError, ConfigFile};

/// Where an agent's module actors run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Scheduler {
    /// Every module is a task of the process's shared multi-thread runtime (`--workers`):
    /// a hand-over that wakes a reader may cost a cross-thread wake, and a step that blocks
    /// holds one worker rather than the agent's thread.
    Shared,
    /// The default. The agent gets an OS thread of its own with a current-thread runtime,
    /// where its blackboard, supervisor and modules run, so a hand-over between two of its
    /// modules is a same-thread task wake; modules declared `long_steps: true`, and those the
    /// agent's `step_budget` moves, run on the shared runtime. On a current-thread runtime (one
    /// worker, paused-clock tests) the agent runs in place.
    #[default]
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

/// How long a module's steps may be on its agent's thread (`scheduler: agent_thread`) before
/// the runtime moves it to the shared runtime, as if it were declared `long_steps: true`:
/// when the mean of `steps` timed steps in a row exceeds `mean_us` µs, the module is restarted
/// there at its next step boundary (its state lives in the blackboard) and a `moved`
/// supervisor event says so. A single step that holds the thread for `held_ms` without yielding
/// (it blocks, or computes in one go) is reported at once as a `held` event and the module moved
/// when that step returns. `mean_us: 0` and `held_ms: 0` turn each rule off. Without
/// `agent_thread` it does nothing (every module is on the shared runtime already).
///
/// ```ron
/// Agent(name: "r", step_budget: (mean_us: 1000, steps: 20, held_ms: 100), modules: [...])
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct StepBudget {
    /// The longest mean step allowed, µs: 0 (never move) or 50..=60 000 000.
    pub mean_us: u64,
    /// Timed steps the mean is taken over: 1..=1 000 000.
    pub steps: u32,
    /// The longest one step may hold the agent's thread, ms: 0 (never move a module for it)
    /// or 10..=60 000.
    pub held_ms: u64,
}

impl Default for StepBudget {
    /// 1 ms over 20 steps: a longer mean step holds up the agent's other modules more than a
    /// cross-thread hand-over (a few µs) would cost the module. 100 ms in one step: a 1 kHz
    /// module beside it would miss a hundred periods.
    fn default() -> Self {
        StepBudget {
            mean_us: 1000,
            steps: 20,
            held_ms: 100,
        }
    }
}

/// Smallest non-zero `mean_us`: below it the clock reads of timing would be the budget.
const MIN_MEAN_US: u64 = 50;
/// Largest `mean_us` (a minute).
const MAX_MEAN_US: u64 = 60_000_000;
/// Largest `steps`.
const MAX_STEPS: u32 = 1_000_000;
/// Smallest non-zero `held_ms`: the watcher samples the thread four times per `held_ms`.
const MIN_HELD_MS: u64 = 10;
/// Largest `held_ms` (a minute).
const MAX_HELD_MS: u64 = 60_000;

impl ConfigFile {
    /// The `step_budget` fields out of range, located at the field.
    pub(super) fn check_step_budget(&self) -> Vec<ConfigError> {
        let b = self.config.step_budget;
        let mut errors = Vec::new();
        if b.mean_us != 0 && !(MIN_MEAN_US..=MAX_MEAN_US).contains(&b.mean_us) {
            errors.push(self.locate_field(
                "mean_us",
                format!(
                    "step_budget: mean_us is {}; expected 0 (never move a module) or {MIN_MEAN_US}..={MAX_MEAN_US} µs",
                    b.mean_us
                ),
            ));
        }
        if !(1..=MAX_STEPS).contains(&b.steps) {
            errors.push(self.locate_field(
                "steps",
                format!(
                    "step_budget: steps is {}; expected 1..={MAX_STEPS} timed steps",
                    b.steps
                ),
            ));
        }
        if b.held_ms != 0 && !(MIN_HELD_MS..=MAX_HELD_MS).contains(&b.held_ms) {
            errors.push(self.locate_field(
                "held_ms",
                format!(
                    "step_budget: held_ms is {}; expected 0 (never move a module for one long step) or {MIN_HELD_MS}..={MAX_HELD_MS} ms",
                    b.held_ms
                ),
            ));
        }
        errors
    }

    /// An error at `field:` inside the `step_budget:` that sets it (overlays win), else at
    /// `step_budget:` (a module's `long_steps:` must not be taken for `steps:`).
    fn locate_field(&self, field: &str, message: String) -> ConfigError {
        for (file, text) in self.sources.iter().rev() {
            let Some(start) = text.find("step_budget") else {
                continue;
            };
            let rest = &text[start..];
            let end = rest.find(')').unwrap_or(rest.len());
            let at = rest[..end]
                .match_indices(&format!("{field}:"))
                .find(|(i, _)| !rest[..*i].ends_with(|c: char| c == '_' || c.is_alphanumeric()))
                .map_or(start, |(i, _)| start + i);
            return ConfigError::at(file, text, at, message);
        }
        self.locate("step_budget", message)
    }

    /// `realtime_priority` out of 1..=99, or on an agent without a thread of its own.
    pub(super) fn check_realtime_priority(&self) -> Vec<ConfigError> {
        self.check_agent_thread_field(
            "realtime_priority",
            self.config.realtime_priority,
            (1, 99),
            "a SCHED_FIFO priority",
            "is for the agent's own thread",
        )
    }

    /// `long_steps_nice` out of 1..=19, or on an agent without a thread of its own (under
    /// `shared` every module runs on the shared runtime, and none would run below another).
    pub(super) fn check_long_steps_nice(&self) -> Vec<ConfigError> {
        self.check_agent_thread_field(
            "long_steps_nice",
            self.config.long_steps_nice,
            (1, 19),
            "how many nice levels below the agent's thread its long-step modules run",
            "puts long-step modules below the agent's own thread",
        )
    }

    /// A setting `field` of the agent's own thread, `value` if given: refused outside
    /// `low..=high` (`expected` says what the number is) or without such a thread (`does`
    /// says what the setting needs it for), where it is written.
    fn check_agent_thread_field(
        &self,
        field: &str,
        value: Option<u8>,
        (low, high): (u8, u8),
        expected: &str,
        does: &str,
    ) -> Vec<ConfigError> {
        let Some(value) = value else {
            return Vec::new();
        };
        let message = if !(low..=high).contains(&value) {
            format!("{field} is {value}; expected {expected}, {low}..={high}")
        } else if self.config.scheduler != Scheduler::AgentThread {
            format!(
                "{field} {does}, which only `scheduler: agent_thread` gives it; this agent's scheduler is `{}`: remove `{field}` or use `scheduler: agent_thread`",
                self.config.scheduler.name()
            )
        } else {
            return Vec::new();
        };
        vec![self.locate(field, message)]
    }

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
