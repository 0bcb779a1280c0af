use petrel_actors::{Context, Input, Module, Output, Param, Ports, Range, Schedule};

/// `demo.scale`: `out = factor * in + offset`, optionally low-pass filtered.
pub struct Scale {
    input: Input<f64>,
    factor: Param<f64>,
    offset: Param<f64>,
    smoothing: Param<f64>,
    out: Output<f64>,
}

impl Module for Scale {
    const TYPE: &'static str = "demo.scale";
    const DESCRIPTION: &'static str =
        "Writes factor * in/value + offset, low-pass filtered by params/smoothing.";

    fn declare(ports: &mut Ports) -> Self {
        Scale {
            input: ports.input("in/value", 0.0, "value to scale"),
            factor: ports.param_in("params/factor", 1.0, Range::new(-1e9, 1e9), "multiplier"),
            offset: ports.param_in(
                "params/offset",
                0.0,
                Range::new(-1e9, 1e9),
                "added after scaling",
            ),
            smoothing: ports.param_in(
                "params/smoothing",
                0.0,
                Range::new(0.0, 1.0),
                "0 = no filter .. 1 = frozen: weight of the previous output",
            ),
            out: ports.output("out/value", 0.0, "the scaled (and smoothed) value"),
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::new()
            .on_change(&self.input)
            .on_change(&self.factor)
            .on_change(&self.offset)
    }

    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let target = self.factor.value() * self.input.value() + self.offset.value();
        let alpha = self.smoothing.value().clamp(0.0, 1.0);
        // A past output that is not a number (a NaN input once) is no history to smooth
        // with: weighted even by 0 it stays NaN, and the output never recovered.
        let previous = Some(self.out.value()).filter(|p| p.is_finite());
        self.out.set(match previous {
            Some(previous) => alpha * previous + (1.0 - alpha) * target,
            None => target,
        });
        Ok(())
    }
}
