//! `petrel record info`: what a recording holds, like `mcap info` and `ros2 bag info`.

use std::collections::BTreeMap;
use std::fmt;

use crate::read::Recording;
use crate::sink::{DROPPED_METADATA, RECORDING_METADATA};

/// One channel's figures.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelFigures {
    /// Topic.
    pub topic: String,
    /// Schema name.
    pub schema: String,
    /// Message encoding.
    pub encoding: String,
    /// petrel's type, if petrel wrote it.
    pub petrel_type: String,
    /// Messages.
    pub count: u64,
    /// Messages per second over the recording's duration.
    pub rate_hz: f64,
    /// Dropped by the recorder.
    pub dropped: u64,
}

/// What `petrel record info` prints.
#[derive(Clone, Debug, PartialEq)]
pub struct Info {
    /// File size, bytes.
    pub bytes: u64,
    /// `foxglove` or `ros2` (from petrel's metadata), or `?`.
    pub format: String,
    /// Whether the file was finished (summary and footer written).
    pub finished: bool,
    /// Where reading stopped early, if it did.
    pub problem: Option<String>,
    /// Where the chunk open when the recording was killed starts.
    pub interrupted_at: Option<u64>,
    /// Messages.
    pub messages: u64,
    /// Chunks.
    pub chunks: usize,
    /// Log time of the first and last message, ns.
    pub span_ns: Option<(u64, u64)>,
    /// Dropped in all.
    pub dropped: u64,
    /// Channels, by topic.
    pub channels: Vec<ChannelFigures>,
}

impl Info {
    /// The figures of a recording.
    pub fn of(rec: &Recording) -> Info {
        let span_ns = rec.messages.iter().map(|m| m.log_ns).fold(
            None,
            |acc: Option<(u64, u64)>, t| match acc {
                None => Some((t, t)),
                Some((a, b)) => Some((a.min(t), b.max(t))),
            },
        );
        let seconds = span_ns.map_or(0.0, |(a, b)| (b - a) as f64 / 1e9);
        let mut dropped: BTreeMap<&str, u64> = BTreeMap::new();
        for (name, values) in &rec.metadata {
            if name == DROPPED_METADATA {
                for (topic, n) in values {
                    *dropped.entry(topic).or_default() += n.parse::<u64>().unwrap_or(0);
                }
            }
        }
        let mut counts: BTreeMap<u16, u64> = BTreeMap::new();
        for m in &rec.messages {
            *counts.entry(m.channel).or_default() += 1;
        }
        let mut channels: Vec<ChannelFigures> = rec
            .channels
            .iter()
            .map(|(id, c)| {
                let count = counts.get(id).copied().unwrap_or(0);
                ChannelFigures {
                    topic: c.topic.clone(),
                    schema: c.schema.clone(),
                    encoding: c.message_encoding.clone(),
                    petrel_type: c.petrel_type().unwrap_or("").to_string(),
                    count,
                    rate_hz: if seconds > 0.0 {
                        count as f64 / seconds
                    } else {
                        0.0
                    },
                    dropped: dropped.get(c.topic.as_str()).copied().unwrap_or(0),
                }
            })
            .collect();
        channels.sort_by(|a, b| a.topic.cmp(&b.topic));
        let format = rec
            .metadata
            .iter()
            .find(|(n, _)| n == RECORDING_METADATA)
            .and_then(|(_, m)| m.get("format").cloned())
            .unwrap_or_else(|| "?".into());
        Info {
            bytes: rec.len,
            format,
            finished: rec.finished,
            problem: rec.problem.as_ref().map(ToString::to_string),
            interrupted_at: rec.interrupted_at,
            messages: rec.messages.len() as u64,
            chunks: rec.chunks,
            span_ns,
            dropped: dropped.values().sum(),
            channels,
        }
    }
}

impl fmt::Display for Info {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let state = match (&self.problem, self.finished) {
            (Some(p), _) => format!("damaged: {p}; figures below cover what comes before"),
            (None, true) => "finished (summary and index written)".into(),
            (None, false) => match self.interrupted_at {
                Some(at) => format!("unfinished (no summary: the recording is still being written, or was killed); readable up to its last whole chunk, the chunk at byte {at} was being written"),
                None => "unfinished (no summary: the recording is still being written, or was killed); readable up to its last whole chunk".into(),
            },
        };
        writeln!(f, "size:      {} bytes", self.bytes)?;
        writeln!(f, "state:     {state}")?;
        writeln!(f, "format:    {}", self.format)?;
        let duration = self.span_ns.map_or(0.0, |(a, b)| (b - a) as f64 / 1e9);
        writeln!(f, "duration:  {duration:.3} s")?;
        writeln!(f, "messages:  {} in {} chunks", self.messages, self.chunks)?;
        writeln!(f, "dropped:   {}", self.dropped)?;
        writeln!(f, "channels:  {}", self.channels.len())?;
        let width = self
            .channels
            .iter()
            .map(|c| c.topic.len())
            .max()
            .unwrap_or(5)
            .max(5);
        let swidth = self
            .channels
            .iter()
            .map(|c| c.schema.len())
            .max()
            .unwrap_or(6)
            .max(6);
        writeln!(
            f,
            "  {:width$}  {:swidth$}  {:>8}  {:>9}  {:>7}  petrel type",
            "topic", "schema", "count", "rate Hz", "dropped"
        )?;
        for c in &self.channels {
            writeln!(
                f,
                "  {:width$}  {:swidth$}  {:>8}  {:>9.2}  {:>7}  {}",
                c.topic, c.schema, c.count, c.rate_hz, c.dropped, c.petrel_type
            )?;
        }
        Ok(())
    }
}
