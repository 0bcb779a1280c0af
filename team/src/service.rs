//! What this agent answers: its modules (`@info`), current values by query (`session.get` on
//! a property's key), and remote writes (`@set`) where its `remote_write` patterns allow.

use std::sync::Arc;

use petrel_actors::team::pattern_matches;
use petrel_actors::PropertyKind;
use zenoh::query::Query;

use crate::wire::{Attachment, StampClock};
use crate::Ctx;

/// Answers an `@info` query: `{"agent", "zid", "team", "modules": [names], "types": {module:
/// type}, "properties": [{"key", "kind", "type", "link"?}]}`, as the agent is now (modules
/// added at run time included).
pub(crate) async fn info(ctx: Arc<Ctx>, query: Query) {
    match info_json(&ctx).await {
        Ok(payload) => {
            let _ = query
                .reply(query.key_expr().clone(), payload)
                .encoding(zenoh::bytes::Encoding::APPLICATION_JSON)
                .await;
        }
        Err(e) => {
            let _ = query.reply_err(e).await;
        }
    }
}

/// The `@info` JSON of this agent as it is now.
pub(crate) async fn info_json(ctx: &Ctx) -> Result<Vec<u8>, String> {
    let listing = ctx.blackboard.listing().await.map_err(|e| e.to_string())?;
    let names: Vec<&str> = listing.modules.iter().map(|m| m.name.as_str()).collect();
    let types: serde_json::Map<String, serde_json::Value> = listing
        .modules
        .iter()
        .map(|m| (m.name.clone(), m.type_name.clone().into()))
        .collect();
    let info = serde_json::json!({
        "agent": ctx.agent,
        "zid": ctx.zid,
        "team": ctx.config.name,
        "pid": std::process::id(),
        "host": host_name(),
        "modules": names,
        "types": types,
        "properties": listing.properties,
    });
    Ok(serde_json::to_vec(&info).expect("JSON of strings"))
}

/// This machine's host name, for telling apart two runs of one agent; `None` if the OS does
/// not say.
fn host_name() -> Option<String> {
    let mut buf = [0u8; 256];
    // SAFETY: the buffer is valid for its length; gethostname writes at most that many bytes.
    let rc = unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) };
    let end = buf.iter().position(|&b| b == 0)?;
    (rc == 0 && end > 0).then(|| String::from_utf8_lossy(&buf[..end]).into_owned())
}

/// Answers a query for the current value of one of this agent's properties, or, for a
/// key with `*` (one segment) or `**` (any), of every value property it matches, each
/// reply under the property's own key. Queues have no current value and are left out.
pub(crate) async fn get(ctx: Arc<Ctx>, query: Query) {
    let Some(key) = ctx.keys.parse_value(&ctx.agent, query.key_expr().as_str()) else {
        return;
    };
    let key = key.to_string();
    if !key.contains('*') {
        match ctx.blackboard.any_handle(&key).await {
            Ok(handle) => reply_value(&ctx, &query, query.key_expr().as_str(), &key, &handle).await,
            Err(e) => {
                let _ = query.reply_err(e.to_string()).await;
            }
        }
        return;
    }
    let listing = match ctx.blackboard.listing().await {
        Ok(l) => l,
        Err(e) => {
            let _ = query.reply_err(e.to_string()).await;
            return;
        }
    };
    for property in listing
        .properties
        .iter()
        .filter(|p| pattern_matches(&key, &p.key))
    {
        // Queues and properties removed since the listing have no value to give.
        if let Ok(handle) = ctx.blackboard.any_handle(&property.key).await {
            let reply_key = ctx
                .keys
                .data(crate::keys::CANONICAL, &ctx.agent, &property.key);
            reply_value(&ctx, &query, &reply_key, &property.key, &handle).await;
        }
    }
}

async fn reply_value(
    ctx: &Ctx,
    query: &Query,
    reply_key: &str,
    key: &str,
    handle: &petrel_actors::AnyHandle,
) {
    let sample = handle.read();
    let type_info = handle.type_info();
    match type_info.to_json(&sample.value) {
        Ok(payload) => {
            let attachment = Attachment {
                seq: sample.version,
                stamp_ns: StampClock::now().to_unix_ns(sample.written),
                type_name: type_info.name().to_string(),
                zid: ctx.zid.clone(),
            };
            // Said like a stream sample's (`export.rs`), for clients that read the encoding.
            let encoding = zenoh::bytes::Encoding::APPLICATION_JSON.with_schema(type_info.name());
            let _ = query
                .reply(reply_key.to_string(), payload)
                .encoding(encoding)
                .attachment(attachment.encode())
                .await;
        }
        Err(e) => {
            let _ = query.reply_err(format!("cannot encode `{key}`: {e}")).await;
        }
    }
}

/// Why a remote write was refused, in words the writer can act on.
pub(crate) async fn set(ctx: Arc<Ctx>, query: Query) {
    let Some(key) = ctx.keys.parse_set(&ctx.agent, query.key_expr().as_str()) else {
        return;
    };
    let key = key.to_string();
    let payload = query
        .payload()
        .map(|p| p.to_bytes().into_owned())
        .unwrap_or_default();
    let ron = query.encoding() == Some(&crate::client::ron_encoding());
    match apply_set(&ctx, &key, &payload, ron).await {
        Ok(()) => {
            tracing::info!(property = %key, "remote write");
            let _ = query.reply(query.key_expr().clone(), "ok").await;
        }
        Err(why) => {
            tracing::warn!(property = %key, "remote write refused: {why}");
            let _ = query.reply_err(why).await;
        }
    }
}

async fn apply_set(ctx: &Ctx, key: &str, payload: &[u8], ron: bool) -> Result<(), String> {
    let (kind, type_info) = ctx
        .blackboard
        .kind_of(key)
        .await
        .map_err(|e| e.to_string())?;
    if !matches!(kind, PropertyKind::Param | PropertyKind::Control) {
        return Err(format!(
            "`{key}` ({kind}) cannot be set from another agent: only params/ and control/ properties can"
        ));
    }
    if !ctx
        .config
        .remote_write
        .iter()
        .any(|p| pattern_matches(p, key))
    {
        let allowed = match ctx.config.remote_write.is_empty() {
            true => "none (add patterns to `remote_write` in its team section)".to_string(),
            false => ctx.config.remote_write.join(", "),
        };
        return Err(format!(
            "agent `{}` does not allow remote writes to `{key}`; allowed: {allowed}",
            ctx.agent
        ));
    }
    if ron {
        let text = std::str::from_utf8(payload).map_err(|_| "the RON text is not UTF-8")?;
        return ctx
            .blackboard
            .set_text(key, text)
            .await
            .map_err(|e| e.to_string());
    }
    let value = type_info
        .from_json(payload)
        .map_err(|e| format!("`{key}` takes a {} as JSON: {e}", type_info.name()))?;
    let handle = ctx
        .blackboard
        .any_handle(key)
        .await
        .map_err(|e| e.to_string())?;
    handle.set(value).map_err(|e| e.to_string())
}
