//! The writer core: recorded values → MCAP files through the `mcap` crate. Chunked, zstd or
//! LZ4 compressed ([`ChunkCompression`]), indexed; files split by the [`SplitPolicy`]; drops
//! counted per channel and written in the summary. Synchronous: the recorder runs it on its
//! own thread.

mod file;

use std::collections::{BTreeMap, HashMap};
use std::io::{self, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use mcap::records::{MessageHeader, Metadata};
use mcap::Writer;
use petrel_actors::{AnyValue, TypeInfo};

pub use file::{ChunkCompression, CHUNK_BYTES, ZSTD_LEVEL};

use crate::encode::{Codec, Format, Kind, Stamp};
use crate::select::{split_path, SplitPolicy};
use file::Counted;

/// Name of the metadata record holding the drop counts (per topic) of a file.
pub const DROPPED_METADATA: &str = "petrel.dropped";
/// Name of the metadata record saying who wrote the file.
pub const RECORDING_METADATA: &str = "petrel.recording";

/// Channel metadata keys petrel writes (and replay reads).
pub mod meta {
    /// `petrel://agent/module/path` of the recorded property.
    pub const URL: &str = "petrel.url";
    /// petrel's type name of its values.
    pub const TYPE: &str = "petrel.type";
    /// `value` or `queue`.
    pub const KIND: &str = "petrel.kind";
    /// `true` when JSON values sit in a `value` field.
    pub const WRAPPED: &str = "petrel.wrapped";
}

/// One channel a recording writes to.
#[derive(Clone, Debug)]
pub struct ChannelSpec {
    /// The MCAP topic.
    pub topic: String,
    /// `petrel://agent/module/path` (empty for the log).
    pub url: String,
    /// Type of the values.
    pub type_info: TypeInfo,
    /// Whether it is a queue (every item) or a value (its changes).
    pub queue: bool,
}

/// One value to write.
pub struct Entry {
    /// Which channel ([`Sink::channel`]'s answer).
    pub channel: usize,
    /// The value.
    pub value: AnyValue,
    /// Queue sequence number or value version.
    pub sequence: u64,
    /// When it was written (its stamp), ns since the Unix epoch.
    pub publish_ns: u64,
    /// When the recorder took it, ns since the Unix epoch.
    pub log_ns: u64,
}

struct Channel {
    spec: ChannelSpec,
    codec: Option<Codec>,
    /// Its id in the current file, once added there.
    id: Option<u16>,
    written: u64,
    dropped: u64,
    /// Values that could not be encoded (counted, logged once).
    failed: u64,
}

/// What a finished recording wrote.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SinkReport {
    /// The files, in order.
    pub files: Vec<PathBuf>,
    /// Messages written.
    pub written: u64,
    /// Messages dropped because the recorder could not keep up.
    pub dropped: u64,
    /// Values that could not be encoded.
    pub failed: u64,
    /// Channels in the recording: those that got a message (a channel appears in a file
    /// with its first message, so one that got none is not there for a reader to count).
    pub channels: usize,
}

/// Writes a recording.
pub struct Sink {
    base: PathBuf,
    format: Format,
    compression: ChunkCompression,
    split: SplitPolicy,
    writer: Option<Writer<Counted>>,
    /// Bytes written to the current file.
    file_len: Arc<AtomicU64>,
    files: Vec<PathBuf>,
    file_first_ns: Option<u64>,
    channels: Vec<Channel>,
    by_topic: HashMap<String, usize>,
    buffer: Vec<u8>,
}

impl Sink {
    /// Creates the first file (and its directory), zstd-compressed.
    pub fn create(
        path: impl Into<PathBuf>,
        format: Format,
        split: SplitPolicy,
    ) -> io::Result<Self> {
        Self::create_compressed(path, format, ChunkCompression::default(), split)
    }

    /// Creates the first file (and its directory), its chunks compressed with `compression`.
    pub fn create_compressed(
        path: impl Into<PathBuf>,
        format: Format,
        compression: ChunkCompression,
        split: SplitPolicy,
    ) -> io::Result<Self> {
        let mut sink = Sink {
            base: path.into(),
            format,
            compression,
            split,
            writer: None,
            file_len: Arc::default(),
            files: Vec::new(),
            file_first_ns: None,
            channels: Vec::new(),
            by_topic: HashMap::new(),
            buffer: Vec::new(),
        };
        sink.open_next()?;
        Ok(sink)
    }

    fn open_next(&mut self) -> io::Result<()> {
        let path = split_path(&self.base, self.files.len());
        self.file_len = Arc::default();
        let part = self.files.len();
        let writer = file::open_writer(
            &path,
            self.format,
            self.compression,
            part,
            self.file_len.clone(),
        )?;
        self.writer = Some(writer);
        self.files.push(path);
        self.file_first_ns = None;
        // Each file reads alone: its channels are added again.
        for c in &mut self.channels {
            c.id = None;
        }
        Ok(())
    }

    /// The channel of `spec.topic`, added if new (it appears in the file with its first message).
    pub fn channel(&mut self, spec: ChannelSpec) -> usize {
        if let Some(&i) = self.by_topic.get(&spec.topic) {
            return i;
        }
        let i = self.channels.len();
        self.by_topic.insert(spec.topic.clone(), i);
        self.channels.push(Channel {
            spec,
            codec: None,
            id: None,
            written: 0,
            dropped: 0,
            failed: 0,
        });
        i
    }

    /// Counts `n` values of `channel` the recorder could not take.
    pub fn dropped(&mut self, channel: usize, n: u64) {
        if let Some(c) = self.channels.get_mut(channel) {
            c.dropped += n;
        }
    }

    /// Writes one value, splitting first if the file is full.
    pub fn write(&mut self, entry: &Entry) -> io::Result<()> {
        let bytes = self.file_len.load(Ordering::Relaxed);
        if self.split.full(bytes, self.file_first_ns, entry.log_ns) {
            self.finish_file()?;
            self.open_next()?;
        }
        let format = self.format;
        let Some(c) = self.channels.get_mut(entry.channel) else {
            return Ok(());
        };
        let codec = *c.codec.get_or_insert_with(|| match c.spec.url.is_empty() {
            true => Codec::log(format),
            false => Codec::for_value(format, &c.spec.type_info, &entry.value),
        });
        self.buffer.clear();
        let stamp = Stamp::from_ns(entry.publish_ns);
        if let Err(e) = codec.encode(&c.spec.type_info, &entry.value, stamp, &mut self.buffer) {
            if c.failed == 0 {
                tracing::warn!(topic = %c.spec.topic, error = %e, "cannot record a value");
            }
            c.failed += 1;
            return Ok(());
        }
        let writer = self.writer.as_mut().expect("a sink always has a file open");
        let id = match c.id {
            Some(id) => id,
            None => *c.id.insert(add_channel(writer, &c.spec, codec)?),
        };
        writer
            .write_to_known_channel(
                &MessageHeader {
                    channel_id: id,
                    sequence: entry.sequence as u32,
                    log_time: entry.log_ns,
                    publish_time: entry.publish_ns,
                },
                &self.buffer,
            )
            .map_err(io::Error::other)?;
        c.written += 1;
        self.file_first_ns.get_or_insert(entry.log_ns);
        Ok(())
    }

    /// Closes the current chunk and hands it to the OS: a process killed after this leaves
    /// a file readable up to here.
    pub fn flush(&mut self) -> io::Result<()> {
        match self.writer.as_mut() {
            Some(w) => w.flush().map_err(io::Error::other),
            None => Ok(()),
        }
    }

    fn finish_file(&mut self) -> io::Result<()> {
        let Some(mut writer) = self.writer.take() else {
            return Ok(());
        };
        let dropped: BTreeMap<String, String> = self
            .channels
            .iter()
            .filter(|c| c.dropped > 0)
            .map(|c| (c.spec.topic.clone(), c.dropped.to_string()))
            .collect();
        writer
            .write_metadata(&Metadata {
                name: DROPPED_METADATA.into(),
                metadata: dropped,
            })
            .map_err(io::Error::other)?;
        writer.finish().map_err(io::Error::other)?;
        writer.into_inner().flush()
    }

    /// Finishes the last file (summary, indexes, drop counts) and says what was written.
    pub fn finish(mut self) -> io::Result<SinkReport> {
        self.finish_file()?;
        Ok(SinkReport {
            files: std::mem::take(&mut self.files),
            written: self.channels.iter().map(|c| c.written).sum(),
            dropped: self.channels.iter().map(|c| c.dropped).sum(),
            failed: self.channels.iter().map(|c| c.failed).sum(),
            channels: self.channels.iter().filter(|c| c.written > 0).count(),
        })
    }
}

/// Adds the channel of `spec` and its schema to the current file.
fn add_channel(writer: &mut Writer<Counted>, spec: &ChannelSpec, codec: Codec) -> io::Result<u16> {
    let schema = codec.schema(spec.type_info.name());
    let schema_id = writer
        .add_schema(&schema.name, schema.encoding, &schema.data)
        .map_err(io::Error::other)?;
    let mut metadata = BTreeMap::new();
    if !spec.url.is_empty() {
        metadata.insert(meta::URL.into(), spec.url.clone());
        metadata.insert(meta::TYPE.into(), spec.type_info.name().into());
        let kind = if spec.queue { "queue" } else { "value" };
        metadata.insert(meta::KIND.into(), kind.into());
    }
    if let Kind::Json { wrapped: true } = codec.kind {
        metadata.insert(meta::WRAPPED.into(), "true".into());
    }
    writer
        .add_channel(schema_id, &spec.topic, schema.message_encoding, &metadata)
        .map_err(io::Error::other)
}
