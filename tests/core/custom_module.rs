//! The path a user takes to add a module type: implement `Module`, register it with `Petrel`.

use petrel::actors::{
    Agent, ConfigFile, Context, Input, Module, Output, Ports, Schedule, DEFAULT_STOP_TIMEOUT,
};

use crate::support::advance;

/// A user's module: a moving average over the last `params/window` values of its input.
struct MovingAverage {
    input: Input<f64>,
    window: Input<i64>,
    out: Output<f64>,
    recent: Vec<f64>,
}

impl Module for MovingAverage {
    const TYPE: &'static str = "user.moving_average";
    const DESCRIPTION: &'static str = "Mean of the last params/window values of in/value.";
    fn declare(ports: &mut Ports) -> Self {
        MovingAverage {
            input: ports.input("in/value", 0.0, "value to average"),
            window: ports.param("params/window", 4, "how many values"),
            out: ports.output("out/mean", 0.0, "the moving average"),
            recent: Vec::new(),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.input)
    }
    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if ctx.cause().first() {
            return Ok(());
        }
        self.recent.push(self.input.value());
        let window = self.window.value().max(1) as usize;
        if self.recent.len() > window {
            self.recent.remove(0);
        }
        self.out
            .set(self.recent.iter().sum::<f64>() / self.recent.len() as f64);
        Ok(())
    }
}

#[tokio::test(start_paused = true)]
async fn a_user_module_registered_through_the_builder_runs_in_an_agent() {
    let petrel = petrel::Petrel::new().module::<MovingAverage>();
    let described = petrel
        .registry()
        .get("user.moving_average")
        .expect("registered")
        .properties();
    assert!(described
        .iter()
        .any(|p| p.path == "params/window" && p.default_text() == "4"));
    let file = ConfigFile::parse(
        "user.ron",
        r#"Agent(name: "r1", modules: [
            (name: "count", type: "demo.counter", values: {"params/period_ms": 10}),
            (name: "avg", type: "user.moving_average", values: {"params/window": 3}, links: {"in/value": "count/out/value"}),
        ])"#,
    )
    .unwrap();
    let agent = Agent::start(&file, petrel.registry()).await.unwrap();
    advance(55).await;
    assert_eq!(
        *agent.blackboard().get::<f64>("avg/out/mean").await.unwrap(),
        4.0,
        "mean of 3, 4, 5"
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}
