//! Standard output that a closed pipe ends quietly.
//!
//! `println!` panics when standard output is a closed pipe (`petrel run … | head -1`): a
//! printing module would then fail, restart and fail again until its supervisor gave up.
//! [`outln!`](crate::outln) writes the same line, and takes a closed pipe as the end of the
//! output: nothing more is printed, once logged, and the run goes on.

use std::fmt;
use std::io::{ErrorKind, Write};
use std::sync::atomic::{AtomicBool, Ordering};

static CLOSED: AtomicBool = AtomicBool::new(false);

/// Writes `args` and a newline to standard output unless it was found closed; see
/// [`outln!`](crate::outln).
pub fn write_line(args: fmt::Arguments<'_>) {
    if CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut out = std::io::stdout().lock();
    let written = out
        .write_fmt(args)
        .and_then(|()| out.write_all(b"\n"))
        .and_then(|()| out.flush());
    match written {
        Ok(()) => {}
        Err(e) if e.kind() == ErrorKind::BrokenPipe => {
            if !CLOSED.swap(true, Ordering::Relaxed) {
                tracing::info!("standard output was closed: nothing more is printed");
            }
        }
        Err(e) => tracing::warn!("cannot write to standard output: {e}"),
    }
}

/// `println!` for modules and long runs: a closed standard output ends the output (nothing
/// more is printed) instead of panicking.
///
/// ```
/// petrel_actors::outln!("[{}] {:.3}", "filter", 2.5);
/// ```
#[macro_export]
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::stdout::write_line(::std::format_args!($($arg)*))
    };
}
