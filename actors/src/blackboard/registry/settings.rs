//! What a config says beyond properties — supervision, groups, recording, the scheduler,
//! step budget, real-time priority and the long-step threads' nice offset, and each module's group, restart policy, watchdog, stop timeout and
//! `long_steps` — kept with the registry so that a snapshot writes it back and a snapshot run
//! behaves like the run it froze.

use std::collections::HashMap;

use crate::config::{AgentConfig, ModuleConfig, RecordSection, Scheduler, StepBudget};
use crate::supervision::{GroupConfig, RestartPolicy, SupervisionConfig};

/// The agent's settings that live outside the blackboard.
#[derive(Debug, Clone, Default)]
pub(crate) struct Settings {
    supervision: SupervisionConfig,
    groups: Vec<GroupConfig>,
    record: Option<RecordSection>,
    scheduler: Scheduler,
    step_budget: StepBudget,
    realtime_priority: Option<u8>,
    long_steps_nice: Option<u8>,
    modules: HashMap<String, ModuleSettings>,
}

/// One module's settings that live outside the blackboard.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct ModuleSettings {
    group: Option<String>,
    restart: RestartPolicy,
    watchdog_ms: Option<u64>,
    shutdown_timeout_ms: Option<u64>,
    long_steps: bool,
}

impl Settings {
    pub fn of(config: &AgentConfig) -> Self {
        Settings {
            supervision: config.supervision.clone(),
            groups: config.groups.clone(),
            record: config.record.clone(),
            scheduler: config.scheduler,
            step_budget: config.step_budget,
            realtime_priority: config.realtime_priority,
            long_steps_nice: config.long_steps_nice,
            modules: config
                .modules
                .iter()
                .map(|m| (m.name.clone(), ModuleSettings::of(m)))
                .collect(),
        }
    }

    /// A module added while the agent runs.
    pub fn add_module(&mut self, m: &ModuleConfig) {
        self.modules.insert(m.name.clone(), ModuleSettings::of(m));
    }

    pub fn remove_module(&mut self, module: &str) {
        self.modules.remove(module);
    }

    /// The agent-level fields, as `field: value` RON.
    pub fn agent_fields(&self) -> Vec<String> {
        let mut fields = vec![format!("supervision: {}", ron_text(&self.supervision))];
        if !self.groups.is_empty() {
            fields.push(format!("groups: {}", ron_text(&self.groups)));
        }
        if let Some(record) = &self.record {
            fields.push(format!("record: {}", ron_text(record)));
        }
        if self.scheduler != Scheduler::default() {
            fields.push(format!("scheduler: {}", self.scheduler.name()));
        }
        if self.step_budget != StepBudget::default() {
            fields.push(format!("step_budget: {}", ron_text(&self.step_budget)));
        }
        if let Some(priority) = self.realtime_priority {
            fields.push(format!("realtime_priority: {priority}"));
        }
        if let Some(offset) = self.long_steps_nice {
            fields.push(format!("long_steps_nice: {offset}"));
        }
        fields
    }

    /// `module`'s fields, as `field: value` RON (its restart policy always, the rest when set).
    pub fn module_fields(&self, module: &str) -> Vec<String> {
        let Some(m) = self.modules.get(module) else {
            return Vec::new();
        };
        let mut fields = Vec::new();
        if let Some(group) = &m.group {
            fields.push(format!("group: {group:?}"));
        }
        fields.push(format!("restart: {}", ron_text(&m.restart)));
        if let Some(ms) = m.watchdog_ms {
            fields.push(format!("watchdog_ms: {ms}"));
        }
        if let Some(ms) = m.shutdown_timeout_ms {
            fields.push(format!("shutdown_timeout_ms: {ms}"));
        }
        if m.long_steps {
            fields.push("long_steps: true".to_string());
        }
        fields
    }
}

impl ModuleSettings {
    fn of(m: &ModuleConfig) -> Self {
        ModuleSettings {
            group: m.group.clone(),
            restart: m.restart,
            watchdog_ms: m.watchdog_ms,
            shutdown_timeout_ms: m.shutdown_timeout_ms,
            long_steps: m.long_steps,
        }
    }
}

/// Settings are plain data: writing them cannot fail.
fn ron_text<T: serde::Serialize>(value: &T) -> String {
    crate::value::spaced_ron(&ron::to_string(value).expect("settings serialize to RON"))
}
