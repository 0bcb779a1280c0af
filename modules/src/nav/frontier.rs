//! Frontier-based exploration: where to go next on a map that is still being built.
//!
//! A frontier cell is a known free cell next to an unknown one. Only frontiers the robot can
//! reach matter: a breadth-first search from the robot's cell crosses known free cells that
//! keep `clearance` from every occupied cell (the robot's body must fit), so frontiers behind
//! walls, through gaps too narrow, or seen only through a doorway the laser looked through are
//! left alone. Reachable frontier cells are grouped (8-connected) into frontiers; tiny ones
//! (sensor specks) are ignored. The next target is the frontier cell nearest its frontier's
//! centre, of the frontier with the lowest `travel - gain_weight * size` (near and large
//! first). Exploration is done when the robot's cell is known and no reachable frontier is
//! left. Nothing here knows the world: only the map the robot built.
//!
//! A robot that searches with a camera passes a *searched* map too ([`crate::nav::searched`],
//! same geometry): then the frontier cells are the reachable free cells it marks not
//! searched, so exploration also leads to known floor the laser saw but the camera never
//! looked at, and is done only when every reachable free cell was searched. Free cells next
//! to unknown space are not searched either until the camera looked at them from its range,
//! so the unknown is still explored; but once searched they are no frontier: the laser looked
//! past them from closer than that and saw nothing beyond (a shelf's inside through a gap in
//! its face), and driving there again would change nothing.

use std::collections::VecDeque;

use petrel_actors::{OccupancyGrid, Point2, Pose2};

use crate::sim::error::{non_negative, positive, ParamError};

/// Explorer parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct FrontierParams {
    /// Distance the robot's centre keeps from occupied cells, metres (default 0.3: a 0.2 m
    /// robot plus a margin).
    pub clearance: f64,
    /// Map value from which a cell is occupied (default 50, as the planner).
    pub occupied_threshold: i8,
    /// Frontiers with fewer cells are ignored (default 4).
    pub min_frontier_cells: usize,
    /// Metres of travel one frontier cell is worth (default 0.05).
    pub gain_weight: f64,
    /// Targets within this distance of a blacklisted point are skipped, metres (default 0.6).
    pub blacklist_radius: f64,
    /// Only frontier cells in this rectangle `[x0, y0, x1, y1]` count (a robot's share of a
    /// team's search); the way there may cross anything. `None` (default): everywhere.
    pub area: Option<[f64; 4]>,
}

impl Default for FrontierParams {
    fn default() -> Self {
        FrontierParams {
            clearance: 0.3,
            occupied_threshold: 50,
            min_frontier_cells: 4,
            gain_weight: 0.05,
            blacklist_radius: 0.6,
            area: None,
        }
    }
}

impl FrontierParams {
    /// Checks every parameter.
    pub fn validate(&self) -> Result<(), ParamError> {
        non_negative("clearance", self.clearance)?;
        non_negative("gain_weight", self.gain_weight)?;
        positive("blacklist_radius", self.blacklist_radius)?;
        if !(1..=100).contains(&self.occupied_threshold) {
            return Err(ParamError {
                param: "occupied_threshold".into(),
                message: format!("expected 1..=100, got {}", self.occupied_threshold),
            });
        }
        if let Some([x0, y0, x1, y1]) = self.area {
            let finite = [x0, y0, x1, y1].iter().all(|v| v.is_finite());
            if !finite || x0 >= x1 || y0 >= y1 {
                return Err(ParamError {
                    param: "area".into(),
                    message: format!(
                        "expected `[x0, y0, x1, y1]` with x0 < x1 and y0 < y1, got {:?}",
                        [x0, y0, x1, y1]
                    ),
                });
            }
        }
        if self.min_frontier_cells == 0 {
            return Err(ParamError {
                param: "min_frontier_cells".into(),
                message: "expected at least 1, got 0".into(),
            });
        }
        Ok(())
    }
}

/// One reachable frontier.
#[derive(Clone, Debug, PartialEq)]
pub struct Frontier {
    /// Where to drive to explore it (a reachable frontier cell's centre).
    pub target: Point2,
    /// Cells in it.
    pub size: usize,
    /// Travel to `target` through known free space, metres.
    pub travel: f64,
}

/// What exploration says about a map.
#[derive(Clone, Debug, PartialEq)]
pub enum Exploration {
    /// The robot's cell is still unknown (no scan yet): nothing to decide.
    Waiting,
    /// Reachable frontiers, best first.
    Frontiers(Vec<Frontier>),
    /// No reachable frontier is left.
    Done,
}

/// Map cell classes for the search.
#[derive(Clone, Copy, PartialEq)]
enum Class {
    Unknown,
    Free,
    Occupied,
}

/// Finds reachable frontiers on `map` from `robot`, skipping targets near `blacklist`.
pub fn explore(
    map: &OccupancyGrid,
    robot: Pose2,
    blacklist: &[Point2],
    params: &FrontierParams,
) -> Exploration {
    explore_searched(map, None, robot, blacklist, params)
}

/// [`explore`], where the frontier cells are the reachable free cells that `searched` (a grid
/// of `map`'s geometry, -1 = not searched) does not mark as searched. A `searched` grid of
/// another geometry (none published yet) is ignored: the laser's frontiers count until then.
pub fn explore_searched(
    map: &OccupancyGrid,
    searched: Option<&OccupancyGrid>,
    robot: Pose2,
    blacklist: &[Point2],
    params: &FrontierParams,
) -> Exploration {
    let (w, h) = (map.width as i64, map.height as i64);
    if w == 0 || h == 0 || map.data.len() < (w * h) as usize || map.resolution <= 0.0 {
        return Exploration::Waiting;
    }
    let res = map.resolution;
    let class = |i: usize| match map.data[i] {
        v if v < 0 => Class::Unknown,
        v if v >= params.occupied_threshold => Class::Occupied,
        _ => Class::Free,
    };
    let index = |c: i64, r: i64| (r * w + c) as usize;
    let (rc, rr) = map.cell_of(robot.x(), robot.y());
    if rc < 0 || rr < 0 || rc >= w || rr >= h || class(index(rc, rr)) == Class::Unknown {
        return Exploration::Waiting;
    }
    // Cells too close to an occupied one for the robot's centre.
    let reach = (params.clearance / res).ceil() as i64;
    let mut blocked = vec![false; (w * h) as usize];
    for r in 0..h {
        for c in 0..w {
            if class(index(c, r)) != Class::Occupied {
                continue;
            }
            for dr in -reach..=reach {
                for dc in -reach..=reach {
                    let (cc, rr2) = (c + dc, r + dr);
                    let d = ((dc * dc + dr * dr) as f64).sqrt() * res;
                    if cc >= 0 && rr2 >= 0 && cc < w && rr2 < h && d <= params.clearance {
                        blocked[index(cc, rr2)] = true;
                    }
                }
            }
        }
    }
    // Breadth-first from the robot; a robot that starts too close to a wall may cross blocked
    // cells for as far as the clearance, to get out.
    let mut dist = vec![u32::MAX; (w * h) as usize];
    let mut queue = VecDeque::from([(rc, rr)]);
    dist[index(rc, rr)] = 0;
    let escape = reach as u32;
    while let Some((c, r)) = queue.pop_front() {
        let d = dist[index(c, r)];
        for (dc, dr) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
            let (nc, nr) = (c + dc, r + dr);
            if nc < 0 || nr < 0 || nc >= w || nr >= h {
                continue;
            }
            let i = index(nc, nr);
            if dist[i] != u32::MAX || class(i) != Class::Free || (blocked[i] && d + 1 > escape) {
                continue;
            }
            dist[i] = d + 1;
            queue.push_back((nc, nr));
        }
    }
    let inside = |c: i64, r: i64| {
        params.area.is_none_or(|[x0, y0, x1, y1]| {
            let centre = map.cell_center(c, r).0;
            (x0..=x1).contains(&centre.x) && (y0..=y1).contains(&centre.y)
        })
    };
    // Until the robot can reach some of its area, every frontier counts (the nearest to the
    // area first): the area is still unknown, and the way there is what must be explored.
    let reached = (0..h).any(|r| (0..w).any(|c| dist[index(c, r)] != u32::MAX && inside(c, r)));
    let in_area = |c: i64, r: i64| !reached || inside(c, r);
    let searched = searched.filter(|s| {
        (s.width, s.height, s.resolution, s.origin) == (map.width, map.height, res, map.origin)
            && s.data.len() == map.data.len()
    });
    let is_frontier = |c: i64, r: i64| {
        let i = index(c, r);
        in_area(c, r)
            && dist[i] != u32::MAX
            && !blocked[i]
            && match searched {
                Some(s) => s.data[i] < 0,
                None => [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|(dc, dr)| {
                    let (nc, nr) = (c + dc, r + dr);
                    nc >= 0 && nr >= 0 && nc < w && nr < h && class(index(nc, nr)) == Class::Unknown
                }),
            }
    };
    // Group reachable frontier cells into 8-connected frontiers.
    let mut seen = vec![false; (w * h) as usize];
    let mut frontiers = Vec::new();
    for r in 0..h {
        for c in 0..w {
            if seen[index(c, r)] || !is_frontier(c, r) {
                continue;
            }
            let mut cells = Vec::new();
            let mut stack = vec![(c, r)];
            seen[index(c, r)] = true;
            while let Some((fc, fr)) = stack.pop() {
                cells.push((fc, fr));
                for dr in -1..=1 {
                    for dc in -1..=1 {
                        let (nc, nr) = (fc + dc, fr + dr);
                        if nc >= 0
                            && nr >= 0
                            && nc < w
                            && nr < h
                            && !seen[index(nc, nr)]
                            && is_frontier(nc, nr)
                        {
                            seen[index(nc, nr)] = true;
                            stack.push((nc, nr));
                        }
                    }
                }
            }
            if cells.len() < params.min_frontier_cells {
                continue;
            }
            let n = cells.len() as f64;
            let mx = cells.iter().map(|p| p.0 as f64).sum::<f64>() / n;
            let my = cells.iter().map(|p| p.1 as f64).sum::<f64>() / n;
            let centre = |p: &(i64, i64)| map.cell_center(p.0, p.1);
            let allowed = |p: &&(i64, i64)| {
                let q = centre(p);
                blacklist
                    .iter()
                    .all(|b| (b.0 - q.0).norm() > params.blacklist_radius)
            };
            let best = cells.iter().filter(allowed).min_by(|a, b| {
                let da = (a.0 as f64 - mx).powi(2) + (a.1 as f64 - my).powi(2);
                let db = (b.0 as f64 - mx).powi(2) + (b.1 as f64 - my).powi(2);
                da.total_cmp(&db)
            });
            if let Some(cell) = best {
                frontiers.push(Frontier {
                    target: centre(cell),
                    size: cells.len(),
                    travel: dist[index(cell.0, cell.1)] as f64 * res,
                });
            }
        }
    }
    if frontiers.is_empty() {
        return Exploration::Done;
    }
    let score = |f: &Frontier| match (reached, params.area) {
        (false, Some([x0, y0, x1, y1])) => {
            let (x, y) = (f.target.0.x, f.target.0.y);
            (x0 - x)
                .max(x - x1)
                .max(0.0)
                .hypot((y0 - y).max(y - y1).max(0.0))
        }
        _ => f.travel - params.gain_weight * f.size as f64,
    };
    frontiers.sort_by(|a, b| score(a).total_cmp(&score(b)));
    Exploration::Frontiers(frontiers)
}

/// Known area of `map` (free or occupied cells), square metres.
pub fn known_area(map: &OccupancyGrid) -> f64 {
    map.data.iter().filter(|&&v| v >= 0).count() as f64 * map.resolution * map.resolution
}

#[cfg(test)]
mod tests;
