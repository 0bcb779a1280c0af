//! Threads below the agent's own for its long-step modules (`long_steps_nice:` of an agent
//! config): a multi-thread runtime per nice offset, shared by every agent of the process that
//! asks for that offset.
//!
//! Why: a module with long steps runs off the agent's thread (`long_steps: true`, or moved by
//! the step budget) so that it never holds the others up inside the process. On a machine whose
//! CPUs it keeps busy, it still competes with the agent's thread for them: a periodic module's
//! tick waits until the OS gives the agent's thread a CPU, up to a time slice (a 1 kHz
//! module's p99 rose from about 0.1 ms alone to up to 0.9 ms beside 20 busy modules on the
//! CI's VM; BENCHMARKS.md, "Long steps below the agent's thread"). Threads with a higher nice value
//! lose such contests and keep only what is left of the CPUs. Unlike `realtime_priority`, any
//! process may raise its own threads' nice values: no root, no `CAP_SYS_NICE`.

use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

use tokio::runtime::{Handle, Runtime};

/// The highest nice value Linux has (the lowest priority).
const MAX_NICE: i32 = 19;

/// The runtimes made so far, by nice offset. Never dropped: their threads serve the process's
/// agents until it exits, like the fine timer's.
static RUNTIMES: OnceLock<Mutex<HashMap<u8, Runtime>>> = OnceLock::new();

/// The runtime whose threads run `offset` nice levels below the calling thread (at most at
/// nice 19), with as many workers as `shared`, made at the first call for that offset.
pub(crate) fn runtime(offset: u8, shared: &Handle) -> Result<Handle, String> {
    let mut runtimes = RUNTIMES
        .get_or_init(Mutex::default)
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    if let Some(runtime) = runtimes.get(&offset) {
        return Ok(runtime.handle().clone());
    }
    // Process-wide threads started later by these threads would inherit their nice value:
    // the fine timer, which the agent's periodic modules tick on, is started here first.
    crate::fine_timer::start();
    let nice = (current_nice() + i32::from(offset)).min(MAX_NICE);
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(shared.metrics().num_workers().max(1))
        .thread_name(format!("petrel-long-{offset}"))
        .on_thread_start(move || set_nice(nice))
        .enable_all()
        .build()
        .map_err(|e| format!("the threads for long steps (long_steps_nice {offset}): {e}"))?;
    let handle = runtime.handle().clone();
    runtimes.insert(offset, runtime);
    Ok(handle)
}

/// The calling thread's nice value (Linux keeps one per thread).
fn current_nice() -> i32 {
    // SAFETY: a query of the calling thread's own nice value (`who` 0): no pointer is passed,
    // and it cannot fail for the calling thread.
    unsafe { libc::getpriority(libc::PRIO_PROCESS, 0) }
}

/// Sets the calling thread's nice value. Raising it never needs a privilege, so a refusal
/// (a sandbox forbidding the call) is reported rather than taken silently.
fn set_nice(nice: i32) {
    // SAFETY: changes the calling thread's own nice value only (`who` 0 is the calling thread
    // on Linux, where the nice value is per thread).
    if unsafe { libc::setpriority(libc::PRIO_PROCESS, 0, nice) } != 0 {
        let e = std::io::Error::last_os_error();
        tracing::warn!(
            nice,
            error = %e,
            "long_steps_nice: the OS refused a nice value for a long-step thread; its modules run at the agent's priority"
        );
    }
}
