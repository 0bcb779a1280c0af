//! `realtime_priority:`: the agent's own thread and the fine timer thread run under
//! `SCHED_FIFO`, or, where the OS does not allow it, the agent is refused at start with what
//! to do; a snapshot keeps the setting.

use std::time::Duration;

use petrel::actors::{Agent, ConfigFile};

use crate::support::{config, refused, registry};

/// The scheduling policy and priority of this process's thread named `comm` (a thread's name
/// as the kernel keeps it: its first 15 bytes).
fn policy_of(comm: &str) -> Option<(i32, i32)> {
    for entry in std::fs::read_dir("/proc/self/task").ok()?.flatten() {
        let Some(tid) = entry.file_name().to_str().and_then(|t| t.parse().ok()) else {
            continue;
        };
        let name = std::fs::read_to_string(entry.path().join("comm")).unwrap_or_default();
        if name.trim_end() == comm {
            let mut param = libc::sched_param { sched_priority: 0 };
            // SAFETY: plain queries of a thread of this process, into a valid sched_param.
            let policy = unsafe { libc::sched_getscheduler(tid) };
            unsafe { libc::sched_getparam(tid, &mut param) };
            return Some((policy, param.sched_priority));
        }
    }
    None
}

/// Whether this process may put a thread under `SCHED_FIFO` at `priority`, tried on a thread
/// of its own: what the runtime needs, asked of the OS without it.
fn fifo_allowed(priority: i32) -> bool {
    std::thread::spawn(move || {
        let param = libc::sched_param {
            sched_priority: priority,
        };
        // SAFETY: changes the policy of this short-lived thread only.
        unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) == 0 }
    })
    .join()
    .unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_realtime_priority_runs_the_agent_and_timer_threads_under_sched_fifo_or_is_refused() {
    let text = r#"Agent(name: "rt", realtime_priority: 10, modules: [
        (name: "tick", type: "demo.counter", values: {"params/period_ms": 1}),
    ])"#;
    match Agent::start(&config(text), &registry()).await {
        Ok(agent) => {
            assert_eq!(
                policy_of("petrel-agent-rt"),
                Some((libc::SCHED_FIFO, 10)),
                "the agent's thread"
            );
            let (policy, priority) = policy_of("petrel-fine-tim").expect("the timer thread");
            assert_eq!(policy, libc::SCHED_FIFO, "the fine timer thread");
            assert!(priority >= 10, "{priority}");
            let snapshot = agent.snapshot().await.unwrap();
            agent.stop(Duration::from_secs(5)).await;
            let resumed = ConfigFile::parse("snapshot.ron", &snapshot).unwrap();
            assert_eq!(resumed.config.realtime_priority, Some(10), "{snapshot}");
        }
        Err(e) => {
            let e = e.to_string();
            assert!(
                !fifo_allowed(10),
                "refused although the OS allows SCHED_FIFO here: {e}"
            );
            assert!(
                e.contains("realtime_priority 10") && e.contains("CAP_SYS_NICE"),
                "{e}"
            );
        }
    }
}

#[test]
fn a_realtime_priority_out_of_range_or_without_an_agent_thread_is_refused_where_it_is_written() {
    let e = refused("Agent(name: \"r\",\n    realtime_priority: 100, modules: [])");
    assert!(e.starts_with("bad.ron:2:5:"), "{e}");
    assert!(
        e.contains("realtime_priority is 100; expected") && e.contains("1..=99"),
        "{e}"
    );
    let e = refused("Agent(name: \"r\", scheduler: shared, realtime_priority: 5, modules: [])");
    assert!(e.starts_with("bad.ron:1:"), "{e}");
    assert!(e.contains("scheduler: agent_thread"), "{e}");
    assert!(refused("Agent(name: \"r\", realtime_priority: 0, modules: [])").contains("1..=99"));
}
