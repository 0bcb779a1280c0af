//! The log tail the console shows: the last lines of the agent's log, fed by whoever owns
//! the logging setup (the `petrel` binary adds a tracing layer that pushes here).

use std::sync::Arc;
use std::time::{SystemTime, UNIX_EPOCH};

use parking_lot::Mutex;
use serde::Serialize;

use crate::core::view::Recent;

/// Lines kept.
pub const LOG_LINES: usize = 500;

/// One log line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LogLine {
    /// Milliseconds since the Unix epoch.
    pub unix_ms: u64,
    /// `ERROR`, `WARN`, `INFO`, ...
    pub level: String,
    /// The emitting module path (tracing target).
    pub target: String,
    /// The message with its fields.
    pub message: String,
}

/// The last [`LOG_LINES`] log lines, shared between the logger and the console.
#[derive(Clone)]
pub struct LogTail {
    lines: Arc<Mutex<Recent<LogLine>>>,
}

impl Default for LogTail {
    fn default() -> Self {
        LogTail {
            lines: Arc::new(Mutex::new(Recent::new(LOG_LINES))),
        }
    }
}

impl LogTail {
    /// Adds a line stamped now.
    pub fn push(&self, level: &str, target: &str, message: String) {
        let unix_ms = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_millis() as u64);
        self.lines.lock().push(LogLine {
            unix_ms,
            level: level.to_string(),
            target: target.to_string(),
            message,
        });
    }

    /// The kept lines, oldest first, and how many were ever pushed.
    pub fn lines(&self) -> (Vec<LogLine>, u64) {
        let lines = self.lines.lock();
        (lines.items(), lines.total())
    }
}
