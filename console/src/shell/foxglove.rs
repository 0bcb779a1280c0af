//! The Foxglove live view's server: its own address (Foxglove connects to `ws://ADDR/`), the
//! console's access rules (loopback or token; Foxglove's app as the one other origin), and
//! per subscription a tap on the property that encodes each change or queue item and hands
//! the frame to the socket without ever making the module wait (a full socket drops frames).
//! The log is one more channel, fed by [`LiveLog`] as lines are written.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::{SystemTime, UNIX_EPOCH};

use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Request, State};
use axum::http::{header, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use petrel_actors::team::Tap;
use petrel_actors::{AnyValue, Blackboard, PropertyKind};
use serde_json::Value;
use tokio::sync::{broadcast, mpsc, watch};
use tokio::task::JoinHandle;
use tokio::time::Instant;

use crate::core::access::{self, Access};
use crate::core::foxglove::{self as protocol, Channel, ClientOp, Level, SUBPROTOCOL};
use crate::live::{ChannelEncoder, LiveEncoders, LiveLog};
use crate::{ConsoleError, ConsoleOptions};

/// Frames waiting for a slow client; beyond them frames are dropped.
const BACKLOG: usize = 256;

/// A running Foxglove live view; [`stop`](FoxgloveServer::stop) ends it.
pub struct FoxgloveServer {
    addr: SocketAddr,
    access: Access,
    server: super::server::Server,
    stopping: watch::Sender<bool>,
}

struct Live {
    agents: Vec<(String, Blackboard)>,
    encoders: Arc<dyn LiveEncoders>,
    log: Option<LiveLog>,
    access: Access,
    bound: SocketAddr,
    /// An instant and the Unix time then: write times become message stamps.
    epoch: (Instant, u64),
    stopping: watch::Receiver<bool>,
}

impl FoxgloveServer {
    /// Binds `options.addr` and serves `agents`' properties, encoded by `encoders`, and the
    /// lines `log` carries when `encoders` give the log a channel.
    pub async fn start(
        options: ConsoleOptions,
        agents: Vec<(String, Blackboard)>,
        encoders: Arc<dyn LiveEncoders>,
        log: Option<LiveLog>,
    ) -> Result<FoxgloveServer, ConsoleError> {
        let binding = super::server::Binding::bind(&options).await?;
        let (bound, access) = (binding.addr, binding.access.clone());
        let unix_ns = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .unwrap_or_default()
            .as_nanos() as u64;
        let (stopping, stopped_rx) = watch::channel(false);
        let live = Arc::new(Live {
            agents,
            encoders,
            log,
            access: access.clone(),
            bound,
            epoch: (Instant::now(), unix_ns),
            stopping: stopped_rx,
        });
        let app = Router::new()
            .route("/", get(upgrade))
            .layer(middleware::from_fn_with_state(live.clone(), guard))
            .with_state(live);
        let server = binding.serve(app, "Foxglove live view");
        Ok(FoxgloveServer {
            addr: bound,
            access,
            server,
            stopping,
        })
    }

    /// The address it listens on.
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// The token, if any, and whether it was generated (so the user has to be told it).
    pub fn token(&self) -> (Option<&str>, bool) {
        (self.access.token.as_deref(), self.access.generated)
    }

    /// The address to give Foxglove, with the token when there is one.
    pub fn url(&self) -> String {
        match &self.access.token {
            Some(t) => format!("ws://{}/?token={t}", self.addr),
            None => format!("ws://{}/", self.addr),
        }
    }

    /// Stops serving: open connections close and their subscriptions end.
    pub async fn stop(mut self) {
        self.stopping.send_replace(true);
        self.server.stop().await;
    }
}

async fn guard(State(live): State<Arc<Live>>, request: Request, next: Next) -> Response {
    let headers = request.headers();
    let text = |name| headers.get(name).and_then(|v| v.to_str().ok());
    if let Err(e) =
        access::check_foxglove_origin(live.bound, text(header::HOST), text(header::ORIGIN))
    {
        return (StatusCode::FORBIDDEN, e.to_string()).into_response();
    }
    let presented = access::presented_token(text(header::AUTHORIZATION), request.uri().query());
    if !live.access.admits(presented) {
        return (
            StatusCode::UNAUTHORIZED,
            "this live view needs its token: `?token=...`",
        )
            .into_response();
    }
    next.run(request).await
}

async fn upgrade(State(live): State<Arc<Live>>, ws: WebSocketUpgrade) -> Response {
    ws.protocols([SUBPROTOCOL])
        .on_upgrade(move |socket| async move {
            if let Err(e) = serve(socket, live).await {
                tracing::debug!(error = %e, "Foxglove connection closed");
            }
        })
}

/// An advertised channel: where its values come from and how they are encoded.
#[derive(Clone)]
struct Source {
    topic: String,
    feed: Feed,
    encoder: Arc<dyn ChannelEncoder>,
}

#[derive(Clone)]
enum Feed {
    /// A property's changes or a queue's items.
    Property { bb: Blackboard, key: String },
    /// The log lines written from now on.
    Log(LiveLog),
}

/// The channels of every property that holds data (not linked inputs), numbered from 1.
async fn channels(live: &Live) -> (Vec<Channel>, HashMap<u32, Source>) {
    let (mut channels, mut sources) = (Vec::new(), HashMap::new());
    for (agent, bb) in &live.agents {
        let Ok(listing) = bb.listing().await else {
            continue;
        };
        for p in listing.properties {
            let linked_input = p.link.is_some() || p.kind == "queue input";
            let Ok((kind, type_info)) = bb.kind_of(&p.key).await else {
                continue;
            };
            if linked_input || matches!(kind, PropertyKind::QueueIn) {
                continue;
            }
            let first: Option<AnyValue> = bb.expr_handle(&p.key).await.ok().map(|h| h.read().value);
            let Some((c, encoder)) =
                live.encoders
                    .channel(agent, &p.key, &type_info, first.as_ref())
            else {
                continue;
            };
            let feed = Feed::Property {
                bb: bb.clone(),
                key: p.key,
            };
            advertise(&mut channels, &mut sources, c, feed, encoder);
        }
    }
    if let (Some(log), Some((c, encoder))) = (&live.log, live.encoders.log()) {
        advertise(
            &mut channels,
            &mut sources,
            c,
            Feed::Log(log.clone()),
            encoder,
        );
    }
    (channels, sources)
}

/// Adds channel `c` with the next id.
fn advertise(
    channels: &mut Vec<Channel>,
    sources: &mut HashMap<u32, Source>,
    c: crate::live::LiveChannel,
    feed: Feed,
    encoder: Arc<dyn ChannelEncoder>,
) {
    let id = channels.len() as u32 + 1;
    let topic = c.topic.clone();
    channels.push(Channel {
        id,
        topic: c.topic,
        encoding: c.encoding,
        schema_name: c.schema_name,
        schema: c.schema,
        schema_encoding: c.schema_encoding,
    });
    sources.insert(
        id,
        Source {
            topic,
            feed,
            encoder,
        },
    );
}

async fn serve(mut socket: WebSocket, live: Arc<Live>) -> Result<(), axum::Error> {
    let session = live.epoch.1.to_string();
    send(&mut socket, protocol::server_info("petrel", &session)).await?;
    let (channels, sources) = channels(&live).await;
    send(&mut socket, protocol::advertise(&channels)).await?;
    let (tx, mut frames) = mpsc::channel::<Vec<u8>>(BACKLOG);
    let mut subscriptions: HashMap<u32, JoinHandle<()>> = HashMap::new();
    let mut stopping = live.stopping.clone();
    let result = loop {
        tokio::select! {
            incoming = socket.recv() => {
                let Some(message) = incoming.transpose()? else { break Ok(()) };
                let Message::Text(text) = message else { continue };
                match protocol::parse_client(&text) {
                    Ok(ClientOp::Subscribe(subs)) => {
                        for s in subs {
                            let Some(source) = sources.get(&s.channel_id) else {
                                let why = format!("no channel {}", s.channel_id);
                                send(&mut socket, protocol::status(Level::Warning, &why)).await?;
                                continue;
                            };
                            // The log's lines count from the subscription, this one's own line included.
                            let lines = match &source.feed {
                                Feed::Log(log) => Some(log.subscribe()),
                                Feed::Property { .. } => None,
                            };
                            tracing::info!(topic = %source.topic, "a Foxglove client subscribed");
                            let task = tokio::spawn(stream(source.clone(), lines, s.id, live.epoch, tx.clone()));
                            if let Some(old) = subscriptions.insert(s.id, task) {
                                old.abort();
                            }
                        }
                    }
                    Ok(ClientOp::Unsubscribe(ids)) => {
                        for id in ids {
                            if let Some(task) = subscriptions.remove(&id) {
                                task.abort();
                            }
                        }
                    }
                    Ok(ClientOp::Unsupported(op)) => {
                        let why = format!("`{op}` is not offered: this live view only streams");
                        send(&mut socket, protocol::status(Level::Warning, &why)).await?;
                    }
                    Err(e) => send(&mut socket, protocol::status(Level::Error, &e)).await?,
                }
            }
            Some(frame) = frames.recv() => socket.send(Message::Binary(frame.into())).await?,
            _ = async { stopping.wait_for(|s| *s).await.map(|_| ()) } => {
                let _ = socket.send(Message::Close(None)).await;
                break Ok(());
            }
        }
    };
    for (_, task) in subscriptions {
        task.abort();
    }
    result
}

/// Streams one subscription: the current value at once, then every change or queue item (or,
/// for the log, each line from `lines`).
async fn stream(
    source: Source,
    lines: Option<broadcast::Receiver<(u64, AnyValue)>>,
    subscription: u32,
    epoch: (Instant, u64),
    out: mpsc::Sender<Vec<u8>>,
) {
    let stamp = |at: Instant| -> u64 {
        match at.checked_duration_since(epoch.0) {
            Some(after) => epoch.1.saturating_add(after.as_nanos() as u64),
            None => epoch
                .1
                .saturating_sub(epoch.0.duration_since(at).as_nanos() as u64),
        }
    };
    let send_at = |value: &AnyValue, ns: u64| {
        let mut payload = Vec::new();
        match source.encoder.encode(value, ns, &mut payload) {
            // A full socket drops the frame: the module never waits for Foxglove.
            Ok(()) => {
                out.try_send(protocol::message_data(subscription, ns, &payload))
                    .is_ok()
                    || !out.is_closed()
            }
            Err(e) => {
                tracing::debug!(topic = %source.topic, error = %e, "cannot encode for Foxglove");
                true
            }
        }
    };
    let send = |value: &AnyValue, at: Instant| send_at(value, stamp(at));
    let (bb, key) = match (&source.feed, lines) {
        (Feed::Property { bb, key }, _) => (bb, key),
        (Feed::Log(log), lines) => {
            let mut lines = lines.unwrap_or_else(|| log.subscribe());
            loop {
                match lines.recv().await {
                    Ok((ns, line)) if !send_at(&line, ns) => return,
                    Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
                    Err(broadcast::error::RecvError::Closed) => return,
                }
            }
        }
    };
    match bb.tap(key).await {
        Ok(Tap::Value(tap)) => {
            let mut sent = None;
            loop {
                let (value, version, written) = tap.read();
                if sent != Some(version) && !send(&value, written) {
                    return;
                }
                sent = Some(version);
                tap.changed().await;
            }
        }
        Ok(Tap::Queue(mut tap)) => loop {
            for (_, pushed, item) in tap.take(256) {
                if !send(&item, pushed) {
                    return;
                }
            }
            tap.changed().await;
        },
        Err(e) => tracing::debug!(%key, error = %e, "cannot tap for Foxglove"),
    }
}

async fn send(socket: &mut WebSocket, message: Value) -> Result<(), axum::Error> {
    socket.send(Message::Text(message.to_string().into())).await
}
