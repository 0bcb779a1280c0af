//! Running a process from a test with a deadline: a tool that hangs fails its test with
//! what it printed so far instead of stalling the whole suite.

use std::process::{Child, Command, Output, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// How long a command-line call may take before its test fails. Generous: debug builds on a
/// loaded 2-core machine, and the slowest calls wait for a team session.
pub const PROCESS_DEADLINE: Duration = Duration::from_secs(60);

/// Runs `cmd` to completion and returns its output; SIGKILLs it and panics if it is still
/// running after [`PROCESS_DEADLINE`]. The wait happens on its own thread so the deadline is
/// an explicit signal (a channel receive with a timeout), never a polling sleep.
pub fn output_within_deadline(cmd: &mut Command) -> Output {
    let child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {cmd:?}: {e}"));
    wait_within_deadline(child, &format!("{cmd:?}"))
}

/// Waits for a started `child` (named `what` in failures) and returns what is left of its
/// output, as [`output_within_deadline`] does.
#[allow(dead_code)] // Not every test binary that includes this file waits on its own children.
pub fn wait_within_deadline(child: Child, what: &str) -> Output {
    let pid = child.id() as libc::pid_t;
    let (done, finished) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = done.send(child.wait_with_output());
    });
    match finished.recv_timeout(PROCESS_DEADLINE) {
        Ok(out) => out.expect("waiting for the process"),
        Err(_) => {
            // Still running, so not yet reaped: the pid is still this child's.
            unsafe { libc::kill(pid, libc::SIGKILL) };
            let out = finished
                .recv_timeout(PROCESS_DEADLINE)
                .map(|o| o.map(|o| String::from_utf8_lossy(&o.stderr).into_owned()));
            panic!("{what} still ran after {PROCESS_DEADLINE:?}; killed. stderr: {out:?}");
        }
    }
}

/// Runs the `petrel` binary of this package with `args` (log level `warn`) and a deadline.
#[allow(dead_code)] // Not every test binary that includes this file runs the CLI this way.
pub fn petrel(args: &[&str]) -> Output {
    output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(args)
            .env("RUST_LOG", "warn"),
    )
}

/// A process's output as text (lossy: a test shows what it got, whatever it is).
#[allow(dead_code)]
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}
