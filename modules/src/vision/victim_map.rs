//! Victim mapping: detections seen from estimated poses become victim positions in the map
//! frame, seen by repetition, de-duplicated, then handled one at a time by a mission.
//!
//! Each detection is placed in the map (pose ⊕ bearing and range) and merged into the nearest
//! candidate within `merge_radius` (a running mean of its sightings), or starts a new one. A
//! candidate is *seen* after `confirm_hits` sightings: one noisy frame is not a victim. A seen
//! candidate keeps absorbing sightings, so its position keeps improving, and a second sighting
//! of it never makes a second victim.
//!
//! A mission then handles seen candidates one at a time: the *target* is the pending (seen,
//! neither reported nor dismissed) candidate nearest to the robot, kept until it is reported
//! (it joins the found list) or dismissed (a mission that could not confirm it); its approach
//! pose is `standoff` metres from it on the line to the robot, facing it (the robot's own
//! position once it is that close). Sightings of
//! a dismissed candidate are absorbed by it and raise nothing again.

use petrel_actors::{Point2, Pose2};

use super::detector::Detection;

/// Mapper parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct VictimMapParams {
    /// Sightings closer than this to a candidate are the same victim, metres (default 1.5).
    pub merge_radius: f64,
    /// Sightings that make a candidate a seen victim (default 3).
    pub confirm_hits: u32,
    /// Detections with lower confidence are ignored (default 0.1).
    pub min_confidence: f64,
    /// Detections further than this are ignored: range estimates degrade with distance,
    /// metres (default 5.0).
    pub max_range: f64,
    /// Distance from the target victim to its approach pose, metres (default 1.0).
    pub standoff: f64,
    /// The target is in view while one of the last this many frames saw it (default 3).
    pub view_frames: u32,
}

impl Default for VictimMapParams {
    fn default() -> Self {
        VictimMapParams {
            merge_radius: 1.5,
            confirm_hits: 3,
            min_confidence: 0.1,
            max_range: 5.0,
            standoff: 1.0,
            view_frames: 3,
        }
    }
}

impl VictimMapParams {
    /// Checks every parameter; the error names the parameter.
    pub fn validate(&self) -> Result<(), String> {
        for (name, v) in [
            ("merge_radius", self.merge_radius),
            ("max_range", self.max_range),
            ("standoff", self.standoff),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("`params/{name}`: expected metres > 0, got {v}"));
            }
        }
        if self.confirm_hits == 0 {
            return Err("`params/confirm_hits`: expected at least 1, got 0".into());
        }
        if self.view_frames == 0 {
            return Err("`params/view_frames`: expected at least 1, got 0".into());
        }
        if !(0.0..=1.0).contains(&self.min_confidence) {
            return Err(format!(
                "`params/min_confidence`: expected a number in [0, 1], got {}",
                self.min_confidence
            ));
        }
        Ok(())
    }
}

/// Where a candidate is in its handling.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Handling {
    Open,
    Reported,
    Dismissed,
}

#[derive(Clone, Debug)]
struct Candidate {
    sum: (f64, f64),
    hits: u32,
    handling: Handling,
    /// The frame that last saw it.
    last_frame: u64,
}

impl Candidate {
    fn position(&self) -> Point2 {
        Point2::new(self.sum.0 / self.hits as f64, self.sum.1 / self.hits as f64)
    }
}

/// The candidate a mission handles now.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    /// Its position, map frame.
    pub position: Point2,
    /// Where to look at it from: `standoff` away on the line to the robot, facing it.
    pub approach: Pose2,
    /// One of the last `view_frames` frames saw it.
    pub in_view: bool,
}

/// Victim candidates, seen victims and their handling.
#[derive(Clone, Debug, Default)]
pub struct VictimMap {
    params: VictimMapParams,
    candidates: Vec<Candidate>,
    /// Frames so far (see [`VictimMap::next_frame`]).
    frame: u64,
    /// The target's index.
    target: Option<usize>,
    /// Reported candidates, in report order.
    reported: Vec<usize>,
}

impl VictimMap {
    /// An empty map.
    pub fn new(params: VictimMapParams) -> Self {
        VictimMap {
            params,
            ..VictimMap::default()
        }
    }

    /// Starts a new camera frame: the detections added next are this frame's.
    pub fn next_frame(&mut self) {
        self.frame += 1;
    }

    /// Adds one detection seen from `pose` (the camera at the robot's centre, looking ahead);
    /// returns the victim's position if this sighting made it a seen victim.
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
        let frame = self.frame;
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
                c.last_frame = frame;
                (c.hits == p.confirm_hits && c.handling != Handling::Dismissed)
                    .then(|| c.position())
            }
            None => {
                self.candidates.push(Candidate {
                    sum: (x, y),
                    hits: 1,
                    handling: Handling::Open,
                    last_frame: frame,
                });
                (p.confirm_hits == 1).then(|| Point2::new(x, y))
            }
        }
    }

    fn is_seen(&self, c: &Candidate) -> bool {
        c.hits >= self.params.confirm_hits && c.handling != Handling::Dismissed
    }

    /// Seen victims (reported or pending), in the order they were first seen.
    pub fn seen(&self) -> Vec<Point2> {
        self.candidates
            .iter()
            .filter(|c| self.is_seen(c))
            .map(Candidate::position)
            .collect()
    }

    /// Reported victims (the found list), in report order.
    pub fn reported(&self) -> Vec<Point2> {
        self.reported
            .iter()
            .map(|&i| self.candidates[i].position())
            .collect()
    }

    /// Seen victims neither reported nor dismissed.
    pub fn pending(&self) -> usize {
        self.candidates
            .iter()
            .filter(|c| self.is_seen(c) && c.handling == Handling::Open)
            .count()
    }

    /// The target for a robot at `robot`: the one picked before while it is pending, or else
    /// the nearest pending victim (None when nothing is pending).
    pub fn target(&mut self, robot: Point2) -> Option<Target> {
        let open = |c: &Candidate, p: &VictimMapParams| {
            c.hits >= p.confirm_hits && c.handling == Handling::Open
        };
        if !self
            .target
            .is_some_and(|i| open(&self.candidates[i], &self.params))
        {
            self.target = self
                .candidates
                .iter()
                .enumerate()
                .filter(|(_, c)| open(c, &self.params))
                .map(|(i, c)| (i, (c.position().0 - robot.0).norm()))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(i, _)| i);
        }
        let i = self.target?;
        let c = &self.candidates[i];
        let position = c.position();
        // On the line from the victim to the robot, so that the robot drives straight at it and
        // ends up facing it; a robot already that close stays where it is.
        let away = robot.0 - position.0;
        let approach = if away.norm() <= self.params.standoff {
            robot.0
        } else {
            position.0 + away.normalize() * self.params.standoff
        };
        let facing = (position.0 - approach).y.atan2((position.0 - approach).x);
        Some(Target {
            position,
            approach: Pose2::new(approach.x, approach.y, facing),
            in_view: self.frame - c.last_frame < u64::from(self.params.view_frames),
        })
    }

    /// Reports the target: it joins the found list. Returns its position (None: no target).
    pub fn report(&mut self) -> Option<Point2> {
        let i = self.target.take()?;
        self.candidates[i].handling = Handling::Reported;
        self.reported.push(i);
        Some(self.candidates[i].position())
    }

    /// Dismisses the target (not a victim after all). Returns its position (None: no target).
    pub fn dismiss(&mut self) -> Option<Point2> {
        let i = self.target.take()?;
        self.candidates[i].handling = Handling::Dismissed;
        Some(self.candidates[i].position())
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
        assert_eq!(m.seen().len(), 1);
        // A second victim far away is a new candidate, confirmed on its own.
        for _ in 0..3 {
            m.add(
                Pose2::new(1.0, 2.0, 0.0),
                &seen(std::f64::consts::FRAC_PI_2, 3.0),
            );
        }
        assert_eq!(m.seen().len(), 2);
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
        assert!(m.seen().is_empty());
        let bad = VictimMapParams {
            confirm_hits: 0,
            ..VictimMapParams::default()
        };
        assert!(bad.validate().unwrap_err().contains("confirm_hits"));
    }

    #[test]
    fn the_target_is_the_nearest_pending_victim_until_reported_or_dismissed() {
        let mut m = VictimMap::new(VictimMapParams::default());
        let robot = Pose2::new(0.0, 0.0, 0.0);
        assert_eq!(m.target(robot.position()), None);
        // Victims at (4, 0) and (0, 3), three sightings each, in one frame.
        m.next_frame();
        for _ in 0..3 {
            m.add(robot, &seen(0.0, 4.0));
            m.add(robot, &seen(std::f64::consts::FRAC_PI_2, 3.0));
        }
        assert_eq!(m.pending(), 2);
        let t = m.target(robot.position()).unwrap();
        assert!((t.position.0.y - 3.0).abs() < 1e-9, "nearest first: {t:?}");
        // One metre short of it, on the robot's side, facing it; seen this frame.
        assert!((t.approach.y() - 2.0).abs() < 1e-9 && t.approach.x().abs() < 1e-9);
        assert!((t.approach.theta() - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        assert!(t.in_view);
        // Kept while pending, even when the robot is now nearer the other one.
        let near_other = Point2::new(3.5, 0.0);
        assert_eq!(m.target(near_other).unwrap().position, t.position);
        // Out of view after `view_frames` frames without a sighting.
        for _ in 0..3 {
            m.next_frame();
        }
        assert!(!m.target(near_other).unwrap().in_view);
        assert_eq!(m.report(), Some(t.position));
        assert_eq!(m.reported(), vec![t.position]);
        assert_eq!(m.pending(), 1);
        let second = m.target(near_other).unwrap();
        assert!((second.position.0.x - 4.0).abs() < 1e-9);
        assert!(m.dismiss().is_some());
        assert_eq!((m.pending(), m.seen().len()), (0, 1));
        assert_eq!(m.target(near_other), None);
        assert_eq!(m.report(), None, "nothing left to report");
        // Sightings of a dismissed candidate raise nothing again.
        for _ in 0..5 {
            assert_eq!(m.add(robot, &seen(0.0, 4.0)), None);
        }
        assert_eq!(m.pending(), 0);
    }
}
