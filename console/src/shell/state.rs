//! What the server holds: the agents with their cached property handles and histories.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::Arc;
use tokio::time::Instant;

use parking_lot::Mutex;
use petrel_actors::{AgentListing, AnyHandle, Blackboard, BlackboardError};
use serde::Serialize;
use serde_json::Value;
use tokio::task::JoinHandle;

use crate::core::access::Access;
use crate::core::plan::{Firing, PlanGraph};
use crate::core::throttle::is_bulky;
use crate::core::view::{self, Recent};
use crate::{AgentSource, LogTail};

/// Events and switches kept per agent.
pub(crate) const HISTORY: usize = 200;

/// What happened in one agent, as the background readers saw it.
pub(crate) struct History {
    /// Supervisor events (`_supervisor/events`), as JSON.
    pub events: Recent<Value>,
    /// Context switches (`out/changes` of context managers), with the module.
    pub switches: Recent<Value>,
    /// Plan firings per mission module.
    pub firings: HashMap<String, Recent<Firing>>,
}

/// One agent, as the console serves it.
pub(crate) struct AgentState {
    pub name: String,
    pub blackboard: Blackboard,
    pub plans: Vec<PlanGraph>,
    pub history: Arc<Mutex<History>>,
    handles: Mutex<HashMap<String, AnyHandle>>,
}

/// A value as the API returns it.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct ValueView {
    pub key: String,
    #[serde(rename = "type")]
    pub type_name: String,
    pub version: u64,
    /// The short display every type has.
    pub text: String,
    /// The value as JSON, left out for bulky types (grids, images, scans, paths).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub json: Option<Value>,
}

impl AgentState {
    /// The agent's modules and properties (through its blackboard actor).
    pub async fn listing(&self) -> Result<AgentListing, BlackboardError> {
        self.blackboard.listing().await
    }

    /// A read handle to `key` (for a queue: its latest item), made once and kept.
    pub async fn handle(&self, key: &str) -> Result<AnyHandle, BlackboardError> {
        if let Some(h) = self.handles.lock().get(key) {
            return Ok(h.clone());
        }
        let h = self.blackboard.expr_handle(key).await?;
        self.handles.lock().insert(key.to_string(), h.clone());
        Ok(h)
    }

    /// Forgets every cached handle of a property that is gone (a removed module).
    pub fn forget(&self, keep: &dyn Fn(&str) -> bool) {
        self.handles.lock().retain(|k, _| keep(k));
    }
}

/// The value behind `handle`, as the API shows it; `full` includes bulky values' JSON.
pub(crate) fn value_view(handle: &AnyHandle, full: bool) -> ValueView {
    let sample = handle.read();
    let type_info = handle.type_info();
    let json = (full || !is_bulky(type_info.name()))
        .then(|| type_info.to_json(&sample.value).ok())
        .flatten()
        .and_then(|bytes| serde_json::from_slice(&bytes).ok());
    ValueView {
        key: handle.key().to_string(),
        type_name: type_info.name().to_string(),
        version: sample.version,
        text: view::bulky_summary(&sample.value).unwrap_or_else(|| type_info.short(&sample.value)),
        json,
    }
}

/// Everything the handlers share.
pub(crate) struct Shared {
    pub agents: Vec<AgentState>,
    pub logs: LogTail,
    pub access: Access,
    pub bound: SocketAddr,
    pub started: Instant,
    tasks: Mutex<Vec<JoinHandle<()>>>,
    /// Turns true when the console stops: open WebSockets close on it.
    stopping: tokio::sync::watch::Sender<bool>,
}

impl Shared {
    /// The agents, with their background readers started.
    pub async fn new(
        agents: Vec<AgentSource>,
        logs: LogTail,
        access: Access,
        bound: SocketAddr,
    ) -> Self {
        let started = Instant::now();
        let mut tasks = Vec::new();
        let mut states = Vec::new();
        for source in agents {
            let history = Arc::new(Mutex::new(History {
                events: Recent::new(HISTORY),
                switches: Recent::new(HISTORY),
                firings: HashMap::new(),
            }));
            tasks.extend(super::collect::start(&source, &history, started).await);
            states.push(AgentState {
                name: source.name,
                blackboard: source.blackboard,
                plans: source.plans,
                history,
                handles: Mutex::default(),
            });
        }
        Shared {
            agents: states,
            logs,
            access,
            bound,
            started,
            tasks: Mutex::new(tasks),
            stopping: tokio::sync::watch::Sender::new(false),
        }
    }

    /// The agent called `name`.
    pub fn agent(&self, name: &str) -> Option<&AgentState> {
        self.agents.iter().find(|a| a.name == name)
    }

    /// Ends the background readers and tells open WebSockets to close.
    pub fn stop(&self) {
        self.stopping.send_replace(true);
        for task in self.tasks.lock().drain(..) {
            task.abort();
        }
    }

    /// Resolves when the console stops.
    pub fn stopped(&self) -> impl std::future::Future<Output = ()> + Send + 'static {
        let mut stopping = self.stopping.subscribe();
        async move {
            let _ = stopping.wait_for(|s| *s).await;
        }
    }
}
