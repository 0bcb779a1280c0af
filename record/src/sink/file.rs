//! The file side of the sink: how chunks are compressed ([`ChunkCompression`]) and the output
//! the `mcap` writer writes to ([`Counted`]), opened by [`open_writer`].

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use mcap::records::Metadata;
use mcap::{Compression, WriteOptions, Writer};
use serde::{Deserialize, Serialize};

use super::RECORDING_METADATA;
use crate::encode::Format;

/// Chunk size target: small enough that a killed run loses little, large enough to compress.
pub const CHUNK_BYTES: u64 = 512 * 1024;

/// zstd level of the chunks: the fastest standard level, and cheaper in CPU than the `mcap`
/// crate's LZ4 frames, whose XXH32 content checksum its options cannot turn off (BENCHMARKS.md).
pub const ZSTD_LEVEL: u32 = 1;

/// How chunks are compressed. Every MCAP reader (Foxglove, the `mcap` CLI, rosbag2) reads both.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ChunkCompression {
    /// zstd level 1: less CPU on the robot and smaller files than LZ4 on petrel's recordings
    /// (BENCHMARKS.md, 2026-11-24).
    #[default]
    Zstd,
    /// LZ4 frames: faster for readers to decompress, more CPU to write (the `mcap` crate's
    /// frames carry a content checksum) and larger files.
    Lz4,
}

impl ChunkCompression {
    /// The `mcap` crate's compression and level for it.
    fn mcap(self) -> (Compression, u32) {
        match self {
            ChunkCompression::Zstd => (Compression::Zstd, ZSTD_LEVEL),
            // Level 0: LZ4's default fast mode (levels ≥ 3 are the slow LZ4 HC).
            ChunkCompression::Lz4 => (Compression::Lz4, 0),
        }
    }
}

impl std::str::FromStr for ChunkCompression {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "zstd" => Ok(ChunkCompression::Zstd),
            "lz4" => Ok(ChunkCompression::Lz4),
            other => Err(format!("expected `zstd` or `lz4`, got `{other}`")),
        }
    }
}

/// The file as the `mcap` writer sees it: buffered, its length counted (the split size)
/// without asking the OS, and its position tracked here. The writer asks for its position
/// before every message index and summary record (hundreds per chunk with many channels);
/// `BufWriter`'s `Seek` answers that by flushing and an `lseek`, which made each of those
/// small records a system call of its own.
pub(super) struct Counted {
    file: BufWriter<File>,
    /// The position in the file.
    pos: u64,
    /// The file's length (the furthest byte written), shared with the sink.
    len: Arc<AtomicU64>,
}

/// Write buffer: a chunk's compressed output and its indexes go out in a few large writes.
const WRITE_BUFFER: usize = 256 * 1024;

impl Counted {
    fn new(file: File, len: Arc<AtomicU64>) -> Self {
        Counted {
            file: BufWriter::with_capacity(WRITE_BUFFER, file),
            pos: 0,
            len,
        }
    }
}

impl Write for Counted {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.file.write(buf)?;
        self.pos += n as u64;
        self.len.fetch_max(self.pos, Ordering::Relaxed);
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.file.flush()
    }
}

impl Seek for Counted {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        if pos == SeekFrom::Current(0) {
            return Ok(self.pos);
        }
        self.pos = self.file.seek(pos)?;
        Ok(self.pos)
    }
    fn stream_position(&mut self) -> io::Result<u64> {
        Ok(self.pos)
    }
}

/// Creates `path` and an `mcap` writer on it: chunks of [`CHUNK_BYTES`] compressed with
/// `compression` on the calling thread, the profile of `format`, and a first metadata record
/// saying who wrote the file (`part`: its number in a split recording). `len` follows the
/// file's length as it is written.
pub(super) fn open_writer(
    path: &Path,
    format: Format,
    compression: ChunkCompression,
    part: usize,
    len: Arc<AtomicU64>,
) -> io::Result<Writer<Counted>> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let file = Counted::new(File::create(path)?, len);
    let profile = match format {
        Format::Ros2 => "ros2",
        Format::Foxglove | Format::FoxgloveJson => "",
    };
    let (compression, level) = compression.mcap();
    let mut writer = WriteOptions::new()
        .compression(Some(compression))
        .compression_level(level)
        // On the writer thread itself: zstd's worker threads would add CPU, not save it.
        .compression_threads(0)
        .chunk_size(Some(CHUNK_BYTES))
        .profile(profile)
        .library(concat!("petrel-record/", env!("CARGO_PKG_VERSION")))
        .create(file)
        .map_err(io::Error::other)?;
    let about = BTreeMap::from([
        ("format".to_string(), format!("{format:?}").to_lowercase()),
        ("part".to_string(), part.to_string()),
    ]);
    writer
        .write_metadata(&Metadata {
            name: RECORDING_METADATA.into(),
            metadata: about,
        })
        .map_err(io::Error::other)?;
    Ok(writer)
}
