//! Your own module type in your own `petrel` binary.
//!
//! ```text
//! cargo run --example custom_module -- modules describe user.moving_average
//! cargo run --example custom_module -- run examples/custom_module.ron --for 3s
//! ```

use petrel::actors::{Context, Input, Module, Output, Ports, Schedule};

/// Publishes the mean of the last `params/window` values of `in/value`.
struct MovingAverage {
    input: Input<f64>,
    window: Input<i64>,
    mean: Output<f64>,
    recent: std::collections::VecDeque<f64>,
}

impl Module for MovingAverage {
    const TYPE: &'static str = "user.moving_average";
    const DESCRIPTION: &'static str = "Mean of the last params/window values of in/value.";

    fn declare(ports: &mut Ports) -> Self {
        MovingAverage {
            input: ports.input("in/value", 0.0, "value to average"),
            window: ports.param("params/window", 4, "how many recent values"),
            mean: ports.output("out/mean", 0.0, "the moving average"),
            recent: Default::default(),
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.input) // step whenever the input changes
    }

    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        self.recent.push_back(self.input.value());
        while self.recent.len() > self.window.value().max(1) as usize {
            self.recent.pop_front();
        }
        self.mean
            .set(self.recent.iter().sum::<f64>() / self.recent.len() as f64);
        Ok(())
    }
}

fn main() -> std::process::ExitCode {
    petrel::Petrel::new().module::<MovingAverage>().main()
}

// `cargo test` runs this example's config with the module (Cargo.toml: `test = true`).
#[cfg(test)]
mod tests {
    #[test]
    fn the_example_config_runs_and_averages_the_counter() {
        let dir = std::env::temp_dir().join(format!("petrel-example-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let snapshot = dir.join("snapshot.ron");
        let code = petrel::Petrel::new()
            .module::<super::MovingAverage>()
            .main_with([
                "petrel",
                "run",
                concat!(env!("CARGO_MANIFEST_DIR"), "/examples/custom_module.ron"),
                "--for",
                "1s",
                "--no-remote",
                "--snapshot-out",
                snapshot.to_str().unwrap(),
            ]);
        assert_eq!(code, std::process::ExitCode::SUCCESS);
        let config = petrel::actors::ConfigFile::load(&snapshot).unwrap().config;
        let value = |module: &str, path: &str| -> f64 {
            let m = config.modules.iter().find(|m| m.name == module).unwrap();
            m.values[path].clone().into_rust().unwrap()
        };
        let mean = value("avg", "out/mean");
        // The mean of five consecutive counts is the middle one; the counter may have counted
        // once more after the average stopped (modules stop in reverse order).
        let count = value("count", "out/value");
        assert!(mean >= 1.0 && mean.fract() == 0.0, "mean {mean}");
        assert!(
            (count - 3.0..=count - 2.0).contains(&mean),
            "mean {mean} of counts up to {count}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
