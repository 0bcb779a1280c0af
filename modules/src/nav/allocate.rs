//! Frontiers of a team's merged map handed out to its robots (pure).
//!
//! Each robot keeps the frontier it claimed while a frontier reachable from it stays within
//! `keep_radius` of the claim (its target does not jump around as the frontier shrinks).
//! Robots without a claim are then served nearest first: the robot-frontier pair with the
//! shortest travel among unclaimed frontiers is claimed, and so on, so no two robots ever
//! share a frontier and each gets its nearest unclaimed one. Frontiers within `keep_radius`
//! of a claim count as claimed (robots see the same frontier from different places, and the
//! frontier search may put its target on different cells for them). A robot that left the
//! team, or that has no candidates any more, loses its claim, and the frontier is free for
//! the others at the same allocation.

use std::collections::BTreeMap;

use petrel_actors::Point2;

use super::Frontier;

/// What one allocation changed for a robot.
#[derive(Clone, Debug, PartialEq)]
pub enum Change {
    /// The robot was given a frontier.
    Assigned {
        /// Who.
        robot: String,
        /// Where to go.
        target: Point2,
    },
    /// The robot's claim ended: it left (not among the candidates), or its frontier is gone.
    Released {
        /// Who.
        robot: String,
        /// What it had claimed.
        target: Point2,
    },
}

/// Claims of the team's robots, one frontier each at most.
#[derive(Clone, Debug)]
pub struct Allocator {
    keep_radius: f64,
    claims: BTreeMap<String, Point2>,
}

impl Allocator {
    /// No claims yet; frontiers within `keep_radius` metres are one.
    pub fn new(keep_radius: f64) -> Self {
        Allocator {
            keep_radius,
            claims: BTreeMap::new(),
        }
    }

    /// The frontier `robot` is to explore, if any.
    pub fn claim_of(&self, robot: &str) -> Option<Point2> {
        self.claims.get(robot).copied()
    }

    /// Ends `robot`'s claim (it gave its frontier up); returns what it had claimed.
    pub fn release(&mut self, robot: &str) -> Option<Point2> {
        self.claims.remove(robot)
    }

    /// Allocates given each present robot's reachable frontiers (`travel` from it); robots
    /// absent from `candidates` have left. Returns what changed, releases first.
    pub fn allocate(&mut self, candidates: &BTreeMap<String, Vec<Frontier>>) -> Vec<Change> {
        let mut changes = Vec::new();
        let near = |a: Point2, b: Point2, r: f64| (a.0 - b.0).norm() <= r;
        let keep = self.keep_radius;
        let claims = std::mem::take(&mut self.claims);
        for (robot, target) in claims {
            let still = candidates
                .get(&robot)
                .is_some_and(|list| list.iter().any(|f| near(f.target, target, keep)));
            if still {
                self.claims.insert(robot, target);
            } else {
                changes.push(Change::Released { robot, target });
            }
        }
        loop {
            let claimed = |p: Point2| self.claims.values().any(|c| near(*c, p, keep));
            // The shortest travel of any robot without a claim to any unclaimed frontier; ties
            // go to the first robot by name, then the first frontier, so runs repeat.
            let best = candidates
                .iter()
                .filter(|(robot, _)| !self.claims.contains_key(*robot))
                .flat_map(|(robot, list)| list.iter().map(move |f| (robot, f)))
                .filter(|(_, f)| !claimed(f.target))
                .min_by(|a, b| a.1.travel.total_cmp(&b.1.travel));
            let Some((robot, f)) = best else { break };
            self.claims.insert(robot.clone(), f.target);
            changes.push(Change::Assigned {
                robot: robot.clone(),
                target: f.target,
            });
        }
        changes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(x: f64, y: f64, travel: f64) -> Frontier {
        Frontier {
            target: Point2::new(x, y),
            size: 10,
            travel,
        }
    }

    fn candidates(list: &[(&str, Vec<Frontier>)]) -> BTreeMap<String, Vec<Frontier>> {
        list.iter()
            .map(|(r, l)| (r.to_string(), l.clone()))
            .collect()
    }

    fn assigned(a: &Allocator, robot: &str) -> Option<(f64, f64)> {
        a.claim_of(robot).map(|p| (p.0.x, p.0.y))
    }

    #[test]
    fn no_two_robots_share_a_frontier_and_each_gets_its_nearest_unclaimed_one() {
        let mut a = Allocator::new(0.5);
        // Both are nearest to (1, 1); r1 is nearer to it, so r2 gets its next nearest.
        let c = candidates(&[
            ("r1", vec![f(1.0, 1.0, 2.0), f(5.0, 5.0, 9.0)]),
            (
                "r2",
                vec![f(1.0, 1.0, 3.0), f(5.0, 5.0, 4.0), f(8.0, 1.0, 6.0)],
            ),
            // r3 sees r1's frontier with its target two cells away: still taken.
            ("r3", vec![f(1.2, 1.0, 2.5), f(8.0, 1.0, 7.0)]),
        ]);
        let changes = a.allocate(&c);
        assert_eq!(assigned(&a, "r1"), Some((1.0, 1.0)));
        assert_eq!(assigned(&a, "r2"), Some((5.0, 5.0)));
        assert_eq!(assigned(&a, "r3"), Some((8.0, 1.0)));
        assert_eq!(changes.len(), 3);
        // Nothing left for a fourth robot: it waits rather than share.
        let mut c4 = c.clone();
        c4.insert("r4".into(), vec![f(5.0, 5.0, 0.5)]);
        assert!(a.allocate(&c4).is_empty());
        assert_eq!(assigned(&a, "r4"), None);
    }

    #[test]
    fn a_claim_is_kept_while_its_frontier_lasts_and_released_when_it_is_gone() {
        let mut a = Allocator::new(0.5);
        a.allocate(&candidates(&[("r1", vec![f(1.0, 1.0, 5.0)])]));
        // A nearer frontier appears, and the old one shrank a little: r1 keeps its target.
        let c = candidates(&[("r1", vec![f(3.0, 3.0, 1.0), f(1.3, 1.0, 4.0)])]);
        assert!(a.allocate(&c).is_empty());
        assert_eq!(assigned(&a, "r1"), Some((1.0, 1.0)));
        // Explored: released and the next one assigned at once.
        let changes = a.allocate(&candidates(&[("r1", vec![f(3.0, 3.0, 1.0)])]));
        assert_eq!(
            changes,
            [
                Change::Released {
                    robot: "r1".into(),
                    target: Point2::new(1.0, 1.0)
                },
                Change::Assigned {
                    robot: "r1".into(),
                    target: Point2::new(3.0, 3.0)
                },
            ]
        );
    }

    #[test]
    fn a_departed_robots_claim_is_released_and_taken_over() {
        let mut a = Allocator::new(0.5);
        let both = candidates(&[
            ("r1", vec![f(1.0, 1.0, 1.0)]),
            ("r2", vec![f(1.0, 1.0, 8.0), f(9.0, 9.0, 9.0)]),
        ]);
        a.allocate(&both);
        assert_eq!(assigned(&a, "r1"), Some((1.0, 1.0)));
        assert_eq!(assigned(&a, "r2"), Some((9.0, 9.0)));
        // r2 reaches its frontier (gone), r1 leaves the team: r2 takes r1's frontier.
        let changes = a.allocate(&candidates(&[("r2", vec![f(1.0, 1.0, 8.0)])]));
        assert_eq!(
            changes,
            [
                Change::Released {
                    robot: "r1".into(),
                    target: Point2::new(1.0, 1.0)
                },
                Change::Released {
                    robot: "r2".into(),
                    target: Point2::new(9.0, 9.0)
                },
                Change::Assigned {
                    robot: "r2".into(),
                    target: Point2::new(1.0, 1.0)
                },
            ]
        );
        assert_eq!(assigned(&a, "r1"), None);
    }
}
