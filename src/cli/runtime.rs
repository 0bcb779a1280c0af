//! The async runtime a command runs on.

use std::process::ExitCode;

use tokio::runtime::{Builder, Runtime};

/// A multi-thread runtime with `workers` threads (`None`: one per core); when the system
/// refuses one, the error is printed and the command exits with failure.
pub(crate) fn start(workers: Option<usize>) -> Result<Runtime, ExitCode> {
    let mut builder = Builder::new_multi_thread();
    if let Some(workers) = workers {
        builder.worker_threads(workers);
    }
    builder.enable_all().build().map_err(|e| {
        eprintln!("error: cannot start the async runtime: {e}");
        ExitCode::FAILURE
    })
}
