//! The Foxglove live view: the agents' properties served over the Foxglove WebSocket protocol
//! ([`core::foxglove`](crate::core::foxglove)), so Foxglove shows the laser, the map and the
//! image while the robot runs.
//!
//! Channels and messages are those of a recording: the console does not encode anything
//! itself. The root package hands in [`LiveEncoders`] built on petrel-record's encoders (topic
//! names, schemas, messages), so a live channel and a recorded one are the same.

use std::sync::Arc;

use petrel_actors::{AnyValue, TypeInfo};
use tokio::sync::broadcast;

/// Log lines a live view has not sent yet before it drops the oldest (a client that reads
/// slower than the log is written).
const LOG_BACKLOG: usize = 1024;

/// A channel's topic and schema, as a recording names them.
#[derive(Debug, Clone, PartialEq)]
pub struct LiveChannel {
    /// The topic, `/agent/module/path`.
    pub topic: String,
    /// Message encoding (`protobuf`, `json`, `cdr`).
    pub encoding: String,
    /// Schema name (`foxglove.LaserScan`, ...).
    pub schema_name: String,
    /// Schema as text (a binary protobuf one base64-encoded, as the protocol carries it).
    pub schema: String,
    /// Schema encoding (`protobuf`, `jsonschema`, `ros2msg`).
    pub schema_encoding: String,
}

/// Encodes the messages of one channel.
pub trait ChannelEncoder: Send + Sync + 'static {
    /// Appends the message of `value`, stamped `stamp_ns` (ns since the Unix epoch), to `out`.
    fn encode(&self, value: &AnyValue, stamp_ns: u64, out: &mut Vec<u8>) -> Result<(), String>;
}

/// Decides the channel of each property.
pub trait LiveEncoders: Send + Sync + 'static {
    /// The channel of `agent`'s property `key` of type `type_info`, whose current value (or
    /// latest queue item) is `first`, and its encoder; `None` leaves it out.
    fn channel(
        &self,
        agent: &str,
        key: &str,
        type_info: &TypeInfo,
        first: Option<&AnyValue>,
    ) -> Option<(LiveChannel, Arc<dyn ChannelEncoder>)>;

    /// The channel of the log lines [`LiveLog`] carries, and their encoder; `None` (the
    /// default) serves no log.
    fn log(&self) -> Option<(LiveChannel, Arc<dyn ChannelEncoder>)> {
        None
    }
}

/// The log as it is written, for the live view's log channel: whoever owns the logging setup
/// pushes each line (a value the [`LiveEncoders::log`] encoder reads) with its time. Pushing
/// never waits; with no client subscribed it costs nothing more.
#[derive(Clone)]
pub struct LiveLog {
    lines: broadcast::Sender<(u64, AnyValue)>,
}

impl Default for LiveLog {
    fn default() -> Self {
        LiveLog {
            lines: broadcast::channel(LOG_BACKLOG).0,
        }
    }
}

impl LiveLog {
    /// Hands `line`, logged at `stamp_ns` (ns since the Unix epoch), to the subscribed clients.
    pub fn push(&self, stamp_ns: u64, line: AnyValue) {
        let _ = self.lines.send((stamp_ns, line));
    }

    /// The lines pushed from now on.
    pub(crate) fn subscribe(&self) -> broadcast::Receiver<(u64, AnyValue)> {
        self.lines.subscribe()
    }
}
