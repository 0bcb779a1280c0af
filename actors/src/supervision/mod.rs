//! Supervision: what the agent supervisor does when a module fails.
//!
//! Modelled on Erlang/OTP supervisors and Akka's backoff supervisor:
//! - a tree: the agent supervisor → optional named groups → modules; children start in config
//!   order and stop in reverse order;
//! - a **strategy** per agent or group: `one_for_one` (restart the failed module),
//!   `one_for_all` (restart every module of its group), `rest_for_one` (restart it and the
//!   modules after it in its group);
//! - a **restart policy** per module: `permanent` (always restarted), `transient` (restarted
//!   after a failure, not after a normal stop), `temporary` (never restarted);
//! - an **intensity**: at most `max_restarts` restarts within `within_s` seconds per
//!   supervisor (defaults 5 in 10 s); beyond that a group fails to the agent, and the agent gives
//!   up: `on_give_up: stop_agent` (stop everything, exit non-zero) or `disable_module` (keep
//!   running without that module);
//! - **backoff** between restarts of a module: exponential from `min_ms` to `max_ms` with random
//!   `jitter`, reset once the module ran `reset_after_ms` without failing.
//!
//! A failure is a panic in any module hook, an `Err` from `init` or `step`, or a step that
//! exceeds the module's watchdog. A restarted module binds to the same blackboard cells, so its
//! parameters, state and outputs are as the failed instance left them; its queue readers rewind
//! to their last acknowledged item (see [`QueueReader`](crate::QueueReader) for the guarantee).

mod long_steps;
mod policy;

pub(crate) use long_steps::LongStepWatch;
pub(crate) use policy::{plan_restart, Member, RestartPlan};
pub use policy::{Backoff, Intensity};

use serde::{Deserialize, Serialize};

use crate::types::PropertyType;

/// How a supervisor restarts its children when one fails.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Strategy {
    /// Restart only the failed module.
    #[default]
    OneForOne,
    /// Restart every module of the group (stopping the others first, in reverse order).
    OneForAll,
    /// Restart the failed module and every module after it in the group's order.
    RestForOne,
}

/// Whether a module is restarted when it ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RestartPolicy {
    /// Always restarted.
    #[default]
    Permanent,
    /// Restarted after a failure, not after a normal stop.
    Transient,
    /// Never restarted.
    Temporary,
}

/// What the agent does when restarts exceed its intensity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GiveUp {
    /// Stop every module in reverse order; `petrel run` exits non-zero with a report.
    #[default]
    StopAgent,
    /// Leave the module that failed stopped (status `failed`) and keep the agent running.
    DisableModule,
}

/// Backoff settings (milliseconds).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct BackoffConfig {
    /// Delay before the first restart.
    pub min_ms: u64,
    /// Longest delay.
    pub max_ms: u64,
    /// Random spread, as a fraction of the delay (0 = none, 0.2 = ±20 %).
    pub jitter: f64,
    /// A module that ran this long without failing starts again from `min_ms`.
    pub reset_after_ms: u64,
}

impl Default for BackoffConfig {
    fn default() -> Self {
        BackoffConfig {
            min_ms: 10,
            max_ms: 2_000,
            jitter: 0.2,
            reset_after_ms: 10_000,
        }
    }
}

/// The `supervision` section of an agent config.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct SupervisionConfig {
    /// The agent's strategy for its top-level modules and groups.
    pub strategy: Strategy,
    /// Restarts allowed within `within_s` before giving up.
    pub max_restarts: u32,
    /// The intensity window, seconds.
    pub within_s: f64,
    /// What to do beyond the intensity.
    pub on_give_up: GiveUp,
    /// Delays between restarts.
    pub backoff: BackoffConfig,
    /// Default time a module gets to stop before it is killed, ms.
    pub shutdown_timeout_ms: u64,
}

impl Default for SupervisionConfig {
    fn default() -> Self {
        SupervisionConfig {
            strategy: Strategy::OneForOne,
            max_restarts: 5,
            within_s: 10.0,
            on_give_up: GiveUp::StopAgent,
            backoff: BackoffConfig::default(),
            shutdown_timeout_ms: 5_000,
        }
    }
}

/// A named group of modules with its own strategy and intensity.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GroupConfig {
    /// Group name, referenced by modules' `group`.
    pub name: String,
    /// The group's strategy.
    #[serde(default)]
    pub strategy: Strategy,
    /// Restarts allowed within `within_s` before the group fails to the agent.
    #[serde(default = "default_max_restarts")]
    pub max_restarts: u32,
    /// The intensity window, seconds.
    #[serde(default = "default_within")]
    pub within_s: f64,
}

fn default_max_restarts() -> u32 {
    SupervisionConfig::default().max_restarts
}

fn default_within() -> f64 {
    SupervisionConfig::default().within_s
}

/// One supervision event, as pushed to the agent's `_supervisor/events` queue.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SupervisorEvent {
    /// Seconds since the agent started.
    pub time_s: f64,
    /// The module concerned (or the group, for `escalated`).
    pub module: String,
    /// `failed`, `restarted`, `escalated`, `gave_up`, `stopped`, `added`, `removed`,
    /// `held` (one step of it is holding its agent's thread past the agent's
    /// `step_budget.held_ms`; written while it holds), or `moved` (off its agent's thread: its
    /// steps exceeded the agent's `step_budget`).
    pub kind: String,
    /// The panic message, error or explanation.
    pub reason: String,
    /// Restarts of this module so far.
    pub restarts: i64,
}

impl PropertyType for SupervisorEvent {
    const TYPE_NAME: &'static str = "SupervisorEvent";
}

/// Where supervision events are published, inside the agent.
pub const EVENTS_MODULE: &str = "_supervisor";
/// The queue path of supervision events.
pub const EVENTS_PATH: &str = "events";
