//! Publishing this agent's properties to the readers that want them: one task per wanted
//! stream (property and pace), started when the first reader's `@want` token appears and
//! stopped when the last one goes.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;
use std::time::Duration;

use petrel_actors::team::{Mode, Qos, QueueTap, Reliability, Tap, ValueTap};
use petrel_actors::{AnyValue, TypeInfo};
use tokio::sync::{mpsc, Notify};
use tokio::task::JoinHandle;
use tokio::time::Instant;
use zenoh::bytes::Encoding;
use zenoh::pubsub::Publisher;
use zenoh::qos::CongestionControl;

use crate::keys::parse_variant;
use crate::lossy::degrade;
use crate::wire::{Attachment, StampClock, ERROR_TYPE, OPEN_TYPE};
use crate::Ctx;

/// Most streams one agent publishes at once: a peer declaring wants without end cannot make
/// it start tasks without end.
pub const MAX_EXPORTS: usize = 10_000;

/// A reader's token appeared (`true`) or went (`false`).
pub(crate) type WantEvent = (String, bool);

/// Runs the exports `wants` ask for until the channel closes.
pub(crate) async fn run(ctx: Arc<Ctx>, mut wants: mpsc::Receiver<WantEvent>) {
    let mut exports: HashMap<(String, String), Export> = HashMap::new();
    let mut refused = 0_u64;
    while let Some((token, alive)) = wants.recv().await {
        let Some((_reader, variant, key)) = ctx.keys.parse_want(&ctx.agent, &token) else {
            continue;
        };
        let id = (variant.to_string(), key.to_string());
        if !alive {
            if let Some(export) = exports.get_mut(&id) {
                export.readers.remove(&token);
                if export.readers.is_empty() {
                    export.task.abort();
                    exports.remove(&id);
                }
            }
            continue;
        }
        if let Some(export) = exports.get_mut(&id) {
            if export.readers.insert(token) {
                export.newcomer.notify_one();
            }
            continue;
        }
        let Some(qos) = parse_variant(variant) else {
            refused += 1;
            tracing::warn!(%token, refused, "a reader wants a stream at a pace petrel does not know");
            continue;
        };
        if exports.len() >= MAX_EXPORTS {
            refused += 1;
            tracing::warn!(%token, refused, "too many streams wanted (at most {MAX_EXPORTS}): refused");
            continue;
        }
        let newcomer = Arc::new(Notify::new());
        let task = tokio::spawn(export(
            ctx.clone(),
            id.0.clone(),
            qos,
            id.1.clone(),
            newcomer.clone(),
        ));
        let readers = HashSet::from([token]);
        exports.insert(
            id,
            Export {
                readers,
                task,
                newcomer,
            },
        );
    }
    for export in exports.into_values() {
        export.task.abort();
    }
}

/// A stream being published.
struct Export {
    /// The `@want` tokens asking for it.
    readers: HashSet<String>,
    task: JoinHandle<()>,
    newcomer: Arc<Notify>,
}

/// `newcomer` is raised when another reader wants the stream: it gets the current value
/// (a queue's readers get what comes from then on).
async fn export(ctx: Arc<Ctx>, variant: String, qos: Qos, key: String, newcomer: Arc<Notify>) {
    let data_key = ctx.keys.data(&variant, &ctx.agent, &key);
    let congestion = match qos.reliability {
        Reliability::Reliable => CongestionControl::Block,
        Reliability::BestEffort => CongestionControl::Drop,
    };
    let publisher = match ctx
        .session
        .declare_publisher(data_key.clone())
        .congestion_control(congestion)
        .await
    {
        Ok(p) => p,
        Err(e) => {
            tracing::error!(key = %data_key, error = %e, "cannot publish a property");
            return;
        }
    };
    let mut out = Sender {
        ctx: &ctx,
        publisher,
        lossy: qos.lossy,
        type_info: None,
    };
    let tap = ctx.blackboard.tap(&key).await;
    out.type_info = tap.as_ref().ok().map(Tap::type_info);
    match tap {
        Ok(Tap::Value(tap)) => export_value(&mut out, tap, qos.mode, &newcomer).await,
        Ok(Tap::Queue(tap)) => export_queue(&mut out, tap, &newcomer).await,
        Err(e) => {
            tracing::warn!(property = %key, error = %e, "a reader wants a property this agent cannot publish");
            let why = format!("agent `{}` cannot publish `{key}`: {e}", ctx.agent);
            loop {
                out.control(ERROR_TYPE, &why).await;
                newcomer.notified().await;
            }
        }
    }
}

async fn export_value(out: &mut Sender<'_>, tap: ValueTap, mode: Mode, newcomer: &Notify) {
    let mut seq = 0_u64;
    let mut last_version = None;
    let mut ticks = match mode {
        Mode::Periodic { ms } => Some(tokio::time::interval(Duration::from_millis(ms))),
        Mode::OnChange { .. } => None,
    };
    let mut last_sent: Option<Instant> = None;
    let mut force = true;
    loop {
        let (value, version, written) = tap.read();
        if force || ticks.is_some() || last_version != Some(version) {
            force = false;
            last_version = Some(version);
            out.send(&value, seq, written).await;
            seq += 1;
            last_sent = Some(Instant::now());
        }
        let wait = async {
            match (&mut ticks, mode) {
                (Some(ticks), _) => {
                    ticks.tick().await;
                }
                (None, Mode::OnChange { min_interval_ms }) => {
                    tap.changed().await;
                    if let (Some(sent), 1..) = (last_sent, min_interval_ms) {
                        let next = sent + Duration::from_millis(min_interval_ms);
                        tokio::time::sleep_until(next).await;
                    }
                }
                (None, Mode::Periodic { .. }) => unreachable!("periodic streams tick"),
            }
        };
        tokio::select! {
            _ = wait => {}
            _ = newcomer.notified() => force = true,
        }
    }
}

/// Items taken from a queue tap per round: a long backlog is sent in slices, so a slow
/// network never holds one huge batch.
const QUEUE_SLICE: usize = 64;

async fn export_queue(out: &mut Sender<'_>, mut tap: QueueTap, newcomer: &Notify) {
    out.control(OPEN_TYPE, "").await;
    loop {
        tokio::select! {
            _ = tap.changed() => {}
            // A new reader's link is live before the next item.
            _ = newcomer.notified() => out.control(OPEN_TYPE, "").await,
        }
        loop {
            let items = tap.take(QUEUE_SLICE);
            if items.is_empty() {
                break;
            }
            for (seq, stamp, value) in &items {
                out.send(value, *seq, *stamp).await;
            }
        }
    }
}

struct Sender<'a> {
    ctx: &'a Ctx,
    publisher: Publisher<'static>,
    lossy: bool,
    type_info: Option<TypeInfo>,
}

impl Sender<'_> {
    async fn send(&mut self, value: &AnyValue, seq: u64, written: Instant) {
        let Some(type_info) = self.type_info else {
            return;
        };
        let value = if self.lossy {
            degrade(value)
        } else {
            value.clone()
        };
        let payload = match type_info.to_json(&value) {
            Ok(p) => p,
            Err(e) => {
                tracing::error!(key = %self.publisher.key_expr(), error = %e, "cannot encode a value");
                return;
            }
        };
        let attachment = Attachment {
            seq,
            stamp_ns: StampClock::now().to_unix_ns(written),
            type_name: type_info.name().to_string(),
            zid: self.ctx.zid.clone(),
        };
        let put = self
            .publisher
            .put(payload)
            .encoding(Encoding::APPLICATION_JSON.with_schema(type_info.name()))
            .attachment(attachment.encode());
        if let Err(e) = put.await {
            tracing::debug!(key = %self.publisher.key_expr(), error = %e, "send failed");
        }
    }

    /// Sends a control sample (`@open`, `@error`) with a text payload.
    async fn control(&self, type_name: &str, why: &str) {
        let attachment = Attachment {
            seq: 0,
            stamp_ns: StampClock::now().to_unix_ns(Instant::now()),
            type_name: type_name.into(),
            zid: self.ctx.zid.clone(),
        };
        let _ = self
            .publisher
            .put(why.to_string())
            .attachment(attachment.encode())
            .await;
    }
}
