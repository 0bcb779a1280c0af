use super::*;

/// A map from text rows (top first): `#` occupied, `.` free, `?` unknown; 0.1 m cells.
fn map(rows: &[&str]) -> OccupancyGrid {
    crate::nav::text_map::text_map(rows, 0.1, (0.0, 0.0))
}

fn params() -> FrontierParams {
    FrontierParams {
        clearance: 0.05,
        ..FrontierParams::default()
    }
}

/// A room whose right side is unknown, with a walled-off unknown pocket on the left.
const ROOM: [&str; 10] = [
    "##########????",
    "#........#????",
    "#.........????",
    "#.........????",
    "#.........????",
    "#.........????",
    "#..###...#????",
    "#..#?#...#????",
    "#..###...#????",
    "##########????",
];

#[test]
fn the_reachable_frontier_is_found_and_the_walled_pocket_is_not() {
    let m = map(&ROOM);
    let Exploration::Frontiers(f) = explore(&m, Pose2::new(0.25, 0.45, 0.0), &[], &params()) else {
        panic!("expected frontiers");
    };
    assert_eq!(f.len(), 1, "{f:?}");
    // The opening on the right is column 9, rows 4..=7 (y 0.4 .. 0.8), target near its middle.
    let t = f[0].target;
    assert!(
        (t.0.x - 0.95).abs() < 1e-9 && (0.45..=0.75).contains(&t.0.y),
        "{t:?}"
    );
    assert_eq!(f[0].size, 4);
    assert!(f[0].travel > 0.6 && f[0].travel < 1.2, "{}", f[0].travel);
}

#[test]
fn a_closed_map_is_done_an_unknown_robot_cell_waits() {
    let closed: Vec<String> = ROOM
        .iter()
        .map(|r| r.replace("..????", "..#???").replace(".#????", ".#???#"))
        .collect();
    let closed: Vec<&str> = closed.iter().map(String::as_str).collect();
    assert_eq!(
        explore(&map(&closed), Pose2::new(0.25, 0.45, 0.0), &[], &params()),
        Exploration::Done
    );
    assert_eq!(
        explore(&map(&ROOM), Pose2::new(1.25, 0.45, 0.0), &[], &params()),
        Exploration::Waiting
    );
    assert_eq!(
        explore(&OccupancyGrid::default(), Pose2::default(), &[], &params()),
        Exploration::Waiting
    );
}

#[test]
fn blacklisted_small_and_too_narrow_frontiers_are_skipped() {
    let m = map(&ROOM);
    let robot = Pose2::new(0.25, 0.45, 0.0);
    let blacklist = [Point2::new(0.95, 0.6)];
    assert_eq!(explore(&m, robot, &blacklist, &params()), Exploration::Done);
    let big = FrontierParams {
        min_frontier_cells: 5,
        ..params()
    };
    assert_eq!(explore(&m, robot, &[], &big), Exploration::Done);
    // With 0.3 m of clearance the robot cannot pass the 0.4 m gap: nothing reachable.
    let wide = FrontierParams {
        clearance: 0.3,
        ..params()
    };
    assert_eq!(explore(&m, robot, &[], &wide), Exploration::Done);
    let bad = FrontierParams {
        min_frontier_cells: 0,
        ..params()
    };
    assert_eq!(bad.validate().unwrap_err().param, "min_frontier_cells");
}

#[test]
fn near_large_frontiers_come_first_and_known_area_counts_cells() {
    let m = map(&[
        "????????????",
        "#..........#",
        "#..........#",
        "#..........#",
        "#####..#####",
        "#..........#",
        "#.........?#",
        "############",
    ]);
    let robot = Pose2::new(0.25, 0.15, 0.0);
    let frontiers = |gain_weight| {
        let p = FrontierParams {
            min_frontier_cells: 1,
            gain_weight,
            ..params()
        };
        match explore(&m, robot, &[], &p) {
            Exploration::Frontiers(f) => f,
            other => panic!("expected frontiers, got {other:?}"),
        }
    };
    let near = frontiers(0.0);
    assert_eq!(near.len(), 2, "{near:?}");
    assert!(
        near[0].size == 2 && near[0].travel < near[1].travel,
        "nearest first: {near:?}"
    );
    let large = frontiers(0.05);
    assert_eq!(
        large[0].size, 10,
        "the large one is worth the detour: {large:?}"
    );
    assert!((known_area(&m) - 0.83).abs() < 1e-9, "{}", known_area(&m));
}

#[test]
fn an_area_keeps_only_the_frontiers_inside_it() {
    // Two openings: right (x 0.9 .. 1.0) and top (y 0.9 .. 1.0).
    let m = map(&[
        "#####????###",
        "#..........?",
        "#..........?",
        "#..........?",
        "############",
    ]);
    let robot = Pose2::new(0.25, 0.15, 0.0);
    let only = |area| {
        let p = FrontierParams {
            area,
            min_frontier_cells: 1,
            ..params()
        };
        match explore(&m, robot, &[], &p) {
            Exploration::Frontiers(f) => f.iter().map(|f| f.target).collect::<Vec<_>>(),
            other => panic!("expected frontiers, got {other:?}"),
        }
    };
    assert_eq!(only(None).len(), 2);
    let right = only(Some([1.0, 0.0, 1.2, 0.5]));
    assert!(right.len() == 1 && right[0].0.x > 1.0, "{right:?}");
    let top = only(Some([0.0, 0.3, 1.0, 0.5]));
    assert!(
        top.len() == 1 && top[0].0.y > 0.3 && top[0].0.x < 1.0,
        "{top:?}"
    );
    // An area the robot cannot reach yet: every frontier counts, the nearest to it first.
    let far = FrontierParams {
        area: Some([1.5, 0.0, 3.0, 0.5]),
        min_frontier_cells: 1,
        ..params()
    };
    let Exploration::Frontiers(f) = explore(&m, robot, &[], &far) else {
        panic!("expected frontiers");
    };
    assert!(f.len() == 2 && f[0].target.0.x > 1.0, "{f:?}");
    // Reached and fully known: done, whatever lies outside it.
    let known = FrontierParams {
        area: Some([0.0, 0.0, 0.4, 0.3]),
        ..params()
    };
    assert_eq!(explore(&m, robot, &[], &known), Exploration::Done);
    let bad = FrontierParams {
        area: Some([1.0, 0.0, 0.0, 1.0]),
        ..params()
    };
    assert_eq!(bad.validate().unwrap_err().param, "area");
}

#[test]
fn known_floor_not_searched_is_explored_until_searched() {
    // A closed room: no laser frontier, so exploration alone is done.
    let m = map(&[
        "##########",
        "#........#",
        "#........#",
        "#........#",
        "#........#",
        "##########",
    ]);
    let robot = Pose2::new(0.15, 0.15, 0.0);
    assert_eq!(explore(&m, robot, &[], &params()), Exploration::Done);
    // The camera searched everything but the room's right end (columns 6..=8).
    let searched = |unsearched_from: i64| {
        let mut s = m.clone();
        s.data = (0..m.data.len() as i64)
            .map(|i| if i % 10 >= unsearched_from { -1 } else { 0 })
            .collect();
        s
    };
    let part = searched(6);
    let Exploration::Frontiers(f) = explore_searched(&m, Some(&part), robot, &[], &params()) else {
        panic!("the unsearched end should be a frontier");
    };
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(f[0].size, 12, "3 columns x 4 free rows");
    assert!((0.6..0.9).contains(&f[0].target.0.x), "{:?}", f[0].target);
    // Searched everywhere (walls included or not): done again.
    assert_eq!(
        explore_searched(&m, Some(&searched(10)), robot, &[], &params()),
        Exploration::Done
    );
    // A searched grid of another geometry (none published yet) is ignored.
    assert_eq!(
        explore_searched(&m, Some(&OccupancyGrid::default()), robot, &[], &params()),
        Exploration::Done
    );
    // The edge of unknown space is a frontier while it is not searched, and no longer once
    // the camera searched it (the laser looked past it and saw nothing).
    let open_end = map(&[
        "##########",
        "#........?",
        "#........?",
        "#........?",
        "#........?",
        "##########",
    ]);
    assert!(matches!(
        explore_searched(&open_end, Some(&part), robot, &[], &params()),
        Exploration::Frontiers(_)
    ));
    assert_eq!(
        explore_searched(&open_end, Some(&searched(10)), robot, &[], &params()),
        Exploration::Done
    );
    // Unsearched floor the robot cannot reach does not count.
    let walled = map(&[
        "##########",
        "#.....#..#",
        "#.....#..#",
        "#.....#..#",
        "#.....#..#",
        "##########",
    ]);
    assert_eq!(
        explore_searched(&walled, Some(&part), robot, &[], &params()),
        Exploration::Done
    );
}
