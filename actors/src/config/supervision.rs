//! Checks of the `supervision:` section, `groups:` and the modules' supervision fields.

use std::collections::HashSet;

use super::{ConfigError, ConfigFile};

/// Largest `max_restarts` accepted.
const MAX_RESTARTS_LIMIT: u32 = 100_000;
/// Longest intensity window accepted, seconds.
const MAX_WINDOW_S: f64 = 86_400.0;

/// Longest stop timeout, watchdog or restart back-off accepted: one hour.
const MAX_WAIT_MS: u64 = 3_600_000;
/// Longest `reset_after_ms` accepted: one day.
const MAX_RESET_MS: u64 = 86_400_000;

fn hours(ms: u64) -> String {
    match ms / 3_600_000 {
        1 => "one hour".into(),
        h => format!("{h} hours"),
    }
}

impl ConfigFile {
    /// Checks the `supervision` section, groups, and the modules' supervision fields.
    pub(super) fn check_supervision(&self) -> Vec<ConfigError> {
        let mut errors = Vec::new();
        // Named in events, the run summary and module settings like a module.
        for g in &self.config.groups {
            if !crate::url::valid_segment(&g.name) {
                errors.push(self.locate(
                    &format!("\"{}\"", g.name),
                    format!(
                        "group name {}: {}",
                        super::shown_name(&g.name),
                        super::NAME_RULE
                    ),
                ));
            }
        }
        let at = |needle: &str, message: String| self.locate(&format!("{needle}:"), message);
        let s = &self.config.supervision;
        // At the field as written in its section (`section` starts it).
        let mut intensity = |what: &str, max: u32, within: f64, section: &str| {
            if max > MAX_RESTARTS_LIMIT {
                errors.push(self.locate_after(
                    section,
                    "max_restarts:",
                    format!("{what}: max_restarts is {max}; expected 0..={MAX_RESTARTS_LIMIT}"),
                ));
            }
            if !(within > 0.0 && within <= MAX_WINDOW_S) {
                errors.push(self.locate_after(section, "within_s:", format!("{what}: within_s is {}; expected a number of seconds in (0, {MAX_WINDOW_S}]", crate::short_number(within))));
            }
        };
        intensity("supervision", s.max_restarts, s.within_s, "supervision:");
        for g in &self.config.groups {
            intensity(
                &format!("group `{}`", g.name),
                g.max_restarts,
                g.within_s,
                &format!("\"{}\"", g.name),
            );
        }
        let b = &s.backoff;
        if b.min_ms > b.max_ms {
            errors.push(at(
                "backoff",
                format!(
                    "supervision backoff: min_ms ({}) is above max_ms ({})",
                    b.min_ms, b.max_ms
                ),
            ));
        }
        if !(0.0..=1.0).contains(&b.jitter) {
            errors.push(at(
                "jitter",
                format!(
                    "supervision backoff: jitter is {}; expected 0.0..=1.0",
                    crate::short_number(b.jitter)
                ),
            ));
        }
        // Durations a stop or a restart waits: bounded, so that a stop always ends (u64::MAX
        // milliseconds overflowed the clock and the process never stopped).
        let mut bounded = |what: String, needle: &str, ms: u64, max: u64| {
            if ms > max {
                errors.push(at(
                    needle,
                    format!(
                        "{what} is {ms} ms; expected at most {max} ms ({})",
                        hours(max)
                    ),
                ));
            }
        };
        bounded(
            "supervision backoff: min_ms".into(),
            "min_ms",
            b.min_ms,
            MAX_WAIT_MS,
        );
        bounded(
            "supervision backoff: max_ms".into(),
            "max_ms",
            b.max_ms,
            MAX_WAIT_MS,
        );
        let reset = b.reset_after_ms;
        bounded(
            "supervision backoff: reset_after_ms".into(),
            "reset_after_ms",
            reset,
            MAX_RESET_MS,
        );
        let stop = s.shutdown_timeout_ms;
        bounded(
            "supervision: shutdown_timeout_ms".into(),
            "shutdown_timeout_ms",
            stop,
            MAX_WAIT_MS,
        );
        for m in &self.config.modules {
            if let Some(ms) = m.shutdown_timeout_ms {
                let what = format!("module `{}`: shutdown_timeout_ms", m.name);
                bounded(what, "shutdown_timeout_ms", ms, MAX_WAIT_MS);
            }
            if let Some(ms) = m.watchdog_ms {
                bounded(
                    format!("module `{}`: watchdog_ms", m.name),
                    "watchdog_ms",
                    ms,
                    MAX_WAIT_MS,
                );
            }
        }
        let mut seen = HashSet::new();
        for g in &self.config.groups {
            if !seen.insert(g.name.as_str()) {
                errors.push(self.locate(
                    &format!("\"{}\"", g.name),
                    format!("duplicate group name `{}`", g.name),
                ));
            }
        }
        for m in &self.config.modules {
            if m.name.starts_with('_') {
                errors.push(self.error(
                    &m.name,
                    None,
                    format!(
                        "module name `{}`: names starting with `_` are reserved for the runtime",
                        m.name
                    ),
                ));
            }
            if let Some(group) = &m.group {
                if !seen.contains(group.as_str()) {
                    let mut known: Vec<&str> =
                        self.config.groups.iter().map(|g| g.name.as_str()).collect();
                    known.dedup();
                    let known = if known.is_empty() {
                        "none are defined".to_string()
                    } else {
                        format!("groups: {}", known.join(", "))
                    };
                    errors.push(self.error(
                        &m.name,
                        Some(group),
                        format!("module `{}`: unknown group `{group}` ({known})", m.name),
                    ));
                }
            }
            if m.watchdog_ms == Some(0) {
                errors.push(self.error(
                    &m.name,
                    Some("watchdog_ms"),
                    format!("module `{}`: watchdog_ms must be above 0", m.name),
                ));
            }
        }
        errors
    }
}
