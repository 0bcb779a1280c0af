//! Where an agent's properties come from: its blackboard, when it runs in this process, or a
//! team client, when the console attaches to agents running elsewhere (`petrel console`).
//!
//! The console does not depend on the team transport: the root package implements
//! [`RemoteAgent`] over petrel-team's `Client`, the one the CLI tools (`petrel ls`, `get`, `set`,
//! `echo`, `top`) use, so the console reads and writes remote agents with the very same
//! requests and checks.

use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;

use petrel_actors::{AgentListing, Blackboard};

use crate::core::plan::PlanGraph;

/// A boxed future, as the object-safe [`RemoteAgent`] returns them.
pub type BoxFuture<'a, T> = Pin<Box<dyn Future<Output = T> + Send + 'a>>;

/// A value or queue item of a remote agent, as the team transport carries it.
#[derive(Debug, Clone, PartialEq)]
pub struct RemoteSample {
    /// The owner's sequence number (a value's version, a queue item's number).
    pub seq: u64,
    /// The petrel type name.
    pub type_name: String,
    /// The value as JSON.
    pub json: Vec<u8>,
}

/// What a followed remote property delivers.
#[derive(Debug, Clone, PartialEq)]
pub enum RemoteEvent {
    /// A queue's stream is open (items pushed from now on will come).
    Opened,
    /// A value (the current one first) or a queue item.
    Sample(RemoteSample),
    /// The owner cannot publish it, saying why (no such property, ...).
    Refused(String),
}

/// A followed remote property; dropping it stops the stream.
pub trait RemoteWatch: Send + 'static {
    /// The next event (`None`: the stream ended).
    fn next(&mut self) -> BoxFuture<'_, Option<RemoteEvent>>;
}

/// One agent reached over a team: the requests the console makes of it. Errors are the
/// transport's or the owner's words, shown as they are.
pub trait RemoteAgent: Send + Sync + 'static {
    /// The agent's modules and properties (its `@info` answer).
    fn listing(&self) -> BoxFuture<'_, Result<AgentListing, String>>;
    /// The current values of the value properties whose `module/path` matches `pattern`
    /// (`*` one segment, `**` any), with their keys.
    fn get_matching<'a>(
        &'a self,
        pattern: &'a str,
    ) -> BoxFuture<'a, Result<Vec<(String, RemoteSample)>, String>>;
    /// Sets `key` from RON text; the owner checks it as for `petrel set`.
    fn set_ron<'a>(&'a self, key: &'a str, ron_text: &'a str) -> BoxFuture<'a, Result<(), String>>;
    /// Follows `key`: its current value, then every change or queue item.
    fn watch<'a>(&'a self, key: &'a str) -> BoxFuture<'a, Result<Box<dyn RemoteWatch>, String>>;
}

/// How the console reaches an agent.
#[derive(Clone)]
pub enum Backend {
    /// In this process: everything is read from (and every edit written to) its blackboard.
    Local(Blackboard),
    /// Over a team.
    Remote(Arc<dyn RemoteAgent>),
}

/// An agent the console shows.
#[derive(Clone)]
pub struct AgentSource {
    /// The agent's name.
    pub name: String,
    /// How it is reached.
    pub backend: Backend,
    /// The structure of the plans its `mission.pnp` modules run (the console reads no plan
    /// files itself).
    pub plans: Vec<PlanGraph>,
}

impl AgentSource {
    /// An agent of this process, without plans to draw.
    pub fn new(name: &str, blackboard: Blackboard) -> Self {
        AgentSource {
            name: name.to_string(),
            backend: Backend::Local(blackboard),
            plans: Vec::new(),
        }
    }

    /// An agent reached over a team, without plans to draw.
    pub fn remote(name: &str, agent: Arc<dyn RemoteAgent>) -> Self {
        AgentSource {
            name: name.to_string(),
            backend: Backend::Remote(agent),
            plans: Vec::new(),
        }
    }
}
