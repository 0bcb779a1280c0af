//! The step budget on a loaded machine: a step counts the time it ran or blocked, not the time
//! its thread waited for a CPU, so a module the OS keeps waiting stays on its agent's thread,
//! while one that really computes past the budget still moves.
//!
//! The load is made, not hoped for: the module pins its agent's thread to one CPU and the test
//! pins three busy threads there, so every step waits about three times its own work. Every
//! wait is on an observable signal (a property, an event) and bounded by a deadline; the busy
//! threads stop when the test ends or after 30 s, whichever comes first.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use petrel::actors::{Agent, Context, Input, Module, Output, Ports, Schedule};

use crate::support::{config, registry, until};

/// The CPU the busy threads and the module's thread share: the first one this process may use.
fn shared_cpu() -> usize {
    // SAFETY: a zeroed cpu_set_t is a valid empty set, filled by the call.
    let mut set: libc::cpu_set_t = unsafe { std::mem::zeroed() };
    // SAFETY: the size passed is the set's own.
    let got = unsafe { libc::sched_getaffinity(0, std::mem::size_of_val(&set), &mut set) };
    assert_eq!(got, 0, "sched_getaffinity");
    // SAFETY: CPU_ISSET reads the set within its size.
    (0..libc::CPU_SETSIZE as usize)
        .find(|&cpu| unsafe { libc::CPU_ISSET(cpu, &set) })
        .expect("some CPU")
}

/// Pins the calling thread to `cpu`.
fn pin_here(cpu: usize) {
    // SAFETY: as in `shared_cpu`; 0 names the calling thread.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_SET(cpu, &mut set);
        assert_eq!(
            libc::sched_setaffinity(0, std::mem::size_of_val(&set), &set),
            0
        );
    }
}

/// The CPU time the calling thread has used.
fn thread_cpu_time() -> Duration {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec for the call to fill.
    assert_eq!(
        unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) },
        0
    );
    Duration::new(t.tv_sec as u64, t.tv_nsec as u32)
}

/// `test.busy`: every 2 ms, a step that computes for `in/cpu_us` of its thread's CPU time
/// (however long the OS makes that take), after pinning its agent's thread to `in/cpu`.
struct Busy {
    cpu: Input<i64>,
    cpu_us: Input<i64>,
    thread: Output<String>,
    pinned: bool,
}

impl Module for Busy {
    const TYPE: &'static str = "test.busy";
    const DESCRIPTION: &'static str = "Computes for a given CPU time in every step.";
    fn declare(ports: &mut Ports) -> Self {
        Busy {
            cpu: ports.input("in/cpu", 0, "the CPU to pin its thread to"),
            cpu_us: ports.input("in/cpu_us", 0, "CPU time per step, µs"),
            thread: ports.output("out/thread", String::new(), "its thread's name"),
            pinned: false,
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().period(Duration::from_millis(2))
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let name = std::thread::current().name().unwrap_or("").to_string();
        if *self.thread.get() != name {
            self.thread.set(name.clone());
            self.pinned = false;
        }
        // Only the agent's thread: once moved, the module must not pin a shared worker.
        if !self.pinned && name.starts_with("petrel-agent") {
            pin_here(self.cpu.value() as usize);
            self.pinned = true;
        }
        let work = Duration::from_micros(self.cpu_us.value().max(0) as u64);
        let until = thread_cpu_time() + work;
        while thread_cpu_time() < until {
            std::hint::spin_loop();
        }
        Ok(())
    }
}

/// Three threads busy on `cpu` until `stop` or 30 s.
fn hogs(cpu: usize, stop: &Arc<AtomicBool>) -> Vec<std::thread::JoinHandle<()>> {
    (0..3)
        .map(|_| {
            let stop = stop.clone();
            std::thread::spawn(move || {
                pin_here(cpu);
                let until = Instant::now() + Duration::from_secs(30);
                while !stop.load(Ordering::Relaxed) && Instant::now() < until {
                    std::hint::spin_loop();
                }
            })
        })
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_module_kept_waiting_by_the_os_stays_and_one_computing_past_the_budget_moves() {
    let cpu = shared_cpu();
    let text = format!(
        r#"Agent(name: "r", scheduler: agent_thread, step_budget: (mean_us: 5000, steps: 5), modules: [
        (name: "log", type: "test.event_log", links: {{"in/events": "_supervisor/events"}}),
        (name: "busy", type: "test.busy", values: {{"in/cpu": {cpu}, "in/cpu_us": 2000}}),
    ])"#
    );
    let mut types = registry();
    types.register::<Busy>();
    let stop = Arc::new(AtomicBool::new(false));
    let busy_threads = hogs(cpu, &stop);
    let agent = Agent::start(&config(&text), &types).await.unwrap();

    // 2 ms of work a step, sharing its CPU with three busy threads: about 8 ms in wall time.
    let slow = until(&agent, "busy/stats/mean_step_us", |m: &f64| *m > 5000.0).await;
    // Eight windows of five steps, each over the budget in wall time and checked.
    until(&agent, "busy/stats/steps", |s: &i64| *s >= 45).await;
    let kinds = agent
        .blackboard()
        .get::<String>("log/out/kinds")
        .await
        .unwrap();
    assert!(
        !kinds.contains("moved:busy"),
        "moved for the OS's wait (wall mean {slow} µs): {kinds}"
    );
    let thread = agent
        .blackboard()
        .get::<String>("busy/out/thread")
        .await
        .unwrap();
    assert_eq!(*thread, "petrel-agent-r");

    // 8 ms of work a step is over the budget however it is counted.
    agent
        .blackboard()
        .set("busy/in/cpu_us", 8000_i64)
        .await
        .unwrap();
    until(&agent, "log/out/kinds", |k: &String| {
        k.contains("moved:busy")
    })
    .await;
    stop.store(true, Ordering::Relaxed);
    for thread in busy_threads {
        thread.join().unwrap();
    }
    let summary = agent.stop(Duration::from_secs(5)).await;
    let busy = summary.module("busy").unwrap();
    assert_eq!((busy.moves, busy.failures), (1, 0), "{busy:?}");
}
