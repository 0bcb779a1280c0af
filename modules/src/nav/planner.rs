//! Global path planning: A* on the inflated map, replanning, and a look-ahead local target.

use std::sync::Arc;

use nalgebra::{Isometry2, Vector2};
use petrel_actors::{OccupancyGrid, Point2, Pose2};

use super::astar::astar;
use super::costmap::{CostMap, CostParams};
use crate::sim::error::{positive, ParamError};

/// Planner parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannerParams {
    /// How the map is inflated and costed.
    pub cost: CostParams,
    /// Distance to the goal position at which it counts as reached, metres (default 0.25).
    pub goal_tolerance: f64,
    /// Arc length along the path from the robot's closest point to the local target (default 0.8).
    pub lookahead: f64,
    /// Distance from the path that triggers a replan, metres (default 0.6).
    pub max_deviation: f64,
    /// When set, the goal is reached only once the robot also faces the goal's heading within
    /// this many radians: at the goal's position it turns in place (a robot sent to look at
    /// something). `None` (default): the goal's heading is ignored.
    pub heading_tolerance: Option<f64>,
}

impl Default for PlannerParams {
    fn default() -> Self {
        PlannerParams {
            cost: CostParams::default(),
            goal_tolerance: 0.25,
            lookahead: 0.8,
            max_deviation: 0.6,
            heading_tolerance: None,
        }
    }
}

impl PlannerParams {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.cost.validate()?;
        positive("goal_tolerance", self.goal_tolerance)?;
        positive("lookahead", self.lookahead)?;
        positive("max_deviation", self.max_deviation)?;
        check_heading_tolerance(self.heading_tolerance)
    }
}

/// [`PlannerParams::heading_tolerance`]: none, or an angle in (0, π].
fn check_heading_tolerance(tolerance: Option<f64>) -> Result<(), ParamError> {
    match tolerance {
        Some(t) if !(t > 0.0 && t <= std::f64::consts::PI) => Err(ParamError {
            param: "heading_tolerance".into(),
            message: format!("expected an angle in (0, π] rad, got {t}"),
        }),
        _ => Ok(()),
    }
}

/// What the planner produces at each step.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannerOutput {
    /// The current global path in world coordinates (empty when arrived or failed).
    pub path: Arc<[Point2]>,
    /// Where to head next, in the robot frame; the identity when arrived or failed (stay).
    /// At the goal's position, facing it (`heading_tolerance`): the origin turned by the
    /// heading still to turn.
    pub local_target: Pose2,
    /// The robot is within `goal_tolerance` of the goal (and faces its heading, if asked to).
    pub arrived: bool,
    /// No path to the goal exists on the current map.
    pub failed: bool,
    /// A new path was computed in this step.
    pub replanned: bool,
}

/// The planner's state between steps.
#[derive(Clone, Debug)]
pub struct Planner {
    params: PlannerParams,
    path: Arc<[Point2]>,
    /// Index of the path point closest to the robot at the last step.
    progress: usize,
    goal: Option<Pose2>,
    /// The map data the current path (or failure) was computed or last checked against.
    checked_map: Option<Arc<[i8]>>,
    failed: bool,
    replans: u64,
}

impl Planner {
    /// A planner with no path yet.
    pub fn new(params: PlannerParams) -> Result<Self, ParamError> {
        params.validate()?;
        Ok(Planner {
            params,
            path: Arc::from(Vec::new()),
            progress: 0,
            goal: None,
            checked_map: None,
            failed: false,
            replans: 0,
        })
    }

    /// Number of A* searches run so far.
    pub fn replans(&self) -> u64 {
        self.replans
    }

    /// Changes [`PlannerParams::heading_tolerance`] (a mission asks to face one goal and not
    /// the next). Out of range is refused, as by [`PlannerParams::validate`].
    pub fn set_heading_tolerance(&mut self, tolerance: Option<f64>) -> Result<(), ParamError> {
        check_heading_tolerance(tolerance)?;
        self.params.heading_tolerance = tolerance;
        Ok(())
    }

    /// Plans (or keeps following) a path from `robot` to `goal` on `map`.
    ///
    /// Replans when the goal moved, the map changed so that an obstacle now lies on the
    /// remaining path, or the robot strayed more than `max_deviation` from it. After a
    /// failure it tries again only when the map or the goal changes.
    pub fn step(&mut self, map: &OccupancyGrid, robot: Pose2, goal: Pose2) -> PlannerOutput {
        let goal_changed = self
            .goal
            .is_none_or(|g| (g.0.translation.vector - goal.0.translation.vector).norm() > 1e-9);
        let map_changed = self
            .checked_map
            .as_ref()
            .is_none_or(|m| !Arc::ptr_eq(m, &map.data));
        self.goal = Some(goal);
        if !well_formed(map) {
            // A malformed map (data length not width x height, bad resolution) cannot be
            // planned on; report failure rather than index out of bounds.
            self.path = Arc::from(Vec::new());
            self.failed = true;
            self.checked_map = None;
            return self.output(Pose2::default(), false, true, false);
        }
        let to_goal = (goal.0.translation.vector - robot.0.translation.vector).norm();
        if to_goal <= self.params.goal_tolerance {
            self.path = Arc::from(Vec::new());
            self.failed = false;
            // Facing the goal, if asked to: the heading still to turn, the short way round.
            let turn = self.params.heading_tolerance.and_then(|tolerance| {
                let error = goal.theta() - robot.theta();
                Some(error.sin().atan2(error.cos())).filter(|turn| turn.abs() > tolerance)
            });
            return match turn {
                Some(turn) => self.output(Pose2::new(0.0, 0.0, turn), false, false, false),
                None => self.output(Pose2::default(), true, false, false),
            };
        }
        let mut replan = goal_changed || self.path.is_empty() && !self.failed;
        if self.failed {
            replan |= map_changed;
        } else if !replan {
            let deviation = self.advance_progress(robot);
            replan = deviation > self.params.max_deviation || map_changed && self.path_blocked(map);
        }
        if map_changed {
            self.checked_map = Some(map.data.clone());
        }
        if replan {
            self.plan(map, robot, goal);
            if !self.failed {
                self.advance_progress(robot);
            }
        }
        if self.failed {
            return self.output(Pose2::default(), false, true, replan);
        }
        let target = self.local_target(robot);
        self.output(target, false, false, replan)
    }

    fn output(
        &self,
        local_target: Pose2,
        arrived: bool,
        failed: bool,
        replanned: bool,
    ) -> PlannerOutput {
        PlannerOutput {
            path: self.path.clone(),
            local_target,
            arrived,
            failed,
            replanned,
        }
    }

    fn plan(&mut self, map: &OccupancyGrid, robot: Pose2, goal: Pose2) {
        self.replans += 1;
        self.progress = 0;
        let cost = CostMap::build(map, &self.params.cost);
        let cell = |p: &Pose2| {
            let (col, row) = map.cell_of(p.x(), p.y());
            cost.index(col, row)
        };
        let target = cell(&goal).and_then(|g| self.reachable_goal_cell(&cost, g, map.resolution));
        let found = match (cell(&robot), target) {
            (Some(s), Some((g, _))) => astar(&cost, s, g, map.resolution),
            _ => None,
        };
        self.failed = found.is_none();
        let Some((cells, _)) = found else {
            self.path = Arc::from(Vec::new());
            return;
        };
        let mut points: Vec<Point2> = cells
            .iter()
            .map(|&k| {
                let (col, row) = ((k % cost.width) as i64, (k / cost.width) as i64);
                map.cell_center(col, row)
            })
            .collect();
        // End exactly at the goal rather than at its cell centre, unless the goal itself is
        // too close to an obstacle and a nearby cell stands in for it.
        if target.is_some_and(|(_, exact)| exact) {
            *points.last_mut().expect("a path has at least one cell") = goal.position();
        }
        self.path = points.into();
    }

    /// The cell to plan to for goal cell `g`: `g` itself if the robot may stand there
    /// (`true`), else the cell with the most clearance that is still within
    /// `goal_tolerance` of it (`false`), so that a goal placed close to a wall stays reachable.
    fn reachable_goal_cell(&self, cost: &CostMap, g: usize, res: f64) -> Option<(usize, bool)> {
        if cost.cost[g].is_finite() {
            return Some((g, true));
        }
        let reach = (self.params.goal_tolerance / res).floor() as i64;
        let (gc, gr) = ((g % cost.width) as i64, (g / cost.width) as i64);
        let mut best: Option<(f32, usize)> = None;
        for dr in -reach..=reach {
            for dc in -reach..=reach {
                let within =
                    ((dc * dc + dr * dr) as f64).sqrt() * res <= self.params.goal_tolerance * 0.9;
                if let Some(k) = cost
                    .index(gc + dc, gr + dr)
                    .filter(|&k| within && cost.cost[k].is_finite())
                {
                    if best.is_none_or(|(c, _)| cost.clearance[k] > c) {
                        best = Some((cost.clearance[k], k));
                    }
                }
            }
        }
        best.map(|(_, k)| (k, false))
    }

    /// Moves `progress` to the path point closest to the robot (searching a window ahead,
    /// so a path that doubles back is not short-cut) and returns the distance to it.
    fn advance_progress(&mut self, robot: Pose2) -> f64 {
        let r = robot.0.translation.vector;
        let end = (self.progress + 200).min(self.path.len());
        let mut best = (f64::INFINITY, self.progress);
        for (i, p) in self.path[self.progress..end].iter().enumerate() {
            let d = (p.0.coords - r).norm();
            if d < best.0 {
                best = (d, self.progress + i);
            }
        }
        self.progress = best.1;
        best.0
    }

    /// Whether any obstacle lies within the robot radius of the remaining path.
    fn path_blocked(&self, map: &OccupancyGrid) -> bool {
        let res = map.resolution;
        let reach = (self.params.cost.robot_radius / res).ceil() as i64;
        let r2 = (self.params.cost.robot_radius / res).powi(2);
        // The first stretch is where the robot already is; obstacles there are the local
        // controller's business, and a path escaping from a wall would always look blocked.
        let skip = (self.params.cost.lethal_clearance() / res).ceil() as usize;
        let from = (self.progress + skip).min(self.path.len());
        self.path[from..].iter().any(|p| {
            let (col, row) = map.cell_of(p.0.x, p.0.y);
            (-reach..=reach).any(|dr| {
                (-reach..=reach).any(|dc| {
                    ((dc * dc + dr * dr) as f64) <= r2
                        && map
                            .get(col + dc, row + dr)
                            .is_some_and(|v| v >= self.params.cost.occupied_threshold)
                })
            })
        })
    }

    /// The point `lookahead` metres along the path from `progress`, with the path's
    /// direction there, in the robot frame.
    fn local_target(&self, robot: Pose2) -> Pose2 {
        let path = &self.path;
        let mut i = self.progress;
        let mut left = self.params.lookahead;
        while i + 1 < path.len() {
            let seg = (path[i + 1].0 - path[i].0).norm();
            if seg >= left {
                break;
            }
            left -= seg;
            i += 1;
        }
        let (point, dir) = if i + 1 < path.len() {
            let d = (path[i + 1].0 - path[i].0).normalize();
            (path[i].0 + d * left, d)
        } else {
            let last = path[path.len() - 1].0;
            let prev = if path.len() > 1 {
                path[path.len() - 2].0
            } else {
                robot.position().0
            };
            let d = last - prev;
            (
                last,
                if d.norm() > 1e-12 {
                    d.normalize()
                } else {
                    Vector2::x()
                },
            )
        };
        let world = Isometry2::new(point.coords, dir.y.atan2(dir.x));
        Pose2(robot.0.inverse() * world)
    }
}

/// Whether `map` is consistent enough to index: data length, resolution and origin.
pub fn well_formed(map: &OccupancyGrid) -> bool {
    map.data.len() == map.width as usize * map.height as usize
        && map.resolution.is_finite()
        && map.resolution > 0.0
        && map.origin.x().is_finite()
        && map.origin.y().is_finite()
}

#[cfg(test)]
mod tests;
