//! The background readers of a remote agent: supervisor events, context switches and plan
//! firings followed over the team, as `petrel events` follows them.

use std::sync::Arc;
use tokio::time::Instant;

use parking_lot::Mutex;
use serde_json::{json, Value};
use tokio::task::JoinHandle;

use super::collect::firing_of;
use super::remote::RemoteCell;
use super::state::{History, HISTORY};
use crate::core::plan::PlanGraph;
use crate::core::view::Recent;
use crate::source::{RemoteAgent, RemoteEvent};

/// Starts the readers of one remote agent.
pub(crate) async fn start(
    remote: &Arc<dyn RemoteAgent>,
    plans: &[PlanGraph],
    history: &Arc<Mutex<History>>,
    started: Instant,
) -> Vec<JoinHandle<()>> {
    let Ok(listing) = remote.listing().await else {
        return Vec::new();
    };
    let has = |key: &str| listing.properties.iter().any(|p| p.key == key);
    let mut tasks = Vec::new();
    if has("_supervisor/events") {
        let history = history.clone();
        tasks.push(follow(remote, "_supervisor/events", move |item| {
            history.lock().events.push(item)
        }));
    }
    for m in listing
        .modules
        .iter()
        .filter(|m| m.type_name == "context.manager")
    {
        let key = format!("{}/out/changes", m.name);
        if has(&key) {
            let (history, module) = (history.clone(), m.name.clone());
            tasks.push(follow(remote, &key, move |item| {
                history
                    .lock()
                    .switches
                    .push(json!({"module": module, "change": item}))
            }));
        }
    }
    for plan in plans {
        let key = format!("{}/out/firings", plan.module);
        if !has(&key) {
            continue;
        }
        history
            .lock()
            .firings
            .insert(plan.module.clone(), Recent::new(HISTORY));
        let fired = RemoteCell::follow(remote, &format!("{}/out/fired", plan.module))
            .await
            .ok();
        let (module, history) = (plan.module.clone(), history.clone());
        tasks.push(follow(remote, &key, move |item| {
            let fired = fired
                .as_ref()
                .and_then(|c| c.sample())
                .and_then(|s| serde_json::from_slice::<i64>(&s.json).ok())
                .unwrap_or(0);
            if let Some(recent) = history.lock().firings.get_mut(&module) {
                recent.push(firing_of(&item, started, fired));
            }
        }));
    }
    tasks
}

/// Hands every item of the remote queue `key`, as JSON, to `keep`.
fn follow(
    remote: &Arc<dyn RemoteAgent>,
    key: &str,
    mut keep: impl FnMut(Value) + Send + 'static,
) -> JoinHandle<()> {
    let (remote, key) = (remote.clone(), key.to_string());
    tokio::spawn(async move {
        let mut stream = match remote.watch(&key).await {
            Ok(s) => s,
            Err(e) => {
                tracing::debug!(%key, error = %e, "the console cannot follow this queue");
                return;
            }
        };
        while let Some(event) = stream.next().await {
            if let RemoteEvent::Sample(s) = event {
                keep(serde_json::from_slice(&s.json).unwrap_or(Value::Null));
            }
        }
    })
}
