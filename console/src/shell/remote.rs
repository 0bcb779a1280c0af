//! Remote properties followed over a team: a task per followed property keeps its latest
//! sample, which readers (the API, the WebSocket's sampling) read without a round trip, as
//! they read a local property's cell.

use std::sync::Arc;
use std::time::Duration;

use serde_json::Value;
use tokio::sync::watch;
use tokio::task::JoinHandle;

use super::state::ValueView;
use crate::core::throttle::is_bulky;
use crate::core::view;
use crate::source::{RemoteAgent, RemoteEvent, RemoteSample};

/// How long a first read waits for the owner's current value.
pub(crate) const FIRST_VALUE_WAIT: Duration = Duration::from_secs(3);

#[derive(Debug, Clone)]
enum Latest {
    /// Nothing heard yet.
    Waiting,
    /// A queue with no item since it was followed.
    Open,
    Sample(Arc<RemoteSample>),
    Refused(String),
    /// The stream ended (the agent left, the session closed) before any value.
    Ended,
}

/// One followed remote property.
pub(crate) struct RemoteCell {
    latest: watch::Receiver<Latest>,
    task: JoinHandle<()>,
}

impl Drop for RemoteCell {
    fn drop(&mut self) {
        // The task owns the stream: ending it drops the owner's reader token.
        self.task.abort();
    }
}

impl RemoteCell {
    /// Starts following `key` of `agent`.
    pub async fn follow(agent: &Arc<dyn RemoteAgent>, key: &str) -> Result<RemoteCell, String> {
        let mut stream = agent.watch(key).await?;
        let (tx, latest) = watch::channel(Latest::Waiting);
        let task = tokio::spawn(async move {
            while let Some(event) = stream.next().await {
                let next = match event {
                    RemoteEvent::Opened => match *tx.borrow() {
                        // A later open (another reader came) changes nothing.
                        Latest::Sample(_) => continue,
                        _ => Latest::Open,
                    },
                    RemoteEvent::Sample(s) => Latest::Sample(Arc::new(s)),
                    RemoteEvent::Refused(why) => Latest::Refused(why),
                };
                tx.send_replace(next);
            }
            tx.send_if_modified(|l| match l {
                Latest::Waiting | Latest::Open => {
                    *l = Latest::Ended;
                    true
                }
                _ => false,
            });
        });
        Ok(RemoteCell { latest, task })
    }

    /// The latest sample, if one came.
    pub fn sample(&self) -> Option<Arc<RemoteSample>> {
        match &*self.latest.borrow() {
            Latest::Sample(s) => Some(s.clone()),
            _ => None,
        }
    }

    /// The latest sample, waiting (at most [`FIRST_VALUE_WAIT`]) for the first one.
    pub async fn first(&self) -> Result<Arc<RemoteSample>, String> {
        let mut latest = self.latest.clone();
        let heard = tokio::time::timeout(
            FIRST_VALUE_WAIT,
            latest.wait_for(|l| !matches!(l, Latest::Waiting)),
        )
        .await;
        let state = match heard {
            Ok(Ok(state)) => state.clone(),
            Ok(Err(_)) => Latest::Ended,
            Err(_) => return Err("the agent sent no value in time".into()),
        };
        match state {
            Latest::Sample(s) => Ok(s),
            Latest::Open => Err("no item in this queue yet".into()),
            Latest::Refused(why) => Err(why),
            Latest::Ended | Latest::Waiting => Err("the agent stopped answering".into()),
        }
    }

    /// Whether the owner refused to publish it (so it is not worth keeping).
    pub fn refused(&self) -> bool {
        matches!(&*self.latest.borrow(), Latest::Refused(_) | Latest::Ended)
    }
}

/// A remote sample as the API shows it; `full` includes bulky values' JSON.
pub(crate) fn remote_view(key: &str, sample: &RemoteSample, full: bool) -> ValueView {
    let json: Option<Value> = serde_json::from_slice(&sample.json).ok();
    ValueView {
        key: key.to_string(),
        type_name: sample.type_name.clone(),
        version: sample.seq,
        text: view::json_text(&sample.type_name, json.as_ref()),
        json: json.filter(|_| full || !is_bulky(&sample.type_name)),
    }
}
