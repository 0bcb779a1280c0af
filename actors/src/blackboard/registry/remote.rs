//! Links to other agents' properties, the taps a team transport publishes through, and the
//! runtime's `_team/...` properties.

use std::sync::Arc;

use super::{BlackboardError, Entry, ModuleEntry, Registry};
use crate::cell::Endpoint;
use crate::ports::{Handle, PropertyDecl, PropertyKind};
use crate::queue::{QueueCore, ReaderEndpoint};
use crate::team::{
    link_state, LinkStatus, LinkTarget, Message, Outbox, OutboxStatus, OutboxWriter, Qos, QueueTap,
    RemoteFeed, RemoteLink, RemoteLinks, RemoteQueue, RemoteValue, StatusWriter, Tap, TeamConfig,
    TeamEvent, TeamMembers, ValueTap, INBOX, OUTBOX, TEAM_MODULE,
};
use crate::url::PropertyUrl;
use crate::value::TypeInfo;

/// Membership events `_team/events` keeps for its slowest reader.
const TEAM_EVENTS_CAPACITY: usize = 256;

impl Registry {
    /// Links `from` to another agent's property: `from` keeps reading its own cell (or private
    /// queue), which the team transport feeds; `stats/links/<path>` says how the link fares.
    pub(crate) fn link_remote(
        &mut self,
        from: &str,
        source: PropertyUrl,
        qos: Qos,
    ) -> Result<(), BlackboardError> {
        let from = self.key_of(from)?;
        let entry = &self.entries[&from];
        if !entry.decl.kind.linkable() {
            return Err(BlackboardError::NotLinkable {
                key: from,
                kind: entry.decl.kind,
            });
        }
        let feed = match (&entry.handle, &entry.own_queue) {
            (Handle::Value(ep), _) => RemoteFeed::Value(RemoteValue { ep: ep.clone() }),
            (Handle::QueueIn(_), Some(own)) => RemoteFeed::Queue(RemoteQueue { core: own.clone() }),
            _ => {
                return Err(BlackboardError::NotLinkable {
                    key: from,
                    kind: entry.decl.kind,
                })
            }
        };
        let (module, path) = from.split_once('/').expect("keys are module/path");
        let status_key = format!("{module}/stats/links/{path}");
        let status = match self.entries.get(&status_key).map(|e| &e.handle) {
            Some(Handle::Value(ep)) => ep.clone(),
            _ => {
                let decl = PropertyDecl {
                    path: format!("stats/links/{path}"),
                    kind: PropertyKind::Stats,
                    type_info: TypeInfo::of::<LinkStatus>(),
                    default: None,
                    doc: format!("how the remote link of `{path}` fares"),
                    capacity: None,
                    range: None,
                    read_at_start: false,
                    shape: None,
                };
                let ep =
                    Endpoint::new(&status_key, decl.type_info, Arc::new(LinkStatus::default()));
                self.entries.insert(
                    status_key,
                    Entry {
                        decl,
                        handle: Handle::Value(ep.clone()),
                        remote: None,
                        own_queue: None,
                    },
                );
                ep
            }
        };
        let status = StatusWriter::new(status);
        status.set(LinkStatus {
            state: link_state::WAITING.into(),
            source: source.to_string(),
            ..LinkStatus::default()
        });
        self.links.set(&from, None);
        let entry = self.entries.get_mut(&from).expect("checked above");
        entry.remote = Some(LinkTarget {
            url: source.to_string(),
            qos: Some(qos),
        });
        self.resolve(&from);
        self.remote.insert(RemoteLink {
            input: from,
            source,
            qos,
            feed,
            status,
        });
        Ok(())
    }

    /// Forgets the remote link of `key`, if it has one.
    pub(super) fn drop_remote(&mut self, key: &str) {
        if let Some(entry) = self.entries.get_mut(key) {
            if entry.remote.take().is_some() {
                self.remote.remove(key);
            }
        }
    }

    /// The core of an output queue, for writers outside the agent's modules.
    pub(crate) fn queue_out(&self, address: &str) -> Result<Arc<QueueCore>, BlackboardError> {
        let key = self.key_of(address)?;
        let entry = &self.entries[&key];
        match &entry.handle {
            Handle::QueueOut(core) => Ok(core.clone()),
            _ => Err(BlackboardError::NotSettable {
                key,
                kind: entry.decl.kind,
            }),
        }
    }

    /// The agent's links to other agents, shared with the team transport.
    pub fn remote_links(&self) -> Arc<RemoteLinks> {
        self.remote.clone()
    }

    /// A tap on a value property or output queue, for a transport that publishes it.
    pub(crate) fn tap(&self, address: &str) -> Result<Tap, BlackboardError> {
        let key = self.key_of(address)?;
        let entry = &self.entries[&key];
        match &entry.handle {
            Handle::Value(ep) => Ok(Tap::Value(ValueTap::new(ep.clone()))),
            Handle::QueueOut(core) => Ok(Tap::Queue(QueueTap::new(queue_tap(&key, core)))),
            Handle::QueueIn(_) => Err(BlackboardError::QueueInput {
                linked_to: self.link_of(&key).map(str::to_string),
                key,
            }),
        }
    }

    /// Where a replay writes in place of a module: one of its outputs (`out/` value or queue).
    pub(crate) fn feed(&self, address: &str) -> Result<RemoteFeed, BlackboardError> {
        let key = self.key_of(address)?;
        let entry = &self.entries[&key];
        match (&entry.handle, entry.decl.kind) {
            (Handle::Value(ep), PropertyKind::Output) => {
                Ok(RemoteFeed::Value(RemoteValue { ep: ep.clone() }))
            }
            (Handle::QueueOut(core), _) => {
                Ok(RemoteFeed::Queue(RemoteQueue { core: core.clone() }))
            }
            _ => Err(BlackboardError::NotSettable {
                key,
                kind: entry.decl.kind,
            }),
        }
    }

    /// The kind and type of a property.
    pub(crate) fn kind_of(
        &self,
        address: &str,
    ) -> Result<(PropertyKind, TypeInfo), BlackboardError> {
        let key = self.key_of(address)?;
        let decl = &self.entries[&key].decl;
        Ok((decl.kind, decl.type_info))
    }

    /// The outboxes (`out/outbox`, a queue of [`Message`]s) not yet handed to the transport,
    /// each with its tap and the writer of its `stats/outbox`.
    pub(crate) fn outboxes(&mut self) -> Vec<Outbox> {
        for module in self.order.clone() {
            self.tap_outbox(&module);
        }
        std::mem::take(&mut self.pending_outboxes)
    }

    /// Taps `module`'s outbox, if it has one not yet tapped, and declares its `stats/outbox`.
    pub(crate) fn tap_outbox(&mut self, module: &str) {
        let key = format!("{module}/{OUTBOX}");
        let core = match self.entries.get(&key) {
            Some(Entry {
                decl,
                handle: Handle::QueueOut(core),
                ..
            }) if decl.type_info.is::<Message>() => core.clone(),
            _ => return,
        };
        if !self.tapped_outboxes.insert(module.to_string()) {
            return;
        }
        let tap = QueueTap::new(queue_tap(&key, &core));
        let key = format!("{module}/stats/outbox");
        let ep = match self.entries.get(&key).map(|e| &e.handle) {
            Some(Handle::Value(ep)) => ep.clone(),
            _ => {
                let decl = PropertyDecl {
                    path: "stats/outbox".into(),
                    kind: PropertyKind::Stats,
                    type_info: TypeInfo::of::<OutboxStatus>(),
                    default: None,
                    doc: "messages of out/outbox delivered, refused and dropped".into(),
                    capacity: None,
                    range: None,
                    read_at_start: false,
                    shape: None,
                };
                let ep = Endpoint::new(&key, decl.type_info, Arc::new(OutboxStatus::default()));
                self.insert_runtime(key, decl, Handle::Value(ep.clone()));
                ep
            }
        };
        self.pending_outboxes.push(Outbox {
            module: module.to_string(),
            status: OutboxWriter::new(ep),
            tap,
        });
    }

    /// Forgets the outbox of a removed module (one added again under its name is tapped anew).
    pub(crate) fn forget_outbox(&mut self, module: &str) {
        self.tapped_outboxes.remove(module);
        self.pending_outboxes.retain(|o| o.module != module);
    }

    /// Where messages for `module` go: its `in/inbox` (a queue of [`Message`]s), fed like a
    /// remote queue when not linked.
    pub(crate) fn inbox(&self, module: &str) -> Result<RemoteQueue, BlackboardError> {
        let key = self.key_of(&format!("{module}/{INBOX}"))?;
        let entry = &self.entries[&key];
        match (&entry.own_queue, entry.decl.type_info.is::<Message>()) {
            (Some(own), true) => Ok(RemoteQueue { core: own.clone() }),
            _ => Err(BlackboardError::BadValue {
                key,
                expected: "a queue input of Message",
                reason: format!(
                    "it is a {} of {}",
                    entry.decl.kind,
                    entry.decl.type_info.name()
                ),
            }),
        }
    }

    /// The team section the agent was built with.
    pub(crate) fn team(&self) -> Option<&TeamConfig> {
        self.team.as_ref()
    }

    /// Declares `_team/members` and the `_team/events` queue (for agents that join `team`).
    pub(crate) fn declare_team(&mut self, team: &TeamConfig) {
        self.team = Some(team.clone());
        for module in self.order.clone() {
            self.tap_outbox(&module);
        }
        if self.modules.contains_key(TEAM_MODULE) {
            return;
        }
        let members = PropertyDecl {
            path: "members".into(),
            kind: PropertyKind::Output,
            type_info: TypeInfo::of::<TeamMembers>(),
            default: Some(Arc::new(TeamMembers::default())),
            doc: "the alive agents of the team and their modules".into(),
            capacity: None,
            range: None,
            read_at_start: false,
            shape: None,
        };
        let key = format!("{TEAM_MODULE}/members");
        let ep = Endpoint::new(&key, members.type_info, Arc::new(TeamMembers::default()));
        self.insert_runtime(key, members, Handle::Value(ep));
        let events = PropertyDecl {
            path: "events".into(),
            kind: PropertyKind::QueueOut,
            type_info: TypeInfo::of::<TeamEvent>(),
            default: None,
            doc: "agents that joined, left or rejoined the team".into(),
            capacity: Some(TEAM_EVENTS_CAPACITY),
            range: None,
            read_at_start: false,
            shape: None,
        };
        let key = format!("{TEAM_MODULE}/events");
        let core = QueueCore::new(&key, events.type_info, TEAM_EVENTS_CAPACITY);
        self.insert_runtime(key, events, Handle::QueueOut(core));
        let entry = ModuleEntry {
            type_name: "runtime.team".into(),
            signal: Arc::default(),
        };
        self.insert_module(TEAM_MODULE, entry);
    }

    fn insert_runtime(&mut self, key: String, decl: PropertyDecl, handle: Handle) {
        let entry = Entry {
            decl,
            handle,
            remote: None,
            own_queue: None,
        };
        self.entries.insert(key, entry);
    }
}

static NEXT_TAP: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1 << 62);

/// A reader of `core` for a tap (ids far from module readers').
fn queue_tap(key: &str, core: &Arc<QueueCore>) -> Arc<ReaderEndpoint> {
    let id = NEXT_TAP.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    ReaderEndpoint::new(id, &format!("{key}#tap{id}"), core.type_info, core.clone())
}
