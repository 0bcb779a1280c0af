//! `Context::settle`: a step lets the modules it woke answer, sees their answer, and is not
//! stepped again for it; a change made after it settled still wakes it.
//! `Context::settle_agent`: a step lets a whole chain of modules downstream run.

use petrel::actors::{Agent, Context, Input, Module, ModuleRegistry, Output, Ports, Schedule};

/// `test.asker`: when `in/go` changes, writes `out/question` (= `in/go`), settles, and
/// records in `out/answered` whether `in/answer` already equals the question.
pub struct Asker {
    go: Input<f64>,
    answer: Input<f64>,
    question: Output<f64>,
    answered: Output<i64>,
    settled: Output<i64>,
}

impl Module for Asker {
    const TYPE: &'static str = "test.asker";
    const DESCRIPTION: &'static str = "Asks, settles, and checks the answer in the same step.";
    fn declare(ports: &mut Ports) -> Self {
        Asker {
            go: ports.input("in/go", 0.0, "the next question"),
            answer: ports.input("in/answer", 0.0, "the answer"),
            question: ports.output("out/question", 0.0, "the question"),
            answered: ports.output("out/answered", 0, "steps that saw their answer"),
            settled: ports.output("out/settled", 0, "settles that reported a change"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.go).on_change(&self.answer)
    }
    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let go = self.go.value();
        if go == self.question.value() {
            return Ok(());
        }
        self.question.set(go);
        if ctx.settle().await {
            self.settled.set(self.settled.value() + 1);
        }
        if self.answer.value() == go {
            self.answered.set(self.answered.value() + 1);
        }
        Ok(())
    }
}

/// Values `test.feeder` writes in one step.
const FED: i64 = 20;

/// `test.feeder`: when `in/go` changes, writes 1, 2, ... [`FED`] to `out/value` in one step,
/// settling the agent after each, and counts in `out/answered` the values that came back
/// through `in/back` before the next was written (`settle` = "one": one yield instead).
pub struct Feeder {
    go: Input<f64>,
    back: Input<f64>,
    settle: Input<String>,
    value: Output<f64>,
    answered: Output<i64>,
    quiet: Output<i64>,
}

impl Module for Feeder {
    const TYPE: &'static str = "test.feeder";
    const DESCRIPTION: &'static str = "Writes a burst of values, settling the agent after each.";
    fn declare(ports: &mut Ports) -> Self {
        Feeder {
            go: ports.input("in/go", 0.0, "a change starts a burst"),
            back: ports.input("in/back", 0.0, "the value at the end of the chain"),
            settle: ports.param("params/settle", "agent".to_string(), "agent or one"),
            value: ports.output("out/value", 0.0, "the value fed"),
            answered: ports.output("out/answered", 0, "values back before the next"),
            quiet: ports.output("out/quiet", 0, "settles after which the agent was quiet"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.go)
    }
    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if ctx.cause().first() {
            return Ok(());
        }
        let (mut answered, mut quiet) = (0, 0);
        for k in 1..=FED {
            self.value.set(k as f64);
            match self.settle.get().as_str() {
                "one" => {
                    ctx.settle().await;
                }
                _ => quiet += i64::from(ctx.settle_agent().await),
            }
            if self.back.value() == k as f64 {
                answered += 1;
            }
        }
        self.quiet.set(quiet);
        self.answered.set(answered);
        Ok(())
    }
}

fn registry() -> ModuleRegistry {
    let mut r = crate::support::registry();
    r.register::<Asker>();
    r.register::<Feeder>();
    r
}

/// A feeder and a chain of three echoes back to it, settled as `settle` says (and `more`
/// modules beside).
fn chain(scheduler: &str, settle: &str) -> String {
    chain_with(scheduler, settle, "")
}

fn chain_with(scheduler: &str, settle: &str, more: &str) -> String {
    format!(
        r#"Agent(name: "r1", scheduler: {scheduler}, modules: [{more}
        (name: "feeder", type: "test.feeder", values: {{"params/settle": "{settle}"}},
         links: {{"in/back": "e3/out/value"}}),
        (name: "e1", type: "test.echo", links: {{"in/value": "feeder/out/value"}}),
        (name: "e2", type: "test.echo", links: {{"in/value": "e1/out/value"}}),
        (name: "e3", type: "test.echo", links: {{"in/value": "e2/out/value"}}),
    ])"#
    )
}

/// Starts a burst and returns how many of its values came back before the next, and after
/// how many settles the agent was quiet.
async fn burst(text: &str) -> (i64, i64) {
    let agent = Agent::start(&crate::support::config(text), &registry())
        .await
        .unwrap();
    let answered = fire(&agent, 1.0).await;
    let quiet = *agent
        .blackboard()
        .get::<i64>("feeder/out/quiet")
        .await
        .unwrap();
    let summary = agent.stop(petrel::actors::DEFAULT_STOP_TIMEOUT).await;
    assert_eq!(summary.failures(), 0, "{summary}");
    (answered, quiet)
}

/// Starts a burst of the feeder with `go` = `n` (a change) and returns how many of its
/// values came back before the next, once it ended (within 20 s).
async fn fire(agent: &Agent, n: f64) -> i64 {
    let bb = agent.blackboard();
    let answered = bb.handle::<i64>("feeder/out/answered").await.unwrap();
    let before = answered.read().version;
    bb.handle::<f64>("feeder/in/go").await.unwrap().set(n);
    let waited = tokio::time::timeout(std::time::Duration::from_secs(20), async {
        while answered.read().version == before {
            answered.changed().await;
        }
    })
    .await;
    assert!(waited.is_ok(), "the burst should end");
    *answered.get()
}

#[tokio::test(start_paused = true)]
async fn settling_the_agent_lets_a_chain_downstream_answer_every_value() {
    assert_eq!(burst(&chain("shared", "agent")).await, (FED, FED));
    // One yield lets the first echo run, not the chain: the measure can fail.
    assert!(burst(&chain("shared", "one")).await.0 < FED);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn settling_the_agent_on_its_own_thread_lets_a_chain_answer_every_value() {
    assert_eq!(burst(&chain("agent_thread", "agent")).await, (FED, FED));
}

/// A module that is never quiet: each settle gives up (after its yields, then once after its
/// millisecond waits), and the chain still answered every value meanwhile. On the wall clock:
/// a paused one never advances while a module is always runnable.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn settling_beside_a_module_that_is_never_quiet_gives_up_and_the_chain_still_answers() {
    // An echo of its own output writes at every step, so it wakes itself for ever.
    let looper = r#"(name: "looper", type: "test.echo", links: {"in/value": "looper/out/value"}),"#;
    let text = chain_with("agent_thread", "agent", looper);
    assert_eq!(burst(&text).await, (FED, 0));
}

/// Modules added while the agent runs are waited for too: the feeder's first burst goes
/// through one echo; then two more join the chain, and the second burst through all three
/// comes back whole (with the modules of the first call alone, none came back in time).
#[tokio::test(start_paused = true)]
async fn settling_the_agent_waits_for_modules_added_while_it_runs() {
    use petrel::actors::ModuleConfig;
    let text = r#"Agent(name: "r1", modules: [
        (name: "feeder", type: "test.feeder", links: {"in/back": "e1/out/value"}),
        (name: "e1", type: "test.echo", links: {"in/value": "feeder/out/value"}),
    ])"#;
    let agent = Agent::start(&crate::support::config(text), &registry())
        .await
        .unwrap();
    assert_eq!(fire(&agent, 1.0).await, FED, "through one echo");
    for (name, source) in [("e2", "e1/out/value"), ("e3", "e2/out/value")] {
        let echo = ModuleConfig {
            name: name.into(),
            type_name: "test.echo".into(),
            links: [("in/value".to_string(), source.into())].into(),
            ..Default::default()
        };
        agent.modules().add(echo).await.unwrap();
    }
    let bb = agent.blackboard();
    bb.link("feeder/in/back", "e3/out/value").await.unwrap();
    assert_eq!(
        fire(&agent, 2.0).await,
        FED,
        "through three echoes, two added"
    );
    let summary = agent.stop(petrel::actors::DEFAULT_STOP_TIMEOUT).await;
    assert_eq!(summary.failures(), 0, "{summary}");
}

const CONFIG: &str = r#"Agent(name: "r1", modules: [
    (name: "asker", type: "test.asker", links: {"in/answer": "echo/out/value"}),
    (name: "echo", type: "test.echo", links: {"in/value": "asker/out/question"}),
])"#;

#[tokio::test(start_paused = true)]
async fn a_settled_step_sees_the_answer_and_is_not_stepped_again_for_it() {
    let agent = Agent::start(&crate::support::config(CONFIG), &registry())
        .await
        .unwrap();
    let bb = agent.blackboard();
    let go = bb.handle::<f64>("asker/in/go").await.unwrap();
    let answered = bb.handle::<i64>("asker/out/answered").await.unwrap();
    for k in 1..=5 {
        go.set(k as f64);
        crate::support::advance(1).await;
        assert_eq!(*answered.get(), k, "question {k} answered within its step");
    }
    let settled = *bb.get::<i64>("asker/out/settled").await.unwrap();
    assert_eq!(settled, 5, "each settle reported the answer");
    let summary = agent.stop(petrel::actors::DEFAULT_STOP_TIMEOUT).await;
    // The first step and the one the echo's first write woke, then one per question: the
    // answers woke no step of their own.
    assert_eq!(summary.module("asker").unwrap().steps, 2 + 5);
}

#[tokio::test(start_paused = true)]
async fn a_change_after_settling_still_wakes_the_module() {
    let agent = Agent::start(&crate::support::config(CONFIG), &registry())
        .await
        .unwrap();
    let bb = agent.blackboard();
    let go = bb.handle::<f64>("asker/in/go").await.unwrap();
    let question = bb.handle::<f64>("asker/out/question").await.unwrap();
    go.set(1.0);
    crate::support::advance(1).await;
    // Written after the step settled and ended: the asker must step for it.
    go.set(2.0);
    crate::support::advance(1).await;
    assert_eq!(*question.get(), 2.0);
    let summary = agent.stop(petrel::actors::DEFAULT_STOP_TIMEOUT).await;
    // Two at start (see above), then one per question.
    assert_eq!(summary.module("asker").unwrap().steps, 2 + 2);
}
