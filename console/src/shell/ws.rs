//! `GET /api/ws?agent=NAME`: values pushed as they change. The client sends
//! `{"watch": ["module/path", ...]}` (or `{"watch": "all"}`) to choose what it sees; the
//! server answers `{"values": [...]}` with each watched property at its first sight and then
//! at most once per its throttle interval, only when it changed.
//!
//! The connection samples versions at the throttle's pace instead of waking on every write:
//! a module writing at 1 kHz costs the console ten reads a second, never a thousand.

use std::sync::Arc;
use std::time::Instant;

use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Query, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use serde_json::{json, Value};

use super::state::{AgentState, Shared, Watched};
use crate::core::throttle::Throttle;

#[derive(Deserialize)]
pub(crate) struct WsQuery {
    agent: String,
}

/// Upgrades to a WebSocket watching `agent`'s properties.
pub(crate) async fn upgrade(
    State(shared): State<Arc<Shared>>,
    Query(q): Query<WsQuery>,
    ws: WebSocketUpgrade,
) -> Response {
    let Some(agent) = shared.agent(&q.agent).filter(|a| !a.has_left()) else {
        return (
            StatusCode::NOT_FOUND,
            format!("no agent `{}` here", q.agent),
        )
            .into_response();
    };
    ws.on_upgrade(move |socket| async move {
        if let Err(e) = serve(socket, &agent, shared.stopped()).await {
            tracing::debug!(error = %e, "console socket closed");
        }
    })
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Watch {
    All(String),
    Keys(Vec<String>),
}

#[derive(Deserialize)]
struct ClientMessage {
    watch: Watch,
}

struct Watching {
    handles: Vec<Watched>,
    throttle: Throttle,
}

async fn serve(
    mut socket: WebSocket,
    agent: &AgentState,
    stopped: impl std::future::Future<Output = ()>,
) -> Result<(), axum::Error> {
    let mut watched = empty();
    let mut stopped = std::pin::pin!(stopped);
    loop {
        // Tokio's clock, not the system's: under a paused test clock the two differ.
        let wake = tokio::time::Instant::from_std(watched.throttle.next_check(now()));
        tokio::select! {
            incoming = socket.recv() => {
                let Some(message) = incoming.transpose()? else { return Ok(()) };
                let Message::Text(text) = message else { continue };
                match serde_json::from_str::<ClientMessage>(&text) {
                    Ok(m) => {
                        let (w, problems) = watch(agent, m.watch).await;
                        watched = w;
                        if !problems.is_empty() {
                            send(&mut socket, json!({ "errors": problems })).await?;
                        }
                    }
                    Err(e) => send(&mut socket, json!({ "errors": [format!("expected {{\"watch\": [keys] or \"all\"}}: {e}")] })).await?,
                }
            }
            _ = tokio::time::sleep_until(wake) => {}
            _ = &mut stopped => {
                let _ = socket.send(Message::Close(None)).await;
                return Ok(());
            }
        }
        if agent.has_left() {
            let _ = socket.send(Message::Close(None)).await;
            return Ok(());
        }
        let now = now();
        let values: Vec<_> = watched
            .handles
            .iter()
            .enumerate()
            .filter_map(|(i, h)| h.version().map(|v| (i, v, h)))
            .filter(|(i, version, _)| watched.throttle.due(*i, *version, now))
            .filter_map(|(_, _, h)| h.view())
            .collect();
        if !values.is_empty() {
            send(&mut socket, json!({ "values": values })).await?;
        }
    }
}

fn now() -> Instant {
    tokio::time::Instant::now().into_std()
}

async fn send(socket: &mut WebSocket, message: Value) -> Result<(), axum::Error> {
    socket.send(Message::Text(message.to_string().into())).await
}

/// Handles for what the client asked to watch, and the keys that could not be watched.
async fn watch(agent: &AgentState, watch: Watch) -> (Watching, Vec<String>) {
    let listing = match agent.listing().await {
        Ok(listing) => listing,
        Err(e) => return (empty(), vec![e]),
    };
    let keys = match watch {
        Watch::Keys(keys) => keys,
        Watch::All(all) if all == "all" => {
            listing.properties.iter().map(|p| p.key.clone()).collect()
        }
        Watch::All(other) => {
            return (
                empty(),
                vec![format!("`{other}`: watch takes a list of keys or \"all\"")],
            )
        }
    };
    let mut watched = empty();
    let mut problems = Vec::new();
    for key in keys {
        let type_name = listing
            .properties
            .iter()
            .find(|p| p.key == key)
            .map_or("", |p| p.type_name.as_str());
        match agent.watched(&key, type_name).await {
            Ok(w) => {
                watched.throttle.add(w.interval());
                watched.handles.push(w);
            }
            Err(e) => problems.push(format!("{key}: {e}")),
        }
    }
    (watched, problems)
}

fn empty() -> Watching {
    Watching {
        handles: Vec::new(),
        throttle: Throttle::default(),
    }
}
