use std::time::Duration;

use petrel_actors::{Context, Input, Module, Param, Ports, Range, Schedule};
use tokio::time::Instant;

/// `demo.printer`: prints its input to standard output when it changes, at most every `params/every_ms`.
pub struct Printer {
    input: Input<f64>,
    label: Param<String>,
    every_ms: Param<i64>,
    last_print: Option<Instant>,
}

impl Module for Printer {
    const TYPE: &'static str = "demo.printer";
    const DESCRIPTION: &'static str =
        "Prints in/value on standard output when it changes (rate-limited).";

    fn declare(ports: &mut Ports) -> Self {
        Printer {
            input: ports.input("in/value", 0.0, "value to print"),
            label: ports.param(
                "params/label",
                String::new(),
                "text before the value (default: module name)",
            ),
            every_ms: ports.param_in(
                "params/every_ms",
                0,
                Range::new(0.0, 3.6e6),
                "print at most once per this many ms (0 = every change)",
            ),
            last_print: None,
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.input)
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let every = Duration::from_millis(self.every_ms.value().max(0) as u64);
        if ctx.cause().first()
            || self
                .last_print
                .is_some_and(|t| ctx.now().duration_since(t) < every)
        {
            return Ok(());
        }
        self.last_print = Some(ctx.now());
        let label = self.label.get();
        let label = if label.is_empty() {
            ctx.module()
        } else {
            label.as_str()
        };
        let sample = self.input.read();
        petrel_actors::outln!("[{label}] {:.3} (#{})", *sample, sample.version);
        Ok(())
    }
}
