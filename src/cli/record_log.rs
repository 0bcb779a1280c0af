//! The tracing log as a recording's log channel: a layer that hands each event at info and
//! above to the recorder's [`LogSink`] while a recording runs, and to the Foxglove live view's
//! [`LiveLog`] while one serves (and costs a lock check when neither does).

use std::fmt::Write as _;
use std::sync::RwLock;
use std::time::{SystemTime, UNIX_EPOCH};

use petrel_console::live::LiveLog;
use petrel_record::{LogLevel, LogRecord, LogSink};
use tracing::field::{Field, Visit};
use tracing::{Event, Level, Subscriber};
use tracing_subscriber::layer::Context;
use tracing_subscriber::Layer;

static SINK: RwLock<Option<LogSink>> = RwLock::new(None);
static LIVE: RwLock<Option<LiveLog>> = RwLock::new(None);

/// Sends the log to `sink` from now on (`None`: stop).
pub(crate) fn install(sink: Option<LogSink>) {
    *SINK.write().unwrap_or_else(|e| e.into_inner()) = sink;
}

/// Sends the log to the live view's `live` from now on (`None`: stop).
pub(crate) fn install_live(live: Option<LiveLog>) {
    *LIVE.write().unwrap_or_else(|e| e.into_inner()) = live;
}

/// The layer; `logging::init` adds it.
pub(crate) struct RecordLayer;

/// An event's message followed by its fields (`message k=v ...`); the console's log tail
/// uses it too.
#[derive(Default)]
pub(crate) struct Text(pub(crate) String);

impl Visit for Text {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        match field.name() {
            "message" => {
                let rest = std::mem::take(&mut self.0);
                let _ = write!(self.0, "{value:?}");
                self.0.push_str(&rest);
            }
            name => {
                let _ = write!(self.0, " {name}={value:?}");
            }
        }
    }
    fn record_str(&mut self, field: &Field, value: &str) {
        match field.name() {
            "message" => self.0.insert_str(0, value),
            name => {
                let _ = write!(self.0, " {name}={value}");
            }
        }
    }
}

impl<S: Subscriber> Layer<S> for RecordLayer {
    fn on_event(&self, event: &Event<'_>, _ctx: Context<'_, S>) {
        let meta = event.metadata();
        if *meta.level() > Level::INFO {
            return;
        }
        let sink = SINK.read().unwrap_or_else(|e| e.into_inner());
        let live = LIVE.read().unwrap_or_else(|e| e.into_inner());
        if sink.is_none() && live.is_none() {
            return;
        }
        let mut text = Text::default();
        event.record(&mut text);
        let level = match *meta.level() {
            Level::ERROR => LogLevel::Error,
            Level::WARN => LogLevel::Warn,
            _ => LogLevel::Info,
        };
        let stamp_ns = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos() as u64);
        let record = LogRecord {
            stamp_ns,
            level,
            target: meta.target().to_string(),
            message: text.0,
            file: meta.file().unwrap_or_default().to_string(),
            line: meta.line().unwrap_or(0),
        };
        if let Some(live) = live.as_ref() {
            live.push(stamp_ns, std::sync::Arc::new(record.clone()));
        }
        if let Some(sink) = sink.as_ref() {
            sink.record(record);
        }
    }
}
