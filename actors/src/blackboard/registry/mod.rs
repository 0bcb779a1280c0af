//! The blackboard's registry: which properties, queues and links exist in one agent.
//!
//! Pure and synchronous, so configs can be checked without starting anything; the blackboard
//! actor owns one at run time and applies structure changes to it one at a time.

use std::collections::{BTreeMap, HashMap};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use crate::cell::{Cell, Signal};
use crate::ports::{Handle, Ports, PropertyDecl, PropertyKind};

use super::error::BlackboardError;

mod instances;
mod links;
mod module_graph;
pub use module_graph::{GraphLink, GraphNode, ModuleGraph};
mod remote;
mod settings;
mod values;
mod watch;
use crate::queue::{dropped_path, QueueCore};
use crate::team::{LinkTarget, RemoteLinks};
use crate::url::PropertyUrl;
use crate::value::TypeInfo;
use links::LinkGraph;
pub use watch::{TapFilter, WatchedTap};

pub(crate) struct Entry {
    pub decl: PropertyDecl,
    pub handle: Handle,
    /// A link to another agent's property: the input reads its own cell (or private queue),
    /// which the team transport feeds.
    pub remote: Option<LinkTarget>,
    /// For queue inputs: the private queue read while unlinked.
    own_queue: Option<Arc<QueueCore>>,
}

/// Whether a property is made by the runtime beside a module's own declarations (queue drop
/// counters, remote link status): not handed to the module when it binds.
fn is_runtime_stat(decl: &PropertyDecl) -> bool {
    decl.kind == PropertyKind::Stats
        && (decl.path.starts_with("stats/dropped/") || decl.path.starts_with("stats/links/"))
}

/// Events `_supervisor/events` keeps for its slowest reader.
const EVENTS_CAPACITY: usize = 1024;

pub(crate) struct ModuleEntry {
    pub type_name: String,
    /// Raised when a watched input or queue changes; kept across restarts.
    pub signal: Arc<Signal>,
}

/// All properties, queues and links of one agent.
pub struct Registry {
    agent: String,
    order: Vec<String>,
    modules: HashMap<String, ModuleEntry>,
    entries: BTreeMap<String, Entry>,
    /// Local links between entries (`module/path` keys).
    links: LinkGraph,
    /// Inputs linked to other agents, shared with the team transport.
    remote: Arc<RemoteLinks>,
    /// The team the agent joins, for snapshots.
    team: Option<crate::team::TeamConfig>,
    /// What the config says beyond properties, for snapshots.
    settings: settings::Settings,
    /// Outboxes tapped but not yet handed to the team transport, and the modules whose
    /// outbox was tapped (each is tapped once).
    pending_outboxes: Vec<crate::team::Outbox>,
    tapped_outboxes: std::collections::HashSet<String>,
    /// Recorders' watches: properties to tap as they are declared.
    tap_watches: Vec<watch::TapWatch>,
    /// Counts the modules added and removed, shared with the [`Blackboard`](crate::Blackboard)
    /// handle: a step that settles the agent looks the modules up again when it moved.
    modules_changed: Arc<AtomicU64>,
    /// The modules on a cycle of links, with the link and module generations they were worked
    /// out at (see [`feedback_cycle`](Self::feedback_cycle)).
    cyclic: parking_lot::Mutex<Option<module_graph::Cyclic>>,
}

/// The most items an output queue may be configured to hold (items are shared, so this
/// bounds bookkeeping, not copies).
pub const MAX_QUEUE_CAPACITY: usize = 1 << 20;

impl Registry {
    /// An empty registry for `agent`.
    pub fn new(agent: &str) -> Self {
        Registry {
            agent: agent.to_string(),
            order: Vec::new(),
            modules: HashMap::new(),
            entries: BTreeMap::new(),
            links: LinkGraph::default(),
            remote: Arc::default(),
            team: None,
            settings: Default::default(),
            pending_outboxes: Vec::new(),
            tapped_outboxes: Default::default(),
            tap_watches: Vec::new(),
            modules_changed: Arc::default(),
            cyclic: Default::default(),
        }
    }

    /// The agent name.
    pub fn agent(&self) -> &str {
        &self.agent
    }

    /// Keeps what `config` says beyond properties (supervision, groups, recording, module
    /// settings), for snapshots.
    pub fn keep_settings(&mut self, config: &crate::config::AgentConfig) {
        self.settings = settings::Settings::of(config);
    }

    /// The agent's settings beyond properties, as `field: value` RON.
    pub(crate) fn agent_settings(&self) -> Vec<String> {
        self.settings.agent_fields()
    }

    /// `module`'s settings beyond properties, as `field: value` RON.
    pub(crate) fn module_settings(&self, module: &str) -> Vec<String> {
        self.settings.module_fields(module)
    }

    /// Module names in declaration order.
    pub fn modules(&self) -> &[String] {
        &self.order
    }

    /// The wake-up signals of every module, running or not.
    pub(crate) fn signals(&self) -> Vec<Arc<Signal>> {
        self.modules.values().map(|m| m.signal.clone()).collect()
    }

    /// The count of modules added and removed so far, read without asking the blackboard.
    pub(crate) fn modules_changed(&self) -> Arc<AtomicU64> {
        self.modules_changed.clone()
    }

    /// Adds or replaces a module's entry.
    fn insert_module(&mut self, module: &str, entry: ModuleEntry) {
        self.modules.insert(module.to_string(), entry);
        self.modules_changed.fetch_add(1, Ordering::Release);
    }

    /// Removes a module's entry.
    fn remove_module_entry(&mut self, module: &str) {
        self.modules.remove(module);
        self.modules_changed.fetch_add(1, Ordering::Release);
    }

    pub(crate) fn module(&self, name: &str) -> Option<&ModuleEntry> {
        self.modules.get(name)
    }

    /// Adopts the cells a fresh declaration of `module` created.
    pub(crate) fn declare(
        &mut self,
        module: &str,
        type_name: &str,
        ports: Ports,
    ) -> Result<(), BlackboardError> {
        if !ports.errors.is_empty() {
            return Err(BlackboardError::Declaration(ports.errors.join("; ")));
        }
        if self.modules.contains_key(module) {
            return Err(BlackboardError::Declaration(format!(
                "module `{module}` is declared twice"
            )));
        }
        for (decl, handle) in ports.decls.into_iter().zip(ports.handles) {
            let own_queue = match &handle {
                Handle::QueueIn(reader) => {
                    let dropped = PropertyDecl {
                        path: dropped_path(&decl.path),
                        kind: PropertyKind::Stats,
                        type_info: TypeInfo::of::<i64>(),
                        default: Some(Arc::new(0_i64)),
                        doc: format!("items `{}` lost by lagging behind its queue", decl.path),
                        capacity: None,
                        range: None,
                        read_at_start: false,
                        shape: None,
                    };
                    let key = format!("{module}/{}", dropped.path);
                    let entry = Entry {
                        decl: dropped,
                        handle: Handle::Value(reader.dropped.clone()),
                        remote: None,
                        own_queue: None,
                    };
                    self.entries.insert(key, entry);
                    Some(reader.source())
                }
                _ => None,
            };
            let key = format!("{module}/{}", decl.path);
            self.entries.insert(
                key,
                Entry {
                    decl,
                    handle,
                    remote: None,
                    own_queue,
                },
            );
        }
        self.order.push(module.to_string());
        let entry = ModuleEntry {
            type_name: type_name.to_string(),
            signal: Arc::default(),
        };
        self.insert_module(module, entry);
        if self.team.is_some() {
            self.tap_outbox(module);
        }
        Ok(())
    }

    /// The cells of `module`, by path, for binding a (re)started instance.
    pub(crate) fn handles(&self, module: &str) -> Option<HashMap<String, Handle>> {
        self.modules.get(module)?;
        let prefix = format!("{module}/");
        Some(
            self.entries
                .range(prefix.clone()..)
                .take_while(|(k, _)| k.starts_with(&prefix))
                .filter(|(_, e)| !is_runtime_stat(&e.decl))
                .map(|(k, e)| (k[prefix.len()..].to_string(), e.handle.clone()))
                .collect(),
        )
    }

    /// The declarations of `module`'s properties, in path order.
    pub fn declarations(&self, module: &str) -> Vec<&PropertyDecl> {
        let prefix = format!("{module}/");
        self.entries
            .range(prefix.clone()..)
            .take_while(|(k, _)| k.starts_with(&prefix))
            .map(|(_, e)| &e.decl)
            .collect()
    }

    /// The type name of `module`.
    pub fn module_type(&self, module: &str) -> Option<&str> {
        self.modules.get(module).map(|m| m.type_name.as_str())
    }

    /// Turns a full or short address into the key `module/path` of an existing property.
    pub fn key_of(&self, address: &str) -> Result<String, BlackboardError> {
        let url =
            PropertyUrl::parse(address).map_err(|e| BlackboardError::BadAddress(e.to_string()))?;
        if let Some(agent) = url.agent() {
            if agent != self.agent {
                return Err(BlackboardError::BadAddress(format!(
                    "`{address}` names agent `{agent}`, but this is agent `{}` (only a link may name another agent's property)",
                    self.agent
                )));
            }
        }
        let key = url.key();
        if self.entries.contains_key(&key) {
            return Ok(key);
        }
        if !self.modules.contains_key(url.module()) {
            let mut known: Vec<&str> = self.order.iter().map(String::as_str).collect();
            known.sort_unstable();
            return Err(BlackboardError::UnknownModule {
                module: url.module().into(),
                agent: self.agent.clone(),
                known: known.join(", "),
            });
        }
        Err(BlackboardError::UnknownProperty {
            module: url.module().into(),
            path: url.path().into(),
            known: self.known_paths(url.module()),
        })
    }

    fn known_paths(&self, module: &str) -> String {
        self.declarations(module)
            .iter()
            .filter(|d| !matches!(d.kind, PropertyKind::Stats | PropertyKind::Control))
            .map(|d| d.path.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Links `from` (an input, parameter or queue input) to `to`; reads of `from` then read `to`.
    /// A `to` naming another agent (`petrel://robot2/mod/out/x`) makes a remote link with the
    /// default transport settings (see [`link_target`](Self::link_target)).
    pub fn link(&mut self, from: &str, to: &str) -> Result<(), BlackboardError> {
        self.link_target(from, &LinkTarget::new(to))
    }

    /// Links `from` to a target in either config form: a local property, or another agent's
    /// property with its transport settings.
    pub fn link_target(&mut self, from: &str, to: &LinkTarget) -> Result<(), BlackboardError> {
        let url =
            PropertyUrl::parse(&to.url).map_err(|e| BlackboardError::BadAddress(e.to_string()))?;
        if let Some(agent) = url.agent().filter(|a| *a != self.agent) {
            if !self.modules.contains_key(crate::team::TEAM_MODULE) {
                return Err(BlackboardError::BadAddress(format!(
                    "`{}` names agent `{agent}`, but this is agent `{}`, which has no `team:` section to reach other agents (add `team: (name: \"...\", connect: [...])`)",
                    to.url, self.agent
                )));
            }
            return self.link_remote(from, url, to.qos.unwrap_or_default());
        }
        self.link_local(from, &to.url)
    }

    fn link_local(&mut self, from: &str, to: &str) -> Result<(), BlackboardError> {
        let (from, to) = self.check_link(from, to)?;
        self.drop_remote(&from);
        self.links.set(&from, Some(&to));
        self.resolve(&from);
        Ok(())
    }

    /// Whether `from` could be linked to `to`, a property of this agent, as the links stand:
    /// `from` linkable, both values or both queues, one type, and no cycle. Returns both keys.
    /// For checks made before a run (a context rule's `relink`) as well as for linking.
    pub fn check_link(&self, from: &str, to: &str) -> Result<(String, String), BlackboardError> {
        let from = self.key_of(from)?;
        let to = self.key_of(to)?;
        let (f, t) = (&self.entries[&from].decl, &self.entries[&to].decl);
        if !f.kind.linkable() {
            return Err(BlackboardError::NotLinkable {
                key: from,
                kind: f.kind,
            });
        }
        if f.kind.is_queue() != t.kind.is_queue() {
            return Err(BlackboardError::KindMismatch {
                from,
                from_kind: f.kind,
                to,
                to_kind: t.kind,
            });
        }
        if f.type_info != t.type_info {
            let (from_type, to_type) = (f.type_info.name(), t.type_info.name());
            return Err(BlackboardError::TypeMismatch {
                from,
                from_type,
                to,
                to_type,
            });
        }
        if let Some(chain) = self.links.cycle(&from, &to) {
            return Err(BlackboardError::Cycle(chain));
        }
        Ok((from, to))
    }

    /// Removes the link of `from`: it reads its own value (or private queue) again.
    pub fn unlink(&mut self, from: &str) -> Result<(), BlackboardError> {
        let from = self.key_of(from)?;
        self.drop_remote(&from);
        self.links.set(&from, None);
        self.resolve(&from);
        Ok(())
    }

    /// The link target of `key`, if linked (a full URL for a link to another agent).
    pub fn link_of(&self, key: &str) -> Option<&str> {
        let entry = self.entries.get(key)?;
        entry
            .remote
            .as_ref()
            .map(|r| r.url.as_str())
            .or_else(|| self.links.target(key))
    }

    /// Points every endpoint and queue reader whose link chain passes through `changed` (the
    /// property whose link just changed) at the end of its chain. Only those are touched (a
    /// walk back along the links into `changed`), so building N links costs what they link.
    fn resolve(&self, changed: &str) {
        let target = &self.entries[self.links.end(changed)];
        for key in self.links.through(changed) {
            match (&self.entries[key].handle, &target.handle) {
                (Handle::Value(ep), Handle::Value(t)) => ep.retarget(t.own.clone()),
                (Handle::QueueIn(reader), Handle::QueueOut(core)) => reader.retarget(core.clone()),
                (Handle::QueueIn(reader), Handle::QueueIn(_)) => {
                    if let Some(own) = &target.own_queue {
                        reader.retarget(own.clone());
                    }
                }
                _ => {}
            }
        }
    }

    /// Every property with its current own value (not its link target's), links, and queue
    /// capacities, module by module; what a snapshot writes.
    pub(crate) fn entries(&self) -> impl Iterator<Item = (&String, &Entry)> {
        self.entries.iter()
    }

    /// The cell a value property stores its own value in.
    pub(crate) fn own_cell(entry: &Entry) -> Option<&Arc<Cell>> {
        match &entry.handle {
            Handle::Value(ep) => Some(&ep.own),
            _ => None,
        }
    }
}
