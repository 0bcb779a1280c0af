//! What `sim.world` remembers of a multi-robot run for its picture: each body's trajectory,
//! and where and when a body whose robot agent left the team stopped.

use petrel_actors::{Point2, Pose2};

use crate::sim::render::{save_png, RenderLayers, Track};
use crate::sim::{Grid, WorldFeatures};

/// Simulated seconds between trajectory samples.
const SAMPLE_S: f64 = 0.2;

/// One colour per robot, cycled: distinct on the map's greys and from the victims' green/red.
const COLOURS: [[u8; 3]; 6] = [
    [31, 119, 180],
    [255, 127, 14],
    [148, 103, 189],
    [23, 190, 207],
    [227, 119, 194],
    [140, 86, 75],
];

/// The bodies' trajectories and departures; kept in `state/tracks` across a restart.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Tracks {
    names: Vec<String>,
    points: Vec<Vec<Point2>>,
    /// When and where each body's robot left the team (its agent died).
    departed: Vec<Option<(f64, Point2)>>,
    present: Vec<bool>,
    next_sample: f64,
}

impl Tracks {
    /// Tracks of the bodies `names` (each the name of its robot's agent).
    pub fn new(names: &[String]) -> Self {
        Tracks {
            names: names.to_vec(),
            points: vec![Vec::new(); names.len()],
            departed: vec![None; names.len()],
            present: vec![false; names.len()],
            next_sample: 0.0,
        }
    }

    /// Whether these are the tracks of the bodies `names` (a restarted world's memory).
    pub fn is_of(&self, names: &[String]) -> bool {
        !self.names.is_empty() && self.names == names
    }

    /// Records the bodies' true poses at simulated time `t`, every [`SAMPLE_S`].
    pub fn sample(&mut self, t: f64, poses: impl Iterator<Item = Pose2>) {
        if t + 1e-9 < self.next_sample {
            return;
        }
        self.next_sample = t + SAMPLE_S;
        for (track, pose) in self.points.iter_mut().zip(poses) {
            track.push(Point2::new(pose.x(), pose.y()));
        }
    }

    /// The team's members now: a body's robot that was present and is gone died at `t`.
    /// Returns the names of those that left.
    pub fn members(&mut self, present: &[String], t: f64) -> Vec<String> {
        let mut left = Vec::new();
        for (i, name) in self.names.iter().enumerate() {
            let here = present.contains(name);
            if self.present[i] && !here && self.departed[i].is_none() {
                let at = self.points[i].last().copied().unwrap_or_default();
                self.departed[i] = Some((t, at));
                left.push(name.clone());
            }
            self.present[i] |= here;
        }
        left
    }

    /// One line per body: its colour and, if its robot died, when and where.
    pub fn legend(&self) -> String {
        let mut out = String::new();
        for (i, name) in self.names.iter().enumerate() {
            let [r, g, b] = COLOURS[i % COLOURS.len()];
            out += &format!("  {name}: #{r:02x}{g:02x}{b:02x}");
            if let Some((t, p)) = self.departed[i] {
                out += &format!(
                    ", left the team at t = {t:.1} s at ({:.2}, {:.2})",
                    p.0.x, p.0.y
                );
            }
            out += "\n";
        }
        out
    }

    /// Writes the picture: the world, its victims, every body's trajectory in its colour.
    pub fn save(
        &self,
        path: &std::path::Path,
        grid: &Grid,
        features: &WorldFeatures,
    ) -> Result<(), String> {
        let tracks: Vec<Track> = self
            .points
            .iter()
            .enumerate()
            .map(|(i, points)| Track {
                points,
                colour: COLOURS[i % COLOURS.len()],
                stopped: self.departed[i].is_some(),
            })
            .collect();
        // The world's victims as rings (the world does not know which were found: the team's
        // list is the coordinator's).
        let victims: Vec<(Point2, bool)> = features.victims.iter().map(|v| (*v, true)).collect();
        let layers = RenderLayers {
            tracks: &tracks,
            victims: &victims,
            ..RenderLayers::default()
        };
        save_png(path, &grid.to_occupancy(), &layers).map_err(|e| e.to_string())
    }
}

impl petrel_actors::PropertyType for Tracks {
    const TYPE_NAME: &'static str = "sim.world_tracks";
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_robot_that_leaves_is_marked_where_its_body_last_was() {
        let names = vec!["r1".to_string(), "r2".to_string()];
        let mut t = Tracks::new(&names);
        let all = names.clone();
        assert!(t.members(&all, 0.0).is_empty());
        t.sample(
            0.0,
            [Pose2::new(1.0, 1.0, 0.0), Pose2::new(2.0, 1.0, 0.0)].into_iter(),
        );
        t.sample(
            0.1,
            [Pose2::new(9.0, 9.0, 0.0), Pose2::new(9.0, 9.0, 0.0)].into_iter(),
        );
        t.sample(
            0.2,
            [Pose2::new(1.5, 1.0, 0.0), Pose2::new(2.5, 1.0, 0.0)].into_iter(),
        );
        assert_eq!(t.points[0].len(), 2, "one sample per 0.2 s");
        assert_eq!(t.members(&["r2".to_string()], 3.0), ["r1"]);
        assert_eq!(t.members(&["r2".to_string()], 4.0), Vec::<String>::new());
        assert_eq!(
            t.legend(),
            "  r1: #1f77b4, left the team at t = 3.0 s at (1.50, 1.00)\n  r2: #ff7f0e\n"
        );
    }
}
