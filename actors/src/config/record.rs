//! The `record:` section of an agent config: what a run records to MCAP. Pure data; the
//! `petrel-record` crate checks the ranges and does the recording.

use serde::{Deserialize, Serialize};

/// `record: (file: "out/run.mcap", include: ["**"], max_bytes: 100000000)`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RecordSection {
    /// The file to write (relative to the working directory); `petrel run --record` overrides it.
    #[serde(default)]
    pub file: Option<String>,
    /// `foxglove` (default) or `ros2`; `--record-format` overrides it.
    #[serde(default)]
    pub format: Option<String>,
    /// Chunk compression, `zstd` (default) or `lz4`; `--record-compression` overrides it.
    #[serde(default)]
    pub compression: Option<String>,
    /// Properties and queues to record, as URL globs (`robot/out/*`, `**/laserScan`,
    /// `petrel://robot1/**`) where `*` matches within one segment and `**` across segments.
    #[serde(default = "everything")]
    pub include: Vec<String>,
    /// Globs of properties not to record, even if `include` matches them.
    #[serde(default)]
    pub exclude: Vec<String>,
    /// Whether the tracing log is recorded as a log channel.
    #[serde(default = "yes")]
    pub log: bool,
    /// Start a new file once this many bytes are written (`run.mcap`, `run.1.mcap`, ...).
    #[serde(default)]
    pub max_bytes: Option<u64>,
    /// Start a new file once a file spans this many seconds of recorded time.
    #[serde(default)]
    pub max_duration_s: Option<f64>,
}

impl Default for RecordSection {
    fn default() -> Self {
        RecordSection {
            file: None,
            format: None,
            compression: None,
            include: everything(),
            exclude: Vec::new(),
            log: true,
            max_bytes: None,
            max_duration_s: None,
        }
    }
}

fn everything() -> Vec<String> {
    vec!["**".into()]
}

fn yes() -> bool {
    true
}
