//! What a team's search did, for its summary (pure): who explored how many frontiers, who
//! left the team when, who stalled, and which frontier of a departed robot went to whom, how
//! long after.

use petrel_actors::{Point2, PropertyType};
use serde::{Deserialize, Serialize};

/// A departed robot's frontier given to another robot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reassignment {
    /// The robot that left.
    pub from: String,
    /// The robot that took its frontier over.
    pub to: String,
    /// The frontier.
    pub target: Point2,
    /// When `from` was seen leaving, and when `to` was given its frontier (simulated s).
    pub left_at: f64,
    /// When `to` was given the frontier.
    pub at: f64,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
struct RobotLog {
    name: String,
    present: bool,
    left_at: Option<f64>,
    assigned: usize,
    taken_over: usize,
    stalled: usize,
}

/// The log of one search. Kept in the search module's `state/log`, so that a move or a
/// restart of the module does not start its summary over.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TeamLog {
    radius: f64,
    robots: Vec<RobotLog>,
    /// Frontiers released by departed robots, not yet given to anyone: (robot, target, left at).
    orphans: Vec<(String, Point2, f64)>,
    reassignments: Vec<Reassignment>,
    done_at: Option<f64>,
}

impl PropertyType for TeamLog {
    const TYPE_NAME: &'static str = "nav.team_log";
}

impl TeamLog {
    /// Whether this is the log of a search by `robots` (in that order).
    pub fn is_of(&self, robots: &[String]) -> bool {
        !self.robots.is_empty() && self.robots.iter().map(|r| &r.name).eq(robots.iter())
    }

    /// A log of `robots`; an assignment within `radius` metres of an orphaned frontier takes
    /// it over.
    pub fn new(robots: impl IntoIterator<Item = String>, radius: f64) -> Self {
        TeamLog {
            radius,
            robots: robots
                .into_iter()
                .map(|name| RobotLog {
                    name,
                    ..RobotLog::default()
                })
                .collect(),
            orphans: Vec::new(),
            reassignments: Vec::new(),
            done_at: None,
        }
    }

    /// The team's members at `t`: returns the robots that left since the last call (a robot
    /// leaves once it was present; one that rejoins may leave again).
    pub fn membership(&mut self, present: &[String], t: f64) -> Vec<String> {
        let mut left = Vec::new();
        for r in &mut self.robots {
            let here = present.contains(&r.name);
            if r.present && !here {
                r.left_at = Some(t);
                left.push(r.name.clone());
            }
            r.present = here;
        }
        left
    }

    /// `robot`'s claim on `target` ended; `departed` when it left the team.
    pub fn released(&mut self, robot: &str, target: Point2, departed: bool) {
        let left_at = self.robot(robot).and_then(|r| r.left_at);
        if let (true, Some(left_at)) = (departed, left_at) {
            self.orphans.push((robot.to_string(), target, left_at));
        }
    }

    /// `robot` was given `target` at `t`; when it is a departed robot's frontier, the line
    /// that says so.
    pub fn assigned(&mut self, robot: &str, target: Point2, t: f64) -> Option<String> {
        if let Some(r) = self.robot_mut(robot) {
            r.assigned += 1;
        }
        let radius = self.radius;
        let i = self
            .orphans
            .iter()
            .position(|(_, p, _)| (p.0 - target.0).norm() <= radius)?;
        let (from, target, left_at) = self.orphans.remove(i);
        if let Some(r) = self.robot_mut(robot) {
            r.taken_over += 1;
        }
        let line = format!(
            "{from}'s frontier ({:.2}, {:.2}) reassigned to {robot}, {:.1} s after {from} left",
            target.0.x,
            target.0.y,
            t - left_at
        );
        self.reassignments.push(Reassignment {
            from,
            to: robot.to_string(),
            target,
            left_at,
            at: t,
        });
        Some(line)
    }

    /// `robot` stalled at `at` holding `target` (see [`super::StallWatch`]); the line that says so.
    pub fn stalled(&mut self, robot: &str, at: Point2, target: Point2, stall_s: f64) -> String {
        if let Some(r) = self.robot_mut(robot) {
            r.stalled += 1;
        }
        format!(
            "{robot} stalled at ({:.2}, {:.2}): it did not move for {stall_s:.0} s; its frontier ({:.2}, {:.2}) goes to another robot, and it gets none for {stall_s:.0} s",
            at.0.x, at.0.y, target.0.x, target.0.y
        )
    }

    /// The search ended at `t`.
    pub fn done(&mut self, t: f64) {
        self.done_at.get_or_insert(t);
    }

    /// Departed robots' frontiers given to others, in order.
    pub fn reassignments(&self) -> &[Reassignment] {
        &self.reassignments
    }

    /// The summary printed at the end of a run.
    pub fn summary(&self) -> String {
        let mut out = match self.done_at {
            Some(t) => format!("team search: done at t = {t:.1} s\n"),
            None => "team search: not done\n".to_string(),
        };
        for r in &self.robots {
            out += &format!("  {}: {} frontier(s)", r.name, r.assigned);
            if r.taken_over > 0 {
                out += &format!(", {} taken over", r.taken_over);
            }
            if r.stalled > 0 {
                out += &format!(", stalled {} time(s)", r.stalled);
            }
            if let Some(t) = r.left_at {
                out += &format!(", left the team at t = {t:.1} s");
            }
            out += "\n";
        }
        for x in &self.reassignments {
            out += &format!(
                "  reassigned: {}'s frontier ({:.2}, {:.2}) to {} at t = {:.1} s, {:.1} s after {} left\n",
                x.from, x.target.0.x, x.target.0.y, x.to, x.at, x.at - x.left_at, x.from
            );
        }
        for (from, p, _) in &self.orphans {
            out += &format!(
                "  {from}'s frontier ({:.2}, {:.2}) was explored by others before anyone was sent there\n",
                p.0.x, p.0.y
            );
        }
        out
    }

    fn robot(&self, name: &str) -> Option<&RobotLog> {
        self.robots.iter().find(|r| r.name == name)
    }

    fn robot_mut(&mut self, name: &str) -> Option<&mut RobotLog> {
        self.robots.iter_mut().find(|r| r.name == name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_departed_robots_frontier_is_logged_when_someone_takes_it_over() {
        let names = ["r1", "r2"].map(String::from);
        let mut log = TeamLog::new(names.clone(), 1.0);
        assert!(log.membership(&names, 0.0).is_empty());
        assert_eq!(log.assigned("r1", Point2::new(1.0, 1.0), 0.0), None);
        assert_eq!(log.membership(&names[1..], 40.0), ["r1"]);
        log.released("r1", Point2::new(1.0, 1.0), true);
        // Elsewhere: not r1's frontier. Near it: taken over.
        assert_eq!(log.assigned("r2", Point2::new(5.0, 5.0), 41.0), None);
        let line = log.assigned("r2", Point2::new(1.5, 1.0), 42.5).unwrap();
        assert_eq!(
            line,
            "r1's frontier (1.00, 1.00) reassigned to r2, 2.5 s after r1 left"
        );
        log.done(90.0);
        assert_eq!(
            log.summary(),
            "team search: done at t = 90.0 s\n  r1: 1 frontier(s), left the team at t = 40.0 s\n  r2: 2 frontier(s), 1 taken over\n  reassigned: r1's frontier (1.00, 1.00) to r2 at t = 42.5 s, 2.5 s after r1 left\n"
        );
    }

    #[test]
    fn a_claim_given_up_by_a_present_robot_is_no_orphan() {
        let names = ["r1", "r2"].map(String::from);
        let mut log = TeamLog::new(names.clone(), 1.0);
        log.membership(&names, 0.0);
        log.released("r1", Point2::new(1.0, 1.0), false);
        assert_eq!(log.assigned("r2", Point2::new(1.0, 1.0), 3.0), None);
        assert!(log.reassignments().is_empty());
        let line = log.stalled("r1", Point2::new(1.0, 1.5), Point2::new(2.0, 3.0), 20.0);
        assert_eq!(line, "r1 stalled at (1.00, 1.50): it did not move for 20 s; its frontier (2.00, 3.00) goes to another robot, and it gets none for 20 s");
        assert!(
            log.summary()
                .contains("  r1: 0 frontier(s), stalled 1 time(s)\n"),
            "{}",
            log.summary()
        );
    }

    #[test]
    fn a_log_kept_in_state_comes_back_whole_even_through_a_snapshot() {
        let names = ["r1", "r2"].map(String::from);
        let mut log = TeamLog::new(names.clone(), 1.0);
        log.membership(&names, 0.0);
        log.assigned("r1", Point2::new(1.0, 1.0), 0.0);
        log.assigned("r2", Point2::new(4.0, 1.0), 2.0);
        // A snapshot is read back through RON's dynamic values.
        let back: TeamLog = crate::test_support::through_ron_values(&log);
        assert_eq!(back, log);
        assert!(back.is_of(&names));
        assert!(!back.is_of(&names[..1]), "another team's log is not taken");
        assert!(!TeamLog::default().is_of(&[]), "nothing kept yet");
    }
}
