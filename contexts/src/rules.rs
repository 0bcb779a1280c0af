//! The context rules file (RON) and where things are in it.
//!
//! ```ron
//! Contexts(
//!     contexts: [
//!         (
//!             name: "fast",
//!             when: "robot/out/actualSpeed.v > 0.6",    // entry condition (an expression)
//!             until: "robot/out/actualSpeed.v < 0.4",   // exit condition; default: not `when`
//!             min_dwell_ms: 500,                        // stay active/inactive at least this long
//!             priority: 10,                             // higher wins on a shared target
//!             set: {"vision/params/deblur": "true"},    // values are expressions, re-evaluated
//!             relink: {"mapper/in/pose": "hw/out/odometry"},
//!             enable: ["featureSeeker"], disable: ["explorer"],
//!             start: ["recorder"], stop: ["planner"],
//!             sticky: false,                            // true: keep effects when it ends
//!         ),
//!     ],
//! )
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use petrel_actors::config::{parse_ron, read_text};
use petrel_actors::ConfigError;

use serde::Deserialize;

/// A whole rules file.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(rename = "Contexts", deny_unknown_fields)]
pub struct RulesFile {
    /// The contexts, in declaration order (which breaks no tie: equal priorities on a shared
    /// target are an error).
    #[serde(default)]
    pub contexts: Vec<ContextRule>,
}

/// One context: when it holds, and what it changes while it does.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContextRule {
    /// Unique name.
    pub name: String,
    /// Entry condition.
    pub when: String,
    /// Exit condition (hysteresis); default `not (when)`.
    #[serde(default)]
    pub until: Option<String>,
    /// Minimum time the context stays active or inactive after a change, ms.
    #[serde(default)]
    pub min_dwell_ms: u64,
    /// Higher priority wins when active contexts set the same target.
    #[serde(default)]
    pub priority: i64,
    /// Property → expression giving its value while active.
    #[serde(default, deserialize_with = "petrel_actors::config::unique_keys")]
    pub set: BTreeMap<String, String>,
    /// Input → new source while active.
    #[serde(default, deserialize_with = "petrel_actors::config::unique_keys")]
    pub relink: BTreeMap<String, String>,
    /// Modules whose `enabled` is set true while active.
    #[serde(default)]
    pub enable: Vec<String>,
    /// Modules whose `enabled` is set false while active.
    #[serde(default)]
    pub disable: Vec<String>,
    /// Module instances started while active.
    #[serde(default)]
    pub start: Vec<String>,
    /// Module instances stopped while active.
    #[serde(default)]
    pub stop: Vec<String>,
    /// Keep the effects when the context ends (default: restore what it changed).
    #[serde(default)]
    pub sticky: bool,
    /// Its conditions read what it changes, on purpose (e.g. a brightness divided by the
    /// exposure it sets): `petrel check` does not warn that it may undo itself. The runtime
    /// still names a context that does switch itself on and off in a loop.
    #[serde(default)]
    pub reads_own_changes: bool,
}

/// A problem in a rules file, located in it (the same shape as a config error).
pub type RuleError = ConfigError;

/// A parsed rules file with its text, to locate errors.
#[derive(Debug, Clone)]
pub struct LoadedRules {
    /// The rules.
    pub rules: RulesFile,
    /// Where they came from.
    pub path: PathBuf,
    text: String,
}

impl LoadedRules {
    /// Reads and parses a rules file.
    pub fn load(path: &Path) -> Result<Self, Vec<RuleError>> {
        let text = read_text(path, "context rules").map_err(|e| vec![e])?;
        Self::parse(path, &text)
    }

    /// Parses rules text; `path` names it in errors.
    pub fn parse(path: &Path, text: &str) -> Result<Self, Vec<RuleError>> {
        let rules = parse_ron::<RulesFile>(path, text, "context rules").map_err(|e| vec![e])?;
        Ok(LoadedRules {
            rules,
            path: path.into(),
            text: text.to_string(),
        })
    }

    /// An error about context `context`, at the first quoted `needle` after its name (or at
    /// the name), shifted by `offset` (line, column) inside the quoted text when given.
    pub fn error(
        &self,
        context: &str,
        needle: Option<&str>,
        offset: Option<(u32, u32)>,
        message: String,
    ) -> RuleError {
        self.error_nth(context, 0, needle, offset, message)
    }

    /// [`error`](Self::error) about the `nth` (from 0) context of that name: a name given twice
    /// is reported, and its second context checked, where the second is written.
    pub fn error_nth(
        &self,
        context: &str,
        nth: usize,
        needle: Option<&str>,
        offset: Option<(u32, u32)>,
        message: String,
    ) -> RuleError {
        let quoted = format!("\"{context}\"");
        let found = self.text.match_indices(&quoted).nth(nth);
        let Some((start, _)) = found.or_else(|| self.text.match_indices(&quoted).next()) else {
            return RuleError::in_file(&self.path, message);
        };
        // As written: quoted, or with RON's escapes (an expression holding a string, `"\"x\""`).
        let at = needle
            .and_then(|n| {
                let escaped = ron::to_string(n).unwrap_or_default();
                [format!("\"{n}\""), escaped]
                    .into_iter()
                    .filter(|q| q.len() > 2)
                    .find_map(|q| self.text[start..].find(&q))
                    .map(|i| start + i + 1)
            })
            .unwrap_or(start);
        let mut err = RuleError::at(&self.path, &self.text, at, message);
        if let Some((line, column)) = offset {
            // Expressions are one line in practice; a multi-line one is located by its own lines.
            if line > 1 {
                err.line += line as usize - 1;
                err.column = column as usize;
            } else {
                err.column += column as usize - 1;
            }
        }
        err
    }
}
