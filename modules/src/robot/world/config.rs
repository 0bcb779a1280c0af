//! `sim.world`'s parameters turned into the core's camera and robot configurations.

use anyhow::bail;

use super::super::{count, param_error};
use super::SimWorld;
use crate::sim::camera::CameraConfig;
use crate::sim::{DriveKind, LaserConfig, Limits, OdomNoise, RobotConfig};

impl SimWorld {
    /// The camera's parameters as they are now (contexts change exposure and gain).
    pub(super) fn camera_config(&self) -> anyhow::Result<CameraConfig> {
        let cfg = CameraConfig {
            fov: self.camera_fov_deg.value().to_radians(),
            exposure_ms: self.camera_exposure.value(),
            gain: self.camera_gain.value(),
            ..CameraConfig::default()
        };
        cfg.validate().map_err(|e| param_error(e, &[]))?;
        Ok(cfg)
    }

    pub(super) fn robot_config(&self) -> anyhow::Result<RobotConfig> {
        let drive = match self.drive.get().as_str() {
            "differential" => DriveKind::Differential,
            "holonomic" => DriveKind::Holonomic,
            // Not reached from a config or a tool: the parameter's check lets no other word in.
            other => bail!("invalid parameter `params/drive`: expected differential or holonomic, got `{other}`"),
        };
        let odom_noise = match self.odom_noise.get().as_slice() {
            [] => None,
            &[trans_std, rot_std, rot_per_trans_std] => Some(OdomNoise { trans_std, rot_std, rot_per_trans_std }),
            other => bail!("invalid parameter `params/odom_noise`: expected `[trans_std, rot_std, rot_per_trans_std]` or `[]`, got {other:?}"),
        };
        let rate = self.laser_rate.value();
        let fov_deg = self.laser_fov_deg.value();
        if !(fov_deg > 0.0 && fov_deg <= 360.0) {
            bail!(
                "invalid parameter `params/laser/fov_deg`: expected degrees in (0, 360], got {}",
                petrel_actors::short_number(fov_deg)
            );
        }
        let laser = match self.laser_enabled.value() {
            true => Some(LaserConfig {
                mount: self.laser_mount.value(),
                rays: count("laser/rays", self.laser_rays.value())?,
                fov: fov_deg.to_radians(),
                range_max: self.laser_range_max.value(),
                range_noise_std: self.laser_noise.value(),
                rate_hz: (rate != 0.0).then_some(rate),
            }),
            false => None,
        };
        Ok(RobotConfig {
            radius: self.radius.value(),
            drive,
            limits: Limits {
                max_speed: self.max_speed.value(),
                max_lateral_speed: self.max_lateral_speed.value(),
                max_turn: self.max_turn.value(),
                max_accel: self.max_accel.value(),
                max_turn_accel: self.max_turn_accel.value(),
            },
            odom_noise,
            laser,
        })
    }
}
