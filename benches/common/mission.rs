//! The bench modules around a mission (`pnp_reaction`): the work an action enables, and the
//! trigger that makes requests and waits for the mission to acknowledge each.

use petrel::actors::{Context, Input, Module, Output, Ports, Range, Schedule};

/// `bench.work`: when it steps (it must be enabled), copies `in/go` to `out/done`.
pub struct Work {
    go: Input<i64>,
    done: Output<i64>,
}

impl Module for Work {
    const TYPE: &'static str = "bench.work";
    const DESCRIPTION: &'static str = "Copies in/go to out/done when it steps.";
    fn declare(ports: &mut Ports) -> Self {
        Work {
            go: ports.input("in/go", 0, "request number"),
            done: ports.output("out/done", 0, "last request served"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.go)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        self.done.set(self.go.value());
        Ok(())
    }
}

/// `bench.trigger`: when `in/go` is set to N, makes N requests one after the other: bumps
/// `out/request`, then waits for the mission's acknowledgement, its `out/fired` (linked to
/// `in/ack`) grown by `params/firings` since the request (the transitions one request fires,
/// the last of which brings the plan back to where it waits); after the last answer bumps
/// `out/batches`.
///
/// The acknowledgement is a number the mission publishes once per step, after its rounds:
/// the trigger wakes at most once per mission step and compares two integers.
pub struct Trigger {
    go: Input<i64>,
    ack: Input<i64>,
    firings: Input<i64>,
    request: Output<i64>,
    batches: Output<i64>,
    go_seen: u64,
    remaining: i64,
    /// The acknowledgement that answers the request out, if one is out.
    awaited: Option<i64>,
}

impl Module for Trigger {
    const TYPE: &'static str = "bench.trigger";
    const DESCRIPTION: &'static str = "Makes in/go requests, each acknowledged by the mission.";
    fn declare(ports: &mut Ports) -> Self {
        Trigger {
            go: ports.input("in/go", 0, "requests to make"),
            ack: ports.input("in/ack", 0, "the mission's out/fired"),
            firings: ports.param_in(
                "params/firings",
                1,
                Range::new(1.0, 1000.0),
                "transitions the mission fires per request",
            ),
            request: ports.output("out/request", 0, "request number"),
            batches: ports.output("out/batches", 0, "batches finished"),
            go_seen: 0,
            remaining: 0,
            awaited: None,
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.go).on_change(&self.ack)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let go = self.go.read();
        if go.version != self.go_seen {
            self.go_seen = go.version;
            self.remaining = *go;
        }
        let ack = self.ack.value();
        if let Some(awaited) = self.awaited {
            if ack < awaited {
                return Ok(());
            }
            self.awaited = None;
            if self.remaining == 0 {
                self.batches.set(self.batches.value() + 1);
            }
        }
        if self.remaining > 0 {
            self.remaining -= 1;
            self.awaited = Some(ack + self.firings.value());
            self.request.set(self.request.value() + 1);
        }
        Ok(())
    }
}
