//! A simulated robot: a circular base with kinematics, odometry and an optional laser.

use std::f64::consts::PI;

use crate::seeded::SeededRng;
use petrel_actors::{LaserScan, Pose2, Twist2};
use rand_distr::{Distribution, Normal};

use super::error::{non_negative, positive, ParamError};
use super::grid::Grid;
use super::kinematics::{integrate, limit_command, DriveKind, Limits};
use super::raycast::cast_ray;

/// A planar laser scanner attached to a robot.
#[derive(Clone, Debug, PartialEq)]
pub struct LaserConfig {
    /// Sensor pose in the robot frame (default: at the robot centre, looking forward).
    pub mount: Pose2,
    /// Number of rays (default 181).
    pub rays: usize,
    /// Field of view, radians, centred on the sensor's x axis (default pi = 180 degrees).
    pub fov: f64,
    /// Maximum range, metres; rays that hit nothing report it (default 8.0).
    pub range_max: f64,
    /// Standard deviation of Gaussian range noise, metres (default 0 = exact).
    pub range_noise_std: f64,
    /// Scans per second of simulated time; `None` (default) scans at every step.
    pub rate_hz: Option<f64>,
}

impl Default for LaserConfig {
    fn default() -> Self {
        LaserConfig {
            mount: Pose2::default(),
            rays: 181,
            fov: PI,
            range_max: 8.0,
            range_noise_std: 0.0,
            rate_hz: None,
        }
    }
}

impl LaserConfig {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), ParamError> {
        if self.rays < 2 {
            return Err(ParamError {
                param: "rays".into(),
                message: format!("expected at least 2 rays, got {}", self.rays),
            });
        }
        positive("fov", self.fov)?;
        positive("range_max", self.range_max)?;
        non_negative("range_noise_std", self.range_noise_std)?;
        if let Some(rate) = self.rate_hz {
            positive("rate_hz", rate)?;
        }
        Ok(())
    }
}

/// Gaussian odometry noise, applied to each step's motion increment.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct OdomNoise {
    /// Relative std of the translation increment (0.02 = 2 % of distance travelled).
    pub trans_std: f64,
    /// Relative std of the rotation increment.
    pub rot_std: f64,
    /// Heading std added per metre travelled, rad/m.
    pub rot_per_trans_std: f64,
}

/// Everything that defines a simulated robot.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotConfig {
    /// Radius of the circular footprint, metres (default 0.2).
    pub radius: f64,
    /// Drive kind (default differential).
    pub drive: DriveKind,
    /// Speed and acceleration limits.
    pub limits: Limits,
    /// Odometry noise; `None` (default) gives exact odometry.
    pub odom_noise: Option<OdomNoise>,
    /// Attached laser; default: one [`LaserConfig::default`].
    pub laser: Option<LaserConfig>,
}

impl Default for RobotConfig {
    fn default() -> Self {
        RobotConfig {
            radius: 0.2,
            drive: DriveKind::Differential,
            limits: Limits::default(),
            odom_noise: None,
            laser: Some(LaserConfig::default()),
        }
    }
}

impl RobotConfig {
    /// The default robot, carrying `laser`.
    pub fn with_laser(laser: LaserConfig) -> Self {
        RobotConfig {
            laser: Some(laser),
            ..RobotConfig::default()
        }
    }

    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("radius", self.radius)?;
        self.limits.validate()?;
        if let Some(n) = &self.odom_noise {
            non_negative("trans_std", n.trans_std)?;
            non_negative("rot_std", n.rot_std)?;
            non_negative("rot_per_trans_std", n.rot_per_trans_std)?;
        }
        self.laser.as_ref().map_or(Ok(()), LaserConfig::validate)
    }
}

/// Dynamic state of one simulated robot.
#[derive(Clone, Debug)]
pub(crate) struct Robot {
    pub(crate) config: RobotConfig,
    pub(crate) pose: Pose2,
    pub(crate) odom: Pose2,
    pub(crate) speed: Twist2,
    pub(crate) command: Twist2,
    pub(crate) collisions: u64,
    pub(crate) in_contact: bool,
    pub(crate) next_scan: Option<f64>,
    pub(crate) rng: SeededRng,
}

/// Fraction of the radius that one collision sub-step may move the robot: small enough that a
/// swept disc cannot skip over a wall one cell thick.
const SUBSTEP_FRACTION: f64 = 0.25;

impl Robot {
    /// The robot's footprint.
    pub(crate) fn disc(&self) -> Disc {
        (self.pose.x(), self.pose.y(), self.config.radius)
    }

    /// Moves the robot for `dt` under its current command; returns whether a wall blocked it.
    ///
    /// The motion is swept in sub-steps of at most `radius / 4`; at the first colliding
    /// sub-step the contact point is refined by bisection and the robot stops there.
    /// `discs` are the footprints `(x, y, radius)` of all robots in the world, this one at
    /// index `me` (skipped): robots block each other like walls do.
    pub(crate) fn advance(&mut self, grid: &Grid, discs: &[Disc], me: usize, dt: f64) -> bool {
        let target = limit_command(
            self.command,
            self.speed,
            self.config.drive,
            &self.config.limits,
            dt,
        );
        let start = self.pose;
        let dist = target.v.hypot(target.vy) * dt;
        let n = (dist / (self.config.radius * SUBSTEP_FRACTION))
            .ceil()
            .max(1.0) as usize;
        let r = self.config.radius;
        let collides = |f: f64| {
            let p = integrate(start, target, dt * f);
            grid.disc_collides(p.x(), p.y(), r)
                || discs
                    .iter()
                    .enumerate()
                    .any(|(j, d)| j != me && (p.x() - d.0).hypot(p.y() - d.1) < r + d.2)
        };
        let mut blocked_at = None;
        for i in 1..=n {
            if dist > 0.0 && collides(i as f64 / n as f64) {
                blocked_at = Some(i);
                break;
            }
        }
        let fraction = match blocked_at {
            None => 1.0,
            Some(i) => {
                let (mut lo, mut hi) = ((i - 1) as f64 / n as f64, i as f64 / n as f64);
                for _ in 0..12 {
                    let mid = 0.5 * (lo + hi);
                    if collides(mid) {
                        hi = mid
                    } else {
                        lo = mid
                    }
                }
                lo
            }
        };
        self.pose = integrate(start, target, dt * fraction);
        self.update_odometry(start, self.pose);
        let blocked = blocked_at.is_some();
        // A wall absorbs all momentum: the robot has to accelerate again from rest.
        self.speed = if blocked { Twist2::default() } else { target };
        if blocked && !self.in_contact {
            self.collisions += 1;
        }
        self.in_contact = blocked;
        blocked
    }

    fn update_odometry(&mut self, from: Pose2, to: Pose2) {
        let delta = from.0.inverse() * to.0;
        let Some(noise) = self.config.odom_noise else {
            self.odom = Pose2(self.odom.0 * delta);
            return;
        };
        let (dx, dy, dth) = (
            delta.translation.x,
            delta.translation.y,
            delta.rotation.angle(),
        );
        let dtrans = dx.hypot(dy);
        let scale = 1.0 + gauss(&mut self.rng, noise.trans_std);
        let dth = dth
            + gauss(
                &mut self.rng,
                noise.rot_std * dth.abs() + noise.rot_per_trans_std * dtrans,
            );
        let noisy = Pose2::new(dx * scale, dy * scale, dth);
        self.odom = Pose2(self.odom.0 * noisy.0);
    }

    /// A laser scan from the current true pose.
    ///
    /// Other robots (`discs` except index `me`) are seen as well as walls.
    pub(crate) fn scan(
        &mut self,
        grid: &Grid,
        discs: &[Disc],
        me: usize,
        laser: &LaserConfig,
    ) -> LaserScan {
        let sensor = self.pose.0 * laser.mount.0;
        let (x, y, heading) = (
            sensor.translation.x,
            sensor.translation.y,
            sensor.rotation.angle(),
        );
        let angle_min = -laser.fov / 2.0;
        let angle_increment = laser.fov / (laser.rays - 1) as f64;
        let noisy = laser.range_noise_std > 0.0;
        let mut ranges = Vec::with_capacity(laser.rays);
        for i in 0..laser.rays {
            let a = heading + angle_min + angle_increment * i as f64;
            let mut r = cast_ray(grid, x, y, a, laser.range_max);
            for (j, d) in discs.iter().enumerate() {
                if j != me {
                    r = r.min(ray_disc(x, y, a, *d));
                }
            }
            // No-return rays stay exactly at range_max so consumers can recognise them.
            if noisy && r < laser.range_max {
                r = (r + gauss(&mut self.rng, laser.range_noise_std)).clamp(0.0, laser.range_max);
            }
            ranges.push(r);
        }
        LaserScan {
            angle_min,
            angle_increment,
            range_max: laser.range_max,
            ranges: ranges.into(),
        }
    }
}

/// A robot footprint `(x, y, radius)`.
pub(crate) type Disc = (f64, f64, f64);

/// Distance along the ray from `(x, y)` at `angle` to the disc `d`, infinity if missed, 0 if
/// the ray starts inside it.
fn ray_disc(x: f64, y: f64, angle: f64, d: Disc) -> f64 {
    let (s, c) = angle.sin_cos();
    let (mx, my) = (x - d.0, y - d.1);
    let b = mx * c + my * s;
    let cc = mx * mx + my * my - d.2 * d.2;
    if cc <= 0.0 {
        return 0.0;
    }
    let disc = b * b - cc;
    if b > 0.0 || disc < 0.0 {
        return f64::INFINITY;
    }
    -b - disc.sqrt()
}

/// One sample of N(0, std); std 0 still draws so that the RNG stream does not depend on motion.
fn gauss(rng: &mut SeededRng, std: f64) -> f64 {
    Normal::new(0.0, std.max(0.0)).map_or(0.0, |n| n.sample(rng))
}
