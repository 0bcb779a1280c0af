//! `vision.victim_detector`: camera images in, victim detections and image quality out.

use anyhow::anyhow;
use petrel_actors::{Context, Image, Input, Module, Output, Ports, QueueReader, Range, Schedule};

use crate::vision::{detect, Detections, DetectorParams};

/// `vision.victim_detector`: wraps [`detect`].
pub struct VictimDetector {
    images: QueueReader<Image>,
    threshold: Input<f64>,
    deblur: Input<f64>,
    roi: Input<Vec<f64>>,
    fov_deg: Input<f64>,
    _exposure: Input<f64>,
    _gain: Input<f64>,
    detections: Output<Detections>,
    seen: Output<bool>,
    brightness: Output<f64>,
    sharpness: Output<f64>,
    frames: Output<i64>,
    latency: Output<f64>,
}

impl Module for VictimDetector {
    const TYPE: &'static str = "vision.victim_detector";
    const DESCRIPTION: &'static str =
        "Finds victims (checkerboard signature) in camera images; reports bearing, range, confidence and image quality.";

    fn declare(ports: &mut Ports) -> Self {
        VictimDetector {
            images: ports.queue_in("in/image", "camera frames (mono8)"),
            threshold: ports.param_in("params/threshold", 12.0, Range::new(0.1, 255.0), "texture above the noise floor that marks a victim, grey levels (0, 255]; read every frame"),
            deblur: ports.param_in("params/deblur", 0.0, Range::new(0.0, 4.0), "sharpening amount before detection, [0, 4], 0 = off (costs CPU); read every frame"),
            roi: {
                let roi = ports.param("params/roi", vec![0.0, 0.5, 1.0, 1.0], "region searched, fractions `[x0, y0, x1, y1]` of the image, top-left origin");
                ports.accept_last(roi_fits, "fractions `[x0, y0, x1, y1]` with 0 <= x0 < x1 <= 1 and 0 <= y0 < y1 <= 1");
                roi
            },
            fov_deg: ports.param_in("params/fov_deg", 60.0, Range::new(1.0, 179.0), "the camera's horizontal field of view, degrees"),
            // What this detector needs from its camera: a driver whose settings are linked here
            // follows them (a team robot's body in the world agent does; the detector itself
            // only reads the images).
            _exposure: ports.param_in("params/camera/exposure_ms", 10.0, Range::new(0.01, 200.0), "the camera exposure this detector asks of the driver, ms (0, 200] (context rules raise it in the dark)"),
            _gain: ports.param_in("params/camera/gain", 1.0, Range::new(1.0, 16.0), "the camera gain this detector asks of the driver, [1, 16]"),
            detections: ports.output("out/detections", Detections::default(), "victims in the latest frame: bearing (rad, left positive), range (m), confidence (this and the other frame outputs are stamped with the frame's time)"),
            seen: ports.output("out/victimSeen", false, "the latest frame holds a victim"),
            brightness: ports.output("out/brightness", 0.5, "mean grey level of the latest frame, 0..1"),
            sharpness: ports.output("out/sharpness", 0.0, "mean absolute Laplacian of the latest frame, grey levels"),
            frames: ports.output("out/frames", 0, "frames processed"),
            latency: ports.output("out/latency", 0.0, "age of the latest frame when its results were published, s (wall time: how far behind the camera the detector runs)"),
        }
    }

    fn schedule(&self) -> Schedule {
        Schedule::new().on_items(&self.images)
    }

    async fn init(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        self.params()?;
        Ok(())
    }

    async fn step(&mut self, ctx: &mut Context) -> anyhow::Result<()> {
        // Only the newest frame matters: a detector that falls behind skips, never lags.
        let latest = self.images.drain().pop();
        let Some(image) = latest else {
            return Ok(());
        };
        let params = self.params()?;
        let img = &image.value;
        let out = detect(&img.data, img.width as usize, img.height as usize, &params).ok_or_else(
            || {
                anyhow!(
                    "in/image: expected {} x {} mono8 pixels, got {} bytes ({})",
                    img.width,
                    img.height,
                    img.data.len(),
                    img.encoding
                )
            },
        )?;
        let taken = image.stamp;
        let age = ctx.now().saturating_duration_since(taken);
        self.latency.set(age.as_secs_f64());
        // The rest describes the frame: stamped when it was taken, not when it was processed,
        // so readers place it from the robot's pose of that moment.
        self.brightness.set_at(out.brightness, taken);
        self.sharpness.set_at(out.sharpness, taken);
        let seen = !out.detections.is_empty();
        if seen != self.seen.value() {
            self.seen.set_at(seen, taken);
        }
        self.detections.set_at(Detections(out.detections), taken);
        // Last: a module woken by a new frame count finds this frame's quality already there.
        self.frames.set_at(self.frames.value() + 1, taken);
        Ok(())
    }
}

impl VictimDetector {
    fn params(&self) -> anyhow::Result<DetectorParams> {
        let roi = self.roi.get();
        let roi: [f64; 4] = roi.as_slice().try_into().map_err(|_| {
            anyhow!("invalid parameter `params/roi`: expected `[x0, y0, x1, y1]`, got {roi:?}")
        })?;
        let params = DetectorParams {
            threshold: self.threshold.value(),
            deblur: self.deblur.value(),
            roi,
            fov: self.fov_deg.value().to_radians(),
        };
        params
            .validate()
            .map_err(|e| anyhow!("invalid parameter {e}"))?;
        Ok(params)
    }
}

/// Whether `roi` is one `params/roi` takes: a region the detector accepts.
#[allow(clippy::ptr_arg)] // the parameter is a `Vec<f64>`: a rule on it takes one
fn roi_fits(roi: &Vec<f64>) -> bool {
    <[f64; 4]>::try_from(roi.as_slice()).is_ok_and(|roi| {
        DetectorParams {
            roi,
            ..DetectorParams::default()
        }
        .validate()
        .is_ok()
    })
}
