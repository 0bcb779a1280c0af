//! Watching the team's membership tokens: `_team/members`, `_team/events`, and the links of
//! agents that leave (stale) and come back (live again by themselves).

use std::sync::Arc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use petrel_actors::team::{TeamEvent, TeamMembers};
use petrel_actors::{PropertyHandle, QueueWriter};
use tokio::sync::mpsc;

use crate::membership::Change;
use crate::Ctx;

/// A membership token appeared (`true`) or went (`false`).
pub(crate) type AliveEvent = (String, bool);

/// How long an `@info` query waits for the agent's answer.
const INFO_TIMEOUT: Duration = Duration::from_secs(2);

pub(crate) struct Board {
    pub members: PropertyHandle<TeamMembers>,
    pub events: QueueWriter<TeamEvent>,
}

/// Applies token events until the channel closes.
pub(crate) async fn run(ctx: Arc<Ctx>, board: Arc<Board>, mut alive: mpsc::Receiver<AliveEvent>) {
    while let Some((token, up)) = alive.recv().await {
        let Some((agent, zid)) = ctx.keys.parse_alive(&token) else {
            continue;
        };
        let changes = {
            let mut m = ctx.membership.lock();
            match up {
                true => m.on_alive(agent, zid).into_iter().collect(),
                false => m.on_gone(agent, zid),
            }
        };
        for change in changes {
            apply(&ctx, &board, &change);
            if matches!(change, Change::Joined(_) | Change::Rejoined(_)) {
                tokio::spawn(ask_modules(
                    ctx.clone(),
                    board.clone(),
                    change.agent().to_string(),
                ));
            }
        }
    }
}

fn apply(ctx: &Ctx, board: &Board, change: &Change) {
    let agent = change.agent();
    match change {
        Change::Rejected { zid, .. } => {
            tracing::warn!(agent = %ctx.agent, member = %agent, %zid, "a second agent uses the name `{agent}`: its samples are refused");
        }
        _ => tracing::info!(agent = %ctx.agent, member = %agent, "team: {} {agent}", change.kind()),
    }
    let zid = ctx.membership.lock().zid_of(agent).map(str::to_string);
    for stream in ctx.streams.lock().values().filter(|s| s.owner == agent) {
        match (change, &zid) {
            (Change::Left(_), _) => stream.update(|t| t.owner_left(&ctx.config.name)),
            (Change::Joined(_) | Change::Rejoined(_), Some(zid)) => {
                stream.update(|t| t.owner_is(zid))
            }
            _ => {}
        }
    }
    let unix_ms = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64);
    // The event first: whoever sees the new member list finds the event already queued.
    board.events.push(TeamEvent {
        agent: agent.to_string(),
        kind: change.kind().to_string(),
        unix_ms,
    });
    board.members.set(ctx.membership.lock().members());
}

/// Follows this agent's modules as they are added and removed (`_supervisor/events`): sends
/// the outbox of each new module, and tells the team the new module list (a put on its `@info`
/// key, which members subscribe to), until the task is aborted (which aborts the senders too).
pub(crate) async fn follow_modules(ctx: Arc<Ctx>) {
    use petrel_actors::supervision::{SupervisorEvent, EVENTS_MODULE, EVENTS_PATH};
    use petrel_actors::team::Tap;
    // Watched before the first listing, so a module added in between is not missed.
    let events = ctx
        .blackboard
        .tap(&format!("{EVENTS_MODULE}/{EVENTS_PATH}"))
        .await;
    let mut events = match events {
        Ok(Tap::Queue(tap)) => Some(tap),
        _ => None,
    };
    let mut senders = tokio::task::JoinSet::new();
    let mut first = true;
    loop {
        for outbox in ctx.blackboard.outboxes().await.unwrap_or_default() {
            senders.spawn(crate::mail::send_outbox(ctx.clone(), outbox));
        }
        if !first {
            if let Ok(info) = crate::service::info_json(&ctx).await {
                let _ = ctx.session.put(ctx.keys.info(&ctx.agent), info).await;
            }
        }
        first = false;
        let Some(tap) = events.as_mut() else {
            return std::future::pending().await;
        };
        loop {
            tap.changed().await;
            let changed = tap.take(64).iter().any(|(_, _, e)| {
                e.downcast_ref::<SupervisorEvent>()
                    .is_some_and(|e| e.kind == "added" || e.kind == "removed")
            });
            if changed {
                break;
            }
        }
    }
}

/// Applies the module lists members announce (puts on their `@info` keys) until the channel
/// closes.
pub(crate) async fn follow_announcements(
    ctx: Arc<Ctx>,
    board: Arc<Board>,
    mut announced: mpsc::Receiver<(String, Vec<u8>)>,
) {
    while let Some((key, payload)) = announced.recv().await {
        let Some(agent) = key.rsplit('/').next() else {
            continue;
        };
        take_modules(&ctx, &board, agent, &payload);
    }
}

/// Lists a member's modules from its `@info` JSON, if it comes from the member's session.
fn take_modules(ctx: &Ctx, board: &Board, agent: &str, payload: &[u8]) {
    let Some(zid) = ctx.membership.lock().zid_of(agent).map(str::to_string) else {
        return;
    };
    let Ok(info) = serde_json::from_slice::<serde_json::Value>(payload) else {
        return;
    };
    if info["zid"].as_str() != Some(zid.as_str()) {
        return;
    }
    let modules = info["modules"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|m| m.as_str().map(str::to_string))
                .collect()
        })
        .unwrap_or_default();
    if ctx.membership.lock().set_modules(agent, &zid, modules) {
        board.members.set(ctx.membership.lock().members());
    }
}

/// Asks a member for its modules and lists them in `_team/members`.
async fn ask_modules(ctx: Arc<Ctx>, board: Arc<Board>, agent: String) {
    let Ok(replies) = ctx
        .session
        .get(ctx.keys.info(&agent))
        .timeout(INFO_TIMEOUT)
        .await
    else {
        return;
    };
    while let Ok(reply) = replies.recv_async().await {
        if let Ok(sample) = reply.result() {
            take_modules(&ctx, &board, &agent, &sample.payload().to_bytes());
        }
    }
}
