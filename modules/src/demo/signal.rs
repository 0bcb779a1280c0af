use std::f64::consts::TAU;

use petrel_actors::{Context, Module, Output, Param, Ports, Range, Schedule};

/// `demo.signal`: a periodic waveform generator (sine, square, triangle, sawtooth), to stand in
/// for sensors such as speed or terrain roughness.
pub struct Signal {
    sample_ms: Param<i64>,
    waveform: Param<String>,
    period_s: Param<f64>,
    amplitude: Param<f64>,
    offset: Param<f64>,
    value: Output<f64>,
}

/// The waveforms [`wave`] knows.
const WAVEFORMS: &[&str] = &["sine", "square", "triangle", "sawtooth"];

/// The waveform value in `[-1, 1]` at `phase` (in periods).
fn wave(waveform: &str, phase: f64) -> Option<f64> {
    let p = phase.rem_euclid(1.0);
    Some(match waveform {
        "sine" => (TAU * p).sin(),
        "square" => {
            if p < 0.5 {
                1.0
            } else {
                -1.0
            }
        }
        "triangle" => 1.0 - 4.0 * (p - 0.5).abs(),
        "sawtooth" => 2.0 * p - 1.0,
        _ => return None,
    })
}

impl Module for Signal {
    const TYPE: &'static str = "demo.signal";
    const DESCRIPTION: &'static str =
        "Publishes offset + amplitude * waveform(t / period) every sample period.";

    fn declare(ports: &mut Ports) -> Self {
        Signal {
            sample_ms: ports.param_in(
                "params/sample_ms",
                50,
                Range::new(1.0, 3.6e6),
                "time between samples, ms",
            ),
            // One of the known words, checked wherever it is written: an unknown waveform set
            // at run time had made the signal a silent 0.
            waveform: ports.param_one_of(
                "params/waveform",
                "sine",
                WAVEFORMS,
                "sine, square, triangle or sawtooth",
            ),
            period_s: ports.param_in(
                "params/period_s",
                10.0,
                Range::new(0.001, 1e6),
                "waveform period, s",
            ),
            amplitude: ports.param_in(
                "params/amplitude",
                1.0,
                Range::new(-1e9, 1e9),
                "half the peak-to-peak swing",
            ),
            offset: ports.param_in(
                "params/offset",
                0.0,
                Range::new(-1e9, 1e9),
                "value around which the signal swings",
            ),
            value: ports.output("out/value", 0.0, "the current sample"),
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::every(super::period(self.sample_ms.value()))
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        let t = ctx.steps() as f64 * self.sample_ms.value() as f64 / 1000.0;
        let phase = t / self.period_s.value().max(1e-9);
        // Only known words pass the parameter's check.
        let w = wave(&self.waveform.get(), phase).unwrap_or(0.0);
        self.value
            .set(self.offset.value() + self.amplitude.value() * w);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::wave;

    #[test]
    fn every_listed_waveform_is_known() {
        for w in super::WAVEFORMS {
            assert!(wave(w, 0.3).is_some(), "{w}");
        }
    }

    #[test]
    fn waveforms_hit_their_extremes() {
        assert!((wave("sine", 0.25).unwrap() - 1.0).abs() < 1e-12);
        assert_eq!(wave("square", 0.75), Some(-1.0));
        assert_eq!(wave("triangle", 0.5), Some(1.0));
        assert_eq!(wave("sawtooth", 0.0), Some(-1.0));
        assert_eq!(wave("noise", 0.0), None);
    }
}
