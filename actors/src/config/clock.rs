//! `clock_s:`, the agent's wall clock a snapshot was taken at (an agent started from it goes on
//! from that time: `expr::continue_from`).

use super::{ConfigError, ConfigFile};

impl ConfigFile {
    /// `clock_s` (a snapshot's clock), if given: seconds a clock can read.
    pub(super) fn check_clock(&self) -> Vec<ConfigError> {
        match self.config.clock_s {
            Some(s) if !(s.is_finite() && (0.0..=crate::expr::MAX_CLOCK_S).contains(&s)) => {
                vec![self.locate(
                    "clock_s:",
                    format!(
                        "clock_s is {}; expected the seconds of a snapshot's clock, 0..=1e12",
                        crate::short_number(s)
                    ),
                )]
            }
            _ => Vec::new(),
        }
    }
}
