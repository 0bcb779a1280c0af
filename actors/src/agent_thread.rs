//! An agent's own thread (`scheduler: agent_thread`): an OS thread with a current-thread tokio
//! runtime, where the agent's blackboard, supervisor and module actors run.
//!
//! Why: a module's write wakes its readers. On a multi-thread runtime a woken task may be
//! stolen, and tokio unparks a second worker to do it (an eventfd write and a futex wake,
//! several µs on a VM); with every actor of the agent on one thread, a hand-over between two
//! modules is a same-thread task wake. The actors stay ractor actors with their own mailboxes:
//! only where their tasks run changes, and tools, the CLI and tests reach them as before
//! (mailboxes and cells work across runtimes). ractor spawns an actor on the runtime it is
//! spawned from, so the supervisor spawned here spawns its modules here too.

use std::future::Future;
use std::os::unix::thread::JoinHandleExt;

use tokio::runtime::{Handle, RuntimeFlavor};
use tokio::sync::oneshot;

/// An agent's thread and runtime. Dropping it ends the runtime on its own thread, cancelling
/// the tasks still there.
pub(crate) struct AgentThread {
    runtime: Handle,
    /// The caller's runtime, where modules with `long_steps` run.
    shared: Handle,
    shutdown: Option<oneshot::Sender<()>>,
}

impl AgentThread {
    /// A thread of its own for agent `name`, if the caller runs on a multi-thread runtime. On a
    /// current-thread runtime (`None`) the agent runs in place: it has one thread already, and
    /// a paused test clock must stay the agent's clock. With a `realtime_priority`, the thread
    /// and the fine timer's run under `SCHED_FIFO` (see `realtime.rs`); an error says the OS
    /// refused.
    pub fn start(name: &str, realtime_priority: Option<u8>) -> Result<Option<AgentThread>, String> {
        let shared = Handle::current();
        if shared.runtime_flavor() == RuntimeFlavor::CurrentThread {
            return Ok(None);
        }
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            // A short spin before parking while work comes back quickly (see `park_spin.rs`).
            .on_thread_park(crate::park_spin::before_park)
            .on_thread_unpark(crate::park_spin::after_unpark)
            .build()
            .map_err(|e| e.to_string())?;
        let handle = runtime.handle().clone();
        let (shutdown, ended) = oneshot::channel::<()>();
        let thread = std::thread::Builder::new()
            .name(format!("petrel-agent-{name}"))
            .spawn(move || {
                crate::fine_timer::mark_agent_thread();
                // A current-thread runtime runs its tasks only inside `block_on`.
                runtime.block_on(async {
                    let _ = ended.await;
                });
                drop(runtime);
            })
            .map_err(|e| e.to_string())?;
        let agent = AgentThread {
            runtime: handle,
            shared,
            shutdown: Some(shutdown),
        };
        if let Some(priority) = realtime_priority {
            // Dropping `agent` on an error ends the thread.
            crate::realtime::set_fifo(thread.as_pthread_t(), priority)
                .map_err(|e| crate::realtime::refused("the agent's thread", priority, &e))?;
            crate::fine_timer::raise_priority(priority)
                .map_err(|e| crate::realtime::refused("the fine timer thread", priority, &e))?;
        }
        Ok(Some(agent))
    }

    /// The shared runtime, where modules with `long_steps` run (unless `long_steps_nice` gives
    /// them threads of their own).
    pub fn shared(&self) -> Handle {
        self.shared.clone()
    }

    /// Runs `future` on the agent's thread and waits for its output.
    pub async fn run<F>(&self, future: F) -> Result<F::Output, String>
    where
        F: Future + Send + 'static,
        F::Output: Send + 'static,
    {
        run_on(&self.runtime, future).await
    }
}

/// Runs `future` as a task of `runtime` and waits for its output; a panic there goes on here.
/// An error says the runtime shut down first.
pub(crate) async fn run_on<F>(runtime: &Handle, future: F) -> Result<F::Output, String>
where
    F: Future + Send + 'static,
    F::Output: Send + 'static,
{
    match runtime.spawn(future).await {
        Ok(output) => Ok(output),
        Err(e) if e.is_panic() => std::panic::resume_unwind(e.into_panic()),
        Err(e) => Err(format!("its runtime shut down: {e}")),
    }
}

impl Drop for AgentThread {
    fn drop(&mut self) {
        if let Some(shutdown) = self.shutdown.take() {
            let _ = shutdown.send(());
        }
    }
}
