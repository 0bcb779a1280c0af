use std::collections::BTreeSet;

use super::*;

/// A map from text rows (top first): `#` occupied, `.` free, `?` unknown; 1 m cells, so cell
/// `(c, r)` has its centre at `(c + 0.5, r + 0.5)` plus `origin`.
fn map(rows: &[&str], origin: (f64, f64)) -> OccupancyGrid {
    crate::nav::text_map::text_map(rows, 1.0, origin)
}

/// An all-free `w` x `h` map.
fn open(w: usize, h: usize) -> OccupancyGrid {
    let row = ".".repeat(w);
    map(&vec![row.as_str(); h], (0.0, 0.0))
}

/// The geometry alone: a 100° view (102° less the edge margin), nothing taken off for a
/// victim's width: a cell counts where all four of its corners are in view and `min_range`
/// ahead.
fn params(min_range: f64, max_range: f64) -> SearchParams {
    SearchParams {
        fov: 102f64.to_radians(),
        victim_radius: 0.0,
        min_range,
        max_range,
        min_views: 1,
        edge_range: max_range,
        ..SearchParams::default()
    }
}

/// The searched cells, as `(col, row)`.
fn cells(s: &SearchedMap) -> BTreeSet<(i64, i64)> {
    let g = s.geometry.clone();
    (0..g.height as i64)
        .flat_map(|r| (0..g.width as i64).map(move |c| (c, r)))
        .filter(|&(c, r)| s.is_searched(c, r))
        .collect()
}

#[test]
fn a_camera_searches_exactly_the_cells_in_its_view_and_range() {
    // Camera in cell (0, 5) facing +x, ±50°, from 0.5 m ahead to centres 2.5 m away: the cell
    // ahead and the three of the next column. (1, 4) and (1, 6) reach 72° off at their far
    // corners, (2, 3) and (2, 7) are 2.83 m away.
    let mut s = SearchedMap::new(params(0.5, 2.5)).unwrap();
    let added = s.look(Pose2::new(0.5, 5.5, 0.0), &open(10, 10));
    let expected: BTreeSet<_> = [(1, 5), (2, 4), (2, 5), (2, 6)].into();
    assert_eq!(cells(&s), expected);
    assert_eq!(added, 4);
    assert!((s.area() - 4.0).abs() < 1e-12);
    // Looking again from the same pose adds nothing.
    assert_eq!(s.look(Pose2::new(0.5, 5.5, 0.0), &open(10, 10)), 0);
}

#[test]
fn range_limits_leave_the_near_and_far_floor_unsearched() {
    // A minimum of 1.5 m ahead drops the first column (its near corners are 0.5 m ahead); the
    // second column's are 1.5 m ahead.
    let mut s = SearchedMap::new(params(1.5, 2.5)).unwrap();
    s.look(Pose2::new(0.5, 5.5, 0.0), &open(10, 10));
    assert_eq!(cells(&s), [(2, 4), (2, 5), (2, 6)].into());
    // Ahead, not away: (2, 3) and (2, 7) are 2.83 m away, but their near corners only 1.5 m
    // ahead. A band of 2.4 m ahead to 3 m away leaves the third column's middle cell (2.5 m
    // ahead, 3 m away; its neighbours are 3.16 m away).
    let mut s = SearchedMap::new(params(2.4, 3.0)).unwrap();
    s.look(Pose2::new(0.5, 5.5, 0.0), &open(10, 10));
    assert_eq!(cells(&s), [(3, 5)].into());
}

#[test]
fn heading_and_map_origin_are_honoured() {
    // Facing -y (down) from cell (5, 5) of a map whose corner is at (-2, -3).
    let m = map(&[".........."; 10], (-2.0, -3.0));
    let mut s = SearchedMap::new(params(0.5, 2.5)).unwrap();
    s.look(Pose2::new(3.5, 2.5, -std::f64::consts::FRAC_PI_2), &m);
    let expected: BTreeSet<_> = [(5, 4), (4, 3), (5, 3), (6, 3)].into();
    assert_eq!(cells(&s), expected);
}

#[test]
fn walls_and_unknown_space_hide_what_lies_behind_them() {
    // Camera at cell (0, 2) facing +x, 1 to 4.5 m; a wall cell at (2, 2), unknown at (2, 0).
    let rows = [
        "........", // row 4
        "........", // row 3
        "..#.....", // row 2
        "........", // row 1
        "..?.....", // row 0
    ];
    let mut s = SearchedMap::new(params(1.0, 4.5)).unwrap();
    s.look(Pose2::new(0.5, 2.5, 0.0), &map(&rows, (0.0, 0.0)));
    let got = cells(&s);
    assert!(got.contains(&(2, 2)), "the wall's face was seen: {got:?}");
    for hidden in [(3, 2), (4, 2)] {
        assert!(
            !got.contains(&hidden),
            "{hidden:?} is behind the wall: {got:?}"
        );
    }
    assert!(
        !got.contains(&(2, 0)),
        "unknown cells are never searched: {got:?}"
    );
    assert!(!got.contains(&(3, 0)), "behind unknown space: {got:?}");
    // Beside the wall the view is clear: the lines to (4, 4) and (3, 4) pass above it.
    assert!(got.contains(&(4, 4)) && got.contains(&(3, 4)), "{got:?}");
    // The same pose without the wall sees straight through.
    let mut clear = SearchedMap::new(params(1.0, 4.5)).unwrap();
    clear.look(Pose2::new(0.5, 2.5, 0.0), &open(8, 5));
    assert!(cells(&clear).contains(&(4, 2)));
}

#[test]
fn the_grid_marks_searched_cells_and_a_new_geometry_starts_afresh() {
    let mut s = SearchedMap::new(params(0.5, 2.5)).unwrap();
    assert_eq!(s.grid().width, 0, "nothing before the first look");
    s.look(Pose2::new(0.5, 5.5, 0.0), &open(10, 10));
    let g = s.grid();
    assert_eq!((g.width, g.height), (10, 10));
    assert_eq!(g.get(1, 5), Some(SEARCHED));
    assert_eq!(g.get(0, 5), Some(NOT_SEARCHED));
    assert_eq!(g.data.iter().filter(|&&v| v == SEARCHED).count(), 4);
    s.look(Pose2::new(0.5, 5.5, 0.0), &open(12, 10));
    assert_eq!(s.grid().width, 12);
    assert_eq!(
        cells(&s).len(),
        4,
        "the old cells were dropped, the new look counted"
    );
}

#[test]
fn a_cell_is_searched_only_after_enough_views() {
    let mut s = SearchedMap::new(SearchParams {
        min_views: 2,
        ..params(0.5, 2.5)
    })
    .unwrap();
    assert_eq!(s.look(Pose2::new(0.5, 5.5, 0.0), &open(10, 10)), 0);
    assert!(cells(&s).is_empty(), "one glimpse is not a search");
    // The second frame, turned 34° left, sees (1, 6), (1, 7) and (2, 6): only the cell both
    // frames saw is searched.
    let added = s.look(Pose2::new(0.5, 5.5, 0.6), &open(10, 10));
    let got = cells(&s);
    assert_eq!(added, got.len());
    assert_eq!(got, [(2, 6)].into(), "seen once: the others");
}

#[test]
fn floor_beside_unknown_space_counts_only_from_near() {
    // Unknown space from column 4 on; the camera looks along row 2.
    let edge = map(&["....????"; 5], (0.0, 0.0));
    let p = SearchParams {
        edge_range: 2.5,
        ..params(1.0, 4.5)
    };
    let mut s = SearchedMap::new(p.clone()).unwrap();
    s.look(Pose2::new(0.5, 2.5, 0.0), &edge);
    let got = cells(&s);
    assert!(got.contains(&(2, 2)), "2 m away, not beside it: {got:?}");
    assert!(
        !got.contains(&(3, 2)),
        "3 m away beside the unknown: {got:?}"
    );
    // From a metre nearer it counts...
    let mut near = SearchedMap::new(p).unwrap();
    near.look(Pose2::new(1.5, 2.5, 0.0), &edge);
    assert!(cells(&near).contains(&(3, 2)));
    // ...and from afar once the laser mapped past it.
    s.look(Pose2::new(0.5, 2.5, 0.0), &open(8, 5));
    assert!(cells(&s).contains(&(3, 2)));
}

#[test]
fn bad_parameters_are_refused_by_name() {
    let bad = |p: SearchParams| SearchedMap::new(p).unwrap_err().param;
    assert_eq!(bad(params(3.0, 2.0)), "min_range");
    assert_eq!(bad(params(-1.0, 2.0)), "min_range");
    assert_eq!(bad(params(0.0, 0.0)), "max_range");
    let fov = SearchParams {
        fov: 0.0,
        ..SearchParams::default()
    };
    assert_eq!(bad(fov), "fov");
    let views = SearchParams {
        min_views: 0,
        ..SearchParams::default()
    };
    assert_eq!(bad(views), "min_views");
    for edge_range in [0.5, 1.0, f64::NAN] {
        assert_eq!(
            bad(SearchParams {
                edge_range,
                ..params(1.0, 4.5)
            }),
            "edge_range"
        );
    }
}

#[test]
fn a_heading_change_is_the_shorter_way_round_in_degrees() {
    use std::f64::consts::PI;
    let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
    let change = |a: f64, b: f64| {
        // The positions do not matter.
        heading_change(&Pose2::new(1.0, 2.0, a), &Pose2::new(-3.0, 0.5, b))
    };
    assert!(close(change(0.0, 0.1), 0.1f64.to_degrees()));
    assert!(close(change(0.1, 0.0), 0.1f64.to_degrees()));
    // Across ±π: 2°, not 358°.
    assert!(close(
        change(PI - 0.0174533, -PI + 0.0174533),
        2.0 * 0.0174533f64.to_degrees()
    ));
    // Whole turns do not count.
    assert!(close(change(0.2, 0.2 + 4.0 * PI), 0.0));
    assert!(close(change(0.0, PI), 180.0));
}
