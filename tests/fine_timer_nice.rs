//! `long_steps_nice` must not lower the fine timer thread, which every periodic module of the
//! process ticks on. A thread inherits its creator's nice value and cannot raise it back
//! without a privilege, so a timer started by the first tick of a long-step module (on a
//! lowered thread) stayed lowered. Its own test binary: a fresh process, where no other test
//! has started the timer already.

use std::time::Duration;

use petrel::actors::{Agent, ConfigFile};

/// The nice value of this process's thread named `comm` (the kernel's first 15 bytes).
fn nice_of(comm: &str) -> Option<i32> {
    for entry in std::fs::read_dir("/proc/self/task").ok()?.flatten() {
        let name = std::fs::read_to_string(entry.path().join("comm")).unwrap_or_default();
        if name.trim_end() == comm {
            let tid: u32 = entry.file_name().to_str()?.parse().ok()?;
            // SAFETY: a plain query of a thread of this process.
            return Some(unsafe { libc::getpriority(libc::PRIO_PROCESS, tid) });
        }
    }
    None
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_fine_timer_keeps_the_agents_priority_when_a_lowered_module_ticks_first() {
    // The only periodic module is a long-step one: its tick is the timer's first use.
    let text = r#"Agent(name: "n", long_steps_nice: 10, modules: [
        (name: "slow", type: "demo.counter", values: {"params/period_ms": 5}, long_steps: true),
    ])"#;
    let file = ConfigFile::parse("nice.ron", text).unwrap();
    let agent = Agent::start(&file, petrel::Petrel::new().registry())
        .await
        .unwrap();
    let steps = agent
        .blackboard()
        .handle::<i64>("slow/stats/steps")
        .await
        .unwrap();
    let ticked = tokio::time::timeout(Duration::from_secs(20), async {
        while *steps.get() < 3 {
            steps.changed().await;
        }
    })
    .await;
    let timer = nice_of("petrel-fine-tim");
    let long = nice_of("petrel-long-10");
    agent.stop(Duration::from_secs(5)).await;
    assert!(ticked.is_ok(), "the periodic module never ticked");
    // SAFETY: a plain query of the calling thread.
    let mine = unsafe { libc::getpriority(libc::PRIO_PROCESS, 0) };
    assert_eq!(long, Some((mine + 10).min(19)), "the long-step threads");
    assert_eq!(timer, Some(mine), "the fine timer thread");
}
