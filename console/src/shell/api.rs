//! The JSON API the page uses (and tests and scripts call directly). Each handler reads the
//! agent's blackboard and hands what it read to a `core` function.

use std::collections::HashMap;
use std::sync::Arc;

use axum::extract::rejection::{JsonRejection, QueryRejection};
use axum::extract::{Path, Query, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use petrel_actors::{Image, OccupancyGrid, Pose2};
use serde::Deserialize;
use serde_json::{json, Value};

use super::remote::remote_view;
use super::state::{AgentState, Shared};
use crate::core::{access, map, plan, view};
use crate::source::Backend;

type Api = Result<Json<Value>, ApiError>;

/// A refused request: its status and the reason, answered as `{"error": reason}`.
pub(crate) struct ApiError {
    status: StatusCode,
    message: String,
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        (self.status, Json(json!({ "error": self.message }))).into_response()
    }
}

fn error(status: StatusCode, message: impl Into<String>) -> ApiError {
    ApiError {
        status,
        message: message.into(),
    }
}

/// A query string or body the framework could not read, answered in the API's own form
/// (`{"error": ...}`, with the framework's status: 400, 413 for a body too large, 415 for a
/// body without a JSON content type) rather than its plain text.
fn unreadable(status: StatusCode, text: String) -> ApiError {
    error(status, format!("unreadable request: {text}"))
}

fn unreadable_query(e: QueryRejection) -> ApiError {
    unreadable(e.status(), e.body_text())
}

fn unreadable_body(e: JsonRejection) -> ApiError {
    // A field of the wrong type is a bad request like a bad value (the framework says 422).
    let status = match e.status() {
        StatusCode::UNPROCESSABLE_ENTITY => StatusCode::BAD_REQUEST,
        other => other,
    };
    unreadable(status, e.body_text())
}

/// A property key as the API takes it, `module/path`: one that is not such an address is a
/// bad request (400), not a property that happens to be missing (404).
fn property_key(key: &str) -> Result<&str, ApiError> {
    match key.split_once('/') {
        Some((module, path)) if !module.is_empty() && !path.is_empty() => Ok(key),
        _ => Err(error(
            StatusCode::BAD_REQUEST,
            format!(
                "`{key}` is not a property key; expected `module/path`, e.g. `scale/out/value`"
            ),
        )),
    }
}

fn agent(shared: &Shared, name: &str) -> Result<Arc<AgentState>, ApiError> {
    match shared.agent(name) {
        Some(a) if a.has_left() => {
            Err(error(StatusCode::NOT_FOUND, format!("agent `{name}` left")))
        }
        Some(a) => Ok(a),
        None => {
            let known: Vec<String> = shared.agents().iter().map(|a| a.name.clone()).collect();
            Err(error(
                StatusCode::NOT_FOUND,
                format!("no agent `{name}` here; agents: {}", known.join(", ")),
            ))
        }
    }
}

fn unavailable(e: impl std::fmt::Display) -> ApiError {
    error(StatusCode::SERVICE_UNAVAILABLE, e.to_string())
}

/// `GET /api/agents`: every agent with its modules' status and step figures; `state` is
/// `live`, `left` (gone: shown without modules) or `unreachable` (not answering just now).
pub(crate) async fn agents(State(shared): State<Arc<Shared>>) -> Api {
    let mut out = Vec::new();
    for a in shared.agents() {
        let listing = match a.has_left() {
            true => Err("left".to_string()),
            false => a.listing().await,
        };
        let Ok(listing) = listing else {
            let state = if a.has_left() { "left" } else { "unreachable" };
            out.push(
                json!({"name": a.name, "state": state, "modules": [], "plans": [], "map": false}),
            );
            continue;
        };
        let stats = a.stats(&listing).await;
        out.push(json!({
            "name": a.name,
            "state": "live",
            "remote": matches!(a.backend, Backend::Remote(_)),
            "modules": view::modules(&listing, &stats),
            "plans": a.plans.iter().map(|p| &p.module).collect::<Vec<_>>(),
            "map": map::pick(&listing).any(),
        }));
    }
    Ok(Json(
        json!({ "agents": out, "uptime_s": shared.started.elapsed().as_secs_f64() }),
    ))
}

/// `GET /api/agents/{agent}/properties`: the property browser's rows.
pub(crate) async fn properties(State(shared): State<Arc<Shared>>, Path(name): Path<String>) -> Api {
    let a = agent(&shared, &name)?;
    let listing = a.listing().await.map_err(unavailable)?;
    let keys: std::collections::HashSet<&str> =
        listing.properties.iter().map(|p| p.key.as_str()).collect();
    a.forget(&|k| keys.contains(k));
    Ok(Json(json!({ "properties": view::properties(&listing) })))
}

#[derive(Deserialize)]
pub(crate) struct KeyQuery {
    key: String,
}

/// `GET /api/agents/{agent}/value?key=module/path`: one value in full.
pub(crate) async fn value(
    State(shared): State<Arc<Shared>>,
    Path(name): Path<String>,
    q: Result<Query<KeyQuery>, QueryRejection>,
) -> Api {
    let Query(q) = q.map_err(unreadable_query)?;
    let key = property_key(&q.key)?;
    let a = agent(&shared, &name)?;
    let v = a
        .view(key, true)
        .await
        .map_err(|e| error(StatusCode::NOT_FOUND, e))?;
    Ok(Json(json!(v)))
}

#[derive(Deserialize)]
pub(crate) struct SetRequest {
    key: String,
    /// RON text, as in a config or `petrel set`.
    value: String,
}

/// `POST /api/agents/{agent}/set` `{"key", "value"}`: sets a parameter or control from RON
/// text with `petrel set`'s checks (a remote agent's through the same remote write); 403 for
/// other kinds, 400 with the reason for a bad value or the owner's refusal.
pub(crate) async fn set(
    State(shared): State<Arc<Shared>>,
    Path(name): Path<String>,
    request: Result<Json<SetRequest>, JsonRejection>,
) -> Api {
    let Json(request) = request.map_err(unreadable_body)?;
    let key = property_key(&request.key)?;
    let a = agent(&shared, &name)?;
    match &a.backend {
        Backend::Local(bb) => {
            let (kind, _) = bb
                .kind_of(key)
                .await
                .map_err(|e| error(StatusCode::NOT_FOUND, e.to_string()))?;
            if !access::writable(kind) {
                return Err(error(StatusCode::FORBIDDEN, access::refusal(key, kind)));
            }
            bb.set_text(key, &request.value)
                .await
                .map_err(|e| error(StatusCode::BAD_REQUEST, e.to_string()))?;
        }
        Backend::Remote(remote) => {
            let listing = a.listing().await.map_err(unavailable)?;
            let Some(p) = listing.properties.iter().find(|p| p.key == key) else {
                return Err(error(
                    StatusCode::NOT_FOUND,
                    format!("agent `{}` has no property `{key}`", a.name),
                ));
            };
            if !access::writable_named(&p.kind) {
                return Err(error(StatusCode::FORBIDDEN, access::refusal(key, &p.kind)));
            }
            remote
                .set_ron(key, &request.value)
                .await
                .map_err(|e| error(StatusCode::BAD_REQUEST, e))?;
            tracing::info!(agent = %a.name, property = %key, value = %request.value, "set from the console");
            // The owner answered once the value was set; its stream may not have brought it
            // yet, so the value is asked for.
            let read = remote.get_matching(key).await.map_err(unavailable)?;
            let (_, sample) = read
                .first()
                .ok_or_else(|| unavailable("the agent did not answer"))?;
            return Ok(Json(json!(remote_view(key, sample, false))));
        }
    }
    tracing::info!(agent = %a.name, property = %key, value = %request.value, "set from the console");
    let v = a.view(key, false).await.map_err(unavailable)?;
    Ok(Json(json!(v)))
}

/// `GET /api/agents/{agent}/graph`: modules and links.
pub(crate) async fn graph(State(shared): State<Arc<Shared>>, Path(name): Path<String>) -> Api {
    let a = agent(&shared, &name)?;
    let listing = a.listing().await.map_err(unavailable)?;
    Ok(Json(json!(view::graph(&listing))))
}

/// `GET /api/agents/{agent}/plans`: each plan's net, marking, running actions and recent
/// firings.
pub(crate) async fn plans(State(shared): State<Arc<Shared>>, Path(name): Path<String>) -> Api {
    let a = agent(&shared, &name)?;
    let mut out = Vec::new();
    for graph in &a.plans {
        let read = |path: &str| {
            let key = format!("{}/{path}", graph.module);
            let a = a.clone();
            async move {
                match a.view(&key, false).await {
                    Ok(v) => v.json.unwrap_or_default(),
                    Err(_) => Value::Null,
                }
            }
        };
        let marking = read("out/marking").await;
        let firings = a
            .history
            .lock()
            .firings
            .get(&graph.module)
            .map(|r| r.items())
            .unwrap_or_default();
        out.push(json!({
            "module": graph.module,
            "places": graph.places,
            "transitions": graph.transitions,
            "marking": plan::parse_marking(marking.as_str().unwrap_or_default()),
            "running": read("out/running").await,
            "result": read("out/result").await,
            "fired": read("out/fired").await,
            "firings": firings,
        }));
    }
    Ok(Json(json!({ "plans": out })))
}

/// `GET /api/agents/{agent}/contexts`: active contexts per manager and recent switches.
pub(crate) async fn contexts(State(shared): State<Arc<Shared>>, Path(name): Path<String>) -> Api {
    let a = agent(&shared, &name)?;
    let listing = a.listing().await.map_err(unavailable)?;
    let mut active = HashMap::new();
    for m in listing
        .modules
        .iter()
        .filter(|m| m.type_name == "context.manager")
    {
        if let Ok(v) = a.view(&format!("{}/out/active", m.name), false).await {
            active.insert(m.name.clone(), v.json);
        }
    }
    let switches = a.history.lock().switches.items();
    Ok(Json(json!({ "active": active, "switches": switches })))
}

/// `GET /api/agents/{agent}/events`: recent supervisor events.
pub(crate) async fn events(State(shared): State<Arc<Shared>>, Path(name): Path<String>) -> Api {
    let a = agent(&shared, &name)?;
    let history = a.history.lock();
    Ok(Json(
        json!({ "events": history.events.items(), "total": history.events.total() }),
    ))
}

/// `GET /api/logs`: the log tail.
pub(crate) async fn logs(State(shared): State<Arc<Shared>>) -> Api {
    let (lines, total) = shared.logs.lines();
    Ok(Json(json!({ "lines": lines, "total": total })))
}

#[derive(Deserialize)]
pub(crate) struct MapQuery {
    /// The grid version the page has: the grid is sent only when it changed.
    #[serde(default)]
    grid_version: Option<u64>,
}

/// `GET /api/agents/{agent}/map`: grid (when changed), poses, path, laser, victims, goals.
pub(crate) async fn map(
    State(shared): State<Arc<Shared>>,
    Path(name): Path<String>,
    q: Result<Query<MapQuery>, QueryRejection>,
) -> Api {
    let Query(q) = q.map_err(unreadable_query)?;
    let a = agent(&shared, &name)?;
    let listing = a.listing().await.map_err(unavailable)?;
    let sources = map::pick(&listing);
    let mut out = json!({ "sources": sources });
    if let Some(key) = &sources.grid {
        if let Some((version, grid)) = a.typed::<OccupancyGrid>(key).await {
            out["grid_version"] = json!(version);
            if q.grid_version != Some(version) {
                out["grid"] = map::grid_json(&grid);
            }
        }
    }
    for (name, key) in [("pose", &sources.pose), ("true_pose", &sources.true_pose)] {
        if let Some(key) = key {
            if let Some((_, pose)) = a.typed::<Pose2>(key).await {
                out[name] = map::pose_json(&pose);
            }
        }
    }
    for (name, key) in [
        ("path", &sources.path),
        ("victims", &sources.victims),
        ("goals", &sources.goals),
        ("laser", &sources.laser),
    ] {
        if let Some(key) = key {
            if let Ok(v) = a.view(key, true).await {
                out[name] = v.json.unwrap_or_default();
            }
        }
    }
    Ok(Json(out))
}

/// `GET /api/agents/{agent}/camera`: the latest camera frame (`null` without a camera).
pub(crate) async fn camera(State(shared): State<Arc<Shared>>, Path(name): Path<String>) -> Api {
    let a = agent(&shared, &name)?;
    let listing = a.listing().await.map_err(unavailable)?;
    let Some(key) = map::pick(&listing).camera else {
        return Ok(Json(json!({ "image": null })));
    };
    // No frame yet: the queue's latest item cannot be read before the first push.
    let image = a
        .typed::<Image>(&key)
        .await
        .map(|(_, i)| map::image_json(&i));
    Ok(Json(json!({ "key": key, "image": image })))
}
