//! Whole-system tests of the runtime core: agents started from RON configs, driven and
//! observed through the blackboard. Timing uses tokio's paused clock, never wall-clock sleeps.

mod config_errors;
mod contexts;
mod custom_module;
mod failures;
mod fairness;
mod links;
mod nan_recovery;
mod ordering;
mod ordering_modules;
mod param_rules;
mod placement;
mod queues;
mod realtime;
mod scheduling;
mod settle;
mod snapshot;
mod step_budget;
mod step_budget_load;
mod supervision;
mod support;
