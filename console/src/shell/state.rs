//! What the server holds: the agents (joining and leaving while it runs) with their cached
//! property handles or followed remote properties, and their histories.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use tokio::time::Instant;

use parking_lot::{Mutex, RwLock};
use petrel_actors::{AgentListing, AnyHandle};
use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::Value;
use tokio::task::JoinHandle;

use super::remote::{remote_view, RemoteCell};
use crate::core::access::Access;
use crate::core::plan::{Firing, PlanGraph};
use crate::core::throttle::{interval_of, is_bulky};
use crate::core::view::{self, Recent};
use crate::source::{Backend, RemoteAgent};
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
    pub backend: Backend,
    pub plans: Vec<PlanGraph>,
    pub history: Arc<Mutex<History>>,
    handles: Mutex<HashMap<String, AnyHandle>>,
    cells: Mutex<HashMap<String, Arc<RemoteCell>>>,
    tasks: Mutex<Vec<JoinHandle<()>>>,
    left: AtomicBool,
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

/// A property a WebSocket samples: a local handle or a followed remote property.
pub(crate) enum Watched {
    Local(AnyHandle),
    Remote {
        key: String,
        type_name: String,
        cell: Arc<RemoteCell>,
    },
}

impl Watched {
    /// How often it may be pushed.
    pub fn interval(&self) -> std::time::Duration {
        match self {
            Watched::Local(h) => interval_of(h.type_info().name()),
            Watched::Remote { type_name, .. } => interval_of(type_name),
        }
    }

    /// Its version (`None`: no value yet).
    pub fn version(&self) -> Option<u64> {
        match self {
            Watched::Local(h) => Some(h.version()),
            Watched::Remote { cell, .. } => cell.sample().map(|s| s.seq),
        }
    }

    /// Its value, as pushed (bulky values as a summary).
    pub fn view(&self) -> Option<ValueView> {
        match self {
            Watched::Local(h) => Some(value_view(h, false)),
            Watched::Remote { key, cell, .. } => cell.sample().map(|s| remote_view(key, &s, false)),
        }
    }
}

impl AgentState {
    fn new(source: AgentSource, history: Arc<Mutex<History>>, tasks: Vec<JoinHandle<()>>) -> Self {
        AgentState {
            name: source.name,
            backend: source.backend,
            plans: source.plans,
            history,
            handles: Mutex::default(),
            cells: Mutex::default(),
            tasks: Mutex::new(tasks),
            left: AtomicBool::new(false),
        }
    }

    /// Whether the agent left (a remote agent whose process ended, or that left its team).
    pub fn has_left(&self) -> bool {
        self.left.load(Ordering::Relaxed)
    }

    /// The agent's modules and properties.
    pub async fn listing(&self) -> Result<AgentListing, String> {
        match &self.backend {
            Backend::Local(bb) => bb.listing().await.map_err(|e| e.to_string()),
            Backend::Remote(r) => r.listing().await,
        }
    }

    /// The current values of the modules' `stats/` properties of `listing`, as JSON.
    pub async fn stats(&self, listing: &AgentListing) -> Vec<(String, Value)> {
        match &self.backend {
            Backend::Local(_) => {
                let mut stats = Vec::new();
                for p in listing.properties.iter().filter(|p| view::is_stat(&p.key)) {
                    if let Ok(h) = self.handle(&p.key).await {
                        stats.push((
                            p.key.clone(),
                            value_view(&h, false).json.unwrap_or_default(),
                        ));
                    }
                }
                stats
            }
            // One request for all of them, as `petrel top` makes it.
            Backend::Remote(r) => r
                .get_matching("*/stats/**")
                .await
                .unwrap_or_default()
                .into_iter()
                .map(|(key, s)| (key, serde_json::from_slice(&s.json).unwrap_or_default()))
                .collect(),
        }
    }

    /// A read handle to a local `key` (for a queue: its latest item), made once and kept.
    pub async fn handle(&self, key: &str) -> Result<AnyHandle, String> {
        let Backend::Local(bb) = &self.backend else {
            return Err("a remote agent has no local handles".into());
        };
        if let Some(h) = self.handles.lock().get(key) {
            return Ok(h.clone());
        }
        let h = bb.expr_handle(key).await.map_err(|e| e.to_string())?;
        self.handles.lock().insert(key.to_string(), h.clone());
        Ok(h)
    }

    /// A remote `key`, followed from its first read for as long as the agent is shown.
    pub async fn cell(
        &self,
        remote: &Arc<dyn RemoteAgent>,
        key: &str,
    ) -> Result<Arc<RemoteCell>, String> {
        if let Some(c) = self.cells.lock().get(key).filter(|c| !c.refused()) {
            return Ok(c.clone());
        }
        let cell = Arc::new(RemoteCell::follow(remote, key).await?);
        self.cells.lock().insert(key.to_string(), cell.clone());
        Ok(cell)
    }

    /// `key` for a WebSocket to sample; `type_name` as listed (the throttle's interval).
    pub async fn watched(&self, key: &str, type_name: &str) -> Result<Watched, String> {
        match &self.backend {
            Backend::Local(_) => self.handle(key).await.map(Watched::Local),
            Backend::Remote(r) => Ok(Watched::Remote {
                key: key.to_string(),
                type_name: type_name.to_string(),
                cell: self.cell(r, key).await?,
            }),
        }
    }

    /// The current value of `key`; `full` includes bulky values' JSON.
    pub async fn view(&self, key: &str, full: bool) -> Result<ValueView, String> {
        match &self.backend {
            Backend::Local(_) => self.handle(key).await.map(|h| value_view(&h, full)),
            Backend::Remote(r) => {
                let sample = self.cell(r, key).await?.first().await?;
                Ok(remote_view(key, &sample, full))
            }
        }
    }

    /// The current value of `key` as a `T`, with its version.
    pub async fn typed<T>(&self, key: &str) -> Option<(u64, Arc<T>)>
    where
        T: DeserializeOwned + Send + Sync + 'static,
    {
        match &self.backend {
            Backend::Local(_) => {
                let sample = self.handle(key).await.ok()?.read();
                Some((sample.version, sample.value.downcast::<T>().ok()?))
            }
            Backend::Remote(r) => {
                let sample = self.cell(r, key).await.ok()?.first().await.ok()?;
                let value = serde_json::from_slice(&sample.json).ok()?;
                Some((sample.seq, Arc::new(value)))
            }
        }
    }

    /// Forgets every cached handle of a property that is gone (a removed module).
    pub fn forget(&self, keep: &dyn Fn(&str) -> bool) {
        self.handles.lock().retain(|k, _| keep(k));
        self.cells.lock().retain(|k, _| keep(k));
    }

    /// Marks the agent gone and stops following it.
    fn leave(&self) {
        self.left.store(true, Ordering::Relaxed);
        for task in self.tasks.lock().drain(..) {
            task.abort();
        }
        self.cells.lock().clear();
        self.handles.lock().clear();
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
    agents: RwLock<Vec<Arc<AgentState>>>,
    pub logs: LogTail,
    pub access: Access,
    pub bound: SocketAddr,
    pub started: Instant,
    /// Turns true when the console stops: open WebSockets close on it.
    stopping: tokio::sync::watch::Sender<bool>,
}

impl Shared {
    /// The console's state, with `agents` joined.
    pub async fn new(
        agents: Vec<AgentSource>,
        logs: LogTail,
        access: Access,
        bound: SocketAddr,
    ) -> Self {
        let shared = Shared {
            agents: RwLock::default(),
            logs,
            access,
            bound,
            started: Instant::now(),
            stopping: tokio::sync::watch::Sender::new(false),
        };
        for source in agents {
            shared.join(source).await;
        }
        shared
    }

    /// Shows `source` with its background readers started; it replaces an agent of the same
    /// name (one that left and came back).
    pub async fn join(&self, source: AgentSource) {
        let history = Arc::new(Mutex::new(History {
            events: Recent::new(HISTORY),
            switches: Recent::new(HISTORY),
            firings: HashMap::new(),
        }));
        let tasks = super::collect::start(&source, &history, self.started).await;
        let state = Arc::new(AgentState::new(source, history, tasks));
        let mut agents = self.agents.write();
        match agents.iter_mut().find(|a| a.name == state.name) {
            Some(old) => {
                old.leave();
                *old = state;
            }
            None => agents.push(state),
        }
    }

    /// Shows the agent `name` as gone.
    pub fn leave(&self, name: &str) {
        if let Some(a) = self.agents.read().iter().find(|a| a.name == name) {
            a.leave();
        }
    }

    /// Every agent shown, those that left included.
    pub fn agents(&self) -> Vec<Arc<AgentState>> {
        self.agents.read().clone()
    }

    /// The agent called `name`.
    pub fn agent(&self, name: &str) -> Option<Arc<AgentState>> {
        self.agents.read().iter().find(|a| a.name == name).cloned()
    }

    /// Ends the background readers and tells open WebSockets to close.
    pub fn stop(&self) {
        self.stopping.send_replace(true);
        for a in self.agents.read().iter() {
            a.leave();
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
