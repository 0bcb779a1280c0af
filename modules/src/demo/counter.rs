use petrel_actors::{Context, Module, Output, Param, Ports, Range, Schedule, State};

/// `demo.counter`: counts periodically and publishes `start + count * increment`.
pub struct Counter {
    period_ms: Param<i64>,
    start: Param<f64>,
    increment: Param<f64>,
    count: State<i64>,
    value: Output<f64>,
}

impl Module for Counter {
    const TYPE: &'static str = "demo.counter";
    const DESCRIPTION: &'static str =
        "Counts every period and publishes start + count * increment.";

    fn declare(ports: &mut Ports) -> Self {
        Counter {
            period_ms: ports.param_in(
                "params/period_ms",
                100,
                Range::new(1.0, 3.6e6),
                "time between counts, ms",
            ),
            start: ports.param("params/start", 0.0, "first published value"),
            increment: ports.param("params/increment", 1.0, "added at each count"),
            count: ports.state("state/count", 0, "counts so far (kept across restarts)"),
            value: ports.output("out/value", 0.0, "start + count * increment"),
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::every(super::period(self.period_ms.value()))
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if ctx.cause().first() {
            return Ok(());
        }
        let count = self.count.value() + 1;
        self.count.set(count);
        self.value
            .set(self.start.value() + count as f64 * self.increment.value());
        Ok(())
    }
}
