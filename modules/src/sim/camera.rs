//! A simulated grey camera: one ray per image column, then the sensor's physics.
//!
//! Geometry: each column casts a ray through the grid (walls 1 m high, camera 0.3 m above the
//! floor); victims are 0.3 m high cylinders of 0.25 m radius covered with a checkerboard of
//! 6 cm squares (bright 0.95 / dark 0.1 albedo), their visible signature. Walls darken with
//! distance, so far victims are small and faint.
//!
//! Sensor: the light on what a column sees (1 in the open, [`DARK_LIGHT`] where the ray ends
//! in a dark area, a wall lit by the space in front of its face) times the exposure makes
//! photons; shot noise is their square root plus a read-noise floor, and
//! `gain` scales signal and noise alike before 8-bit quantization. So a dark scene is dim and
//! noisy, a longer exposure cleans it up, and gain brightens it. Motion blurs over the
//! exposure: turning and driving smear columns (a box blur of `turn rate x focal length +
//! speed x 150 px/m` over the exposure time), and rough floor shakes the image up and down and
//! smears rows (`speed x 2000 px/m` over the exposure). A checkerboard smeared by more than a square loses its contrast: that is how
//! blur makes victims vanish.

use petrel_actors::{Pose2, Twist2};
use rand::Rng;
use rand_distr::{Distribution, Normal};

use super::error::{positive, ParamError};
use super::features::WorldFeatures;
use super::grid::Grid;
use super::raycast::cast_ray;

/// Light in dark areas, relative to the open.
pub const DARK_LIGHT: f64 = 0.06;
/// Camera height above the floor, metres.
pub const CAMERA_HEIGHT: f64 = 0.3;
/// Victim radius and height, metres.
pub const VICTIM_RADIUS: f64 = 0.25;
/// Victim height, metres.
pub const VICTIM_HEIGHT: f64 = 0.3;
/// Edge of the victims' checkerboard squares, metres.
pub const CHECKER: f64 = 0.06;
/// Height of another robot's body as the camera sees it, metres (taller than the camera, so
/// a robot in view fills the lower half of the image over its width).
pub const ROBOT_HEIGHT: f64 = 0.4;
/// Another robot's uniform grey albedo: no checkerboard, so it is never taken for a victim.
const ROBOT_ALBEDO: f64 = 0.45;
const WALL_HEIGHT: f64 = 1.0;
/// Photons per millisecond of exposure for a white surface in full light.
const PHOTONS_PER_MS: f64 = 60.0;
/// Photons that fill the 8-bit range at gain 1.
const FULL_SCALE: f64 = 600.0;
/// How far in front of a wall's face its light is taken, metres: the face the camera sees is
/// lit by the space in front of it, and a dark area's edge often lies on the face itself (a
/// room's `dark:` rectangle drawn to its walls), where rounding would light columns at random.
const LIGHT_PROBE: f64 = 0.01;
/// Read noise, photons (std).
const READ_NOISE: f64 = 3.0;
/// Sideways smear per metre per second of forward speed, pixels per second of exposure.
const SPEED_BLUR: f64 = 150.0;
/// Vertical smear per metre per second on rough floor, pixels per second of exposure.
const ROUGH_BLUR: f64 = 2000.0;

/// Camera parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraConfig {
    /// Image width, pixels (default 160).
    pub width: u32,
    /// Image height, pixels (default 120).
    pub height: u32,
    /// Horizontal field of view, radians (default 60°).
    pub fov: f64,
    /// Exposure time, milliseconds (default 10).
    pub exposure_ms: f64,
    /// Sensor gain (default 1).
    pub gain: f64,
    /// Farthest visible surface, metres (default 10).
    pub range_max: f64,
}

impl Default for CameraConfig {
    fn default() -> Self {
        CameraConfig {
            width: 160,
            height: 120,
            fov: 60f64.to_radians(),
            exposure_ms: 10.0,
            gain: 1.0,
            range_max: 10.0,
        }
    }
}

impl CameraConfig {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), ParamError> {
        if !(8..=1024).contains(&self.width) || !(8..=1024).contains(&self.height) {
            return Err(ParamError {
                param: "camera/size".into(),
                message: format!(
                    "expected 8..=1024 pixels each way, got {} x {}",
                    self.width, self.height
                ),
            });
        }
        if !(self.fov > 0.0 && self.fov < std::f64::consts::PI) {
            return Err(ParamError {
                param: "camera/fov_deg".into(),
                message: format!(
                    "expected degrees in (0, 180), got {}",
                    petrel_actors::short_number(self.fov.to_degrees())
                ),
            });
        }
        if !(self.exposure_ms > 0.0 && self.exposure_ms <= 200.0) {
            return Err(ParamError {
                param: "camera/exposure_ms".into(),
                message: format!(
                    "expected milliseconds in (0, 200], got {}",
                    petrel_actors::short_number(self.exposure_ms)
                ),
            });
        }
        if !(self.gain >= 1.0 && self.gain <= 16.0) {
            return Err(ParamError {
                param: "camera/gain".into(),
                message: format!(
                    "expected a gain in [1, 16], got {}",
                    petrel_actors::short_number(self.gain)
                ),
            });
        }
        positive("camera/range_max", self.range_max)
    }

    /// Focal length, pixels.
    pub fn focal(&self) -> f64 {
        self.width as f64 / 2.0 / (self.fov / 2.0).tan()
    }

    /// Bearing of the centre of column `col` in the camera frame (left positive), radians.
    pub fn bearing(&self, col: f64) -> f64 {
        ((self.width as f64 / 2.0 - col) / self.focal()).atan()
    }
}

/// What the robot is doing while the shutter is open.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct CameraMotion {
    /// Actual speed.
    pub speed: Twist2,
    /// Whether the robot is on rough floor.
    pub rough: bool,
}

/// Renders one frame from `pose`: row-major grey pixels, top row first.
pub fn render(
    grid: &Grid,
    features: &WorldFeatures,
    pose: Pose2,
    motion: CameraMotion,
    cfg: &CameraConfig,
    rng: &mut impl Rng,
) -> Vec<u8> {
    render_among(grid, features, &[], pose, motion, cfg, rng)
}

/// What a column's ray meets before the wall: a victim (with the lateral coordinate on its
/// surface, for the checkerboard) or another robot.
#[derive(Clone, Copy)]
enum Body {
    Victim(f64),
    Robot,
}

/// [`render`] in a world shared with other robots: `robots` are their footprints
/// `(x, y, radius)` (not the camera's own), seen as plain grey cylinders [`ROBOT_HEIGHT`] high.
pub fn render_among(
    grid: &Grid,
    features: &WorldFeatures,
    robots: &[(f64, f64, f64)],
    pose: Pose2,
    motion: CameraMotion,
    cfg: &CameraConfig,
    rng: &mut impl Rng,
) -> Vec<u8> {
    let (w, h) = (cfg.width as usize, cfg.height as usize);
    let f = cfg.focal();
    let exposure_s = cfg.exposure_ms / 1000.0;
    // Rough floor tilts the camera by a random pitch for this frame.
    let shake = if motion.rough {
        rng.random_range(-4.0..=4.0) * (0.3 + motion.speed.v.abs())
    } else {
        0.0
    };
    let horizon = h as f64 / 2.0 + shake;
    let mut radiance = vec![0f32; w * h];
    for col in 0..w {
        let bearing = cfg.bearing(col as f64 + 0.5);
        let angle = pose.theta() + bearing;
        let (s, c) = angle.sin_cos();
        // Depth along the optical axis, so walls stay straight (no fish-eye).
        let axial = bearing.cos();
        let wall = cast_ray(grid, pose.x(), pose.y(), angle, cfg.range_max);
        // Light where the column's ray ends (a victim in a dark room is dark from anywhere).
        let light_at = |d: f64| {
            let (x, y) = (pose.x() + d * c, pose.y() + d * s);
            if features.is_dark(x, y) {
                DARK_LIGHT as f32
            } else {
                1.0
            }
        };
        let wall_depth = (wall * axial).max(1e-3);
        let wall_shade = (0.55 / (1.0 + 0.12 * wall)) as f32;
        // The nearest victim or robot this column's ray meets before the wall.
        let mut body: Option<(f64, Body)> = None; // (distance, what)
        let cylinders = features
            .victims
            .iter()
            .map(|v| (v.0.x, v.0.y, VICTIM_RADIUS, true))
            .chain(robots.iter().map(|&(x, y, r)| (x, y, r, false)));
        for (bx, by, radius, is_victim) in cylinders {
            let (dx, dy) = (bx - pose.x(), by - pose.y());
            let along = dx * c + dy * s;
            let across = -dx * s + dy * c;
            if along <= 0.0 || across.abs() >= radius {
                continue;
            }
            let d = along - (radius * radius - across * across).sqrt();
            if d > 0.05 && d < wall && body.is_none_or(|(best, _)| d < best) {
                // Arc length around the victim, so squares keep their size across it.
                let what = match is_victim {
                    true => Body::Victim(radius * (across / radius).asin()),
                    false => Body::Robot,
                };
                body = Some((d, what));
            }
        }
        for row in 0..h {
            let y = row as f64 + 0.5 - horizon; // pixels below the horizon
            let value = body.and_then(|(d, what)| {
                let z = CAMERA_HEIGHT - y * d * axial / f; // height of the point seen
                match what {
                    Body::Victim(lateral) if (0.0..=VICTIM_HEIGHT).contains(&z) => {
                        let square =
                            (z / CHECKER).floor() as i64 + (lateral / CHECKER).floor() as i64;
                        Some(if square.rem_euclid(2) == 0 { 0.95 } else { 0.1 })
                    }
                    Body::Robot if (0.0..=ROBOT_HEIGHT).contains(&z) => Some(ROBOT_ALBEDO),
                    _ => None,
                }
            });
            let lit = match (value, body) {
                (Some(_), Some((d, _))) => light_at(d),
                _ => light_at((wall - LIGHT_PROBE).max(0.0)),
            };
            radiance[row * w + col] = lit
                * value.unwrap_or_else(|| {
                    let z = CAMERA_HEIGHT - y * wall_depth / f;
                    if z < 0.0 {
                        0.3 // floor
                    } else if z > WALL_HEIGHT {
                        0.12 // ceiling
                    } else {
                        wall_shade as f64
                    }
                }) as f32;
        }
    }
    // Pixels swept while the shutter is open: turning sweeps the whole image sideways,
    // driving sweeps the scene outwards (taken as sideways too), rough floor jolts it.
    let blur_h = (motion.speed.omega.abs() * f + motion.speed.v.abs() * SPEED_BLUR) * exposure_s;
    let blur_v = if motion.rough {
        motion.speed.v.abs() * ROUGH_BLUR * exposure_s
    } else {
        0.0
    };
    box_blur(&mut radiance, w, h, blur_h.round() as usize, 1);
    box_blur(&mut radiance, w, h, blur_v.round() as usize, w);
    let photons_per_unit = cfg.exposure_ms * PHOTONS_PER_MS;
    let unit = Normal::new(0.0, 1.0).expect("unit normal");
    radiance
        .iter()
        .map(|&r| {
            let photons = r as f64 * photons_per_unit;
            let noise = (photons + READ_NOISE * READ_NOISE).sqrt() * unit.sample(rng);
            let value = cfg.gain * (photons + noise) * 255.0 / FULL_SCALE;
            value.round().clamp(0.0, 255.0) as u8
        })
        .collect()
}

/// Averages each pixel with the `len - 1` following ones along `stride` (1 = along rows,
/// width = along columns), clamping at the border; `len` < 2 leaves the image as it is.
fn box_blur(img: &mut [f32], w: usize, h: usize, len: usize, stride: usize) {
    if len < 2 {
        return;
    }
    let (lines, count, step_line) = if stride == 1 { (h, w, w) } else { (w, h, 1) };
    let mut line = vec![0f32; count];
    for l in 0..lines {
        let base = l * step_line;
        for (i, v) in line.iter_mut().enumerate() {
            *v = img[base + i * stride];
        }
        // Running sum over a centred window.
        let half = len / 2;
        for i in 0..count {
            let lo = i.saturating_sub(half);
            let hi = (i + len - half).min(count);
            let sum: f32 = line[lo..hi].iter().sum();
            img[base + i * stride] = sum / (hi - lo) as f32;
        }
    }
}

#[cfg(test)]
mod tests;
