//! The maps of a team's robots merged into one (pure).
//!
//! Every robot maps in the world frame (its localizer starts at its body's start pose), so
//! maps of the same geometry merge cell by cell, with no alignment. A cell is unknown only
//! when every robot left it unknown; otherwise the robots that know it vote, and a tie is
//! free: a robot seen by another robot's laser is an obstacle in that map only until the
//! robot itself, or anyone else, maps the cell free, so one stale sighting never walls a
//! corridor off for the whole team. Maps of another size, resolution or origin than the
//! first are left out (a misconfigured robot must not corrupt the team's map).
//!
//! The floor the robots' cameras searched ([`merge_searched`]) merges by union: a cell one
//! robot looked at well enough is searched for the team.

use petrel_actors::OccupancyGrid;

/// The value a merged cell gets when most robots that know it saw it occupied.
const OCCUPIED: i8 = 100;

/// The merge of `maps` (in order; empty maps are skipped), and how many maps were left out
/// because their geometry differs from the first one used. `None` when no map has cells.
pub fn merge_maps(
    maps: &[&OccupancyGrid],
    occupied_threshold: i8,
) -> Option<(OccupancyGrid, usize)> {
    let mut used = maps.iter().filter(|m| is_filled(m));
    let first = *used.next()?;
    let mut same = vec![first];
    let mut left_out = 0;
    for m in used {
        if same_geometry(first, m) {
            same.push(m);
        } else {
            left_out += 1;
        }
    }
    let cells = first.data.len();
    let mut data = vec![-1i8; cells];
    for (i, cell) in data.iter_mut().enumerate() {
        let (mut known, mut occupied) = (0u32, 0u32);
        for m in &same {
            let v = m.data[i];
            if v >= 0 {
                known += 1;
                if v >= occupied_threshold {
                    occupied += 1;
                }
            }
        }
        if known > 0 {
            *cell = if 2 * occupied > known { OCCUPIED } else { 0 };
        }
    }
    let merged = OccupancyGrid {
        data: data.into(),
        ..first.clone()
    };
    Some((merged, left_out))
}

/// The union of the robots' searched grids (`nav.searched`: 0 searched, -1 not) on the
/// geometry of `map` (the team's merged map): searched where any robot searched. Grids of
/// another geometry (a robot whose grid has not arrived yet, or a misconfigured one) are
/// left out. `None` when no grid fits: the explorer then counts the laser's frontiers alone.
pub fn merge_searched(grids: &[&OccupancyGrid], map: &OccupancyGrid) -> Option<OccupancyGrid> {
    let cells = map.data.len();
    let mut fitting = grids
        .iter()
        .filter(|g| is_filled(g) && same_geometry(map, g) && g.data.len() == cells)
        .peekable();
    fitting.peek()?;
    let mut data = vec![-1i8; cells];
    for g in fitting {
        for (cell, &v) in data.iter_mut().zip(g.data.iter()) {
            if v >= 0 {
                *cell = 0;
            }
        }
    }
    Some(OccupancyGrid {
        data: data.into(),
        ..map.clone()
    })
}

/// A grid with as many cells as its size says (an input that never received a map has none).
fn is_filled(m: &OccupancyGrid) -> bool {
    m.width > 0 && m.height > 0 && m.data.len() == m.width as usize * m.height as usize
}

fn same_geometry(a: &OccupancyGrid, b: &OccupancyGrid) -> bool {
    a.width == b.width
        && a.height == b.height
        && a.resolution == b.resolution
        && a.origin == b.origin
}

#[cfg(test)]
mod tests {
    use super::*;
    use petrel_actors::Pose2;

    fn grid(data: &[i8]) -> OccupancyGrid {
        OccupancyGrid {
            width: data.len() as u32,
            height: 1,
            resolution: 0.1,
            origin: Pose2::default(),
            data: data.into(),
        }
    }

    #[test]
    fn known_cells_vote_unknown_only_where_nobody_looked() {
        let a = grid(&[-1, 0, 100, 100, 0, -1]);
        let b = grid(&[-1, -1, 100, 0, 0, 100]);
        let c = grid(&[-1, -1, -1, 0, 80, -1]);
        let (m, left_out) = merge_maps(&[&a, &b, &c], 50).unwrap();
        assert_eq!(left_out, 0);
        // Unknown to all; free to one; occupied to both; occupied to one of three; occupied to
        // one of three; occupied to the only one that saw it.
        assert_eq!(&*m.data, &[-1, 0, 100, 0, 0, 100]);
        // A tie is free: one robot's sighting of another robot is not a wall.
        let (m, _) = merge_maps(&[&a, &b], 50).unwrap();
        assert_eq!(m.data[3], 0);
    }

    #[test]
    fn maps_of_another_geometry_and_empty_maps_are_left_out() {
        let a = grid(&[0, -1]);
        let wider = grid(&[100, 100, 100]);
        let mut moved = grid(&[100, 100]);
        moved.origin = Pose2::new(1.0, 0.0, 0.0);
        let empty = OccupancyGrid::default();
        let (m, left_out) = merge_maps(&[&empty, &a, &wider, &moved], 50).unwrap();
        assert_eq!((&*m.data, left_out), (&[0i8, -1][..], 2));
        assert!(merge_maps(&[&empty], 50).is_none());
        assert!(merge_maps(&[], 50).is_none());
    }

    #[test]
    fn searched_floor_is_the_union_of_the_grids_that_fit_the_map() {
        let map = grid(&[0, 0, 0, 100]);
        let a = grid(&[0, -1, -1, -1]);
        let b = grid(&[-1, -1, 0, -1]);
        let mut moved = grid(&[0, 0, 0, 0]);
        moved.origin = Pose2::new(1.0, 0.0, 0.0);
        let empty = OccupancyGrid::default();
        let union = merge_searched(&[&a, &empty, &moved, &b], &map).unwrap();
        assert_eq!(&*union.data, &[0, -1, 0, -1]);
        assert_eq!((union.width, union.resolution), (map.width, map.resolution));
        assert!(merge_searched(&[&moved, &empty], &map).is_none());
    }
}
