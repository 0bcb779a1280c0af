use petrel_actors::{Context, Input, Module, Output, Param, Ports, Schedule};

/// `demo.camera`: a stand-in image processor. Its images blur with speed unless
/// `params/deblur` is on; it publishes the resulting sharpness.
pub struct Camera {
    speed: Input<f64>,
    deblur: Param<bool>,
    sharpness: Output<f64>,
}

impl Module for Camera {
    const TYPE: &'static str = "demo.camera";
    const DESCRIPTION: &'static str =
        "Stand-in image processor: sharpness drops with speed unless params/deblur.";

    fn declare(ports: &mut Ports) -> Self {
        Camera {
            speed: ports.input("in/speed", 0.0, "robot speed, m/s"),
            deblur: ports.param(
                "params/deblur",
                false,
                "sharpen motion-blurred images (costs CPU)",
            ),
            sharpness: ports.output("out/sharpness", 1.0, "image sharpness, 0..1"),
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::new()
            .on_change(&self.speed)
            .on_change(&self.deblur)
    }

    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let blur = if self.deblur.value() { 0.2 } else { 1.0 };
        self.sharpness
            .set((1.0 - blur * self.speed.value().abs()).clamp(0.0, 1.0));
        Ok(())
    }
}
