//! `Context::settle`: a step lets the modules it woke answer, sees their answer, and is not
//! stepped again for it; a change made after it settled still wakes it.

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

fn registry() -> ModuleRegistry {
    let mut r = crate::support::registry();
    r.register::<Asker>();
    r
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
