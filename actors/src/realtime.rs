//! Real-time priority for the threads periodic modules depend on (`realtime_priority:` of an
//! agent config): the agent's own thread and the process's fine timer thread.
//!
//! Why: beside busy threads (modules with long steps on the shared runtime, other processes),
//! a tick of a periodic module needs two threads to get a CPU in turn, the timer thread and
//! then the agent's; under the ordinary scheduler each may wait a time slice for it. A
//! `SCHED_FIFO` thread runs as soon as it is woken. Linux keeps 5 % of each second for
//! ordinary threads (`sched_rt_runtime_us`), so a real-time thread that never sleeps slows the
//! machine down but does not lock it up; the step budget still moves a module whose steps are
//! long off the agent's thread.

use std::io;

/// Puts `thread` under `SCHED_FIFO` at `priority` (1..=99). Refused without the right to
/// (root, `CAP_SYS_NICE`, or an `RLIMIT_RTPRIO` of at least `priority`).
pub(crate) fn set_fifo(thread: libc::pthread_t, priority: u8) -> io::Result<()> {
    let param = libc::sched_param {
        sched_priority: i32::from(priority),
    };
    // SAFETY: `thread` is a live thread of this process (the callers' threads never exit while
    // the process runs), and `param` is a valid sched_param for the call's duration.
    match unsafe { libc::pthread_setschedparam(thread, libc::SCHED_FIFO, &param) } {
        0 => Ok(()),
        errno => Err(io::Error::from_raw_os_error(errno)),
    }
}

/// What to tell a user whose `realtime_priority` the OS refused.
pub(crate) fn refused(what: &str, priority: u8, e: &io::Error) -> String {
    format!(
        "realtime_priority {priority}: the OS refused SCHED_FIFO for {what} ({e}): run as root, or give the process CAP_SYS_NICE or an RLIMIT_RTPRIO of at least {priority} (`ulimit -r`), or remove realtime_priority"
    )
}
