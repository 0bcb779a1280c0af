//! The run summary printed when an agent stops.

use std::fmt;

/// How one module fared.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ModuleReport {
    /// Instance name.
    pub name: String,
    /// Module type.
    pub module_type: String,
    /// Last status (`stopped`, `failed`, ...).
    pub status: String,
    /// Steps run.
    pub steps: u64,
    /// Failures (panics, errors, hangs).
    pub failures: u64,
    /// Restarts by the supervisor.
    pub restarts: u64,
    /// Moves off the agent's thread to the shared runtime (steps over the agent's
    /// `step_budget`); each starts a new instance, like a restart.
    pub moves: u64,
    /// The last failure's message.
    pub last_error: Option<String>,
}

/// Every module's report, in start order.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RunSummary {
    /// The agent.
    pub agent: String,
    /// One report per module.
    pub modules: Vec<ModuleReport>,
}

impl RunSummary {
    /// The report of module `name`.
    pub fn module(&self, name: &str) -> Option<&ModuleReport> {
        self.modules.iter().find(|m| m.name == name)
    }

    /// Total restarts across modules.
    pub fn restarts(&self) -> u64 {
        self.modules.iter().map(|m| m.restarts).sum()
    }

    /// Total moves across modules.
    pub fn moves(&self) -> u64 {
        self.modules.iter().map(|m| m.moves).sum()
    }

    /// Total failures across modules.
    pub fn failures(&self) -> u64 {
        self.modules.iter().map(|m| m.failures).sum()
    }
}

impl fmt::Display for RunSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let w = self
            .modules
            .iter()
            .map(|m| m.name.len())
            .max()
            .unwrap_or(6)
            .max(6);
        let tw = self
            .modules
            .iter()
            .map(|m| m.module_type.len())
            .max()
            .unwrap_or(4)
            .max(4);
        write!(
            f,
            "agent {}: {}, {}, {}",
            self.agent,
            counted(self.modules.len() as u64, "module"),
            counted(self.failures(), "failure"),
            counted(self.restarts(), "restart")
        )?;
        match self.moves() {
            0 => writeln!(f)?,
            moves => writeln!(f, ", {}", counted(moves, "move"))?,
        }
        writeln!(
            f,
            "  {:<w$}  {:<tw$}  {:<12}  {:>9}  {:>8}  {:>8}  {:>5}",
            "module", "type", "status", "steps", "failures", "restarts", "moves"
        )?;
        for m in &self.modules {
            writeln!(
                f,
                "  {:<w$}  {:<tw$}  {:<12}  {:>9}  {:>8}  {:>8}  {:>5}",
                m.name, m.module_type, m.status, m.steps, m.failures, m.restarts, m.moves
            )?;
            if let Some(e) = &m.last_error {
                writeln!(f, "  {:<w$}  last error: {e}", "")?;
            }
        }
        Ok(())
    }
}

/// `1 restart`, `2 restarts`.
fn counted(n: u64, noun: &str) -> String {
    match n {
        1 => format!("1 {noun}"),
        n => format!("{n} {noun}s"),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn one_is_said_in_the_singular() {
        assert_eq!(super::counted(1, "restart"), "1 restart");
        assert_eq!(super::counted(0, "restart"), "0 restarts");
        assert_eq!(super::counted(5, "module"), "5 modules");
    }
}
