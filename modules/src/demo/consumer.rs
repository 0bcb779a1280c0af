use petrel_actors::{Context, Module, Output, Param, Ports, QueueReader, Range, Schedule, State};

/// `state/last` before the first item.
const NONE_YET: i64 = -1;

/// `demo.consumer`: reads numbered items and checks that none is missing or repeated, from the
/// first one it receives. A queue delivers an item to a reader once, so numbers that go back
/// are not repeats but a producer that started over (a new process numbering from 0): counted
/// in `out/restarts`, and checked on from there.
pub struct Consumer {
    items: QueueReader<i64>,
    report_every: Param<i64>,
    last: State<i64>,
    received: Output<i64>,
    gaps: Output<i64>,
    duplicates: Output<i64>,
    restarts: Output<i64>,
}

impl Module for Consumer {
    const TYPE: &'static str = "demo.consumer";
    const DESCRIPTION: &'static str =
        "Consumes numbered items from in/items and counts gaps and duplicates.";

    fn declare(ports: &mut Ports) -> Self {
        Consumer {
            items: ports.queue_in("in/items", "numbered items to check"),
            report_every: ports.param_in(
                "params/report_every",
                0,
                Range::new(0.0, 1e9),
                "print a line every N items (0 = never)",
            ),
            last: ports.state(
                "state/last",
                NONE_YET,
                "number of the last item seen (kept across restarts); -1: none yet",
            ),
            received: ports.output("out/received", 0, "items received"),
            gaps: ports.output("out/gaps", 0, "items missing between consecutive numbers"),
            duplicates: ports.output(
                "out/duplicates",
                0,
                "items numbered as the one before (delivered twice)",
            ),
            restarts: ports.output(
                "out/restarts",
                0,
                "times the numbers went back: the producer started over (a new process)",
            ),
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::new().on_items(&self.items)
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let batch = self.items.drain();
        if batch.is_empty() {
            return Ok(());
        }
        let (mut last, mut gaps, mut dups, mut restarts) = (
            self.last.value(),
            self.gaps.value(),
            self.duplicates.value(),
            self.restarts.value(),
        );
        for item in &batch {
            let n = *item.value;
            // The first item starts the count, less what this reader lost before it: items sent
            // before the consumer was linked (an agent that joins a team late) are not missing.
            if last == NONE_YET {
                last = (n - 1 - self.items.dropped()).max(NONE_YET);
            }
            if n == last {
                dups += 1;
            } else if n < last {
                restarts += 1;
                petrel_actors::outln!(
                    "[{}] item #{n} after #{last}: the producer started over; checking on from #{n}",
                    ctx.module()
                );
                last = n;
            } else {
                gaps += n - last - 1;
                last = n;
            }
        }
        let before = self.received.value();
        let received = before + batch.len() as i64;
        self.last.set(last);
        self.gaps.set(gaps);
        self.duplicates.set(dups);
        self.restarts.set_if_changed(restarts);
        self.received.set(received);
        let every = self.report_every.value();
        self.report(ctx, every > 0 && received / every != before / every);
        Ok(())
    }

    async fn cleanup(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        self.report(ctx, self.report_every.value() > 0 && !ctx.restarting());
        Ok(())
    }
}

impl Consumer {
    /// Prints the counters when `now`.
    fn report(&self, ctx: &Context, now: bool) {
        if now {
            let (received, last) = (self.received.value(), self.last.value());
            let (gaps, dups) = (self.gaps.value(), self.duplicates.value());
            let restarts = match self.restarts.value() {
                0 => String::new(),
                n => format!(" (the producer started over {n} time(s))"),
            };
            petrel_actors::outln!(
                "[{}] received {received} items, last #{last}, gaps {gaps}, duplicates {dups}{restarts}",
                ctx.module()
            );
        }
    }
}
