//! Reading recordings, whole or damaged: a walk over the file's records that knows the offset
//! of each, so a truncated or corrupted file gives an error naming the offset and what was
//! expected, and everything before it can still be replayed (`--salvage`). Never panics.

use std::collections::BTreeMap;
use std::path::Path;

use std::io::{self, Read};

use mcap::records::{op, ChunkHeader, Record};

use crate::sink::meta;

/// The 8 bytes every MCAP file starts (and, when finished, ends) with.
pub const MAGIC: &[u8] = mcap::MAGIC;

const NOT_MCAP: &str = "the MCAP magic bytes (89 4D 43 41 50 30 0D 0A): this is not an MCAP file";

/// A chunk claiming to decompress to more than this is refused rather than allocated.
pub const MAX_CHUNK_BYTES: u64 = 1 << 30;

/// A recorded channel.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelInfo {
    /// The topic.
    pub topic: String,
    /// Schema name (empty without a schema).
    pub schema: String,
    /// Schema encoding (`jsonschema`, `ros2msg`).
    pub schema_encoding: String,
    /// Message encoding (`json`, `cdr`).
    pub message_encoding: String,
    /// The channel's metadata (`petrel.url`, `petrel.type`, ...).
    pub metadata: BTreeMap<String, String>,
}

impl ChannelInfo {
    /// The recorded property, `petrel://agent/module/path`, if petrel wrote the channel.
    pub fn url(&self) -> Option<&str> {
        self.metadata.get(meta::URL).map(String::as_str)
    }

    /// petrel's type name of the channel's values, if petrel wrote the channel.
    pub fn petrel_type(&self) -> Option<&str> {
        self.metadata.get(meta::TYPE).map(String::as_str)
    }
}

/// One recorded message.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordedMessage {
    /// Its channel id.
    pub channel: u16,
    /// Its sequence number.
    pub sequence: u32,
    /// When the recorder took it, ns.
    pub log_ns: u64,
    /// When it was written, ns.
    pub publish_ns: u64,
    /// The encoded message.
    pub data: Vec<u8>,
}

/// Where and why reading stopped early.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadProblem {
    /// Byte offset in the file.
    pub offset: u64,
    /// What was expected there.
    pub expected: String,
}

impl std::fmt::Display for ReadProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "at byte {}: expected {}", self.offset, self.expected)
    }
}

/// What could be read of a recording.
#[derive(Clone, Debug, Default)]
pub struct Recording {
    /// Channels by id.
    pub channels: BTreeMap<u16, ChannelInfo>,
    /// Messages in file order.
    pub messages: Vec<RecordedMessage>,
    /// Metadata records, by name, in file order.
    pub metadata: Vec<(String, BTreeMap<String, String>)>,
    /// Whether the file ended with its footer and magic (it was finished, not killed).
    pub finished: bool,
    /// Chunks read whole.
    pub chunks: usize,
    /// Where reading stopped before the end, if it did.
    pub problem: Option<ReadProblem>,
    /// Where the chunk being written when the recording was killed starts (its records are
    /// lost; everything before it reads).
    pub interrupted_at: Option<u64>,
    /// The file's length.
    pub len: u64,
}

impl Recording {
    /// Reads `path`; a damaged file is an error naming the file, offset and what was expected
    /// unless `salvage`, which keeps what was read before the damage.
    pub fn open(path: &Path, salvage: bool) -> Result<Recording, String> {
        let bytes =
            std::fs::read(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
        let rec = Recording::parse(&bytes);
        // Salvage keeps what a damaged recording holds; a file that is none holds nothing.
        let not_mcap = !bytes.starts_with(MAGIC);
        match (&rec.problem, salvage || not_mcap) {
            (Some(p), _) if not_mcap => Err(format!("{}: {p}", path.display())),
            (Some(p), false) => Err(format!(
                "{}: {p} (the file is damaged or was cut; `--salvage` replays the {} messages before it)",
                path.display(),
                rec.messages.len()
            )),
            _ => Ok(rec),
        }
    }

    /// Why `path` is no MCAP file, by its first bytes (as [`Recording::open`] says it), if it
    /// is none; `None` too when it cannot be read, which the caller reports its own way.
    pub fn not_mcap(path: &Path) -> Option<String> {
        use std::io::Read;
        let mut head = Vec::with_capacity(MAGIC.len());
        let file = std::fs::File::open(path).ok()?;
        file.take(MAGIC.len() as u64).read_to_end(&mut head).ok()?;
        let problem = Recording::parse(&head).problem?;
        // Eight bytes of a real recording read as one cut short after its magic.
        (problem.offset == 0).then(|| format!("{}: {problem}", path.display()))
    }

    /// Reads a recording from memory, as far as it is readable.
    pub fn parse(bytes: &[u8]) -> Recording {
        let mut rec = Recording {
            len: bytes.len() as u64,
            ..Recording::default()
        };
        if bytes.get(..MAGIC.len()) != Some(MAGIC) {
            rec.problem = Some(ReadProblem {
                offset: 0,
                expected: NOT_MCAP.into(),
            });
            return rec;
        }
        let mut schemas = BTreeMap::new();
        rec.problem = rec.walk(bytes, MAGIC.len(), 0, &mut schemas).err();
        rec
    }

    /// Reads the records of `bytes` from `pos`; offsets in errors are `base + position`. The
    /// top level ends at the footer; a chunk's records end with the chunk.
    fn walk(
        &mut self,
        bytes: &[u8],
        mut pos: usize,
        base: u64,
        schemas: &mut BTreeMap<u16, (String, String)>,
    ) -> Result<(), ReadProblem> {
        let top = base == 0;
        while pos < bytes.len() {
            let offset = base + pos as u64;
            let stop = |expected: String| ReadProblem { offset, expected };
            let Some(head) = bytes.get(pos..pos + 9) else {
                return Err(stop(format!(
                    "a record header (9 bytes), {} left (cut while writing?)",
                    bytes.len() - pos
                )));
            };
            let opcode = head[0];
            let len = u64::from_le_bytes(head[1..9].try_into().expect("8 bytes"));
            let start = pos + 9;
            if top && len == u64::MAX {
                // The mcap writer fills a chunk's length in when it closes the chunk: this
                // one was open when the recording was killed. The file ends here.
                self.interrupted_at = Some(offset);
                return Ok(());
            }
            let end = usize::try_from(len).ok().and_then(|l| start.checked_add(l));
            let Some(body) = end.and_then(|e| bytes.get(start..e)) else {
                return Err(stop(format!(
                    "a record of {len} bytes (opcode 0x{opcode:02x}), {} left (cut while writing?)",
                    bytes.len() - start
                )));
            };
            pos = start + body.len();
            if top && opcode == op::FOOTER {
                self.finished = bytes.get(pos..pos + MAGIC.len()) == Some(MAGIC);
                if !self.finished {
                    return Err(ReadProblem {
                        offset: pos as u64,
                        expected: "the closing MCAP magic bytes after the footer".into(),
                    });
                }
                return Ok(());
            }
            let record = mcap::parse_record(opcode, body)
                .map_err(|e| stop(format!("a valid record (opcode 0x{opcode:02x}): {e}")))?;
            match record {
                Record::Chunk { header, data } if top => {
                    let records = decompress(&header, &data).map_err(stop)?;
                    // A chunk's records count only once the whole chunk reads well.
                    let mut chunk = Recording {
                        channels: self.channels.clone(),
                        ..Recording::default()
                    };
                    let mut chunk_schemas = schemas.clone();
                    chunk.walk(&records, 0, offset, &mut chunk_schemas)?;
                    self.channels = chunk.channels;
                    self.messages.extend(chunk.messages);
                    self.metadata.extend(chunk.metadata);
                    *schemas = chunk_schemas;
                    self.chunks += 1;
                }
                Record::Chunk { .. } => return Err(stop("no chunk inside a chunk".into())),
                other => self.take(other, schemas).map_err(stop)?,
            }
        }
        Ok(())
    }

    fn take(
        &mut self,
        record: Record<'_>,
        schemas: &mut BTreeMap<u16, (String, String)>,
    ) -> Result<(), String> {
        match record {
            Record::Schema { header, .. } => {
                schemas.insert(header.id, (header.name, header.encoding));
            }
            Record::Channel(c) => {
                let (schema, schema_encoding) =
                    schemas.get(&c.schema_id).cloned().unwrap_or_default();
                self.channels.insert(
                    c.id,
                    ChannelInfo {
                        topic: c.topic,
                        schema,
                        schema_encoding,
                        message_encoding: c.message_encoding,
                        metadata: c.metadata,
                    },
                );
            }
            Record::Message { header, data } => {
                if !self.channels.contains_key(&header.channel_id) {
                    return Err(format!(
                        "a message of a known channel, got one of channel {}",
                        header.channel_id
                    ));
                }
                self.messages.push(RecordedMessage {
                    channel: header.channel_id,
                    sequence: header.sequence,
                    log_ns: header.log_time,
                    publish_ns: header.publish_time,
                    data: data.into_owned(),
                });
            }
            Record::Metadata(m) => self.metadata.push((m.name, m.metadata)),
            _ => {}
        }
        Ok(())
    }

    /// The messages of one channel.
    pub fn messages_of(&self, channel: u16) -> impl Iterator<Item = &RecordedMessage> {
        self.messages.iter().filter(move |m| m.channel == channel)
    }
}

/// A chunk's records, decompressed (zstd, LZ4 frames or none) and checked against the CRC-32
/// the writer stored, refusing sizes out of reason. Without the check, damage that still
/// decompresses (or a plain chunk's flipped bytes) was replayed as if recorded.
fn decompress(header: &ChunkHeader, data: &[u8]) -> Result<Vec<u8>, String> {
    let records = inflate(header, data)?;
    // 0: the writer computed no CRC (MCAP's convention).
    let stored = header.uncompressed_crc;
    if stored != 0 {
        let read = crc32fast::hash(&records);
        if read != stored {
            return Err(format!(
                "a chunk whose records match its CRC-32 {stored:08x}, they give {read:08x} (the chunk's data is damaged)"
            ));
        }
    }
    Ok(records)
}

fn inflate(header: &ChunkHeader, data: &[u8]) -> Result<Vec<u8>, String> {
    let size = header.uncompressed_size;
    if size > MAX_CHUNK_BYTES {
        return Err(format!(
            "a chunk of at most {MAX_CHUNK_BYTES} bytes, got one claiming {size}"
        ));
    }
    match header.compression.as_str() {
        "" => Ok(data.to_vec()),
        "zstd" => read_bounded(zstd::stream::read::Decoder::new(data), size, "zstd"),
        // Recordings written before petrel chose zstd.
        "lz4" => read_bounded(lz4::Decoder::new(data), size, "LZ4"),
        other => Err(format!(
            "a chunk compressed with zstd, lz4 or not at all, got `{other}` (petrel reads what it writes)"
        )),
    }
}

/// Reads exactly `size` bytes from a decoder (no more, whatever the data claims).
fn read_bounded(decoder: io::Result<impl Read>, size: u64, what: &str) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(size as usize);
    decoder
        .and_then(|d| d.take(size).read_to_end(&mut out))
        .map_err(|e| format!("a {what} chunk: {e}"))?;
    if out.len() as u64 != size {
        return Err(format!(
            "a {what} chunk of {size} bytes, it decompresses to {}",
            out.len()
        ));
    }
    Ok(out)
}
