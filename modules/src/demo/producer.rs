use petrel_actors::{Context, Module, Param, Ports, QueueWriter, Range, Schedule, State};

/// `demo.producer`: pushes consecutively numbered items into a queue.
pub struct Producer {
    period_ms: Param<i64>,
    batch: Param<i64>,
    next: State<i64>,
    items: QueueWriter<i64>,
}

impl Module for Producer {
    const TYPE: &'static str = "demo.producer";
    const DESCRIPTION: &'static str =
        "Pushes numbered items (0, 1, 2, ...) into out/items, params/batch per period.";

    fn declare(ports: &mut Ports) -> Self {
        Producer {
            period_ms: ports.param_in(
                "params/period_ms",
                50,
                Range::new(1.0, 3.6e6),
                "time between batches, ms",
            ),
            batch: ports.param_in(
                "params/batch",
                1,
                Range::new(0.0, 10000.0),
                "items pushed per period",
            ),
            next: ports.state(
                "state/next",
                0,
                "number of the next item (kept across restarts)",
            ),
            items: ports.queue_out("out/items", 64, "numbered items"),
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::every(super::period(self.period_ms.value()))
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        if ctx.cause().first() {
            return Ok(());
        }
        let mut next = self.next.value();
        for _ in 0..self.batch.value().max(0) {
            self.items.push(next);
            next += 1;
        }
        self.next.set(next);
        Ok(())
    }
}
