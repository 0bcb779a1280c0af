//! The agent's `step_budget` under `scheduler: agent_thread`: a module whose steps exceed it
//! is moved to the shared runtime (a `moved` supervisor event), after which a step that blocks
//! its thread no longer holds up the agent's other modules; out-of-range budgets are refused
//! where they are written.
//!
//! Every wait is on an observable signal (an event, a property) and bounded by a deadline.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use petrel::actors::{Agent, ConfigFile, Context, Input, Module, Output, Ports, Schedule};

use crate::support::{config, registry, until};

/// Released by the test when `test.slow` may stop holding its thread.
static RELEASED: AtomicBool = AtomicBool::new(false);
/// The longest `test.slow` holds its thread, whatever the test does.
const HOLD_LIMIT: Duration = Duration::from_secs(30);

/// `test.slow`: every 2 ms, a step that blocks its thread for 3 ms and notes the thread's
/// name in `out/thread`; once `in/hold` is true, a step that blocks until the test releases
/// it (`out/holding` says it began).
struct Slow {
    hold: Input<bool>,
    thread: Output<String>,
    holding: Output<bool>,
}

impl Module for Slow {
    const TYPE: &'static str = "test.slow";
    const DESCRIPTION: &'static str = "Blocks its thread in every step.";
    fn declare(ports: &mut Ports) -> Self {
        Slow {
            hold: ports.input("in/hold", false, "block until released"),
            thread: ports.output("out/thread", String::new(), "its thread's name"),
            holding: ports.output("out/holding", false, "a blocking step began"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().period(Duration::from_millis(2))
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let name = std::thread::current().name().unwrap_or("").to_string();
        if *self.thread.get() != name {
            self.thread.set(name);
        }
        if !self.hold.value() {
            std::thread::sleep(Duration::from_millis(3));
            return Ok(());
        }
        self.holding.set(true);
        let until = Instant::now() + HOLD_LIMIT;
        while !RELEASED.load(Ordering::Acquire) && Instant::now() < until {
            std::thread::sleep(Duration::from_millis(1));
        }
        self.holding.set(false);
        Ok(())
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_module_over_the_step_budget_moves_and_its_blocking_steps_hold_up_no_one() {
    let text = r#"Agent(name: "r", scheduler: agent_thread, step_budget: (mean_us: 1000, steps: 5), modules: [
        (name: "log", type: "test.event_log", links: {"in/events": "_supervisor/events"}),
        (name: "count", type: "demo.counter", values: {"params/period_ms": 5}),
        (name: "slow", type: "test.slow"),
    ])"#;
    let mut types = registry();
    types.register::<Slow>();
    let agent = Agent::start(&config(text), &types).await.unwrap();

    let kinds = until(&agent, "log/out/kinds", |k: &String| {
        k.contains("moved:slow")
    })
    .await;
    assert!(!kinds.contains("moved:count"), "{kinds}");
    assert!(
        !kinds.contains("failed"),
        "a move is not a failure: {kinds}"
    );
    let moved_to = until(&agent, "slow/out/thread", |t: &String| {
        !t.is_empty() && t != "petrel-agent-r"
    })
    .await;
    assert!(!moved_to.starts_with("petrel-agent"), "{moved_to}");

    // Now a step of `slow` that never returns until released holds a shared worker only.
    agent.blackboard().set("slow/in/hold", true).await.unwrap();
    until(&agent, "slow/out/holding", |h: &bool| *h).await;
    let before = *agent
        .blackboard()
        .get::<f64>("count/out/value")
        .await
        .unwrap();
    let after = until(&agent, "count/out/value", |v: &f64| *v >= before + 3.0).await;
    RELEASED.store(true, Ordering::Release);
    assert!(after >= before + 3.0);
    let summary = agent.stop(Duration::from_secs(5)).await;
    let slow = summary.module("slow").unwrap();
    assert_eq!(slow.failures, 0, "{slow:?}");
    assert_eq!((slow.moves, slow.restarts), (1, 0), "{slow:?}");
}

#[test]
fn a_step_budget_out_of_range_is_refused_where_it_is_written() {
    let text = "Agent(name: \"r\", scheduler: agent_thread,\n    step_budget: (mean_us: 10, steps: 0, held_ms: 5),\n    modules: [])";
    let file = ConfigFile::parse("bad.ron", text).unwrap();
    let Err(errors) = file.build(&registry()) else {
        panic!("a step budget out of range should be refused");
    };
    let errors: Vec<String> = errors.0.iter().map(|e| e.to_string()).collect();
    assert_eq!(errors.len(), 3, "{errors:?}");
    assert!(
        errors[0].starts_with("bad.ron:2:19") && errors[0].contains("mean_us is 10; expected 0"),
        "{errors:?}"
    );
    assert!(
        errors[1].starts_with("bad.ron:2:") && errors[1].contains("steps is 0; expected 1.."),
        "{errors:?}"
    );
    assert!(
        errors[2].starts_with("bad.ron:2:42") && errors[2].contains("held_ms is 5; expected 0"),
        "{errors:?}"
    );
    let unknown = ConfigFile::parse("bad.ron", "Agent(name: \"r\", step_budget: (mean_ms: 1))")
        .unwrap_err()
        .to_string();
    assert!(unknown.contains("mean_ms"), "{unknown}");
}
