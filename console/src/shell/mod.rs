//! The imperative shell: an axum server (HTTP/1 + WebSocket) over the agents' blackboards.
//! Every request passes the access rules of `core::access` first.

mod api;
mod collect;
mod collect_remote;
mod foxglove;
mod remote;
mod server;
mod state;
mod ws;

use std::net::SocketAddr;
use std::sync::Arc;

use axum::extract::{Request, State};
use axum::http::{header, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::Router;

use crate::core::access::{self, Access};
use crate::{AgentSource, ConsoleError, ConsoleOptions, LogTail};
use state::Shared;

pub use foxglove::FoxgloveServer;

/// A running console; [`stop`](Console::stop) ends it (dropping it leaves it serving until the
/// runtime ends).
pub struct Console {
    addr: SocketAddr,
    access: Access,
    server: server::Server,
    shared: Arc<Shared>,
}

impl Console {
    /// Binds `options.addr` and serves the console for `agents`, with `logs` as its log tail.
    pub async fn start(
        options: ConsoleOptions,
        agents: Vec<AgentSource>,
        logs: LogTail,
    ) -> Result<Console, ConsoleError> {
        let binding = server::Binding::bind(&options).await?;
        let (addr, access) = (binding.addr, binding.access.clone());
        let shared = Arc::new(Shared::new(agents, logs, access.clone(), addr).await);
        let server = binding.serve(router(shared.clone()), "console");
        Ok(Console {
            addr,
            access,
            server,
            shared,
        })
    }

    /// Shows another agent (one that joined); it replaces a shown agent of the same name (one
    /// that left and came back).
    pub async fn join(&self, agent: AgentSource) {
        tracing::info!(agent = %agent.name, "the console shows an agent that joined");
        self.shared.join(agent).await;
    }

    /// Shows the agent `name` as gone (its requests are refused; it stays listed as `left`).
    pub fn leave(&self, name: &str) {
        tracing::info!(agent = %name, "the console shows an agent that left");
        self.shared.leave(name);
    }

    /// The address it listens on (the port the system chose for port 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// The token requests must carry, if any.
    pub fn token(&self) -> Option<&str> {
        self.access.token.as_deref()
    }

    /// Whether the token was generated (so the user has to be told it).
    pub fn token_generated(&self) -> bool {
        self.access.generated
    }

    /// The page's address, with the token when there is one.
    pub fn url(&self) -> String {
        match self.token() {
            Some(t) => format!("http://{}/?token={t}", self.addr),
            None => format!("http://{}/", self.addr),
        }
    }

    /// Stops serving: open WebSockets close, background readers end, and the server waits
    /// (at most a second) for answers under way.
    pub async fn stop(mut self) {
        self.shared.stop();
        self.server.stop().await;
    }
}

fn generate_token() -> Result<String, String> {
    let mut bytes = [0u8; 16];
    getrandom::fill(&mut bytes).map_err(|e| e.to_string())?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

fn router(shared: Arc<Shared>) -> Router {
    Router::new()
        .route("/", get(index))
        .route(
            "/app.js",
            get(|| asset(APP_JS, "text/javascript; charset=utf-8")),
        )
        .route(
            "/style.css",
            get(|| asset(STYLE_CSS, "text/css; charset=utf-8")),
        )
        .route("/api/agents", get(api::agents))
        .route("/api/logs", get(api::logs))
        .route("/api/ws", get(ws::upgrade))
        .route("/api/agents/{agent}/properties", get(api::properties))
        .route("/api/agents/{agent}/value", get(api::value))
        .route("/api/agents/{agent}/set", post(api::set))
        .route("/api/agents/{agent}/graph", get(api::graph))
        .route("/api/agents/{agent}/plans", get(api::plans))
        .route("/api/agents/{agent}/contexts", get(api::contexts))
        .route("/api/agents/{agent}/events", get(api::events))
        .route("/api/agents/{agent}/map", get(api::map))
        .route("/api/agents/{agent}/camera", get(api::camera))
        .layer(middleware::from_fn_with_state(shared.clone(), guard))
        .with_state(shared)
}

const INDEX_HTML: &str = include_str!("../../assets/index.html");
const APP_JS: &str = include_str!("../../assets/app.js");
const STYLE_CSS: &str = include_str!("../../assets/style.css");

/// The page; with a token, its script and style sheet are asked for with it (a browser sends
/// the page's query to neither).
async fn index(State(shared): State<Arc<Shared>>) -> Response {
    let page = match &shared.access.token {
        Some(t) => INDEX_HTML
            .replace("\"app.js\"", &format!("\"app.js?token={t}\""))
            .replace("\"style.css\"", &format!("\"style.css?token={t}\"")),
        None => INDEX_HTML.to_string(),
    };
    (
        [
            (header::CONTENT_TYPE, "text/html; charset=utf-8"),
            (header::CACHE_CONTROL, "no-store"),
            // The token is in the page's address: never pass it on.
            (header::REFERRER_POLICY, "no-referrer"),
        ],
        page,
    )
        .into_response()
}

async fn asset(body: &'static str, content_type: &'static str) -> Response {
    (
        [
            (header::CONTENT_TYPE, content_type),
            (header::CACHE_CONTROL, "no-store"),
        ],
        body,
    )
        .into_response()
}

/// Refuses a request from another origin or without the token, before any handler runs.
async fn guard(State(shared): State<Arc<Shared>>, request: Request, next: Next) -> Response {
    let headers = request.headers();
    let text = |name| headers.get(name).and_then(|v| v.to_str().ok());
    if let Err(e) = access::check_origin(shared.bound, text(header::HOST), text(header::ORIGIN)) {
        return (StatusCode::FORBIDDEN, e.to_string()).into_response();
    }
    let presented = access::presented_token(text(header::AUTHORIZATION), request.uri().query());
    if !shared.access.admits(presented) {
        return (
            StatusCode::UNAUTHORIZED,
            "this console needs its token: `?token=...` or `Authorization: Bearer ...`",
        )
            .into_response();
    }
    next.run(request).await
}
