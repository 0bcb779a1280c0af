//! Background readers: the console keeps what happened while nobody looked (supervisor
//! events, context switches, plan firings), each read through a tap as it happens.

use std::sync::Arc;
use tokio::time::Instant;

use parking_lot::Mutex;
use petrel_actors::team::{QueueTap, Tap, ValueTap};
use petrel_actors::{Blackboard, TypeInfo};
use serde_json::{json, Value};
use tokio::task::JoinHandle;

use super::state::{History, HISTORY};
use crate::core::plan::{fired_between, parse_marking, Firing, PlanGraph};
use crate::core::view::Recent;
use crate::source::Backend;
use crate::AgentSource;

/// Starts the readers of one agent.
pub(crate) async fn start(
    source: &AgentSource,
    history: &Arc<Mutex<History>>,
    started: Instant,
) -> Vec<JoinHandle<()>> {
    let bb = match &source.backend {
        Backend::Local(bb) => bb,
        Backend::Remote(remote) => {
            return super::collect_remote::start(remote, &source.plans, history, started).await
        }
    };
    let mut tasks = Vec::new();
    if let Some((tap, type_info)) = queue_tap(bb, "_supervisor/events").await {
        let history = history.clone();
        tasks.push(tokio::spawn(read_queue(tap, type_info, move |item| {
            history.lock().events.push(item)
        })));
    }
    let managers = match bb.listing().await {
        Ok(listing) => listing
            .modules
            .into_iter()
            .filter(|m| m.type_name == "context.manager")
            .map(|m| m.name)
            .collect(),
        Err(_) => Vec::new(),
    };
    for module in managers {
        if let Some((tap, type_info)) = queue_tap(bb, &format!("{module}/out/changes")).await {
            let history = history.clone();
            tasks.push(tokio::spawn(read_queue(tap, type_info, move |item| {
                history
                    .lock()
                    .switches
                    .push(json!({"module": module, "change": item}))
            })));
        }
    }
    for plan in &source.plans {
        // A mission that says what it fired (`out/firings`) is read as it is; older ones are
        // followed through their marking.
        if let Some((tap, type_info)) = queue_tap(bb, &format!("{}/out/firings", plan.module)).await
        {
            history
                .lock()
                .firings
                .insert(plan.module.clone(), Recent::new(HISTORY));
            let fired = bb
                .expr_handle(&format!("{}/out/fired", plan.module))
                .await
                .ok();
            let (module, history) = (plan.module.clone(), history.clone());
            tasks.push(tokio::spawn(read_queue(tap, type_info, move |item| {
                let fired = fired
                    .as_ref()
                    .and_then(|h| h.get::<i64>())
                    .map_or(0, |n| *n);
                let firing = firing_of(&item, started, fired);
                if let Some(recent) = history.lock().firings.get_mut(&module) {
                    recent.push(firing);
                }
            })));
            continue;
        }
        if let Ok(Tap::Value(tap)) = bb.tap(&format!("{}/out/marking", plan.module)).await {
            history
                .lock()
                .firings
                .insert(plan.module.clone(), Recent::new(HISTORY));
            tasks.push(tokio::spawn(follow_marking(
                tap,
                bb.clone(),
                plan.clone(),
                history.clone(),
                started,
            )));
        }
    }
    tasks
}

/// A firing as a mission pushed it to `out/firings` (JSON: transitions, marking), with the
/// count `out/fired` shows.
pub(crate) fn firing_of(item: &Value, started: Instant, fired: i64) -> Firing {
    let transitions = item["transitions"].as_array().map_or(Vec::new(), |a| {
        a.iter()
            .filter_map(|t| t.as_str().map(str::to_string))
            .collect()
    });
    Firing {
        time_s: started.elapsed().as_secs_f64(),
        fired,
        marking: item["marking"].as_str().unwrap_or_default().to_string(),
        transitions,
    }
}

/// A tap on the output queue `key`, with its item type.
async fn queue_tap(bb: &Blackboard, key: &str) -> Option<(QueueTap, TypeInfo)> {
    let tap = bb.tap(key).await.ok()?;
    let type_info = tap.type_info();
    match tap {
        Tap::Queue(q) => Some((q, type_info)),
        Tap::Value(_) => None,
    }
}

/// Hands every item of a queue, as JSON, to `keep`.
async fn read_queue(mut tap: QueueTap, type_info: TypeInfo, mut keep: impl FnMut(Value) + Send) {
    loop {
        tap.changed().await;
        for (_, _, item) in tap.take(256) {
            let json = type_info
                .to_json(&item)
                .ok()
                .and_then(|b| serde_json::from_slice(&b).ok())
                .unwrap_or_else(|| Value::String(type_info.short(&item)));
            keep(json);
        }
    }
}

/// Records each change of a mission's marking as a firing, naming the transitions that
/// explain it.
async fn follow_marking(
    tap: ValueTap,
    bb: Blackboard,
    plan: PlanGraph,
    history: Arc<Mutex<History>>,
    started: Instant,
) {
    let fired_key = format!("{}/out/fired", plan.module);
    let fired = bb.expr_handle(&fired_key).await.ok();
    let text = |tap: &ValueTap| {
        let (value, _, _) = tap.read();
        value.downcast_ref::<String>().cloned().unwrap_or_default()
    };
    let mut before = parse_marking(&text(&tap));
    loop {
        tap.changed().await;
        let marking = text(&tap);
        let after = parse_marking(&marking);
        if after == before {
            continue;
        }
        let firing = Firing {
            time_s: started.elapsed().as_secs_f64(),
            fired: fired
                .as_ref()
                .and_then(|h| h.get::<i64>())
                .map_or(0, |n| *n),
            transitions: fired_between(&plan, &before, &after),
            marking,
        };
        if let Some(recent) = history.lock().firings.get_mut(&plan.module) {
            recent.push(firing);
        }
        before = after;
    }
}
