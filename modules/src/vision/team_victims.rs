//! Victims reported by the robots of a team, merged into one list (pure).
//!
//! Each robot reports a victim once, from its own sightings and its own pose estimate, so two
//! robots' reports of one victim are independent estimates: the list keeps their mean, which
//! is closer than either alone (on the shaking rubble floor one report can land 2 m off).

use petrel_actors::Point2;

/// One victim of the team's list.
#[derive(Clone, Debug, PartialEq)]
pub struct TeamVictim {
    /// Where the reports put it: their mean (map frame).
    pub position: Point2,
    /// How many reports were merged into it.
    pub reports: usize,
    /// Who reported it first.
    pub found_by: String,
    /// Who reported it again (each once), in order.
    pub also_by: Vec<String>,
}

/// What a report was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Report {
    /// A victim nobody had reported: its index in the list.
    New(usize),
    /// Within the merge radius of a known victim: its index.
    Known(usize),
}

/// The team's victims: a report within `radius` of a known victim is that victim.
#[derive(Clone, Debug)]
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

    /// `from` (a robot) reports a victim at `p`.
    pub fn report(&mut self, from: &str, p: Point2) -> Report {
        let near = self
            .victims
            .iter()
            .position(|v| (v.position.0 - p.0).norm() <= self.radius);
        match near {
            Some(i) => {
                let v = &mut self.victims[i];
                v.reports += 1;
                v.position = Point2(v.position.0 + (p.0 - v.position.0) / v.reports as f64);
                if v.found_by != from && !v.also_by.iter().any(|a| a == from) {
                    v.also_by.push(from.to_string());
                }
                Report::Known(i)
            }
            None => {
                self.victims.push(TeamVictim {
                    position: p,
                    reports: 1,
                    found_by: from.to_string(),
                    also_by: Vec::new(),
                });
                Report::New(self.victims.len() - 1)
            }
        }
    }

    /// The list, in the order found.
    pub fn victims(&self) -> &[TeamVictim] {
        &self.victims
    }

    /// One line per victim (`1 (x, y) found by robot_2, also robot_1`), then who found how many.
    pub fn summary(&self) -> String {
        let mut out = format!("team victims: {}\n", self.victims.len());
        for (i, v) in self.victims.iter().enumerate() {
            let also = match v.also_by.is_empty() {
                true => String::new(),
                false => format!(", also {}", v.also_by.join(", ")),
            };
            out += &format!(
                "  {} ({:.2}, {:.2}) found by {}{also}\n",
                i + 1,
                v.position.0.x,
                v.position.0.y,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_near_a_known_victim_are_that_victim_and_finders_are_kept() {
        let mut t = TeamVictims::new(1.0);
        assert_eq!(t.report("r2", Point2::new(1.0, 1.0)), Report::New(0));
        assert_eq!(t.report("r1", Point2::new(1.5, 1.2)), Report::Known(0));
        assert_eq!(t.report("r1", Point2::new(1.4, 0.9)), Report::Known(0));
        assert_eq!(t.report("r2", Point2::new(1.1, 0.9)), Report::Known(0));
        assert_eq!(t.report("r1", Point2::new(5.0, 1.0)), Report::New(1));
        assert_eq!(t.victims()[0].also_by, ["r1"]);
        // The mean of the four reports.
        assert_eq!(t.victims()[0].reports, 4);
        assert_eq!(
            t.summary(),
            "team victims: 2\n  1 (1.25, 1.00) found by r2, also r1\n  2 (5.00, 1.00) found by r1\n  first found: r1: 1, r2: 1\n"
        );
        assert_eq!(TeamVictims::new(1.0).summary(), "team victims: 0\n");
    }
}
