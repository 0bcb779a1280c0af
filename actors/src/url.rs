//! Property addresses: `petrel://<agent>/<module>/<path>`, or `<module>/<path>` inside one agent.

use std::fmt;

/// The URL scheme of every petrel property.
pub const SCHEME: &str = "petrel://";

/// The address of a property, queue or link target.
///
/// The agent is optional only in the short form used inside one agent's config; [`PropertyUrl::in_agent`]
/// fills it in. Segments may contain letters, digits, `_`, `-` and `.`; the path has at least one segment.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PropertyUrl {
    agent: Option<String>,
    module: String,
    path: String,
}

/// Why a string is not a property URL.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("invalid property address `{input}`: {reason} (expected `petrel://agent/module/path` or `module/path`)")]
pub struct UrlError {
    /// The text that failed to parse.
    pub input: String,
    /// What was wrong with it.
    pub reason: &'static str,
}

impl PropertyUrl {
    /// Parses the full (`petrel://robot1/scale/in/value`) or short (`scale/in/value`) form.
    pub fn parse(input: &str) -> Result<Self, UrlError> {
        let err = |reason| UrlError {
            input: input.to_string(),
            reason,
        };
        let (agent, rest) = match input.strip_prefix(SCHEME) {
            Some(rest) => {
                let (agent, rest) = rest.split_once('/').ok_or_else(|| err("missing module"))?;
                (Some(agent), rest)
            }
            None if input.contains("://") => return Err(err("unknown scheme")),
            None => (None, input),
        };
        let (module, path) = rest
            .split_once('/')
            .ok_or_else(|| err("missing property path"))?;
        let valid = valid_segment;
        if let Some(agent) = agent {
            if !valid(agent) {
                return Err(err("bad agent name"));
            }
        }
        if !valid(module) {
            return Err(err("bad module name"));
        }
        if !path.split('/').all(valid) {
            return Err(err("bad path segment"));
        }
        Ok(PropertyUrl {
            agent: agent.map(str::to_string),
            module: module.to_string(),
            path: path.to_string(),
        })
    }

    /// A URL from its parts; `path` is not validated.
    pub fn new(agent: Option<&str>, module: &str, path: &str) -> Self {
        PropertyUrl {
            agent: agent.map(str::to_string),
            module: module.to_string(),
            path: path.to_string(),
        }
    }

    /// The same URL, with the agent set to `agent` if it had none.
    pub fn in_agent(mut self, agent: &str) -> Self {
        self.agent.get_or_insert_with(|| agent.to_string());
        self
    }

    /// The agent, if the URL names one.
    pub fn agent(&self) -> Option<&str> {
        self.agent.as_deref()
    }

    /// The module name.
    pub fn module(&self) -> &str {
        &self.module
    }

    /// The property path inside the module, e.g. `in/value`.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// The short form `module/path`, the key of a property inside its agent.
    pub fn key(&self) -> String {
        format!("{}/{}", self.module, self.path)
    }
}

impl fmt::Display for PropertyUrl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.agent {
            Some(agent) => write!(f, "{SCHEME}{agent}/{}/{}", self.module, self.path),
            None => write!(f, "{}/{}", self.module, self.path),
        }
    }
}

impl std::str::FromStr for PropertyUrl {
    type Err = UrlError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::parse(s)
    }
}

/// The longest name or path segment. Names travel in every message about a property (a team's
/// key expressions, discovery records): a name of 60,000 characters made a message larger than
/// zenoh sends, and the agent aborted when a tool asked it for its listing.
pub(crate) const MAX_SEGMENT: usize = 128;

/// Whether `s` is a valid name or path segment: 1 to [`MAX_SEGMENT`] ASCII letters and digits,
/// `_`, `-`, `.` (agent and module names, and each `/`-separated part of a property path).
pub(crate) fn valid_segment(s: &str) -> bool {
    !s.is_empty()
        && s.len() <= MAX_SEGMENT
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_full_and_short_forms() {
        let full = PropertyUrl::parse("petrel://robot1/obstacleAvoidance/params/maxSpeed").unwrap();
        assert_eq!(full.agent(), Some("robot1"));
        assert_eq!(full.module(), "obstacleAvoidance");
        assert_eq!(full.path(), "params/maxSpeed");
        assert_eq!(
            full.to_string(),
            "petrel://robot1/obstacleAvoidance/params/maxSpeed"
        );
        let short = PropertyUrl::parse("scale/in/value").unwrap();
        assert_eq!(short.agent(), None);
        assert_eq!(
            short.in_agent("r2").to_string(),
            "petrel://r2/scale/in/value"
        );
    }

    #[test]
    fn rejects_malformed_addresses_with_a_reason() {
        for (bad, reason) in [
            ("scale", "missing property path"),
            ("scale/", "bad path segment"),
            ("http://a/b/c", "unknown scheme"),
            ("petrel://r1", "missing module"),
            ("sc ale/in/x", "bad module name"),
            ("scale/in//x", "bad path segment"),
        ] {
            assert_eq!(PropertyUrl::parse(bad).unwrap_err().reason, reason, "{bad}");
        }
    }
}
