//! How long the calling thread has waited for a CPU: the second field of Linux's
//! `/proc/thread-self/schedstat` (`run_delay`, in ns), the time it was runnable but not running.
//!
//! The step budget subtracts this wait from a step's wall time, so that a step the OS kept
//! waiting on a loaded machine does not look long (`supervision/long_steps.rs`). Each thread
//! keeps its file open, so a read is one `pread` (about 0.7 µs on the 2 vCPU VM,
//! BENCHMARKS.md); the module actor reads it only at both ends of the steps the watch asks for.

use std::cell::{Cell, OnceCell};
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::time::Duration;

thread_local! {
    /// This thread's `schedstat`, opened at the first read; `None` where there is none.
    static SCHEDSTAT: OnceCell<Option<File>> = const { OnceCell::new() };
    /// A per-thread address, to tell whether two reads were made on the same thread.
    static THREAD_TAG: Cell<u8> = const { Cell::new(0) };
}

/// A reading of the calling thread's run-queue wait so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunQueueMark {
    waited: Duration,
    thread: usize,
}

impl RunQueueMark {
    /// The calling thread's run-queue wait so far; `None` where the OS does not tell it.
    pub fn now() -> Option<RunQueueMark> {
        let waited = SCHEDSTAT.with(|file| {
            let file = file
                .get_or_init(|| File::open("/proc/thread-self/schedstat").ok())
                .as_ref()?;
            let mut buf = [0u8; 96];
            let read = file.read_at(&mut buf, 0).ok()?;
            run_delay(&buf[..read])
        })?;
        Some(RunQueueMark {
            waited,
            thread: THREAD_TAG.with(|tag| tag as *const Cell<u8> as usize),
        })
    }

    /// The calling thread's run-queue wait since `self`; `None` when it cannot be told (another
    /// thread took `self`, or the OS does not tell it).
    pub fn elapsed(&self) -> Option<Duration> {
        let now = RunQueueMark::now()?;
        (now.thread == self.thread).then(|| now.waited.saturating_sub(self.waited))
    }
}

/// Whether the OS tells this thread's run-queue wait.
pub fn run_queue_known() -> bool {
    RunQueueMark::now().is_some()
}

/// The `run_delay` field of a `schedstat` line ("cpu_ns run_delay_ns timeslices").
fn run_delay(line: &[u8]) -> Option<Duration> {
    let field = line.split(|b| b.is_ascii_whitespace()).nth(1)?;
    let ns = std::str::from_utf8(field).ok()?.parse::<u64>().ok()?;
    Some(Duration::from_nanos(ns))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_second_field_is_the_run_delay() {
        assert_eq!(
            run_delay(b"312979187 57002310 213\n"),
            Some(Duration::from_nanos(57002310))
        );
        assert_eq!(run_delay(b"312979187"), None);
        assert_eq!(run_delay(b"1 x 2"), None);
        assert_eq!(run_delay(b""), None);
    }

    #[test]
    fn a_mark_tells_the_wait_on_its_own_thread_only() {
        let Some(mark) = RunQueueMark::now() else {
            return; // No schedstat here: nothing to read.
        };
        assert!(mark.elapsed().is_some());
        let elsewhere = std::thread::spawn(move || mark.elapsed()).join().unwrap();
        assert_eq!(elsewhere, None);
    }
}
