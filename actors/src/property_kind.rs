//! The roles a property plays in its module, said by its path's prefix (`in/`, `params/`, ...).

use std::fmt;

/// What role a property plays in its module; the path prefix says it (`in/`, `params/`, ...).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PropertyKind {
    /// `in/...`: a value the module reads, usually linked to another module's output.
    Input,
    /// `params/...`: a setting the module reads; set by config, tools or contexts.
    Param,
    /// `out/...`: a value the module publishes.
    Output,
    /// `state/...`: what the module keeps between steps and must find again after a restart.
    State,
    /// `enabled`: whether the module steps.
    Enabled,
    /// `stats/...`: figures the runtime keeps about the module.
    Stats,
    /// `control/...`: requests to the runtime about the module (e.g. fault injection).
    Control,
    /// `out/...` queue: a stream the module produces.
    QueueOut,
    /// `in/...` queue: a stream the module consumes.
    QueueIn,
}

impl PropertyKind {
    /// The path prefix properties of this kind must have.
    pub fn prefix(self) -> &'static str {
        match self {
            PropertyKind::Input | PropertyKind::QueueIn => "in/",
            PropertyKind::Param => "params/",
            PropertyKind::Output | PropertyKind::QueueOut => "out/",
            PropertyKind::State => "state/",
            PropertyKind::Enabled => "enabled",
            PropertyKind::Stats => "stats/",
            PropertyKind::Control => "control/",
        }
    }

    /// Whether a link may point this property elsewhere.
    pub fn linkable(self) -> bool {
        matches!(
            self,
            PropertyKind::Input | PropertyKind::Param | PropertyKind::QueueIn
        )
    }

    /// Whether this is a queue rather than a last-value property.
    pub fn is_queue(self) -> bool {
        matches!(self, PropertyKind::QueueIn | PropertyKind::QueueOut)
    }

    /// Whether the runtime owns it (declared for every module: `enabled`, `stats/...`, `control/...`).
    pub fn is_builtin(self) -> bool {
        matches!(
            self,
            PropertyKind::Enabled | PropertyKind::Stats | PropertyKind::Control
        )
    }

    /// Whether configs and snapshots may set its value.
    pub fn settable(self) -> bool {
        !matches!(self, PropertyKind::Stats) && !self.is_queue()
    }
}

impl fmt::Display for PropertyKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            PropertyKind::Input => "input",
            PropertyKind::Param => "param",
            PropertyKind::Output => "output",
            PropertyKind::State => "state",
            PropertyKind::Enabled => "enabled",
            PropertyKind::Stats => "stats",
            PropertyKind::Control => "control",
            PropertyKind::QueueOut => "queue output",
            PropertyKind::QueueIn => "queue input",
        })
    }
}
