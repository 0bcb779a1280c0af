//! Victim mapping: detections seen from estimated poses become victim positions in the map
//! frame, confirmed by repetition and de-duplicated.
//!
//! Each detection is placed in the map (pose ⊕ bearing and range) and merged into the nearest
//! candidate within `merge_radius` (a running mean of its sightings), or starts a new one. A
//! candidate is confirmed after `confirm_hits` sightings: one noisy frame is not a victim.
//! A confirmed victim keeps absorbing sightings, so its position keeps improving, and a second
//! sighting of it never makes a second victim.

use petrel_actors::{Point2, Pose2};

use super::detector::Detection;

/// Mapper parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct VictimMapParams {
    /// Sightings closer than this to a candidate are the same victim, metres (default 1.5).
    pub merge_radius: f64,
    /// Sightings that confirm a victim (default 3).
    pub confirm_hits: u32,
    /// Detections with lower confidence are ignored (default 0.1).
    pub min_confidence: f64,
    /// Detections further than this are ignored: range estimates degrade with distance,
    /// metres (default 5.0).
    pub max_range: f64,
}

impl Default for VictimMapParams {
    fn default() -> Self {
        VictimMapParams {
            merge_radius: 1.5,
            confirm_hits: 3,
            min_confidence: 0.1,
            max_range: 5.0,
        }
    }
}

impl VictimMapParams {
    /// Checks every parameter; the error names the parameter.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.merge_radius.is_finite() && self.merge_radius > 0.0) {
            return Err(format!(
                "`params/merge_radius`: expected metres > 0, got {}",
                self.merge_radius
            ));
        }
        if self.confirm_hits == 0 {
            return Err("`params/confirm_hits`: expected at least 1, got 0".into());
        }
        if !(0.0..=1.0).contains(&self.min_confidence) {
            return Err(format!(
                "`params/min_confidence`: expected a number in [0, 1], got {}",
                self.min_confidence
            ));
        }
        if !(self.max_range.is_finite() && self.max_range > 0.0) {
            return Err(format!(
                "`params/max_range`: expected metres > 0, got {}",
                self.max_range
            ));
        }
        Ok(())
    }
}

#[derive(Clone, Debug)]
struct Candidate {
    sum: (f64, f64),
    hits: u32,
}

impl Candidate {
    fn position(&self) -> Point2 {
        Point2::new(self.sum.0 / self.hits as f64, self.sum.1 / self.hits as f64)
    }
}

/// Victim candidates and confirmed victims.
#[derive(Clone, Debug, Default)]
pub struct VictimMap {
    params: VictimMapParams,
    candidates: Vec<Candidate>,
}

impl VictimMap {
    /// An empty map.
    pub fn new(params: VictimMapParams) -> Self {
        VictimMap {
            params,
            candidates: Vec::new(),
        }
    }

    /// Adds one detection seen from `pose` (the camera at the robot's centre, looking ahead);
    /// returns the victim's position if this sighting confirmed it.
    pub fn add(&mut self, pose: Pose2, d: &Detection) -> Option<Point2> {
        let p = &self.params;
        if d.confidence < p.min_confidence || d.range > p.max_range || !d.range.is_finite() {
            return None;
        }
        let angle = pose.theta() + d.bearing;
        let (x, y) = (
            pose.x() + d.range * angle.cos(),
            pose.y() + d.range * angle.sin(),
        );
        let nearest = self
            .candidates
            .iter_mut()
            .map(|c| {
                let q = c.position();
                ((q.0.x - x).hypot(q.0.y - y), c)
            })
            .filter(|(dist, _)| *dist <= p.merge_radius)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        match nearest {
            Some((_, c)) => {
                c.sum = (c.sum.0 + x, c.sum.1 + y);
                c.hits += 1;
                (c.hits == p.confirm_hits).then(|| c.position())
            }
            None => {
                self.candidates.push(Candidate {
                    sum: (x, y),
                    hits: 1,
                });
                (p.confirm_hits == 1).then(|| Point2::new(x, y))
            }
        }
    }

    /// Confirmed victims, in the order they were first seen.
    pub fn confirmed(&self) -> Vec<Point2> {
        self.candidates
            .iter()
            .filter(|c| c.hits >= self.params.confirm_hits)
            .map(Candidate::position)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seen(bearing: f64, range: f64) -> Detection {
        Detection {
            bearing,
            range,
            confidence: 0.5,
        }
    }

    #[test]
    fn repeated_sightings_confirm_one_victim_and_do_not_duplicate_it() {
        let mut m = VictimMap::new(VictimMapParams::default());
        // A victim at (3, 2): seen from (1, 2) facing +x, then from (2, 1) facing +y.
        assert_eq!(m.add(Pose2::new(1.0, 2.0, 0.0), &seen(0.0, 2.1)), None);
        assert_eq!(m.add(Pose2::new(1.0, 2.0, 0.0), &seen(0.02, 1.9)), None);
        let confirmed = m
            .add(
                Pose2::new(2.0, 1.0, std::f64::consts::FRAC_PI_2),
                &seen(-0.785, 1.41),
            )
            .unwrap();
        assert!(
            (confirmed.0.x - 3.0).abs() < 0.1 && (confirmed.0.y - 2.0).abs() < 0.1,
            "{confirmed:?}"
        );
        for _ in 0..5 {
            assert_eq!(m.add(Pose2::new(1.0, 2.0, 0.0), &seen(0.0, 2.0)), None);
        }
        assert_eq!(m.confirmed().len(), 1);
        // A second victim far away is a new candidate, confirmed on its own.
        for _ in 0..3 {
            m.add(
                Pose2::new(1.0, 2.0, 0.0),
                &seen(std::f64::consts::FRAC_PI_2, 3.0),
            );
        }
        assert_eq!(m.confirmed().len(), 2);
    }

    #[test]
    fn weak_far_and_single_sightings_are_not_victims() {
        let mut m = VictimMap::new(VictimMapParams::default());
        m.add(Pose2::default(), &seen(0.0, 2.0));
        m.add(
            Pose2::default(),
            &Detection {
                confidence: 0.01,
                ..seen(0.0, 2.0)
            },
        );
        m.add(Pose2::default(), &seen(0.0, 9.0));
        assert!(m.confirmed().is_empty());
        let bad = VictimMapParams {
            confirm_hits: 0,
            ..VictimMapParams::default()
        };
        assert!(bad.validate().unwrap_err().contains("confirm_hits"));
    }
}
