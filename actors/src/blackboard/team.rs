//! The blackboard requests a team transport makes: remote links with transport settings,
//! taps on properties to publish, property kinds for remote writes, queue writers.

use std::sync::Arc;

use super::{Blackboard, BlackboardMsg, Registry, Reply};
use crate::ports::PropertyKind;
use crate::team::{LinkTarget, Outbox, RemoteFeed, RemoteLinks, RemoteQueue, RemoteWriter, Tap};
use crate::types::PropertyType;
use crate::url::PropertyUrl;
use crate::value::TypeInfo;
use crate::{BlackboardError, QueueWriter};

pub(crate) enum TeamRequest {
    Link(String, LinkTarget, Reply<()>),
    Tap(String, Reply<Tap>),
    KindOf(String, Reply<(PropertyKind, TypeInfo)>),
    Queue(String, Reply<Arc<crate::queue::QueueCore>>),
    Outboxes(Reply<Vec<Outbox>>),
    Inbox(String, Reply<RemoteQueue>),
    Listing(Reply<AgentListing>),
    Feed(String, Reply<RemoteFeed>),
    WatchTaps(
        super::TapFilter,
        Reply<tokio::sync::mpsc::UnboundedReceiver<super::WatchedTap>>,
    ),
}

/// What an agent holds, for tools that list it (`petrel ls`): its modules and properties.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct AgentListing {
    /// Modules in declaration order, with their types.
    pub modules: Vec<ModuleListing>,
    /// Every property, in key order.
    pub properties: Vec<PropertyListing>,
}

impl AgentListing {
    /// The type of module `name` (`sim.body`), if the agent has one of that name.
    pub fn module_type(&self, name: &str) -> Option<&str> {
        let m = self.modules.iter().find(|m| m.name == name)?;
        Some(&m.type_name)
    }
}

/// One module of an [`AgentListing`].
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct ModuleListing {
    /// The module's name.
    pub name: String,
    /// Its type, e.g. `nav.planner`.
    #[serde(rename = "type")]
    pub type_name: String,
}

/// One property of an [`AgentListing`].
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct PropertyListing {
    /// `module/path`.
    pub key: String,
    /// Its role, as [`PropertyKind`] displays it (`param`, `queue output`, ...).
    pub kind: String,
    /// Its value type (the item type for queues).
    #[serde(rename = "type")]
    pub type_name: String,
    /// What it is linked to, if it is a linked input.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub link: Option<String>,
}

pub(super) fn handle(reg: &mut Registry, request: TeamRequest) {
    // A reply port whose caller gave up is not the blackboard's failure: ignore send errors.
    match request {
        TeamRequest::Link(from, to, reply) => {
            let result = reg.link_target(&from, &to);
            match &result {
                Ok(()) => tracing::info!(agent = reg.agent(), %from, to = %to.url, "linked"),
                Err(e) => {
                    tracing::warn!(agent = reg.agent(), %from, to = %to.url, error = %e, "link refused")
                }
            }
            let _ = reply.send(result);
        }
        TeamRequest::Tap(key, reply) => {
            let _ = reply.send(reg.tap(&key));
        }
        TeamRequest::KindOf(key, reply) => {
            let _ = reply.send(reg.kind_of(&key));
        }
        TeamRequest::Outboxes(reply) => {
            let _ = reply.send(Ok(reg.outboxes()));
        }
        TeamRequest::Inbox(module, reply) => {
            let _ = reply.send(reg.inbox(&module));
        }
        TeamRequest::Queue(key, reply) => {
            let _ = reply.send(reg.queue_out(&key));
        }
        TeamRequest::Listing(reply) => {
            let _ = reply.send(Ok(listing(reg)));
        }
        TeamRequest::Feed(key, reply) => {
            let _ = reply.send(reg.feed(&key));
        }
        TeamRequest::WatchTaps(wants, reply) => {
            let _ = reply.send(Ok(reg.watch_taps(wants)));
        }
    }
}

fn listing(reg: &Registry) -> AgentListing {
    let modules = reg
        .modules()
        .iter()
        .map(|m| ModuleListing {
            name: m.clone(),
            type_name: reg.module_type(m).unwrap_or_default().to_string(),
        })
        .collect();
    let properties = reg
        .entries()
        .map(|(key, entry)| PropertyListing {
            key: key.clone(),
            kind: entry.decl.kind.to_string(),
            type_name: entry.decl.type_info.name().to_string(),
            link: reg.link_of(key).map(str::to_string),
        })
        .collect();
    AgentListing {
        modules,
        properties,
    }
}

impl Blackboard {
    /// Links `from` to a target in either config form while running (a remote target makes a
    /// link the team transport feeds).
    pub async fn link_target(&self, from: &str, to: LinkTarget) -> Result<(), BlackboardError> {
        self.call(|r| BlackboardMsg::Team(TeamRequest::Link(from.to_string(), to, r)))
            .await
    }

    /// Watches a value property or output queue, for a transport that publishes it.
    pub async fn tap(&self, address: &str) -> Result<Tap, BlackboardError> {
        self.call(|r| BlackboardMsg::Team(TeamRequest::Tap(address.to_string(), r)))
            .await
    }

    /// Taps every property whose `module/path` key `wants` and that holds its own data (value
    /// properties other than linked inputs, output queues): those there now, whose taps are
    /// in the receiver when this returns, and every one declared later (a module added while
    /// running, runtime statistics), tapped before anything can write it. A recorder that
    /// watches before the modules start misses no write. The watch ends with the receiver.
    pub async fn watch_taps(
        &self,
        wants: impl Fn(&str) -> bool + Send + 'static,
    ) -> Result<tokio::sync::mpsc::UnboundedReceiver<super::WatchedTap>, BlackboardError> {
        let wants: super::TapFilter = Box::new(wants);
        self.call(|r| BlackboardMsg::Team(TeamRequest::WatchTaps(wants, r)))
            .await
    }

    /// A writer to a module's output (`out/` value or queue) from outside the module: a replay
    /// publishes recorded outputs through it in place of a module that is not started.
    pub async fn feed(&self, address: &str) -> Result<RemoteFeed, BlackboardError> {
        self.call(|r| BlackboardMsg::Team(TeamRequest::Feed(address.to_string(), r)))
            .await
    }

    /// The kind (`params/`, `out/`, ...) and type of a property.
    pub async fn kind_of(
        &self,
        address: &str,
    ) -> Result<(PropertyKind, TypeInfo), BlackboardError> {
        self.call(|r| BlackboardMsg::Team(TeamRequest::KindOf(address.to_string(), r)))
            .await
    }

    /// A writer to an output queue (e.g. `_team/events`), from outside the agent's modules.
    pub async fn queue_writer<T: PropertyType>(
        &self,
        address: &str,
    ) -> Result<QueueWriter<T>, BlackboardError> {
        let core = self
            .call(|r| BlackboardMsg::Team(TeamRequest::Queue(address.to_string(), r)))
            .await?;
        if core.type_info != TypeInfo::of::<T>() {
            return Err(BlackboardError::BadValue {
                key: address.to_string(),
                expected: T::TYPE_NAME,
                reason: format!("the queue carries {}", core.type_info.name()),
            });
        }
        Ok(QueueWriter::new(core, Arc::default()))
    }

    /// The address, if it names another agent's property.
    pub(super) fn other_agent(&self, address: &str) -> Option<PropertyUrl> {
        let url = PropertyUrl::parse(address).ok()?;
        url.agent()
            .is_some_and(|a| a != &*self.agent)
            .then_some(url)
    }

    /// Sends a write to another agent through the team.
    pub(super) async fn set_remote<T: PropertyType>(
        &self,
        url: PropertyUrl,
        value: &T,
    ) -> Result<(), BlackboardError> {
        let writer = self.writer.read().clone();
        let Some(writer) = writer else {
            return Err(BlackboardError::BadAddress(format!(
                "`{url}` is another agent's property, and agent `{}` is not in a team (a `team:` section, joined)",
                self.agent
            )));
        };
        let json = serde_json::to_vec(value).map_err(|e| BlackboardError::BadValue {
            key: url.to_string(),
            expected: T::TYPE_NAME,
            reason: e.to_string(),
        })?;
        writer
            .set_json(url, json)
            .await
            .map_err(BlackboardError::BadAddress)
    }

    /// Installs (or, with `None`, removes) what carries writes to other agents: the team
    /// transport does it when the agent joins and leaves.
    pub fn set_remote_writer(&self, writer: Option<Arc<dyn RemoteWriter>>) {
        *self.writer.write() = writer;
    }

    /// The outboxes (`out/outbox` queues of messages) not yet handed out, each tapped since
    /// its module was declared, with the writer of its `stats/outbox`. Each is handed out once.
    pub async fn outboxes(&self) -> Result<Vec<Outbox>, BlackboardError> {
        self.call(|r| BlackboardMsg::Team(TeamRequest::Outboxes(r)))
            .await
    }

    /// Where messages for `module` go (its `in/inbox`).
    pub async fn inbox(&self, module: &str) -> Result<RemoteQueue, BlackboardError> {
        self.call(|r| BlackboardMsg::Team(TeamRequest::Inbox(module.to_string(), r)))
            .await
    }

    /// The agent's modules and properties, for tools that list them.
    pub async fn listing(&self) -> Result<AgentListing, BlackboardError> {
        self.call(|r| BlackboardMsg::Team(TeamRequest::Listing(r)))
            .await
    }

    /// This agent's links to other agents, which a team transport feeds.
    pub fn remote_links(&self) -> Arc<RemoteLinks> {
        self.remote.clone()
    }
}
