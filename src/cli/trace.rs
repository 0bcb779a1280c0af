//! `petrel run --trace-out FILE`: a timeline of the run that Perfetto and `chrome://tracing`
//! open. Each module is a track; each of its steps a span; its log events at info and above
//! (restarts, context switches, plan steps) instants on its track. Runtime events that name
//! an agent and a module (the supervisor's) go on that module's track.

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use tracing::field::{Field, Visit};
use tracing::span::{Attributes, Id};
use tracing::{Event, Level, Subscriber};
use tracing_subscriber::layer::Context;
use tracing_subscriber::registry::LookupSpan;
use tracing_subscriber::Layer;

use super::chrome;

/// The track of events that belong to no module.
const RUNTIME_TRACK: u64 = 0;

/// What the trace looks at, decided once per callsite (so a library's trace-level events cost
/// nothing): module and step spans, and petrel's events at info and above.
pub(crate) fn interest(
) -> tracing_subscriber::filter::FilterFn<impl Fn(&tracing::Metadata<'_>) -> bool> {
    tracing_subscriber::filter::filter_fn(|meta| {
        if meta.is_span() {
            return matches!(meta.name(), "module" | "step");
        }
        *meta.level() <= Level::INFO && meta.target().starts_with("petrel")
    })
}

/// Writes the trace as the run goes.
pub(crate) struct TraceLayer {
    shared: Arc<Shared>,
}

/// Flushes the trace and closes its array when dropped (at the end of the run).
pub(crate) struct TraceGuard {
    shared: Arc<Shared>,
}

struct Shared {
    start: Instant,
    out: Mutex<Output>,
}

impl Shared {
    fn out(&self) -> MutexGuard<'_, Output> {
        // A panic while writing leaves nothing half-done that matters: go on writing.
        self.out.lock().unwrap_or_else(|e| e.into_inner())
    }
}

struct Output {
    file: BufWriter<File>,
    tracks: HashMap<String, u64>,
    failed: bool,
}

impl Output {
    fn line(&mut self, event: &str) {
        if !self.failed && writeln!(self.file, ",{event}").is_err() {
            // A full disk must not stop the robot: the trace ends here, and says so at exit.
            self.failed = true;
        }
    }

    fn track(&mut self, name: &str) -> u64 {
        if let Some(&tid) = self.tracks.get(name) {
            return tid;
        }
        let tid = self.tracks.len() as u64 + 1;
        self.tracks.insert(name.to_string(), tid);
        self.line(&chrome::track_name(tid, name));
        tid
    }
}

/// Opens `path` and returns the layer that fills it and the guard that finishes it.
pub(crate) fn open(path: &Path) -> std::io::Result<(TraceLayer, TraceGuard)> {
    let mut file = BufWriter::new(File::create(path)?);
    // The array's first element names the runtime track, so every later line starts with ','.
    write!(file, "[{}", chrome::track_name(RUNTIME_TRACK, "runtime"))?;
    writeln!(file)?;
    let shared = Arc::new(Shared {
        start: Instant::now(),
        out: Mutex::new(Output {
            file,
            tracks: HashMap::new(),
            failed: false,
        }),
    });
    Ok((
        TraceLayer {
            shared: shared.clone(),
        },
        TraceGuard { shared },
    ))
}

impl Drop for TraceGuard {
    fn drop(&mut self) {
        let mut out = self.shared.out();
        let closed = writeln!(out.file, "]").and_then(|()| out.file.flush());
        if closed.is_err() || out.failed {
            eprintln!("warning: the trace could not be written completely");
        }
    }
}

/// What the layer keeps on a `module` span: its track.
struct Track(u64);

/// What the layer keeps on a `step` span: when it began.
struct StepStart(Instant);

impl TraceLayer {
    fn micros(&self, at: Instant) -> f64 {
        at.duration_since(self.shared.start).as_nanos() as f64 / 1e3
    }
}

impl<S: Subscriber + for<'a> LookupSpan<'a>> Layer<S> for TraceLayer {
    fn on_new_span(&self, attrs: &Attributes<'_>, id: &Id, ctx: Context<'_, S>) {
        let Some(span) = ctx.span(id) else { return };
        match attrs.metadata().name() {
            "module" => {
                let mut fields = Fields::default();
                attrs.record(&mut fields);
                let name = fields.track_name().unwrap_or_else(|| "module".into());
                let tid = self.shared.out().track(&name);
                span.extensions_mut().insert(Track(tid));
            }
            "step" => span.extensions_mut().insert(StepStart(Instant::now())),
            _ => {}
        }
    }

    fn on_close(&self, id: Id, ctx: Context<'_, S>) {
        let Some(span) = ctx.span(&id) else { return };
        let Some(start) = span.extensions().get::<StepStart>().map(|s| s.0) else {
            return;
        };
        let tid = span
            .scope()
            .find_map(|s| s.extensions().get::<Track>().map(|t| t.0))
            .unwrap_or(RUNTIME_TRACK);
        let line = chrome::complete(
            "step",
            tid,
            self.micros(start),
            start.elapsed().as_nanos() as f64 / 1e3,
        );
        self.shared.out().line(&line);
    }

    fn on_event(&self, event: &Event<'_>, ctx: Context<'_, S>) {
        let meta = event.metadata();
        if *meta.level() > Level::INFO || !meta.target().starts_with("petrel") {
            return;
        }
        let mut fields = Fields::default();
        event.record(&mut fields);
        let in_module = ctx.event_scope(event).and_then(|scope| {
            scope
                .from_root()
                .find_map(|s| s.extensions().get::<Track>().map(|t| t.0))
        });
        let ts = self.micros(Instant::now());
        let mut out = self.shared.out();
        let tid = match (in_module, fields.track_name()) {
            (Some(tid), _) => tid,
            (None, Some(name)) => out.track(&name),
            (None, None) => RUNTIME_TRACK,
        };
        let name = fields.message.take().unwrap_or_else(|| meta.name().into());
        out.line(&chrome::instant(&name, tid, ts, &fields.others));
    }
}

/// The fields of a span or event: the message, agent and module, and the rest as text.
#[derive(Default)]
struct Fields {
    message: Option<String>,
    agent: Option<String>,
    module: Option<String>,
    others: Vec<(String, String)>,
}

impl Fields {
    /// `agent/module`, when both are known.
    fn track_name(&self) -> Option<String> {
        Some(format!(
            "{}/{}",
            self.agent.as_ref()?,
            self.module.as_ref()?
        ))
    }
}

impl Visit for Fields {
    fn record_str(&mut self, field: &Field, value: &str) {
        self.put(field, value.to_string());
    }

    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        self.put(field, format!("{value:?}"));
    }
}

impl Fields {
    fn put(&mut self, field: &Field, value: String) {
        match field.name() {
            "message" => self.message = Some(value),
            "agent" => self.agent = Some(value),
            "module" => self.module = Some(value),
            name => self.others.push((name.to_string(), value)),
        }
    }
}
