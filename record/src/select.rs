//! What a recording holds and where it goes, decided without any I/O: the options of a
//! `record:` section checked into ranges, URL globs, topic names, file splitting.

use std::path::{Path, PathBuf};

use glob::{MatchOptions, Pattern};
use petrel_actors::config::RecordSection;

use crate::encode::Format;
use crate::sink::ChunkCompression;

/// Smallest split size accepted, bytes: below it a file holds little more than its schemas.
pub const MIN_SPLIT_BYTES: u64 = 64 * 1024;
/// Shortest split duration accepted, seconds.
pub const MIN_SPLIT_S: f64 = 1.0;

/// What to record and how, checked.
#[derive(Clone, Debug)]
pub struct RecordOptions {
    /// The first file; split files get `.1`, `.2`, ... before the extension.
    pub path: PathBuf,
    /// Message family of the standard types.
    pub format: Format,
    /// How chunks are compressed.
    pub compression: ChunkCompression,
    /// Which properties.
    pub selection: Selection,
    /// Whether the tracing log is recorded.
    pub log: bool,
    /// When to start a new file.
    pub split: SplitPolicy,
    /// Values waiting for the writer at most; beyond, they are dropped and counted.
    pub backlog: usize,
}

/// Default [`RecordOptions::backlog`]: a few seconds of a busy agent.
pub const DEFAULT_BACKLOG: usize = 8192;

impl RecordOptions {
    /// Everything, in `format`, to `path`, in one file.
    pub fn everything(path: impl Into<PathBuf>, format: Format) -> Self {
        RecordOptions {
            path: path.into(),
            format,
            compression: ChunkCompression::default(),
            selection: Selection::everything(),
            log: true,
            split: SplitPolicy::default(),
            backlog: DEFAULT_BACKLOG,
        }
    }

    /// Checks a `record:` section; `path`, `format` and `compression` given on the command
    /// line win over the section's. The error says which field is wrong and what was expected.
    pub fn from_section(
        section: &RecordSection,
        path: Option<&Path>,
        format: Option<Format>,
        compression: Option<ChunkCompression>,
    ) -> Result<Self, String> {
        let path = match (path, &section.file) {
            (Some(p), _) => p.to_path_buf(),
            (None, Some(f)) if !f.is_empty() => PathBuf::from(f),
            _ => {
                return Err(
                    "record: expected `file: \"out/run.mcap\"` (or `petrel run --record FILE`)"
                        .into(),
                )
            }
        };
        let format = match (format, &section.format) {
            (Some(f), _) => f,
            (None, Some(f)) => f.parse().map_err(|e| format!("record: format: {e}"))?,
            (None, None) => Format::default(),
        };
        let compression = match (compression, &section.compression) {
            (Some(c), _) => c,
            (None, Some(c)) => c.parse().map_err(|e| format!("record: compression: {e}"))?,
            (None, None) => ChunkCompression::default(),
        };
        let selection = Selection::new(&section.include, &section.exclude)?;
        let split = SplitPolicy::new(section.max_bytes, section.max_duration_s)?;
        Ok(RecordOptions {
            path,
            format,
            compression,
            selection,
            log: section.log,
            split,
            backlog: DEFAULT_BACKLOG,
        })
    }
}

/// Which properties are recorded: URL globs in, globs out.
#[derive(Clone, Debug)]
pub struct Selection {
    include: Vec<Glob>,
    exclude: Vec<Glob>,
}

#[derive(Clone, Debug)]
struct Glob {
    pattern: Pattern,
    /// A `petrel://agent/...` glob (matched against whole URLs) or a `module/path` one.
    full: bool,
}

const MATCH: MatchOptions = MatchOptions {
    case_sensitive: true,
    require_literal_separator: true,
    require_literal_leading_dot: false,
};

impl Glob {
    fn parse(text: &str, field: &str) -> Result<Self, String> {
        let full = text.starts_with("petrel://");
        let pattern = Pattern::new(text)
            .map_err(|e| format!("record: {field}: `{text}` is not a glob ({e}); expected e.g. `robot/out/*` or `**/laserScan`"))?;
        Ok(Glob { pattern, full })
    }

    fn matches(&self, agent: &str, key: &str) -> bool {
        match self.full {
            true => self
                .pattern
                .matches_with(&format!("petrel://{agent}/{key}"), MATCH),
            false => self.pattern.matches_with(key, MATCH),
        }
    }
}

impl Selection {
    /// Every property.
    pub fn everything() -> Self {
        Selection::new(&["**".to_string()], &[]).expect("`**` is a glob")
    }

    /// The selection of these globs.
    pub fn new(include: &[String], exclude: &[String]) -> Result<Self, String> {
        let parse = |list: &[String], field| {
            list.iter()
                .map(|g| Glob::parse(g, field))
                .collect::<Result<Vec<_>, _>>()
        };
        Ok(Selection {
            include: parse(include, "include")?,
            exclude: parse(exclude, "exclude")?,
        })
    }

    /// Whether `agent`'s property `key` (`module/path`) is recorded.
    pub fn wants(&self, agent: &str, key: &str) -> bool {
        self.include.iter().any(|g| g.matches(agent, key))
            && !self.exclude.iter().any(|g| g.matches(agent, key))
    }
}

/// The topic of the tracing log: `/rosout` in ROS 2 files (where rosbag2's tools look for
/// it), `/log` otherwise.
pub fn log_topic(format: crate::Format) -> &'static str {
    match format {
        crate::Format::Ros2 => "/rosout",
        crate::Format::Foxglove | crate::Format::FoxgloveJson => "/log",
    }
}

/// The topic of a property: `/agent/module/path`, with every character a ROS 2 name refuses
/// replaced by `_` (and a segment starting with a digit prefixed by one).
pub fn topic(agent: &str, key: &str) -> String {
    let mut topic = String::with_capacity(agent.len() + key.len() + 2);
    for segment in std::iter::once(agent).chain(key.split('/')) {
        topic.push('/');
        if segment.starts_with(|c: char| c.is_ascii_digit()) {
            topic.push('_');
        }
        topic.extend(
            segment
                .chars()
                .map(|c| match c.is_ascii_alphanumeric() || c == '_' {
                    true => c,
                    false => '_',
                }),
        );
    }
    topic
}

/// When a recording starts a new file.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SplitPolicy {
    /// Bytes per file at most (checked after each message).
    pub max_bytes: Option<u64>,
    /// Recorded nanoseconds per file at most.
    pub max_duration_ns: Option<u64>,
}

impl SplitPolicy {
    /// Checks the limits of a `record:` section.
    pub fn new(max_bytes: Option<u64>, max_duration_s: Option<f64>) -> Result<Self, String> {
        if let Some(b) = max_bytes.filter(|&b| b < MIN_SPLIT_BYTES) {
            return Err(format!(
                "record: max_bytes: expected at least {MIN_SPLIT_BYTES} bytes, got {b}"
            ));
        }
        let max_duration_ns = match max_duration_s {
            None => None,
            Some(s) if s.is_finite() && (MIN_SPLIT_S..=1e9).contains(&s) => Some((s * 1e9) as u64),
            Some(s) => {
                return Err(format!(
                    "record: max_duration_s: expected seconds in [{MIN_SPLIT_S}, 1e9], got {s}"
                ))
            }
        };
        Ok(SplitPolicy {
            max_bytes,
            max_duration_ns,
        })
    }

    /// Whether a file holding `bytes` bytes, whose first message was logged at `first_ns`,
    /// is full once a message logged at `now_ns` would go in.
    pub fn full(&self, bytes: u64, first_ns: Option<u64>, now_ns: u64) -> bool {
        let too_big = self.max_bytes.is_some_and(|m| bytes >= m);
        let too_long = match (self.max_duration_ns, first_ns) {
            (Some(d), Some(first)) => now_ns.saturating_sub(first) >= d,
            _ => false,
        };
        too_big || too_long
    }
}

/// The `index`th file of a recording: the path itself, then `run.1.mcap`, `run.2.mcap`, ...
pub fn split_path(base: &Path, index: usize) -> PathBuf {
    if index == 0 {
        return base.to_path_buf();
    }
    let stem = base.file_stem().unwrap_or_default().to_string_lossy();
    let name = match base.extension() {
        Some(ext) => format!("{stem}.{index}.{}", ext.to_string_lossy()),
        None => format!("{stem}.{index}"),
    };
    base.with_file_name(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn globs_match_within_and_across_segments() {
        let s = Selection::new(
            &[
                "robot/out/*".into(),
                "**/laserScan".into(),
                "petrel://b/**".into(),
            ],
            &["robot/out/pose".into()],
        )
        .unwrap();
        assert!(s.wants("a", "robot/out/odometry"));
        assert!(!s.wants("a", "robot/out/pose"), "excluded");
        assert!(
            !s.wants("a", "robot/stats/steps"),
            "`*` stays in one segment"
        );
        assert!(s.wants("a", "lidar/out/laserScan"));
        assert!(s.wants("b", "x/params/y"));
        assert!(!s.wants("a", "x/params/y"));
        assert!(Selection::everything().wants("a", "_supervisor/events"));
        let err = Selection::new(&["robot/[out".into()], &[]).unwrap_err();
        assert!(
            err.contains("include") && err.contains("robot/[out"),
            "{err}"
        );
    }

    #[test]
    fn topics_are_ros_names() {
        assert_eq!(
            topic("robot1", "robot/out/laserScan"),
            "/robot1/robot/out/laserScan"
        );
        assert_eq!(
            topic("r-2", "_supervisor/events"),
            "/r_2/_supervisor/events"
        );
        assert_eq!(topic("a", "m/params/3d"), "/a/m/params/_3d");
    }

    #[test]
    fn files_split_on_size_or_duration() {
        let p = SplitPolicy::new(Some(MIN_SPLIT_BYTES), Some(2.0)).unwrap();
        assert!(!p.full(10, Some(0), 1_000_000_000));
        assert!(p.full(MIN_SPLIT_BYTES, Some(0), 0));
        assert!(p.full(10, Some(0), 2_000_000_000));
        assert!(
            !p.full(10, None, 5_000_000_000),
            "an empty file is never full"
        );
        assert!(SplitPolicy::new(Some(10), None)
            .unwrap_err()
            .contains("max_bytes"));
        assert!(SplitPolicy::new(None, Some(f64::NAN))
            .unwrap_err()
            .contains("max_duration_s"));
        assert_eq!(
            split_path(Path::new("out/run.mcap"), 0),
            Path::new("out/run.mcap")
        );
        assert_eq!(
            split_path(Path::new("out/run.mcap"), 2),
            Path::new("out/run.2.mcap")
        );
    }

    #[test]
    fn sections_are_checked() {
        let section = RecordSection::default();
        let err = RecordOptions::from_section(&section, None, None, None).unwrap_err();
        assert!(err.contains("file"), "{err}");
        let bad = RecordSection {
            file: Some("x.mcap".into()),
            format: Some("rosbag".into()),
            ..RecordSection::default()
        };
        let err = RecordOptions::from_section(&bad, None, None, None).unwrap_err();
        assert!(err.contains("format") && err.contains("rosbag"), "{err}");
        let ok = RecordOptions::from_section(&bad, None, Some(Format::Ros2), None).unwrap();
        assert_eq!(ok.format, Format::Ros2);
        assert_eq!(ok.compression, ChunkCompression::Zstd, "the default");
        let bad = RecordSection {
            file: Some("x.mcap".into()),
            compression: Some("gzip".into()),
            ..RecordSection::default()
        };
        let err = RecordOptions::from_section(&bad, None, None, None).unwrap_err();
        assert!(
            err.contains("compression") && err.contains("gzip") && err.contains("lz4"),
            "{err}"
        );
        let lz4 = RecordSection {
            compression: Some("lz4".into()),
            ..bad.clone()
        };
        let ok = RecordOptions::from_section(&lz4, None, None, None).unwrap();
        assert_eq!(ok.compression, ChunkCompression::Lz4);
        let ok = RecordOptions::from_section(&bad, None, None, Some(ChunkCompression::Lz4));
        assert_eq!(
            ok.unwrap().compression,
            ChunkCompression::Lz4,
            "the command line wins over the section"
        );
    }
}
