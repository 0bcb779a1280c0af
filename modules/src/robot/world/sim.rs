//! `sim.world`'s running simulation: its clock against the wall clock, the robots' commands
//! in, and one simulation step out to every body (odometry, scans, and camera frames when due).

use petrel_actors::Image;
use tokio::time::Instant;

use super::super::world_body::BodyIo;
use super::super::world_tracks::Tracks;
use crate::sim::camera::{self, CameraConfig, CameraMotion};
use crate::sim::{World, WorldFeatures};

/// Simulation steps run at most per wake-up in real-time mode: a host that falls further
/// behind slows simulated time down instead of freezing in a catch-up burst.
const MAX_CATCH_UP_STEPS: u32 = 10;

/// What exists only after a successful init.
pub(super) struct Sim {
    pub world: World,
    /// The robots, by id.
    pub bodies: Vec<BodyIo>,
    pub dt: f64,
    /// Real-time mode: simulated seconds owed to the wall clock since the last step.
    pub owed: f64,
    pub last_wake: Instant,
    /// Victims and dark and rough areas, for the camera.
    pub features: WorldFeatures,
    /// Trajectories and departures, for the picture.
    pub tracks: Tracks,
    /// `_team/members` (an agent in a team): a robot whose agent leaves stops for good.
    pub members: Option<(petrel_actors::AnyHandle, u64)>,
}

impl Sim {
    /// How many simulation steps this wake-up runs: one in deterministic mode, else what the
    /// wall clock has owed since the last wake-up at `time_scale` (at most
    /// [`MAX_CATCH_UP_STEPS`]).
    pub fn steps_due(&mut self, now: Instant, deterministic: bool, time_scale: f64) -> u32 {
        let steps = if deterministic {
            1
        } else {
            let elapsed = now.duration_since(self.last_wake).as_secs_f64();
            self.owed += elapsed * time_scale;
            let n = (self.owed / self.dt).floor().min(MAX_CATCH_UP_STEPS as f64) as u32;
            self.owed = (self.owed - n as f64 * self.dt).min(self.dt);
            n
        };
        self.last_wake = now;
        steps
    }

    /// Stops the bodies of robots whose agents left the team since the last look.
    pub fn note_departures(&mut self) {
        let Some((h, seen)) = self
            .members
            .as_mut()
            .filter(|(h, seen)| h.version() != *seen)
        else {
            return;
        };
        *seen = h.version();
        let members = h
            .get::<petrel_actors::team::TeamMembers>()
            .unwrap_or_default();
        let present: Vec<String> = members.0.iter().map(|m| m.agent.clone()).collect();
        for robot in self.tracks.members(&present, self.world.time()) {
            tracing::warn!(robot = %robot, t = self.world.time(), "a robot's agent left the team: its body stops here");
        }
    }

    /// Each body's command as it stands (stopped once older than `timeout` simulated s).
    pub fn take_commands(&mut self, timeout: f64) -> anyhow::Result<()> {
        for body in &mut self.bodies {
            let cmd = body.command(self.world.time(), timeout);
            self.world.set_command(body.id, cmd)?;
        }
        Ok(())
    }

    /// One simulation step, published to every body with the stamp `now`; a body whose
    /// camera frame is due (`camera`: the world's camera and its rate, when enabled) also
    /// gets its picture.
    pub fn step(
        &mut self,
        now: Instant,
        camera: Option<&(CameraConfig, f64)>,
    ) -> anyhow::Result<()> {
        let outputs = self.world.step(self.dt)?.to_vec();
        for (body, out) in self.bodies.iter_mut().zip(&outputs) {
            let (x, y) = (out.ground_truth.x(), out.ground_truth.y());
            let rough = self.features.is_rough(x, y);
            let vibration = match rough {
                true => 0.3 + 0.5 * out.speed.v.abs(),
                false => 0.05 * out.speed.v.abs(),
            };
            body.publish(out, vibration, now);
            let due = out.odometry.stamp + 1e-9 >= body.next_frame;
            let Some((world_cfg, rate)) = camera.filter(|_| due) else {
                continue;
            };
            let cfg = &body.camera(world_cfg)?;
            body.next_frame = out.odometry.stamp + 1.0 / rate;
            let motion = CameraMotion {
                speed: out.speed,
                rough,
            };
            let others = self.world.footprints_except(body.id);
            let pixels = camera::render_among(
                self.world.grid(),
                &self.features,
                &others,
                out.ground_truth,
                motion,
                cfg,
                &mut body.camera_rng,
            );
            let image = Image {
                width: cfg.width,
                height: cfg.height,
                encoding: "mono8".into(),
                data: pixels.into(),
            };
            body.publish_image(image, now);
        }
        let poses = outputs.iter().map(|o| o.ground_truth);
        self.tracks.sample(self.world.time(), poses);
        Ok(())
    }
}
