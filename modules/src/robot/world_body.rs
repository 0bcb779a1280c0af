//! One robot of `sim.world`'s world: where its command comes from and where its readings go.
//!
//! A single-robot world publishes on its own ports; a world with `params/bodies` publishes on
//! each `sim.body` module's ports. Both go through the same writers (the blackboard's feeds of
//! a module's outputs), so the step is one code path for one robot or many.

use std::sync::Arc;

use anyhow::{bail, Context as _};
use petrel_actors::team::{RemoteFeed, RemoteQueue, RemoteValue};
use petrel_actors::{AnyValue, Blackboard, Image, PropertyHandle, PropertyType, Twist2};
use tokio::time::Instant;

use petrel_actors::{FilePath, Pose2};

use crate::sim::camera::CameraConfig;
use crate::sim::{RobotId, RobotOutput};

/// `params/bodies` of `sim.world`: the names of the `sim.body` modules it hosts, in order.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct BodyNames(pub Vec<String>);

impl PropertyType for BodyNames {
    const TYPE_NAME: &'static str = "sim.bodies";
}

/// The module type a world's `params/bodies` must name.
pub(super) const BODY_TYPE: &str = "sim.body";

/// The ports of one simulated robot and what the world remembers about it between steps.
pub(super) struct BodyIo {
    pub id: RobotId,
    command: PropertyHandle<Twist2>,
    /// Version of `in/controlSpeed` last seen, and the simulated time it was first seen.
    command_seen: (u64, f64),
    odometry: RemoteQueue,
    scans: RemoteQueue,
    images: RemoteQueue,
    pose: RemoteValue,
    speed: RemoteValue,
    collisions: RemoteValue,
    vibration: RemoteValue,
    /// What this body last wrote to `vibration` and `collisions` (see [`write_changed`]).
    last_vibration: Option<f64>,
    last_collisions: Option<i64>,
    sim_time: RemoteValue,
    /// The camera settings of this body (`sim.body`'s `in/camera/...`), 0 = the world's.
    camera_settings: Option<(String, PropertyHandle<f64>, PropertyHandle<f64>)>,
    /// The camera's own noise stream and the simulated time of its next frame.
    pub camera_rng: crate::seeded::SeededRng,
    pub next_frame: f64,
}

/// Checks that every name in `bodies` is a `sim.body` module of this agent, once each.
pub(super) async fn check_bodies(bb: &Blackboard, bodies: &[String]) -> anyhow::Result<()> {
    let listing = bb.listing().await?;
    match bodies_problem(bodies, |name| listing.module_type(name)) {
        Some(problem) => bail!("invalid parameter `params/bodies`: {problem}"),
        None => Ok(()),
    }
}

/// Why `bodies` is not a list of this agent's `sim.body` modules, once each, given each
/// module's type: the same words from `petrel check` and from `init`.
pub(super) fn bodies_problem<'t>(
    bodies: &[String],
    type_of: impl Fn(&str) -> Option<&'t str>,
) -> Option<String> {
    let names: Vec<&str> = bodies.iter().map(String::as_str).collect();
    petrel_actors::module_names_problem(&names, Some(BODY_TYPE), type_of)
}

impl BodyIo {
    /// Binds the ports of module `name` as robot `id`.
    pub async fn bind(bb: &Blackboard, name: &str, id: RobotId, seed: u64) -> anyhow::Result<Self> {
        let at = |path: &str| format!("{name}/{path}");
        let command = bb
            .handle::<Twist2>(&at("in/controlSpeed"))
            .await
            .with_context(|| format!("binding body `{name}`"))?;
        // The first robot keeps the camera stream a single-robot world always had.
        let camera_seed = seed ^ 0xCA3E_7A00 ^ (id as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        Ok(BodyIo {
            id,
            command,
            command_seen: (0, 0.0),
            odometry: queue(bb, &at("out/odometry")).await?,
            scans: queue(bb, &at("out/laserScan")).await?,
            images: queue(bb, &at("out/image")).await?,
            pose: value(bb, &at("out/pose")).await?,
            speed: value(bb, &at("out/actualSpeed")).await?,
            collisions: value(bb, &at("out/collisions")).await?,
            vibration: value(bb, &at("out/vibration")).await?,
            last_vibration: None,
            last_collisions: None,
            sim_time: value(bb, &at("out/simTime")).await?,
            // A single-robot world has none: its own params are the camera's settings.
            camera_settings: match (
                bb.handle::<f64>(&at("in/camera/exposure_ms")).await,
                bb.handle::<f64>(&at("in/camera/gain")).await,
            ) {
                (Ok(e), Ok(g)) => Some((name.to_string(), e, g)),
                _ => None,
            },
            camera_rng: crate::seeded::seeded(camera_seed),
            next_frame: 0.0,
        })
    }

    /// The command to follow now: zero when `in/controlSpeed` has not been rewritten for
    /// `timeout` simulated seconds (0 = never), as a real base stops on a silent controller.
    pub fn command(&mut self, sim_time: f64, timeout: f64) -> Twist2 {
        let command = self.command.read();
        if command.version != self.command_seen.0 {
            self.command_seen = (command.version, sim_time);
        }
        let stale = timeout > 0.0 && sim_time - self.command_seen.1 > timeout;
        if stale {
            Twist2::default()
        } else {
            *command
        }
    }

    /// Publishes one step's readings, stamped `now`.
    pub fn publish(&mut self, out: &RobotOutput, vibration: f64, now: Instant) {
        // The scan goes first: a consumer pairing a scan with the pose estimated from the
        // odometry of the same step then sees the scan before that pose exists.
        if let Some(scan) = &out.scan {
            self.scans.push(any(scan.clone()), now);
        }
        self.odometry.push(any(out.odometry.pose), now);
        self.pose.write(any(out.ground_truth), now);
        self.speed.write(any(out.speed), now);
        // Values that rarely move are written when they do, so their readers and a recording
        // are not handed the same number at every step.
        let collisions = out.collisions as i64;
        write_changed(&self.collisions, &mut self.last_collisions, collisions, now);
        self.sim_time.write(any(out.odometry.stamp), now);
        write_changed(&self.vibration, &mut self.last_vibration, vibration, now);
    }

    /// The camera of this body: the world's, with the body's own exposure and gain where set.
    pub fn camera(&self, world: &CameraConfig) -> anyhow::Result<CameraConfig> {
        let Some((name, exposure, gain)) = &self.camera_settings else {
            return Ok(world.clone());
        };
        let mut cfg = world.clone();
        let (e, g) = (exposure.value(), gain.value());
        if e != 0.0 {
            cfg.exposure_ms = e;
        }
        if g != 0.0 {
            cfg.gain = g;
        }
        cfg.validate().map_err(|e| {
            anyhow::anyhow!(
                "invalid camera setting of body `{name}` (`{name}/in/camera/...`): {}: {}",
                e.param,
                e.message
            )
        })?;
        Ok(cfg)
    }

    /// Publishes a camera frame.
    pub fn publish_image(&self, image: Image, now: Instant) {
        self.images.push(any(image), now);
    }
}

fn any<T: PropertyType>(value: T) -> AnyValue {
    Arc::new(value)
}

async fn queue(bb: &Blackboard, address: &str) -> anyhow::Result<RemoteQueue> {
    match bb.feed(address).await? {
        RemoteFeed::Queue(q) => Ok(q),
        RemoteFeed::Value(_) => bail!("`{address}` is a value, expected an output queue"),
    }
}

async fn value(bb: &Blackboard, address: &str) -> anyhow::Result<RemoteValue> {
    match bb.feed(address).await? {
        RemoteFeed::Value(v) => Ok(v),
        RemoteFeed::Queue(_) => bail!("`{address}` is a queue, expected an output value"),
    }
}

/// Where robot `rank` starts: `configured` (`[x, y, heading_deg]`) or, when empty, the world
/// file's `R` marker of that rank. `body` names the `sim.body` module whose parameter it is.
/// What is wrong with a configured start pose on its own (its shape, a number that is not
/// finite), before any world places it.
pub(super) fn start_problem(configured: &[f64]) -> Option<String> {
    match configured {
        [] => None,
        [_, _, _] if configured.iter().all(|v| v.is_finite()) => None,
        [_, _, _] => Some(format!(
            "expected `[x, y, heading_deg]` of finite numbers, got [{}]",
            configured
                .iter()
                .map(|&v| petrel_actors::short_number(v))
                .collect::<Vec<_>>()
                .join(", ")
        )),
        other => Some(format!(
            "expected `[x, y, heading_deg]` or `[]`, got {} numbers",
            other.len()
        )),
    }
}

pub(super) fn start_pose(
    configured: &[f64],
    markers: &[Pose2],
    rank: usize,
    file: &FilePath,
    body: Option<&String>,
) -> anyhow::Result<Pose2> {
    let param = match body {
        Some(name) => format!("{name}/params/start"),
        None => "params/start".to_string(),
    };
    match configured {
        [] => markers.get(rank).copied().with_context(|| {
            format!(
                "{file} has {} `R` start marker(s), none for robot {}; set `{param}` to `[x, y, heading_deg]`",
                markers.len(),
                rank + 1
            )
        }),
        &[x, y, deg] if start_problem(configured).is_none() => {
            Ok(Pose2::new(x, y, deg.to_radians()))
        }
        other => bail!(
            "invalid parameter `{param}`: {}",
            start_problem(other).unwrap_or_default()
        ),
    }
}

/// Writes `value` unless it equals `last`, what this body wrote there before (a NaN is always
/// written), and remembers it: `Output::set_if_changed` for an output the world writes from
/// outside its module.
fn write_changed<T: PropertyType + PartialEq + Copy>(
    out: &RemoteValue,
    last: &mut Option<T>,
    value: T,
    now: Instant,
) {
    if *last != Some(value) {
        *last = Some(value);
        out.write(any(value), now);
    }
}
