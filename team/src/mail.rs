//! Messages between modules (OpenRDK's mailbox). Each outbox is sent in order, one message at
//! a time, until the recipient acknowledges it: delivery is at least once, and the receiver
//! drops repeats by the sender's sequence numbers. A message for an agent that is not in the
//! team is dropped and counted in the sender's `stats/outbox`.

use std::collections::HashMap;
use std::sync::Arc;

use petrel_actors::team::{Message, Outbox, OutboxStatus};
use tokio::time::Instant;
use zenoh::query::Query;

use crate::client::REQUEST_TIMEOUT;
use crate::wire::{Attachment, StampClock};
use crate::Ctx;

/// Senders whose last sequence number an agent remembers; beyond it the memory is cleared
/// (a flood of senders cannot grow it; repeats may then get through once).
const MAX_SENDERS: usize = 10_000;

/// Pause before asking again a recipient that did not answer.
const RETRY: std::time::Duration = std::time::Duration::from_millis(10);

/// The last sequence number received from each (session, sending module).
pub(crate) type Seen = HashMap<(String, String), u64>;

enum Failure {
    Refused(String),
    Gone(String),
}

/// Sends every message a module pushes to its outbox, until the task is aborted.
pub(crate) async fn send_outbox(ctx: Arc<Ctx>, outbox: Outbox) {
    let Outbox {
        module,
        status,
        mut tap,
    } = outbox;
    let mut st = OutboxStatus::default();
    loop {
        tap.changed().await;
        loop {
            let items = tap.take(64);
            if items.is_empty() {
                break;
            }
            for (seq, _, value) in items {
                let Some(message) = value.downcast_ref::<Message>() else {
                    continue;
                };
                let mut message = message.clone();
                message.from = format!("{}/{module}", ctx.agent);
                match deliver(&ctx, &message, seq).await {
                    Ok(()) => st.delivered += 1,
                    Err(Failure::Refused(why)) => {
                        tracing::warn!(from = %message.from, to = %message.to, "message refused: {why}");
                        st.refused += 1;
                        st.detail = why;
                    }
                    Err(Failure::Gone(why)) => {
                        tracing::warn!(from = %message.from, to = %message.to, "message dropped: {why}");
                        st.dropped += 1;
                        st.detail = why;
                    }
                }
                status.set(st.clone());
            }
        }
    }
}

async fn deliver(ctx: &Ctx, message: &Message, seq: u64) -> Result<(), Failure> {
    let (agent, module) = match message.to.split_once('/') {
        Some((agent, module)) => (agent, module),
        None => (ctx.agent.as_str(), message.to.as_str()),
    };
    if agent == ctx.agent {
        let inbox = ctx.blackboard.inbox(module).await;
        let inbox = inbox.map_err(|e| Failure::Refused(e.to_string()))?;
        inbox.push(Arc::new(message.clone()), Instant::now());
        return Ok(());
    }
    let payload = serde_json::to_vec(message).expect("messages serialize");
    let attachment = Attachment {
        seq,
        stamp_ns: StampClock::now().to_unix_ns(Instant::now()),
        type_name: "Message".into(),
        zid: ctx.zid.clone(),
    }
    .encode();
    loop {
        if ctx.membership.lock().zid_of(agent).is_none() {
            return Err(Failure::Gone(format!("agent `{agent}` is not in the team")));
        }
        let replies = ctx
            .session
            .get(ctx.keys.inbox(agent, module))
            .payload(payload.clone())
            .attachment(attachment.clone())
            .timeout(REQUEST_TIMEOUT)
            .await
            .map_err(|e| Failure::Gone(e.to_string()))?;
        match replies.recv_async().await {
            Ok(reply) => {
                return match reply.result() {
                    Ok(_) => Ok(()),
                    Err(e) => Err(Failure::Refused(
                        String::from_utf8_lossy(&e.payload().to_bytes()).into_owned(),
                    )),
                }
            }
            // No answer (its inbox not yet known here, or unreachable until its lease
            // ends): try again, a little later, while it is a member.
            Err(_) => tokio::time::sleep(RETRY).await,
        }
    }
}

/// Puts a received message into the addressed module's inbox, once.
pub(crate) async fn receive(ctx: Arc<Ctx>, query: Query) {
    let Some(module) = ctx.keys.parse_inbox(&ctx.agent, query.key_expr().as_str()) else {
        return;
    };
    let module = module.to_string();
    let result = accept(&ctx, &module, &query).await;
    let _ = match result {
        Ok(()) => query.reply(query.key_expr().clone(), "ok").await,
        Err(why) => query.reply_err(why).await,
    };
}

async fn accept(ctx: &Ctx, module: &str, query: &Query) -> Result<(), String> {
    let attachment = query
        .attachment()
        .ok_or("no attachment")
        .and_then(|a| Attachment::decode(&a.to_bytes()).map_err(|_| "bad attachment"))?;
    let payload = query
        .payload()
        .map(|p| p.to_bytes().into_owned())
        .unwrap_or_default();
    let message: Message =
        serde_json::from_slice(&payload).map_err(|e| format!("not a message: {e}"))?;
    let inbox = ctx
        .blackboard
        .inbox(module)
        .await
        .map_err(|e| e.to_string())?;
    let sender = (attachment.zid, message.from.clone());
    {
        let mut seen = ctx.seen.lock();
        if seen
            .get(&sender)
            .is_some_and(|last| attachment.seq <= *last)
        {
            return Ok(()); // a repeat after a lost acknowledgement
        }
        if seen.len() >= MAX_SENDERS {
            seen.clear();
        }
        seen.insert(sender, attachment.seq);
    }
    inbox.push(Arc::new(message), Instant::now());
    Ok(())
}
