//! A* search on a [`CostMap`]: 8-connected, octile heuristic.
//!
//! Moving into a cell costs the step length (1 or sqrt 2 cells, in metres) times the cell's
//! cost multiplier. Cells with infinite cost are closed, with one exception: a search that
//! starts inside the lethal band (the robot got too close to a wall) may move through lethal,
//! non-obstacle cells as long as clearance does not decrease, so it can always back out.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::costmap::CostMap;

/// Cost multiplier of a cell crossed while escaping the lethal band.
const ESCAPE_COST: f32 = 10.0;

const NEIGHBOURS: [(i64, i64, f64); 8] = [
    (1, 0, 1.0),
    (-1, 0, 1.0),
    (0, 1, 1.0),
    (0, -1, 1.0),
    (1, 1, std::f64::consts::SQRT_2),
    (1, -1, std::f64::consts::SQRT_2),
    (-1, 1, std::f64::consts::SQRT_2),
    (-1, -1, std::f64::consts::SQRT_2),
];

/// Calls `f(next, step_cost)` for every cell reachable from `cur` in one move; `step` is the
/// cell size in metres. Shared with the brute-force reference in the tests.
#[inline]
pub fn for_each_move(map: &CostMap, cur: usize, step: f64, mut f: impl FnMut(usize, f64)) {
    let (col, row) = ((cur % map.width) as i64, (cur / map.width) as i64);
    let escaping = map.cost[cur].is_infinite();
    for &(dc, dr, len) in &NEIGHBOURS {
        let Some(n) = map.index(col + dc, row + dr) else {
            continue;
        };
        let mult = if map.cost[n].is_finite() {
            map.cost[n]
        } else if escaping && map.clearance[n] > 0.0 && map.clearance[n] >= map.clearance[cur] {
            ESCAPE_COST
        } else {
            continue;
        };
        if dc != 0 && dr != 0 {
            // No squeezing diagonally between two obstacle cells.
            let a = map.index(col + dc, row).expect("inside");
            let b = map.index(col, row + dr).expect("inside");
            if map.clearance[a] <= 0.0 || map.clearance[b] <= 0.0 {
                continue;
            }
        }
        f(n, len * step * mult as f64);
    }
}

/// Octile distance in metres: exact for an obstacle-free map with multiplier 1, never more.
fn octile(map: &CostMap, a: usize, b: usize, step: f64) -> f64 {
    let dx = ((a % map.width) as f64 - (b % map.width) as f64).abs();
    let dy = ((a / map.width) as f64 - (b / map.width) as f64).abs();
    step * (dx.max(dy) + (std::f64::consts::SQRT_2 - 1.0) * dx.min(dy))
}

/// The cheapest path from `start` to `goal` (cell indices, both included) and its cost, or
/// `None` if the goal cannot be reached. `step` is the cell size in metres.
pub fn astar(map: &CostMap, start: usize, goal: usize, step: f64) -> Option<(Vec<usize>, f64)> {
    let n = map.width * map.height;
    if start >= n || goal >= n || map.cost[goal].is_infinite() {
        return None;
    }
    let mut g = vec![f64::INFINITY; n];
    let mut parent = vec![u32::MAX; n];
    let mut open = BinaryHeap::new();
    g[start] = 0.0;
    // Non-negative f64s order like their bit patterns, so the heap can hold plain u64s.
    open.push(Reverse((octile(map, start, goal, step).to_bits(), start)));
    while let Some(Reverse((f_bits, cur))) = open.pop() {
        if cur == goal {
            let mut path = vec![goal];
            let mut k = goal;
            while k != start {
                k = parent[k] as usize;
                path.push(k);
            }
            path.reverse();
            return Some((path, g[goal]));
        }
        let gc = g[cur];
        if f64::from_bits(f_bits) > gc + octile(map, cur, goal, step) + 1e-12 {
            continue; // stale heap entry
        }
        for_each_move(map, cur, step, |next, c| {
            let ng = gc + c;
            if ng < g[next] {
                g[next] = ng;
                parent[next] = cur as u32;
                open.push(Reverse((
                    (ng + octile(map, next, goal, step)).to_bits(),
                    next,
                )));
            }
        });
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nav::costmap::{CostMap, CostParams};
    use petrel_actors::{OccupancyGrid, Pose2};
    use rand::{Rng, SeedableRng};

    /// Plain Dijkstra over the same moves: the brute-force reference.
    fn dijkstra(map: &CostMap, start: usize, goal: usize, step: f64) -> Option<f64> {
        let mut dist = vec![f64::INFINITY; map.width * map.height];
        let mut done = vec![false; dist.len()];
        if map.cost[goal].is_infinite() {
            return None;
        }
        dist[start] = 0.0;
        loop {
            let cur = (0..dist.len())
                .filter(|&k| !done[k] && dist[k].is_finite())
                .min_by(|&a, &b| dist[a].total_cmp(&dist[b]))?;
            if cur == goal {
                return Some(dist[goal]);
            }
            done[cur] = true;
            for_each_move(map, cur, step, |n, c| dist[n] = dist[n].min(dist[cur] + c));
        }
    }

    fn random_map(
        rng: &mut rand::rngs::StdRng,
        w: usize,
        h: usize,
        density: f64,
    ) -> (OccupancyGrid, CostMap) {
        let data: Vec<i8> = (0..w * h)
            .map(|_| {
                if rng.random_bool(density) {
                    100
                } else if rng.random_bool(0.1) {
                    -1
                } else {
                    0
                }
            })
            .collect();
        let grid = OccupancyGrid {
            width: w as u32,
            height: h as u32,
            resolution: 0.1,
            origin: Pose2::default(),
            data: data.into(),
        };
        let params = CostParams {
            robot_radius: 0.04,
            safety_margin: 0.0,
            preferred_clearance: 0.3,
            ..CostParams::default()
        };
        let map = CostMap::build(&grid, &params);
        (grid, map)
    }

    #[test]
    fn astar_matches_brute_force_cost_on_random_grids() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let (mut found, mut missing) = (0, 0);
        for _ in 0..150 {
            let (w, h) = (rng.random_range(3..16), rng.random_range(3..16));
            let density = rng.random_range(0.0..0.35);
            let (_, map) = random_map(&mut rng, w, h, density);
            let (s, g) = (rng.random_range(0..w * h), rng.random_range(0..w * h));
            let a = astar(&map, s, g, 0.1);
            let b = dijkstra(&map, s, g, 0.1);
            match (a, b) {
                (Some((path, cost)), Some(reference)) => {
                    found += 1;
                    assert!(
                        (cost - reference).abs() < 1e-9,
                        "A* {cost} vs Dijkstra {reference}"
                    );
                    assert_eq!((path[0], *path.last().unwrap()), (s, g));
                    // The path is connected and its summed move costs equal the reported cost.
                    let mut sum = 0.0;
                    for pair in path.windows(2) {
                        let mut c = None;
                        for_each_move(&map, pair[0], 0.1, |n, cost| {
                            if n == pair[1] {
                                c = Some(cost)
                            }
                        });
                        sum += c.expect("consecutive path cells are one legal move apart");
                    }
                    assert!((sum - cost).abs() < 1e-9);
                }
                (None, None) => missing += 1,
                (a, b) => panic!("A* {:?} vs Dijkstra {b:?}", a.map(|x| x.1)),
            }
        }
        assert!(
            found > 50 && missing > 5,
            "both outcomes exercised: {found} found, {missing} unreachable"
        );
    }

    #[test]
    fn a_start_inside_the_lethal_band_can_back_out() {
        // Obstacle column at x = 10 cells; start right next to it, goal far away.
        let mut data = vec![0i8; 30 * 10];
        for row in 0..10 {
            data[row * 30 + 10] = 100;
        }
        let grid = OccupancyGrid {
            width: 30,
            height: 10,
            resolution: 0.1,
            origin: Pose2::default(),
            data: data.into(),
        };
        let map = CostMap::build(&grid, &CostParams::default());
        let start = 5 * 30 + 9;
        assert!(map.cost[start].is_infinite());
        let (path, _) = astar(&map, start, 5 * 30 + 2, 0.1).expect("escapes");
        assert!(path.iter().all(|&k| map.clearance[k] > 0.0));
        assert!(
            astar(&map, start, 5 * 30 + 20, 0.1).is_none(),
            "cannot cross the wall"
        );
    }
}
