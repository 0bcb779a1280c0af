//! The JSON API the page uses (and tests and scripts call directly). Each handler reads the
//! agent's blackboard and hands what it read to a `core` function.

use std::collections::HashMap;
use std::sync::Arc;

use axum::extract::{Path, Query, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use petrel_actors::{Image, OccupancyGrid, Pose2};
use serde::Deserialize;
use serde_json::{json, Value};

use super::state::{value_view, AgentState, Shared};
use crate::core::{access, map, plan, view};

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

fn agent<'a>(shared: &'a Shared, name: &str) -> Result<&'a AgentState, ApiError> {
    shared.agent(name).ok_or_else(|| {
        let known: Vec<&str> = shared.agents.iter().map(|a| a.name.as_str()).collect();
        error(
            StatusCode::NOT_FOUND,
            format!("no agent `{name}` here; agents: {}", known.join(", ")),
        )
    })
}

fn unavailable(e: impl std::fmt::Display) -> ApiError {
    error(StatusCode::SERVICE_UNAVAILABLE, e.to_string())
}

/// `GET /api/agents`: every agent with its modules' status and step figures.
pub(crate) async fn agents(State(shared): State<Arc<Shared>>) -> Api {
    let mut out = Vec::new();
    for a in &shared.agents {
        let listing = a.listing().await.map_err(unavailable)?;
        let mut stats = Vec::new();
        for p in listing.properties.iter().filter(|p| view::is_stat(&p.key)) {
            if let Ok(h) = a.handle(&p.key).await {
                stats.push((
                    p.key.clone(),
                    value_view(&h, false).json.unwrap_or_default(),
                ));
            }
        }
        out.push(json!({
            "name": a.name,
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
    Query(q): Query<KeyQuery>,
) -> Api {
    let a = agent(&shared, &name)?;
    let h = a
        .handle(&q.key)
        .await
        .map_err(|e| error(StatusCode::NOT_FOUND, e.to_string()))?;
    Ok(Json(json!(value_view(&h, true))))
}

#[derive(Deserialize)]
pub(crate) struct SetRequest {
    key: String,
    /// RON text, as in a config or `petrel set`.
    value: String,
}

/// `POST /api/agents/{agent}/set` `{"key", "value"}`: sets a parameter or control from RON
/// text with `petrel set`'s checks; 403 for other kinds, 400 with the reason for a bad value.
pub(crate) async fn set(
    State(shared): State<Arc<Shared>>,
    Path(name): Path<String>,
    Json(request): Json<SetRequest>,
) -> Api {
    let a = agent(&shared, &name)?;
    let (kind, _) = a
        .blackboard
        .kind_of(&request.key)
        .await
        .map_err(|e| error(StatusCode::NOT_FOUND, e.to_string()))?;
    if !access::writable(kind) {
        return Err(error(
            StatusCode::FORBIDDEN,
            access::refusal(&request.key, kind),
        ));
    }
    a.blackboard
        .set_text(&request.key, &request.value)
        .await
        .map_err(|e| error(StatusCode::BAD_REQUEST, e.to_string()))?;
    tracing::info!(agent = %a.name, property = %request.key, value = %request.value, "set from the console");
    let h = a.handle(&request.key).await.map_err(unavailable)?;
    Ok(Json(json!(value_view(&h, false))))
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
            async move {
                match a.handle(&key).await {
                    Ok(h) => value_view(&h, false).json.unwrap_or_default(),
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
        if let Ok(h) = a.handle(&format!("{}/out/active", m.name)).await {
            active.insert(m.name.clone(), value_view(&h, false).json);
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
    Query(q): Query<MapQuery>,
) -> Api {
    let a = agent(&shared, &name)?;
    let listing = a.listing().await.map_err(unavailable)?;
    let sources = map::pick(&listing);
    let mut out = json!({ "sources": sources });
    if let Some(key) = &sources.grid {
        if let Ok(h) = a.handle(key).await {
            let sample = h.read();
            out["grid_version"] = json!(sample.version);
            if q.grid_version != Some(sample.version) {
                if let Ok(grid) = sample.value.downcast::<OccupancyGrid>() {
                    out["grid"] = map::grid_json(&grid);
                }
            }
        }
    }
    for (name, key) in [("pose", &sources.pose), ("true_pose", &sources.true_pose)] {
        if let Some(h) = key.as_ref().map(|k| a.handle(k)) {
            if let Some(pose) = h.await.ok().and_then(|h| h.get::<Pose2>()) {
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
            if let Ok(h) = a.handle(key).await {
                out[name] = value_view(&h, true).json.unwrap_or_default();
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
    let image = match a.handle(&key).await {
        Ok(h) => h.get::<Image>().map(|i| map::image_json(&i)),
        // No frame yet: the queue's latest item cannot be read before the first push.
        Err(_) => None,
    };
    Ok(Json(json!({ "key": key, "image": image })))
}
