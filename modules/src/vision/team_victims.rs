//! Victims reported by the robots of a team, merged into one list (pure).
//!
//! Each robot reports a victim from its own sightings and its own pose estimate, so two
//! robots' reports of one victim are independent estimates: the list keeps their mean, which
//! is closer than either alone. A robot's estimate improves as it comes closer (on the shaking
//! rubble floor the first one can land 2 m off), so a report carries the robot's id for the
//! victim and a later report with the same id *revises* it: the list always holds each
//! robot's latest estimate. A revision can show that two entries were one victim (they are
//! merged) or that a report was of another victim (it moves there).

use petrel_actors::Point2;
use serde::{Deserialize, Serialize};

/// One victim of the team's list.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TeamVictim {
    /// Who reported it first.
    pub found_by: String,
    /// The reports: robot, its id for the victim (None: a report that cannot be revised),
    /// latest estimate.
    sources: Vec<(String, Option<u64>, Point2)>,
}

impl TeamVictim {
    fn new(from: &str, id: Option<u64>, p: Point2) -> Self {
        TeamVictim {
            found_by: from.to_string(),
            sources: vec![(from.to_string(), id, p)],
        }
    }

    /// Where the reports put it: the mean of each report's latest estimate (map frame).
    pub fn position(&self) -> Point2 {
        mean(self.sources.iter().map(|s| s.2))
    }

    /// How many reports (robot and id) are merged into it.
    pub fn reports(&self) -> usize {
        self.sources.len()
    }

    /// The other robots whose reports are merged into it, in order.
    pub fn also_by(&self) -> Vec<&str> {
        let mut also: Vec<&str> = Vec::new();
        for (robot, _, _) in &self.sources {
            if *robot != self.found_by && !also.contains(&robot.as_str()) {
                also.push(robot);
            }
        }
        also
    }
}

/// The mean of some points (the origin for none).
fn mean(points: impl Iterator<Item = Point2>) -> Point2 {
    let (mut x, mut y, mut n) = (0.0, 0.0, 0.0);
    for p in points {
        (x, y, n) = (x + p.0.x, y + p.0.y, n + 1.0);
    }
    match n > 0.0 {
        true => Point2::new(x / n, y / n),
        false => Point2::default(),
    }
}

/// What a report did to the list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Report {
    /// A victim nobody had reported: its index in the list.
    New(usize),
    /// Within the merge radius of a known victim: its index.
    Known(usize),
    /// A robot's new estimate of a victim it had reported: its index (the victim moved).
    Revised(usize),
    /// A revision brought two entries within the merge radius: entry `gone` was victim
    /// `kept` (the earlier found); entries after `gone` move up by one.
    Merged {
        /// The index of the victim kept.
        kept: usize,
        /// The index of the entry merged into it, now removed.
        gone: usize,
    },
}

/// The team's victims: a report within `radius` of a known victim is that victim.
///
/// It is also the module's memory (`state/list`), hence serializable.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TeamVictims {
    radius: f64,
    victims: Vec<TeamVictim>,
}

impl TeamVictims {
    /// An empty list merging reports closer than `radius` metres.
    pub fn new(radius: f64) -> Self {
        TeamVictims {
            radius,
            victims: Vec::new(),
        }
    }

    /// This list with the victims of `saved` (a restarted module's memory).
    pub fn resume(self, saved: &TeamVictims) -> Self {
        TeamVictims {
            victims: saved.victims.clone(),
            ..self
        }
    }

    /// `from` (a robot) reports a victim at `p`; `id` is the robot's id for the victim, so a
    /// later report with the same id revises this one (None: it cannot be revised).
    pub fn report(&mut self, from: &str, id: Option<u64>, p: Point2) -> Report {
        let held = id.and_then(|id| {
            self.victims.iter().enumerate().find_map(|(i, v)| {
                let k = v
                    .sources
                    .iter()
                    .position(|s| s.0 == from && s.1 == Some(id))?;
                Some((i, k))
            })
        });
        if let Some((i, k)) = held {
            let others = &self.victims[i].sources;
            let near_the_others = others.len() == 1 || {
                let rest = (0..others.len()).filter(|&j| j != k).map(|j| others[j].2);
                (mean(rest).0 - p.0).norm() <= self.radius
            };
            if near_the_others {
                self.victims[i].sources[k].2 = p;
                return self.merge_into_a_neighbour(i).unwrap_or(Report::Revised(i));
            }
            // The robot now places it away from the others' reports: another victim.
            self.victims[i].sources.remove(k);
        }
        self.add(from, id, p)
    }

    /// Adds a report to the nearest victim within the radius, or as a new victim.
    fn add(&mut self, from: &str, id: Option<u64>, p: Point2) -> Report {
        match self.nearest(p, None) {
            Some(i) => {
                self.victims[i].sources.push((from.to_string(), id, p));
                Report::Known(i)
            }
            None => {
                self.victims.push(TeamVictim::new(from, id, p));
                Report::New(self.victims.len() - 1)
            }
        }
    }

    /// The victim nearest `p` within the radius, other than `except`.
    fn nearest(&self, p: Point2, except: Option<usize>) -> Option<usize> {
        self.victims
            .iter()
            .enumerate()
            .filter(|(i, _)| Some(*i) != except)
            .map(|(i, v)| (i, (v.position().0 - p.0).norm()))
            .filter(|(_, d)| *d <= self.radius)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    }

    /// Merges victim `i`, which moved, with the nearest other victim within the radius: the
    /// later found goes into the earlier.
    fn merge_into_a_neighbour(&mut self, i: usize) -> Option<Report> {
        let j = self.nearest(self.victims[i].position(), Some(i))?;
        let (kept, gone) = (i.min(j), i.max(j));
        let gone_victim = self.victims.remove(gone);
        self.victims[kept].sources.extend(gone_victim.sources);
        Some(Report::Merged { kept, gone })
    }

    /// The list, in the order found.
    pub fn victims(&self) -> &[TeamVictim] {
        &self.victims
    }

    /// One line per victim (`1 (x, y) found by robot_2, also robot_1`), then who found how many.
    pub fn summary(&self) -> String {
        let mut out = format!("team victims: {}\n", self.victims.len());
        for (i, v) in self.victims.iter().enumerate() {
            let also = match v.also_by() {
                also if also.is_empty() => String::new(),
                also => format!(", also {}", also.join(", ")),
            };
            out += &format!(
                "  {} ({:.2}, {:.2}) found by {}{also}\n",
                i + 1,
                v.position().0.x,
                v.position().0.y,
                v.found_by
            );
        }
        let mut finders: Vec<&str> = self.victims.iter().map(|v| v.found_by.as_str()).collect();
        finders.sort();
        finders.dedup();
        let counts: Vec<String> = finders
            .iter()
            .map(|f| {
                let n = self.victims.iter().filter(|v| v.found_by == *f).count();
                format!("{f}: {n}")
            })
            .collect();
        if !counts.is_empty() {
            out += &format!("  first found: {}\n", counts.join(", "));
        }
        out
    }
}

impl petrel_actors::PropertyType for TeamVictims {
    const TYPE_NAME: &'static str = "vision.team_victims";
}

#[cfg(test)]
mod tests;
