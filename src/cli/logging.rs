//! Tracing setup: `RUST_LOG`-style filtering (default `DEFAULT_FILTER`), pretty or JSON lines on stderr,
//! and the timeline trace of `--trace-out` (which sees steps and info events whatever `RUST_LOG`
//! says).

use std::io::IsTerminal;

use tracing_subscriber::layer::SubscriberExt;
use tracing_subscriber::util::SubscriberInitExt;
use tracing_subscriber::{fmt, EnvFilter, Layer};

use super::LogFormat;

/// Without `RUST_LOG`: `info`, but zenoh's session start only at `error`. It warns when a
/// peer in `connect` did not answer within its scouting delay, which is how a team starts (its
/// members in any order; the link status says when a peer is missing), and its other warnings
/// there (a listener that cannot bind) come back as petrel's own error.
const DEFAULT_FILTER: &str = "info,zenoh::net::runtime::orchestrator=error";

/// Sets up logging, and with `trace_out` the timeline trace (whose guard finishes the file
/// when dropped).
pub(crate) fn init(
    format: LogFormat,
    trace_out: Option<&std::path::Path>,
) -> std::io::Result<Option<super::trace::TraceGuard>> {
    let (filter, problem) = match std::env::var("RUST_LOG") {
        Ok(spec) => match EnvFilter::try_new(&spec) {
            Ok(filter) => (filter, None),
            Err(e) => (
                EnvFilter::new("info"),
                Some(format!(
                    "RUST_LOG={spec:?} is not a valid filter ({e}); logging at info"
                )),
            ),
        },
        Err(_) => (EnvFilter::new(DEFAULT_FILTER), None),
    };
    let (trace, guard) = match trace_out {
        Some(path) => {
            let (layer, guard) = super::trace::open(path)?;
            (
                Some(layer.with_filter(super::trace::interest())),
                Some(guard),
            )
        }
        None => (None, None),
    };
    // Colours only for a person at a terminal, not in files and pipes.
    let ansi = std::io::stderr().is_terminal();
    let log = match format {
        LogFormat::Pretty => fmt::layer()
            .compact()
            .with_ansi(ansi)
            .with_writer(std::io::stderr)
            .boxed(),
        LogFormat::Json => fmt::layer()
            .json()
            .with_ansi(ansi)
            .with_writer(std::io::stderr)
            .boxed(),
    };
    // A second initialisation (e.g. in tests running several commands) keeps the first subscriber.
    let _ = tracing_subscriber::registry()
        .with(log.with_filter(filter))
        .with(trace)
        .with(super::record_log::RecordLayer)
        .with(super::console_log::ConsoleLogLayer)
        .try_init();
    if let Some(problem) = problem {
        tracing::warn!("{problem}");
    }
    Ok(guard)
}
