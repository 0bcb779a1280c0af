//! Following a property from a tool (`petrel echo`, `petrel hz`): the tool wants the stream
//! like a linked agent would (subscriber first, then its `@want` token), so the owner sends
//! the current value, then every change or queue item, and stops when the tool goes.

use petrel_actors::url::PropertyUrl;
use tokio::sync::mpsc;

use crate::keys::CANONICAL;
use crate::wire::{Attachment, ERROR_TYPE, OPEN_TYPE};
use crate::{Client, TeamError};

/// Samples buffered for a tool that reads slower than they come; beyond it they are dropped
/// (and counted), never buffered without end.
const BUFFER: usize = 4096;

/// One value or queue item of a watched property.
#[derive(Debug, Clone)]
pub struct Update {
    /// The owner's sequence number (the value's version, or the queue item's number).
    pub seq: u64,
    /// The write stamp, ns since the Unix epoch.
    pub stamp_ns: u64,
    /// The petrel type name.
    pub type_name: String,
    /// The value as JSON.
    pub json: Vec<u8>,
}

/// What a watch delivers.
#[derive(Debug, Clone)]
pub enum WatchEvent {
    /// A queue's stream is open: every item pushed from now on will come.
    Opened,
    /// A value or item.
    Update(Update),
    /// The owner cannot publish the property (no such property, ...), saying why.
    Refused(String),
}

/// A followed property; dropping it stops the stream.
pub struct Watch {
    events: mpsc::Receiver<WatchEvent>,
    _subscriber: zenoh::pubsub::Subscriber<()>,
    _token: zenoh::liveliness::LivelinessToken,
    dropped: std::sync::Arc<std::sync::atomic::AtomicU64>,
}

impl Watch {
    /// The next value or item (`None` once the session is closed).
    pub async fn next(&mut self) -> Option<WatchEvent> {
        self.events.recv().await
    }

    /// Samples dropped because the tool read slower than they came.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(std::sync::atomic::Ordering::Relaxed)
    }
}

impl Client {
    /// Follows `url` (another agent's property, value or output queue).
    pub async fn watch(&self, url: &PropertyUrl) -> Result<Watch, TeamError> {
        let agent = url.agent().unwrap_or_default();
        let key = url.key();
        let (tx, events) = mpsc::channel(BUFFER);
        let dropped = std::sync::Arc::<std::sync::atomic::AtomicU64>::default();
        let counter = dropped.clone();
        let subscriber = self
            .session
            .declare_subscriber(self.keys.data(CANONICAL, agent, &key))
            .callback(move |sample| {
                let Some(a) = sample
                    .attachment()
                    .and_then(|a| Attachment::decode(&a.to_bytes()).ok())
                else {
                    return;
                };
                let payload = sample.payload().to_bytes().into_owned();
                let event = match a.type_name.as_str() {
                    OPEN_TYPE => WatchEvent::Opened,
                    ERROR_TYPE => WatchEvent::Refused(String::from_utf8_lossy(&payload).into()),
                    _ => WatchEvent::Update(Update {
                        seq: a.seq,
                        stamp_ns: a.stamp_ns,
                        type_name: a.type_name,
                        json: payload,
                    }),
                };
                if tx.try_send(event).is_err() {
                    counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                }
            })
            .await?;
        // The reader's name only has to be unique: the session id is.
        let reader = format!("_tool.{}", self.session.zid());
        let token = self
            .session
            .liveliness()
            .declare_token(self.keys.want(agent, &reader, CANONICAL, &key))
            .await?;
        Ok(Watch {
            events,
            _subscriber: subscriber,
            _token: token,
            dropped,
        })
    }
}
