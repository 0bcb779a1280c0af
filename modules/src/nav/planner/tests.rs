//! Planner tests.

use super::*;

/// An all-free `w x h` grid of 0.1 m cells with the given cells set to `value`.
fn grid(w: u32, h: u32, cells: &[(u32, u32)], value: i8) -> OccupancyGrid {
    let mut data = vec![0i8; (w * h) as usize];
    for &(c, r) in cells {
        data[(r * w + c) as usize] = value;
    }
    OccupancyGrid {
        width: w,
        height: h,
        resolution: 0.1,
        origin: Pose2::default(),
        data: data.into(),
    }
}

fn wall(col: u32, rows: std::ops::Range<u32>) -> Vec<(u32, u32)> {
    rows.map(|r| (col, r)).collect()
}

fn min_clearance(path: &[Point2], map: &OccupancyGrid) -> f64 {
    let mut best = f64::INFINITY;
    for p in path {
        for (k, &v) in map.data.iter().enumerate() {
            if v >= 50 {
                let (cx, cy) = (
                    (k as u32 % map.width) as f64 * 0.1 + 0.05,
                    (k as u32 / map.width) as f64 * 0.1 + 0.05,
                );
                let (dx, dy) = ((p.0.x - cx).abs() - 0.05, (p.0.y - cy).abs() - 0.05);
                best = best.min(dx.max(0.0).hypot(dy.max(0.0)));
            }
        }
    }
    best
}

#[test]
fn plans_around_a_wall_with_clearance_and_targets_ahead() {
    let map = grid(60, 40, &wall(30, 0..30), 100);
    let mut p = Planner::new(PlannerParams::default()).unwrap();
    let out = p.step(&map, Pose2::new(1.0, 1.0, 0.0), Pose2::new(5.0, 1.0, 0.0));
    assert!(out.replanned && !out.failed && !out.arrived);
    assert!(
        out.path.iter().any(|q| q.0.y > 3.0),
        "goes around the wall's top end"
    );
    assert!(min_clearance(&out.path, &map) >= 0.25 - 0.02);
    let last = out.path.last().unwrap();
    assert!((last.0.x - 5.0).abs() < 1e-12 && (last.0.y - 1.0).abs() < 1e-12);
    // The path heads up and to the right; the local target is ahead, 0.8 m along the path.
    let t = out.local_target;
    assert!(
        t.x() > 0.0 && (t.x().hypot(t.y()) - 0.8).abs() < 0.15,
        "{t:?}"
    );
    // Same map, same goal: the path is kept.
    let again = p.step(&map, Pose2::new(1.1, 1.1, 0.0), Pose2::new(5.0, 1.0, 0.0));
    assert!(!again.replanned && Arc::ptr_eq(&again.path, &out.path));
    assert_eq!(p.replans(), 1);
    let arrived = p.step(&map, Pose2::new(4.9, 1.1, 0.0), Pose2::new(5.0, 1.0, 0.0));
    assert!(arrived.arrived && arrived.local_target == Pose2::default());
}

#[test]
fn local_target_is_expressed_in_the_robot_frame() {
    let map = grid(60, 20, &[], 0);
    let mut p = Planner::new(PlannerParams::default()).unwrap();
    // Path along +x at y = 1.05; robot faces +y, so "ahead along the path" is to its right.
    let out = p.step(
        &map,
        Pose2::new(1.05, 1.05, std::f64::consts::FRAC_PI_2),
        Pose2::new(5.05, 1.05, 0.0),
    );
    let t = out.local_target;
    assert!(t.x().abs() < 1e-9 && (t.y() + 0.8).abs() < 1e-9, "{t:?}");
    assert!((t.theta() + std::f64::consts::FRAC_PI_2).abs() < 1e-9);
}

#[test]
fn replans_when_a_new_obstacle_blocks_the_path() {
    let mut p = Planner::new(PlannerParams::default()).unwrap();
    let (start, goal) = (Pose2::new(1.0, 2.0, 0.0), Pose2::new(5.0, 2.0, 0.0));
    let first = p.step(&grid(60, 40, &[], 0), start, goal);
    assert!(
        first.path.iter().all(|q| (q.0.y - 2.0).abs() < 0.1),
        "straight line first"
    );
    // A changed map that does not touch the path does not trigger a search.
    let aside = p.step(&grid(60, 40, &[(5, 35)], 100), start, goal);
    assert!(!aside.replanned);
    let blocked = grid(60, 40, &wall(30, 10..30), 100);
    let second = p.step(&blocked, start, goal);
    assert!(second.replanned && !second.failed);
    assert!(min_clearance(&second.path, &blocked) >= 0.23);
    assert_eq!(p.replans(), 2);
}

#[test]
fn fails_without_a_path_and_retries_when_the_map_changes() {
    let mut p = Planner::new(PlannerParams::default()).unwrap();
    let (start, goal) = (Pose2::new(1.0, 2.0, 0.0), Pose2::new(5.0, 2.0, 0.0));
    let closed = grid(60, 40, &wall(30, 0..40), 100);
    let out = p.step(&closed, start, goal);
    assert!(out.failed && out.path.is_empty() && out.local_target == Pose2::default());
    assert!(p.step(&closed, start, goal).failed);
    assert_eq!(p.replans(), 1, "no search while nothing changed");
    let open = grid(60, 40, &wall(30, 0..30), 100);
    assert!(!p.step(&open, start, goal).failed);

    // Unknown space is blocked when `unknown_is_free` is off.
    let params = PlannerParams {
        cost: CostParams {
            unknown_is_free: false,
            ..CostParams::default()
        },
        ..PlannerParams::default()
    };
    let mut strict = Planner::new(params).unwrap();
    assert!(
        strict
            .step(&grid(60, 40, &wall(30, 0..40), -1), start, goal)
            .failed
    );
    assert!(Planner::new(PlannerParams {
        lookahead: 0.0,
        ..PlannerParams::default()
    })
    .is_err());
}

#[test]
fn a_goal_close_to_a_wall_is_approached_within_tolerance() {
    // Wall column at x in [3.0, 3.1]; the goal is 0.15 m from its face, inside the lethal band.
    let map = grid(60, 40, &wall(30, 0..40), 100);
    let mut p = Planner::new(PlannerParams::default()).unwrap();
    let goal = Pose2::new(2.85, 2.0, 0.0);
    let out = p.step(&map, Pose2::new(1.0, 2.0, 0.0), goal);
    assert!(!out.failed);
    let end = out.path.last().unwrap();
    let d = (end.0.x - goal.x()).hypot(end.0.y - goal.y());
    assert!(
        d <= 0.25 && end.0.x <= 3.0 - 0.25,
        "ends {d} m from the goal, clear of the wall"
    );
    assert!(
        p.step(&map, Pose2::new(end.0.x, end.0.y, 0.0), goal)
            .arrived
    );
}

/// A robot sent to look at something (a victim to confirm) is there only once it faces the
/// goal's heading: at the goal's position the planner asks to turn in place, by the shorter
/// way round, and says arrived when the heading is within tolerance. Without the tolerance
/// the heading is ignored, as for a frontier.
#[test]
fn a_goal_to_face_is_reached_only_facing_its_heading() {
    let map = grid(40, 40, &[], 0);
    let goal = Pose2::new(2.0, 2.0, 170f64.to_radians());
    let at = |heading: f64| Pose2::new(2.05, 2.0, heading.to_radians());
    let mut ignoring = Planner::new(PlannerParams::default()).unwrap();
    let out = ignoring.step(&map, at(-150.0), goal);
    assert!(
        out.arrived && out.local_target == Pose2::default(),
        "{out:?}"
    );

    let mut facing = Planner::new(PlannerParams {
        heading_tolerance: Some(0.15),
        ..PlannerParams::default()
    })
    .unwrap();
    // 40° to turn, the short way (clockwise, through 180°), in place.
    let out = facing.step(&map, at(-150.0), goal);
    assert!(!out.arrived && !out.failed, "{out:?}");
    let t = out.local_target;
    assert_eq!((t.x(), t.y()), (0.0, 0.0));
    assert!((t.theta() + 40f64.to_radians()).abs() < 1e-9, "{t:?}");
    // Within 0.15 rad (8.6°): arrived, and the local target says stay.
    let out = facing.step(&map, at(175.0), goal);
    assert!(
        out.arrived && out.local_target == Pose2::default(),
        "{out:?}"
    );
    // Switched off at run time (the mission's next goal is a frontier): heading ignored.
    facing.set_heading_tolerance(None).unwrap();
    assert!(facing.step(&map, at(0.0), goal).arrived);
    let err = facing.set_heading_tolerance(Some(f64::NAN)).unwrap_err();
    assert_eq!(err.param, "heading_tolerance");
}
