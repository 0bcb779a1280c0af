//! Standard output for the commands that print and end (everything but `run`, `replay` and
//! `console`, whose printing goes through `outln!` and whose runs go on).
//!
//! `println!` panics when standard output cannot be written (a full disk, `/dev/full`), and
//! `let _ = write!(…)` said nothing and exited 0 with the output lost. Here the first failed
//! write is kept, later ones are skipped, and [`finish`] turns it into an error message and
//! [`EXIT_OUTPUT`]. A closed pipe never gets here: it ends the process by SIGPIPE first (see
//! `stop_quietly_on_a_closed_pipe`).

use std::fmt;
use std::io::Write;
use std::process::ExitCode;
use std::sync::OnceLock;

/// Exit code when standard output could not be written (`EX_IOERR` of `sysexits.h`).
pub(crate) const EXIT_OUTPUT: u8 = 74;

/// Why the first write that failed failed.
static FAILED: OnceLock<String> = OnceLock::new();

/// Writes `args` to standard output, unless a write failed before.
pub(crate) fn write(args: fmt::Arguments<'_>) {
    if FAILED.get().is_some() {
        return;
    }
    if let Err(e) = std::io::stdout().lock().write_fmt(args) {
        let _ = FAILED.set(e.to_string());
    }
}

/// Keeps `e`, a failed write to standard output made without [`write`], for [`finish`].
pub(crate) fn keep_failure(e: std::io::Error) -> ExitCode {
    let _ = FAILED.set(e.to_string());
    ExitCode::from(EXIT_OUTPUT)
}

/// Whether a write to standard output failed: a command that follows values stops then.
pub(crate) fn failed() -> bool {
    FAILED.get().is_some()
}

/// `code`, or [`EXIT_OUTPUT`] with a message on standard error when standard output could
/// not be written (checked by a last flush too).
pub(crate) fn finish(code: ExitCode) -> ExitCode {
    if let Err(e) = std::io::stdout().lock().flush() {
        let _ = FAILED.set(e.to_string());
    }
    match FAILED.get() {
        None => code,
        Some(e) => {
            eprintln!("error: cannot write to standard output: {e}");
            ExitCode::from(EXIT_OUTPUT)
        }
    }
}

/// `print!` that keeps a failed write for [`finish`] instead of panicking.
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::cli::stdout::write(::std::format_args!($($arg)*))
    };
}

/// `println!` that keeps a failed write for [`finish`] instead of panicking.
macro_rules! sayln {
    () => {
        $crate::cli::stdout::write(::std::format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::cli::stdout::write(::std::format_args!("{}\n", ::std::format_args!($($arg)*)))
    };
}

pub(crate) use {say, sayln};
