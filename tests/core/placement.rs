//! Where an agent's modules run (`scheduler:` and `long_steps:`): on the agent's own thread
//! under `scheduler: agent_thread`, on the shared runtime when declared `long_steps: true` or
//! when the agent's scheduler is `shared`; `long_steps_nice` runs long-step modules on threads
//! below the agent's; the settings are checked and kept by snapshots.

use std::time::Duration;

use petrel::actors::{Agent, ConfigFile, Context, Module, Output, Ports, Schedule};

use crate::support::{config, refused, registry};

/// `test.where`: its first step writes the name of the thread it ran on to `out/thread`, and
/// that thread's nice value to `out/nice`.
struct Where {
    thread: Output<String>,
    nice: Output<i64>,
}

impl Module for Where {
    const TYPE: &'static str = "test.where";
    const DESCRIPTION: &'static str = "Notes the name and nice value of the thread it steps on.";
    fn declare(ports: &mut Ports) -> Self {
        Where {
            thread: ports.output("out/thread", String::new(), "its thread's name"),
            nice: ports.output("out/nice", 0, "its thread's nice value"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new()
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let name = std::thread::current().name().unwrap_or("").to_string();
        self.nice.set(i64::from(nice()));
        self.thread.set(format!("thread `{name}`"));
        Ok(())
    }
}

/// The calling thread's nice value (per thread on Linux).
fn nice() -> i32 {
    // SAFETY: a plain query of the calling thread.
    unsafe { libc::getpriority(libc::PRIO_PROCESS, 0) }
}

/// Where modules `a` (`test.where`) and `long` (`test.where`, `long_steps` under an agent
/// thread) of agent `r` stepped, scheduled as `scheduler` says (`""`: not said), with the
/// agent-level `fields` (e.g. `long_steps_nice: 7, `): each one's thread and its nice value.
async fn placed(scheduler: &str, fields: &str) -> [(String, i64); 2] {
    let long_steps = match scheduler {
        "agent_thread" | "" => "long_steps: true",
        _ => "",
    };
    let scheduler = match scheduler {
        "" => String::new(),
        said => format!("scheduler: {said}, "),
    };
    let text = format!(
        r#"Agent(name: "r", {scheduler}{fields}modules: [
            (name: "a", type: "test.where"),
            (name: "long", type: "test.where", {long_steps}),
        ])"#
    );
    let mut types = registry();
    types.register::<Where>();
    let agent = Agent::start(&config(&text), &types).await.unwrap();
    let mut seen = Vec::new();
    for module in ["a", "long"] {
        let handle = |path: &str| format!("{module}/{path}");
        let bb = agent.blackboard();
        let thread = bb.handle::<String>(&handle("out/thread")).await.unwrap();
        let nice = bb.handle::<i64>(&handle("out/nice")).await.unwrap();
        let stepped = tokio::time::timeout(Duration::from_secs(20), async {
            while thread.get().is_empty() {
                thread.changed().await;
            }
        })
        .await;
        assert!(stepped.is_ok(), "{module} never stepped");
        // Written before the thread's name: read after it, it is the same step's.
        seen.push((thread.get().to_string(), *nice.get()));
    }
    agent.stop(Duration::from_secs(5)).await;
    [seen.remove(0), seen.remove(0)]
}

/// The threads modules `a` and `long` stepped on (see [`placed`]).
async fn threads(scheduler: &str) -> (String, String) {
    let [(a, _), (long, _)] = placed(scheduler, "").await;
    (a, long)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn under_agent_thread_modules_step_on_the_agents_thread_and_long_steps_do_not() {
    let (a, long) = threads("agent_thread").await;
    assert_eq!(a, "thread `petrel-agent-r`");
    assert_ne!(long, a, "a long-step module runs on the shared runtime");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn long_steps_nice_runs_long_step_modules_that_many_nice_levels_below_the_agents_thread() {
    let [(a, a_nice), (long, long_nice)] = placed("", "long_steps_nice: 7, ").await;
    assert_eq!(a, "thread `petrel-agent-r`");
    assert_eq!(long, "thread `petrel-long-7`");
    assert_eq!(
        i64::from(nice()),
        a_nice,
        "the agent's thread keeps the process's"
    );
    assert_eq!(
        long_nice,
        (a_nice + 7).min(19),
        "7 levels below, at most 19"
    );
    // Without it, they run on the shared runtime at the agent's nice value.
    let [(_, a_nice), (long, long_nice)] = placed("", "").await;
    assert!(!long.contains("petrel-long"), "{long}");
    assert_eq!(long_nice, a_nice);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn by_default_an_agent_has_a_thread_of_its_own() {
    let (a, long) = threads("").await;
    assert_eq!(a, "thread `petrel-agent-r`");
    assert_ne!(long, a, "a long-step module runs on the shared runtime");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn under_the_shared_scheduler_no_module_has_an_agent_thread() {
    let (a, long) = threads("shared").await;
    assert!(!a.contains("petrel-agent"), "{a}");
    assert!(!long.contains("petrel-agent"), "{long}");
}

#[test]
fn long_steps_under_the_shared_scheduler_is_refused_where_it_is_written() {
    let text = "Agent(name: \"r\", scheduler: shared, modules: [\n    (name: \"a\", type: \"demo.counter\", long_steps: true),\n])";
    let file = ConfigFile::parse("bad.ron", text).unwrap();
    let Err(errors) = file.build(&registry()) else {
        panic!("a config with long_steps and no agent thread should be refused");
    };
    let errors = errors.0;
    assert_eq!(errors.len(), 1, "{errors:?}");
    let e = errors[0].to_string();
    assert!(e.starts_with("bad.ron:2:"), "{e}");
    assert!(
        e.contains("`long_steps: true`") && e.contains("scheduler: agent_thread"),
        "{e}"
    );
    let typo = ConfigFile::parse("bad.ron", "Agent(name: \"r\", scheduler: agent_threads)")
        .unwrap_err()
        .to_string();
    assert!(
        typo.contains("agent_threads") && typo.contains("agent_thread"),
        "{typo}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_snapshot_keeps_the_scheduler_and_long_steps() {
    let text = r#"Agent(name: "r", scheduler: agent_thread, long_steps_nice: 4, modules: [
        (name: "a", type: "demo.counter", long_steps: true),
        (name: "b", type: "demo.counter"),
    ])"#;
    let agent = Agent::start(&config(text), &registry()).await.unwrap();
    let snapshot = agent.snapshot().await.unwrap();
    agent.stop(Duration::from_secs(5)).await;
    let resumed = ConfigFile::parse("snapshot.ron", &snapshot).unwrap();
    assert_eq!(
        resumed.config.scheduler.name(),
        "agent_thread",
        "{snapshot}"
    );
    let long: Vec<bool> = resumed
        .config
        .modules
        .iter()
        .map(|m| m.long_steps)
        .collect();
    assert_eq!(long, [true, false], "{snapshot}");
    assert_eq!(resumed.config.long_steps_nice, Some(4), "{snapshot}");
}

#[test]
fn a_long_steps_nice_out_of_range_or_without_an_agent_thread_is_refused_where_it_is_written() {
    let e = refused("Agent(name: \"r\",\n    long_steps_nice: 20, modules: [])");
    assert!(e.starts_with("bad.ron:2:5:"), "{e}");
    assert!(
        e.contains("long_steps_nice is 20; expected") && e.contains("1..=19"),
        "{e}"
    );
    assert!(refused("Agent(name: \"r\", long_steps_nice: 0, modules: [])").contains("1..=19"));
    let e = refused("Agent(name: \"r\", scheduler: shared, long_steps_nice: 5, modules: [])");
    assert!(e.starts_with("bad.ron:1:"), "{e}");
    assert!(e.contains("scheduler: agent_thread"), "{e}");
}
