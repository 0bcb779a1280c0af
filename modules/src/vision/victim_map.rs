//! Victim mapping: detections seen from estimated poses become victim positions in the map
//! frame, seen by repetition, de-duplicated, then handled one at a time by a mission.
//!
//! Each detection is placed in the map (pose ⊕ bearing and range) and merged into the nearest
//! candidate within `merge_radius`, or starts a new one. A candidate is *seen* after
//! `confirm_hits` sightings, one of them from within `confirm_range`: one noisy frame is not a
//! victim, and a far victim's range, read a few rows below the horizon, can be metres short
//! frame after frame (its sightings still place and refine a candidate, which is seen once a
//! robot came near enough to read its range well). A seen candidate keeps absorbing
//! sightings, so its position keeps improving, and a second sighting of it never makes a
//! second victim.
//!
//! A candidate's position is the mean of its sightings weighted by how precise each is. The
//! range comes from the row where the victim meets the floor: one row of error (a shaking
//! camera on rough floor pitches by several) moves it by about `range² / (focal × camera
//! height)`, so a sighting's variance grows with `range⁴` and its weight is `1 / range⁴`
//! ([`sighting_weight`]). Two sightings at 5 m confirm a victim, perhaps 1.5 m off; the
//! sightings as the robot comes closer then pull it where it is.
//!
//! What a team is told ([`VictimMap::news`]) follows: each seen victim once it is seen, and
//! again whenever its position moved by more than a set distance since it was last told.
//!
//! A mission then handles seen candidates one at a time: the *target* is the pending (seen,
//! neither reported nor dismissed) candidate nearest to the robot, kept until it is reported
//! (it joins the found list) or dismissed (a mission that could not confirm it); its approach
//! pose is `standoff` metres from it on the line to the robot, facing it (the robot's own
//! position once it is that close). Sightings of
//! a dismissed candidate are absorbed by it and raise nothing again.

use petrel_actors::{Point2, Pose2};
use serde::{Deserialize, Serialize};

use super::detector::Detection;

/// Mapper parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct VictimMapParams {
    /// Sightings closer than this to a candidate are the same victim, metres (default 1.5).
    pub merge_radius: f64,
    /// Sightings that make a candidate a seen victim (default 3).
    pub confirm_hits: u32,
    /// Detections with lower confidence are ignored (default 0.7: real victims are reported
    /// at 0.9 or more in 99 % of sightings, while another robot seen against a wall, most of
    /// all in a dark room, can be a weak sighting, 0 to 0.6, frame after frame).
    pub min_confidence: f64,
    /// Detections further than this are ignored: range estimates degrade with distance,
    /// metres (default 5.0).
    pub max_range: f64,
    /// A candidate is seen only once one of its sightings was this close, metres (default
    /// 5.0: any sighting within `max_range`).
    pub confirm_range: f64,
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
            min_confidence: 0.7,
            max_range: 5.0,
            confirm_range: 5.0,
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
            ("confirm_range", self.confirm_range),
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

/// Where a candidate is in its handling; a string in `state/map` (RON's dynamic values, which
/// snapshots go through, do not keep enum variants).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(into = "String", try_from = "String")]
enum Handling {
    Open,
    Reported,
    Dismissed,
}

impl From<Handling> for String {
    fn from(h: Handling) -> String {
        format!("{h:?}").to_lowercase()
    }
}

impl TryFrom<String> for Handling {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        match s.as_str() {
            "open" => Ok(Handling::Open),
            "reported" => Ok(Handling::Reported),
            "dismissed" => Ok(Handling::Dismissed),
            _ => Err(format!(
                "expected `open`, `reported` or `dismissed`, got `{s}`"
            )),
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Candidate {
    /// Sightings' positions times their weights, summed.
    sum: (f64, f64),
    /// Their weights, summed.
    weight: f64,
    hits: u32,
    /// One of its sightings was within `confirm_range` (true in memories saved before there
    /// was one, so what they had seen stays seen).
    #[serde(default = "yes")]
    near: bool,
    handling: Handling,
    /// The frame that last saw it.
    last_frame: u64,
    /// Where [`VictimMap::news`] last said it was.
    told: Option<Point2>,
}

fn yes() -> bool {
    true
}

impl Candidate {
    fn position(&self) -> Point2 {
        Point2::new(self.sum.0 / self.weight, self.sum.1 / self.weight)
    }

    fn absorb(&mut self, (x, y): (f64, f64), weight: f64, frame: u64, near: bool) {
        self.sum = (self.sum.0 + weight * x, self.sum.1 + weight * y);
        self.weight += weight;
        self.hits += 1;
        self.near |= near;
        self.last_frame = frame;
    }

    /// Seen often enough, once from near enough (dismissed or not).
    fn confirmed(&self, p: &VictimMapParams) -> bool {
        self.hits >= p.confirm_hits && self.near
    }
}

/// How much a sighting at `range` metres counts in its candidate's position: `1 / range⁴`
/// (the variance of a range read from the image row where the victim meets the floor grows
/// with `range⁴`), as if at 0.5 m when nearer (rows are plenty there).
pub fn sighting_weight(range: f64) -> f64 {
    1.0 / range.max(0.5).powi(4)
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
///
/// It is also the module's memory (`state/map`): everything but the parameters is serialized,
/// and [`VictimMap::resume`] takes it back with the parameters of the new instance.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct VictimMap {
    #[serde(skip)]
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

    /// What `saved` held, with parameters `params` (a restarted module's).
    pub fn resume(params: VictimMapParams, saved: &VictimMap) -> Self {
        VictimMap {
            params,
            ..saved.clone()
        }
    }

    /// Whether anything was ever seen (an empty map need not be kept).
    pub fn is_empty(&self) -> bool {
        self.candidates.is_empty()
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
        let weight = sighting_weight(d.range);
        let near = d.range <= p.confirm_range;
        match nearest {
            Some((_, c)) => {
                let before = c.confirmed(p);
                c.absorb((x, y), weight, frame, near);
                (!before && c.confirmed(p) && c.handling != Handling::Dismissed)
                    .then(|| c.position())
            }
            None => {
                let mut c = Candidate {
                    sum: (0.0, 0.0),
                    weight: 0.0,
                    hits: 0,
                    near: false,
                    handling: Handling::Open,
                    last_frame: frame,
                    told: None,
                };
                c.absorb((x, y), weight, frame, near);
                let seen = c.confirmed(p);
                self.candidates.push(c);
                seen.then(|| Point2::new(x, y))
            }
        }
    }

    /// What a team should be told since the last call: each seen victim (not dismissed) not
    /// told yet, and each whose position moved more than `min_move` metres from where it was
    /// last told; as `(id, position)`, the id the victim's for as long as this map lives.
    pub fn news(&mut self, min_move: f64) -> Vec<(usize, Point2)> {
        let p = &self.params;
        let mut news = Vec::new();
        for (id, c) in self.candidates.iter_mut().enumerate() {
            if !c.confirmed(p) || c.handling == Handling::Dismissed {
                continue;
            }
            let now = c.position();
            if c.told.is_none_or(|told| (told.0 - now.0).norm() > min_move) {
                c.told = Some(now);
                news.push((id, now));
            }
        }
        news
    }

    fn is_seen(&self, c: &Candidate) -> bool {
        c.confirmed(&self.params) && c.handling != Handling::Dismissed
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
        let open =
            |c: &Candidate, p: &VictimMapParams| c.confirmed(p) && c.handling == Handling::Open;
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

impl petrel_actors::PropertyType for VictimMap {
    const TYPE_NAME: &'static str = "vision.victim_map";
}

#[cfg(test)]
mod tests;
