//! petrel recording and replay: runs written to MCAP files that Foxglove, the `mcap` CLI and
//! rosbag2 open, and replayed in place of the modules that produced them.
//!
//! Split like the rest of petrel: pure encoders ([`encode`]), a pure selection model
//! ([`select`]), a synchronous writer core ([`sink`]) and reader ([`read`]), and thin shells
//! around them: the recorder on its own thread fed by taps ([`recorder`]), the replay module
//! ([`replay`]). The mapping is documented in `docs/recording.md`.
#![warn(missing_docs)]

mod backlog;
pub mod encode;
pub mod select;
pub mod sink;
mod taps;
pub mod target;

pub use encode::{Codec, Format, Kind, LogLevel, LogRecord, SchemaDef, Stamp};
pub use select::{RecordOptions, Selection, SplitPolicy};
pub use sink::{ChannelSpec, ChunkCompression, Entry, Sink, SinkReport};
pub mod read;
pub mod recorder;

pub use read::{ChannelInfo, ReadProblem, RecordedMessage, Recording};
pub use recorder::{LogSink, Recorder};
pub mod playback;
pub mod replay;

/// Adds the `record.replay` module type.
pub fn register(registry: &mut petrel_actors::ModuleRegistry) {
    registry.register::<playback::Playback>();
}
pub mod info;
