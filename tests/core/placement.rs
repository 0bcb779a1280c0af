//! Where an agent's modules run (`scheduler:` and `long_steps:`): on the agent's own thread
//! under `scheduler: agent_thread`, on the shared runtime when declared `long_steps: true` or
//! when the agent's scheduler is `shared`; the settings are checked and kept by snapshots.

use std::time::Duration;

use petrel::actors::{Agent, ConfigFile, Context, Module, Output, Ports, Schedule};

use crate::support::{config, registry};

/// `test.where`: its first step writes the name of the thread it ran on to `out/thread`.
struct Where {
    thread: Output<String>,
}

impl Module for Where {
    const TYPE: &'static str = "test.where";
    const DESCRIPTION: &'static str = "Notes the name of the thread it steps on.";
    fn declare(ports: &mut Ports) -> Self {
        Where {
            thread: ports.output("out/thread", String::new(), "its thread's name"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new()
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let name = std::thread::current().name().unwrap_or("").to_string();
        self.thread.set(format!("thread `{name}`"));
        Ok(())
    }
}

/// The threads modules `a` (`test.where`) and `long` (`test.where`, `long_steps` under an
/// agent thread) of agent `r` stepped on, scheduled as `scheduler` says (`""`: not said).
async fn threads(scheduler: &str) -> (String, String) {
    let long_steps = match scheduler {
        "agent_thread" | "" => "long_steps: true",
        _ => "",
    };
    let scheduler = match scheduler {
        "" => String::new(),
        said => format!("scheduler: {said}, "),
    };
    let text = format!(
        r#"Agent(name: "r", {scheduler}modules: [
            (name: "a", type: "test.where"),
            (name: "long", type: "test.where", {long_steps}),
        ])"#
    );
    let mut types = registry();
    types.register::<Where>();
    let agent = Agent::start(&config(&text), &types).await.unwrap();
    let mut seen = Vec::new();
    for module in ["a", "long"] {
        let thread = agent
            .blackboard()
            .handle::<String>(&format!("{module}/out/thread"))
            .await
            .unwrap();
        let stepped = tokio::time::timeout(Duration::from_secs(20), async {
            while thread.get().is_empty() {
                thread.changed().await;
            }
        })
        .await;
        assert!(stepped.is_ok(), "{module} never stepped");
        seen.push(thread.get().to_string());
    }
    agent.stop(Duration::from_secs(5)).await;
    (seen.remove(0), seen.remove(0))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn under_agent_thread_modules_step_on_the_agents_thread_and_long_steps_do_not() {
    let (a, long) = threads("agent_thread").await;
    assert_eq!(a, "thread `petrel-agent-r`");
    assert_ne!(long, a, "a long-step module runs on the shared runtime");
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
    let text = r#"Agent(name: "r", scheduler: agent_thread, modules: [
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
}
