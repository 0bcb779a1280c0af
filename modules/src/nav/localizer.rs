//! Simulated localization: odometry plus a deterministic, configurable error.
//!
//! This is not an estimator; it reproduces how a real localizer's output degrades, so that
//! context rules ("localization lost") and recovery behaviours can be exercised on demand.
//! The error grows with distance travelled (`drift_per_meter`) and, much faster, inside
//! scheduled "lost" episodes; outside episodes it decays back toward zero with time constant
//! `recovery_time`, like a localizer re-converging. Quality is `exp(-(e / quality_scale +
//! |e_theta| / heading_quality_scale))`, 1 for a perfect estimate.

use petrel_actors::Pose2;

use crate::sim::error::{finite, non_negative, positive, ParamError};
use crate::sim::Odometry;

/// Parameters of the simulated localizer.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalizerParams {
    /// Position error added per metre travelled, m/m (default 0 = none).
    pub drift_per_meter: f64,
    /// World-frame direction of the position drift, radians (default 0 = +x).
    pub drift_direction: f64,
    /// Simulated-time windows `[start, end)` (seconds) in which the localizer is lost.
    pub lost_episodes: Vec<(f64, f64)>,
    /// Position error growth inside a lost episode, m/s (default 0.3).
    pub lost_drift_speed: f64,
    /// Heading error growth inside a lost episode, rad/s (default 0.1).
    pub lost_heading_rate: f64,
    /// Time constant of error decay outside episodes, s; `None` never recovers (default 2.0).
    pub recovery_time: Option<f64>,
    /// Position error at which quality falls to 1/e, m (default 0.3).
    pub quality_scale: f64,
    /// Heading error at which quality falls to 1/e, rad (default 0.3).
    pub heading_quality_scale: f64,
}

impl Default for LocalizerParams {
    fn default() -> Self {
        LocalizerParams {
            drift_per_meter: 0.0,
            drift_direction: 0.0,
            lost_episodes: Vec::new(),
            lost_drift_speed: 0.3,
            lost_heading_rate: 0.1,
            recovery_time: Some(2.0),
            quality_scale: 0.3,
            heading_quality_scale: 0.3,
        }
    }
}

impl LocalizerParams {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), ParamError> {
        non_negative("drift_per_meter", self.drift_per_meter)?;
        finite("drift_direction", self.drift_direction)?;
        for &(a, b) in &self.lost_episodes {
            if !(a.is_finite() && b.is_finite() && a < b) {
                return Err(ParamError {
                    param: "lost_episodes".into(),
                    message: format!("expected [start, end) with start < end, got [{a}, {b})"),
                });
            }
        }
        non_negative("lost_drift_speed", self.lost_drift_speed)?;
        finite("lost_heading_rate", self.lost_heading_rate)?;
        if let Some(t) = self.recovery_time {
            positive("recovery_time", t)?;
        }
        positive("quality_scale", self.quality_scale)?;
        positive("heading_quality_scale", self.heading_quality_scale)
    }
}

/// Localizer output.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalizerOutput {
    /// Estimated pose (odometry with the simulated error applied).
    pub pose: Pose2,
    /// Localization quality in `[0, 1]`; 1 is perfect.
    pub quality: f64,
    /// Whether the time is inside a scheduled lost episode.
    pub lost: bool,
}

/// The simulated localizer state.
#[derive(Clone, Debug)]
pub struct Localizer {
    params: LocalizerParams,
    last: Option<Odometry>,
    /// World-frame error (x, y, theta) added to odometry.
    error: (f64, f64, f64),
}

impl Localizer {
    /// A localizer with zero initial error.
    pub fn new(params: LocalizerParams) -> Result<Self, ParamError> {
        params.validate()?;
        Ok(Localizer {
            params,
            last: None,
            error: (0.0, 0.0, 0.0),
        })
    }

    /// Consumes one odometry sample and returns the estimate for it.
    pub fn step(&mut self, odom: Odometry) -> LocalizerOutput {
        let p = &self.params;
        let lost = p
            .lost_episodes
            .iter()
            .any(|&(a, b)| odom.stamp >= a && odom.stamp < b);
        if let Some(prev) = self.last {
            let dt = (odom.stamp - prev.stamp).max(0.0);
            let dist = (odom.pose.0.translation.vector - prev.pose.0.translation.vector).norm();
            let (s, c) = p.drift_direction.sin_cos();
            let mut grow = p.drift_per_meter * dist;
            if lost {
                grow += p.lost_drift_speed * dt;
                self.error.2 += p.lost_heading_rate * dt;
            } else if let Some(tau) = p.recovery_time {
                let k = (-dt / tau).exp();
                self.error = (self.error.0 * k, self.error.1 * k, self.error.2 * k);
            }
            self.error.0 += grow * c;
            self.error.1 += grow * s;
        }
        self.last = Some(odom);
        let (ex, ey, et) = self.error;
        let pose = Pose2::new(
            odom.pose.x() + ex,
            odom.pose.y() + ey,
            odom.pose.theta() + et,
        );
        let quality =
            (-(ex.hypot(ey) / p.quality_scale + et.abs() / p.heading_quality_scale)).exp();
        LocalizerOutput {
            pose,
            quality,
            lost,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn odom(t: f64, x: f64) -> Odometry {
        Odometry {
            stamp: t,
            pose: Pose2::new(x, 1.0, 0.2),
        }
    }

    #[test]
    fn without_drift_the_estimate_is_odometry_with_full_quality() {
        let mut l = Localizer::new(LocalizerParams::default()).unwrap();
        for k in 0..10 {
            let out = l.step(odom(k as f64 * 0.1, k as f64));
            assert_eq!(out.pose, odom(0.0, k as f64).pose);
            assert_eq!((out.quality, out.lost), (1.0, false));
        }
    }

    #[test]
    fn a_lost_episode_degrades_quality_then_recovers() {
        let params = LocalizerParams {
            lost_episodes: vec![(2.0, 4.0)],
            ..LocalizerParams::default()
        };
        let mut l = Localizer::new(params).unwrap();
        let mut q = Vec::new();
        for k in 0..=200 {
            let t = k as f64 * 0.05;
            q.push((t, l.step(odom(t, 0.0))));
        }
        let at = |t: f64| q.iter().find(|(s, _)| (s - t).abs() < 1e-9).unwrap().1;
        assert_eq!(at(1.9).quality, 1.0);
        assert!(at(3.0).lost && at(3.0).quality < 0.3);
        assert!(at(3.95).quality < 0.1, "2 s lost at 0.3 m/s and 0.1 rad/s");
        assert!(
            !at(4.0).lost && at(10.0).quality > 0.85,
            "recovered: {}",
            at(10.0).quality
        );
        let pos_err = (at(3.95).pose.x() - 0.0).hypot(at(3.95).pose.y() - 1.0);
        assert!((pos_err - 0.6).abs() < 1e-9, "{pos_err}");
    }

    #[test]
    fn distance_drift_grows_with_travel() {
        let params = LocalizerParams {
            drift_per_meter: 0.05,
            recovery_time: None,
            drift_direction: std::f64::consts::FRAC_PI_2,
            ..LocalizerParams::default()
        };
        let mut l = Localizer::new(params).unwrap();
        let mut out = l.step(odom(0.0, 0.0));
        for k in 1..=10 {
            out = l.step(odom(k as f64, k as f64));
        }
        assert!((out.pose.y() - 1.5).abs() < 1e-9 && (out.pose.x() - 10.0).abs() < 1e-9);
        let bad = LocalizerParams {
            lost_episodes: vec![(3.0, 1.0)],
            ..LocalizerParams::default()
        };
        assert_eq!(Localizer::new(bad).unwrap_err().param, "lost_episodes");
    }
}
