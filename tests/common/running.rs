//! A `petrel` process running in the background, its log read line by line so that a test
//! can wait for a line (with a deadline), signal the process, and collect how it ended.

use std::io::BufRead;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc;

use super::bounded::PROCESS_DEADLINE;

/// A running `petrel`; killed when dropped, so a failed test leaves no process behind.
pub struct Running {
    pub child: Child,
    /// Log lines, read on their own thread so that waiting for one has a deadline.
    log: mpsc::Receiver<String>,
    /// Standard output, read whole on its own thread.
    stdout: Option<std::thread::JoinHandle<String>>,
}

impl Running {
    /// Starts `petrel ARGS` with an `info` log, reachable by tools through the discovery
    /// records in `records`.
    pub fn start(args: &[&str], records: &std::path::Path) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(args)
            .env("RUST_LOG", "info")
            .env("PETREL_RUNTIME_DIR", records)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("petrel runs");
        let stderr = std::io::BufReader::new(child.stderr.take().unwrap());
        let (send, log) = mpsc::channel();
        std::thread::spawn(move || {
            for line in stderr.lines().map_while(Result::ok) {
                if send.send(line).is_err() {
                    break;
                }
            }
        });
        let mut stdout = child.stdout.take().unwrap();
        let stdout = std::thread::spawn(move || {
            let mut text = String::new();
            let _ = std::io::Read::read_to_string(&mut stdout, &mut text);
            text
        });
        Running {
            child,
            log,
            stdout: Some(stdout),
        }
    }

    /// Reads the log up to the first line containing `needle` and returns it with the lines
    /// before it; fails if none comes within the process deadline.
    pub fn wait_for(&mut self, needle: &str) -> (String, Vec<String>) {
        let deadline = std::time::Instant::now() + PROCESS_DEADLINE;
        let mut before = Vec::new();
        loop {
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            match self.log.recv_timeout(left) {
                Ok(line) if line.contains(needle) => return (line, before),
                Ok(line) => before.push(line),
                Err(e) => panic!("no `{needle}` in petrel's log ({e}); before: {before:#?}"),
            }
        }
    }

    /// Sends signal `name` (`INT`, `TERM`, `HUP`...) to the process.
    pub fn signal(&self, name: &str) {
        let sent = Command::new("kill")
            .args([&format!("-{name}"), &self.child.id().to_string()])
            .status()
            .expect("kill runs");
        assert!(sent.success());
    }

    /// Waits (within the process deadline) for the process to end; returns how it ended, its
    /// standard output and the rest of its log.
    #[allow(dead_code)] // Not every test binary that includes this file waits for the end.
    pub fn finish(mut self) -> (ExitStatus, String, String) {
        let mut log = Vec::new();
        let deadline = std::time::Instant::now() + PROCESS_DEADLINE;
        // The log closes when the process ends (or hands its stderr to nobody else).
        loop {
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            match self.log.recv_timeout(left) {
                Ok(line) => log.push(line),
                Err(mpsc::RecvTimeoutError::Disconnected) => break,
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    panic!("petrel still ran after {PROCESS_DEADLINE:?}; log: {log:#?}")
                }
            }
        }
        let status = self.child.wait().expect("waiting for petrel");
        let stdout = self.stdout.take().unwrap().join().unwrap();
        (status, stdout, log.join("\n"))
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        if self.child.try_wait().ok().flatten().is_none() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}
