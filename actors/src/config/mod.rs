//! Agent configuration files (RON): loading, overlays, and checking against module types.
//!
//! ```ron
//! Agent(
//!     name: "robot1",
//!     modules: [
//!         (name: "counter", type: "demo.counter", values: {"params/period_ms": 100}),
//!         (name: "scale", type: "demo.scale",
//!          values: {"params/factor": 2.0},
//!          links: {"in/value": "counter/out/value"}),
//!     ],
//! )
//! ```
//! Checking builds the agent's blackboard [`Registry`] exactly as a run would, so `petrel check`
//! and `petrel run` cannot disagree; every problem found is reported, one per line, with the
//! file, line and column it comes from.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::blackboard::{BlackboardError, Registry};
use crate::module_types::ModuleRegistry;
use crate::supervision::{GroupConfig, RestartPolicy, SupervisionConfig};
use crate::team::{LinkTarget, TeamConfig};

mod clock;
mod error;
mod overlay;
mod record;
mod scheduler;
mod supervision;
mod unique;
mod written;

pub use error::{parse_ron, read_text, ConfigError, ConfigErrors};
pub use record::RecordSection;
pub use scheduler::{Scheduler, StepBudget};
pub use unique::unique_keys;

/// One agent's configuration.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(rename = "Agent", deny_unknown_fields)]
pub struct AgentConfig {
    /// The agent name (the `agent` of every property URL).
    pub name: String,
    /// How the agent supervisor restarts failed modules (see [`crate::supervision`]).
    #[serde(default)]
    pub supervision: SupervisionConfig,
    /// Named groups of modules with their own strategy and intensity.
    #[serde(default)]
    pub groups: Vec<GroupConfig>,
    /// A context rules file (relative to this config's folder) run by a `context.manager`
    /// module named `contexts` that the runtime adds to the agent.
    #[serde(default)]
    pub contexts: Option<String>,
    /// The team this agent joins (see [`crate::team`]); without it the agent runs alone and
    /// its links may name only its own properties.
    #[serde(default)]
    pub team: Option<TeamConfig>,
    /// What a run records to MCAP (see [`RecordSection`]); `petrel run --record` also records
    /// without it.
    #[serde(default)]
    pub record: Option<RecordSection>,
    /// Where the agent's modules run (default `shared`; see [`Scheduler`]).
    #[serde(default)]
    pub scheduler: Scheduler,
    /// When a module's steps are too long for its agent's thread (see [`StepBudget`]).
    #[serde(default)]
    pub step_budget: StepBudget,
    /// A real-time (`SCHED_FIFO`) priority, 1..=99, for the agent's own thread and the
    /// process's fine timer thread, so periodic modules keep their period while other threads
    /// keep the CPUs busy; `agent_thread` only (see [`Scheduler`]). None: ordinary threads.
    #[serde(default)]
    pub realtime_priority: Option<u8>,
    /// How many nice levels below the agent's own thread the threads of its long-step modules
    /// run (1..=19, at most at nice 19), so that beside modules keeping the CPUs busy the
    /// agent's thread gets a CPU first; `agent_thread` only. Needs no privilege. None: those
    /// modules run on the shared runtime, at the process's priority.
    #[serde(default)]
    pub long_steps_nice: Option<u8>,
    /// The agent's wall clock, in seconds, when the snapshot this config is was taken: an agent
    /// started from it goes on from that time (see [`crate::expr::continue_from`]), so the
    /// times its modules' memories keep still count what ran before. Written by snapshots.
    #[serde(default)]
    pub clock_s: Option<f64>,
    /// Module instances, started in this order and stopped in reverse.
    #[serde(default)]
    pub modules: Vec<ModuleConfig>,
}

/// One module instance of an agent.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModuleConfig {
    /// Instance name, unique in the agent.
    pub name: String,
    /// Registered module type, e.g. `demo.scale`. An overlay may leave it out to keep the
    /// base config's; a config must give it (empty here when left out).
    #[serde(rename = "type", default)]
    pub type_name: String,
    /// Property values by path (`params/factor`, `enabled`, ...), checked against their types.
    #[serde(default, deserialize_with = "unique::unique_values")]
    pub values: BTreeMap<String, ron::Value>,
    /// Links: own input or parameter path → target property address, or another agent's
    /// property with transport settings (see [`LinkTarget`]).
    #[serde(default, deserialize_with = "unique_keys")]
    pub links: BTreeMap<String, LinkTarget>,
    /// Capacities of this module's output queues, by path.
    #[serde(default, deserialize_with = "unique_keys")]
    pub capacities: BTreeMap<String, usize>,
    /// The supervision group the module belongs to (default: directly under the agent).
    #[serde(default)]
    pub group: Option<String>,
    /// Whether the module is restarted when it ends.
    #[serde(default)]
    pub restart: RestartPolicy,
    /// A step that takes longer than this many ms is a failure (a hang); overrides the module's own.
    #[serde(default)]
    pub watchdog_ms: Option<u64>,
    /// Time the module gets to stop before it is killed, ms (default: the agent's).
    #[serde(default)]
    pub shutdown_timeout_ms: Option<u64>,
    /// The module's steps are long (or block): under `scheduler: agent_thread` it runs on the
    /// shared runtime instead of its agent's thread, so it never holds up the other modules.
    #[serde(default)]
    pub long_steps: bool,
}

/// A loaded config, with the text it came from (for locating errors).
#[derive(Debug, Clone)]
pub struct ConfigFile {
    /// The merged configuration.
    pub config: AgentConfig,
    /// Files merged into it, base first, with their text.
    sources: Vec<(PathBuf, String)>,
    /// Which source gave each (module, value key) that an overlay set; the base otherwise.
    /// Relative file paths are resolved against their own file's directory.
    value_sources: HashMap<(String, String), usize>,
    /// The fields written in the file (agent fields, and `module/field` for module fields), so
    /// that an overlay replaces exactly what it writes and nothing is silently dropped.
    written: std::collections::BTreeSet<String>,
}

/// What agent and module names may hold: they are segments of every property address.
/// A name as an error shows it, in backticks: escaped, and cut short when it is far too long
/// to read.
pub(super) fn shown_name(name: &str) -> String {
    const SHOWN: usize = 48;
    let escaped = name.escape_debug().to_string();
    match escaped.chars().count() > SHOWN {
        true => format!(
            "`{}…` ({} characters)",
            escaped.chars().take(SHOWN).collect::<String>(),
            name.chars().count()
        ),
        false => format!("`{escaped}`"),
    }
}

/// The most errors of one config located at their line and column (see `build`).
const MAX_LOCATED_ERRORS: usize = 1000;

const NAME_RULE: &str = "expected 1 to 128 letters, digits, `_`, `-` or `.` (a name is part of every property address, `petrel://agent/module/path`)";

impl ConfigFile {
    /// Reads and parses a config file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ConfigErrors> {
        let path = path.as_ref();
        let text = read_text(path, "config").map_err(|e| ConfigErrors(vec![e]))?;
        Self::parse(path, &text)
    }

    /// Parses config text; `path` names it in errors.
    pub fn parse(path: impl AsRef<Path>, text: &str) -> Result<Self, ConfigErrors> {
        let path = path.as_ref();
        let what = "an agent config; see the example in the README";
        let config =
            parse_ron::<AgentConfig>(path, text, what).map_err(|e| ConfigErrors(vec![e]))?;
        Ok(ConfigFile {
            written: written::written_fields(text),
            config,
            sources: vec![(path.into(), text.to_string())],
            value_sources: HashMap::new(),
        })
    }

    /// The directory relative file paths of `module`'s value `key` are taken from: that of the
    /// file that gave the value.
    fn base_dir(&self, module: &str, key: &str) -> PathBuf {
        let source = self
            .value_sources
            .get(&(module.to_string(), key.to_string()))
            .copied()
            .unwrap_or(0);
        let file = &self.sources[source].0;
        file.parent().unwrap_or(Path::new(".")).to_path_buf()
    }

    /// The file the config was loaded from (the base, for overlays).
    pub fn path(&self) -> &Path {
        &self.sources[0].0
    }

    /// The files it was loaded from: the base, then its overlays in order.
    pub fn files(&self) -> impl Iterator<Item = &Path> {
        self.sources.iter().map(|(path, _)| path.as_path())
    }

    /// Builds the agent's blackboard registry: declares every module, applies values,
    /// capacities and links. Returns every problem found.
    pub fn build(&self, types: &ModuleRegistry) -> Result<Registry, ConfigErrors> {
        let mut registry = Registry::new(&self.config.name);
        registry.keep_settings(&self.config);
        let mut errors = self.check_supervision();
        errors.extend(self.check_scheduler());
        errors.extend(self.check_step_budget());
        errors.extend(self.check_realtime_priority());
        errors.extend(self.check_long_steps_nice());
        errors.extend(self.check_clock());
        if !crate::url::valid_segment(&self.config.name) {
            errors.push(self.locate_name(
                &self.config.name,
                "name:",
                format!("agent name {}: {NAME_RULE}", shown_name(&self.config.name)),
            ));
        }
        let mut names = HashSet::new();
        for m in &self.config.modules {
            if !crate::url::valid_segment(&m.name) {
                errors.push(self.locate_name(
                    &m.name,
                    "modules:",
                    format!("module name {}: {NAME_RULE}", shown_name(&m.name)),
                ));
                continue;
            }
            if !names.insert(m.name.as_str()) {
                let e = self.error_at(
                    &m.name,
                    1,
                    None,
                    format!(
                        "duplicate module name `{}`: each module needs its own name",
                        m.name
                    ),
                );
                errors.push(e);
                continue;
            }
            if m.type_name.is_empty() {
                let message = format!(
                    "module `{}` has no `type`; expected e.g. `type: \"demo.counter\"` (`petrel modules` lists them)",
                    m.name
                );
                errors.push(self.locate(&format!("\"{}\"", m.name), message));
                continue;
            }
            let Some(module_type) = types.get(&m.type_name) else {
                let near = types.nearest(&m.type_name);
                let hint = match near.is_empty() {
                    true => "run `petrel modules` to list the types".to_string(),
                    false => format!(
                        "did you mean {}?",
                        near.iter()
                            .map(|n| format!("`{n}`"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                };
                let message = format!(
                    "module `{}`: unknown module type `{}`; {hint}",
                    m.name, m.type_name
                );
                errors.push(self.error_unless_many(&errors, &m.name, Some(&m.type_name), message));
                continue;
            };
            if let Err(e) =
                registry.declare(&m.name, module_type.name(), module_type.declare(&m.name))
            {
                errors.push(self.error(
                    &m.name,
                    None,
                    format!(
                        "module type `{}` declares its properties wrongly: {e}",
                        m.type_name
                    ),
                ));
            }
        }
        registry.declare_events();
        if let Some(team) = &self.config.team {
            registry.declare_team(team);
            errors.extend(
                crate::team::check(team)
                    .into_iter()
                    .map(|e| self.locate("team:", e)),
            );
        }
        let declared: Vec<&ModuleConfig> = self
            .config
            .modules
            .iter()
            .filter(|m| registry.module_type(&m.name) == Some(m.type_name.as_str()))
            .collect();
        // A property linked within the agent reads its link's target: a value beside the link
        // would never be read, and losing it silently is worse than saying so. (A link to
        // another agent is different: the value is what the input holds until the first
        // sample arrives, and keeps if the link breaks.)
        let local = |url: &str| {
            crate::PropertyUrl::parse(url)
                .map(|u| u.agent().is_none_or(|a| a == self.config.name))
                .unwrap_or(true)
        };
        for &m in &declared {
            let both = m
                .links
                .iter()
                .filter(|(k, t)| m.values.contains_key(*k) && local(&t.url));
            for (key, target) in both {
                errors.push(self.error(
                    &m.name,
                    Some(key),
                    format!(
                        "`{}/{key}` has both a value and a link (to `{}`): a linked property reads what it links to, so the value would never be read; remove one of them",
                        m.name, target.url
                    ),
                ));
            }
        }
        // Values first, then links: a link may point at any module, declared before or after.
        let mut failed: Vec<(&ModuleConfig, &str, BlackboardError)> = Vec::new();
        for &m in &declared {
            failed.extend(
                registry
                    .apply_values(m, &|key| self.base_dir(&m.name, key))
                    .into_iter()
                    .map(|(path, e)| (m, path, e)),
            );
        }
        for &m in &declared {
            failed.extend(
                registry
                    .apply_links(m)
                    .into_iter()
                    .map(|(path, e)| (m, path, e)),
            );
        }
        for (m, path, e) in failed {
            let message = describe(&m.name, path, e);
            errors.push(self.error_unless_many(&errors, &m.name, Some(path), message));
        }
        match errors.is_empty() {
            true => Ok(registry),
            false => Err(ConfigErrors(errors)),
        }
    }

    /// An error located at the name `name` as written: quoted as it is, or with RON's escapes
    /// (`"c\td"`, which a user may also have written so).
    /// Written otherwise (`"a\u{2f}b"`), `fallback` is looked for instead.
    fn locate_name(&self, name: &str, fallback: &str, message: String) -> ConfigError {
        let plain = format!("\"{name}\"");
        let escaped = ron::to_string(name).unwrap_or_default();
        let written = |needle: &str| self.sources.iter().any(|(_, text)| text.contains(needle));
        let needle = [plain.as_str(), escaped.as_str()]
            .into_iter()
            .find(|n| !n.is_empty() && written(n))
            .unwrap_or(fallback);
        self.locate(needle, message)
    }

    /// An error located at the first `field` after `section` in the last source that has the
    /// section, else at the section.
    pub(crate) fn locate_after(&self, section: &str, field: &str, message: String) -> ConfigError {
        for (file, text) in self.sources.iter().rev() {
            if let Some(start) = text.find(section) {
                let at = text[start..].find(field).map_or(start, |i| start + i);
                return ConfigError::at(file, text, at, message);
            }
        }
        ConfigError::in_file(self.path(), message)
    }

    /// An error located at the first occurrence of `needle` in the last source that has it.
    pub fn locate(&self, needle: &str, message: String) -> ConfigError {
        for (file, text) in self.sources.iter().rev() {
            if let Some(at) = text.find(needle) {
                return ConfigError::at(file, text, at, message);
            }
        }
        ConfigError::in_file(self.path(), message)
    }

    /// [`error`](Self::error), or past [`MAX_LOCATED_ERRORS`] already found (`errors`: a
    /// generated config with one mistake repeated) an error naming the file alone. Locating an
    /// error searches the text, so 100,000 of them took a minute; the CLI shows the first 200.
    fn error_unless_many(
        &self,
        errors: &[ConfigError],
        module: &str,
        needle: Option<&str>,
        message: String,
    ) -> ConfigError {
        match errors.len() < MAX_LOCATED_ERRORS {
            true => self.error(module, needle, message),
            false => ConfigError::in_file(self.path(), message),
        }
    }

    /// An error located at the first quoted `needle` after module `module`'s name, in the
    /// last source that has it (overlays win), else at the module's name: for checks made
    /// outside [`build`](Self::build), such as a mission's bindings or a module's own files.
    pub fn error(&self, module: &str, needle: Option<&str>, message: String) -> ConfigError {
        self.error_at(module, 0, needle, message)
    }

    /// Like [`error`](Self::error), after the `nth` (from 0) occurrence of the module's name.
    fn error_at(
        &self,
        module: &str,
        nth: usize,
        needle: Option<&str>,
        message: String,
    ) -> ConfigError {
        let quoted_module = format!("\"{module}\"");
        for (file, text) in self.sources.iter().rev() {
            let Some((start, _)) = text.match_indices(&quoted_module).nth(nth) else {
                continue;
            };
            // A needle is a quoted key or value, or a bare field name (`watchdog_ms:`).
            let find = |n: &str| {
                let rest = &text[start..];
                rest.find(&format!("\"{n}\""))
                    .or_else(|| rest.find(&format!("{n}:")))
            };
            let at = needle.and_then(find).map_or(start, |i| start + i);
            return ConfigError::at(file, text, at, message);
        }
        ConfigError::in_file(self.path(), message)
    }
}

/// Says which module and key a registry error is about, in config terms.
pub(crate) fn describe(module: &str, path: &str, error: BlackboardError) -> String {
    match error {
        BlackboardError::UnknownProperty {
            module: m,
            path: p,
            known,
        } if m == module && p == path => {
            format!("module `{module}` has no property `{path}`; it has: {known}")
        }
        BlackboardError::BadValue {
            expected, reason, ..
        } => format!("module `{module}`, `{path}` ({expected}): {reason}"),
        other => format!("module `{module}`, `{path}`: {other}"),
    }
}
