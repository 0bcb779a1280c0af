use super::*;

fn seen(bearing: f64, range: f64) -> Detection {
    Detection {
        bearing,
        range,
        confidence: 0.9,
    }
}

#[test]
fn repeated_sightings_confirm_one_victim_and_do_not_duplicate_it() {
    let mut m = VictimMap::new(VictimMapParams::default());
    // A victim at (3, 2): seen from (1, 2) facing +x, then from (2, 1) facing +y.
    assert_eq!(m.add(Pose2::new(1.0, 2.0, 0.0), &seen(0.0, 2.1)), None);
    assert_eq!(m.add(Pose2::new(1.0, 2.0, 0.0), &seen(0.02, 1.9)), None);
    let confirmed = m
        .add(
            Pose2::new(2.0, 1.0, std::f64::consts::FRAC_PI_2),
            &seen(-0.785, 1.41),
        )
        .unwrap();
    assert!(
        (confirmed.0.x - 3.0).abs() < 0.1 && (confirmed.0.y - 2.0).abs() < 0.1,
        "{confirmed:?}"
    );
    for _ in 0..5 {
        assert_eq!(m.add(Pose2::new(1.0, 2.0, 0.0), &seen(0.0, 2.0)), None);
    }
    assert_eq!(m.seen().len(), 1);
    // A second victim far away is a new candidate, confirmed on its own.
    for _ in 0..3 {
        m.add(
            Pose2::new(1.0, 2.0, 0.0),
            &seen(std::f64::consts::FRAC_PI_2, 3.0),
        );
    }
    assert_eq!(m.seen().len(), 2);
}

#[test]
fn weak_far_and_single_sightings_are_not_victims() {
    let mut m = VictimMap::new(VictimMapParams::default());
    m.add(Pose2::default(), &seen(0.0, 2.0));
    m.add(
        Pose2::default(),
        &Detection {
            confidence: 0.01,
            ..seen(0.0, 2.0)
        },
    );
    // Another robot against a wall can be a sighting of 0.6, frame after frame.
    for _ in 0..5 {
        m.add(
            Pose2::default(),
            &Detection {
                confidence: 0.6,
                ..seen(0.0, 2.0)
            },
        );
    }
    m.add(Pose2::default(), &seen(0.0, 9.0));
    assert!(m.seen().is_empty());
    let bad = VictimMapParams {
        confirm_hits: 0,
        ..VictimMapParams::default()
    };
    assert!(bad.validate().unwrap_err().contains("confirm_hits"));
}

#[test]
fn the_target_is_the_nearest_pending_victim_until_reported_or_dismissed() {
    let mut m = VictimMap::new(VictimMapParams::default());
    let robot = Pose2::new(0.0, 0.0, 0.0);
    assert_eq!(m.target(robot.position()), None);
    // Victims at (4, 0) and (0, 3), three sightings each, in one frame.
    m.next_frame();
    for _ in 0..3 {
        m.add(robot, &seen(0.0, 4.0));
        m.add(robot, &seen(std::f64::consts::FRAC_PI_2, 3.0));
    }
    assert_eq!(m.pending(), 2);
    let t = m.target(robot.position()).unwrap();
    assert!((t.position.0.y - 3.0).abs() < 1e-9, "nearest first: {t:?}");
    // One metre short of it, on the robot's side, facing it; seen this frame.
    assert!((t.approach.y() - 2.0).abs() < 1e-9 && t.approach.x().abs() < 1e-9);
    assert!((t.approach.theta() - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
    assert!(t.in_view);
    // Kept while pending, even when the robot is now nearer the other one.
    let near_other = Point2::new(3.5, 0.0);
    assert_eq!(m.target(near_other).unwrap().position, t.position);
    // Out of view after `view_frames` frames without a sighting.
    for _ in 0..3 {
        m.next_frame();
    }
    assert!(!m.target(near_other).unwrap().in_view);
    assert_eq!(m.report(), Some(t.position));
    assert_eq!(m.reported(), vec![t.position]);
    assert_eq!(m.pending(), 1);
    let second = m.target(near_other).unwrap();
    assert!((second.position.0.x - 4.0).abs() < 1e-9);
    assert!(m.dismiss().is_some());
    assert_eq!((m.pending(), m.seen().len()), (0, 1));
    assert_eq!(m.target(near_other), None);
    assert_eq!(m.report(), None, "nothing left to report");
    // Sightings of a dismissed candidate raise nothing again.
    for _ in 0..5 {
        assert_eq!(m.add(robot, &seen(0.0, 4.0)), None);
    }
    assert_eq!(m.pending(), 0);
}

#[test]
fn near_sightings_outweigh_far_ones() {
    let mut m = VictimMap::new(VictimMapParams {
        confirm_hits: 2,
        ..VictimMapParams::default()
    });
    // A victim at (6, 0), first seen from 4.8 m away 1.2 m short (a camera pitched by a
    // jolt), which confirms it there.
    m.add(Pose2::default(), &seen(0.0, 4.8));
    let first = m.add(Pose2::default(), &seen(0.0, 4.8)).unwrap();
    assert!((first.0.x - 4.8).abs() < 1e-9);
    // One good sighting from 2 m counts 33 times as much as one from 4.8 m: the victim moves
    // to within 0.1 m of where it is (a plain mean of the three would be 0.8 m short).
    m.add(Pose2::new(4.0, 0.0, 0.0), &seen(0.0, 2.0));
    let now = m.seen()[0];
    assert!((now.0.x - 6.0).abs() < 0.1, "{now:?}");
    assert!(sighting_weight(2.0) / sighting_weight(4.8) > 30.0);
    assert_eq!(
        sighting_weight(0.1),
        sighting_weight(0.5),
        "clamped near the camera"
    );
}

/// A far victim's range, read a few rows below the horizon, can be metres short frame after
/// frame (the rescue team's false victims were far ones placed 2 m short, twice in a row).
/// With `confirm_range`, such sightings make a candidate but not a victim; nearer sightings,
/// which read the range well, confirm the real one, and the short candidate is never seen.
#[test]
fn far_sightings_alone_do_not_make_a_victim_under_a_confirm_range() {
    let mut m = VictimMap::new(VictimMapParams {
        confirm_hits: 2,
        confirm_range: 3.5,
        ..VictimMapParams::default()
    });
    // A victim at (6.5, 0) seen from the origin, placed 2 m short, again and again.
    for _ in 0..5 {
        assert_eq!(m.add(Pose2::default(), &seen(0.0, 4.5)), None);
    }
    assert!(m.seen().is_empty() && m.news(0.3).is_empty() && m.pending() == 0);
    assert_eq!(m.target(Point2::new(0.0, 0.0)), None);
    // The robot drives up: from 3 m the range is right, and the real victim is seen there
    // (the short candidate, 2 m away, is another one, and stays unseen).
    let robot = Pose2::new(3.5, 0.0, 0.0);
    assert_eq!(m.add(robot, &seen(0.0, 3.0)), None);
    let found = m.add(robot, &seen(0.0, 3.0)).unwrap();
    assert!((found.0.x - 6.5).abs() < 1e-9, "{found:?}");
    assert_eq!(m.seen(), vec![found]);
    // Without a confirm range (the default: max_range), the short sightings were a victim.
    let mut plain = VictimMap::new(VictimMapParams {
        confirm_hits: 2,
        ..VictimMapParams::default()
    });
    plain.add(Pose2::default(), &seen(0.0, 4.5));
    assert!(plain.add(Pose2::default(), &seen(0.0, 4.5)).is_some());
    let bad = VictimMapParams {
        confirm_range: f64::NAN,
        ..VictimMapParams::default()
    };
    assert!(bad.validate().unwrap_err().contains("confirm_range"));
}

#[test]
fn news_tells_each_seen_victim_once_and_again_when_it_moved() {
    let mut m = VictimMap::new(VictimMapParams::default());
    let robot = Pose2::default();
    m.add(robot, &seen(0.0, 4.5));
    m.add(robot, &seen(0.0, 4.5));
    assert!(m.news(0.3).is_empty(), "not seen yet (three sightings)");
    m.add(robot, &seen(0.0, 4.5));
    let news = m.news(0.3);
    assert_eq!(news.len(), 1);
    assert_eq!(news[0].0, 0);
    assert!((news[0].1 .0.x - 4.5).abs() < 1e-9);
    assert!(m.news(0.3).is_empty(), "told once");
    // Small refinements are not news; a move past the threshold is, with the same id.
    m.add(robot, &seen(0.0, 4.6));
    assert!(m.news(0.3).is_empty());
    m.add(Pose2::new(3.0, 0.0, 0.0), &seen(0.0, 2.0));
    let news = m.news(0.3);
    assert_eq!(news.len(), 1);
    assert_eq!(news[0].0, 0);
    assert!(news[0].1 .0.x > 4.8, "{news:?}");
    // A second victim gets its own id; a dismissed one is never told.
    for _ in 0..3 {
        m.add(robot, &seen(std::f64::consts::FRAC_PI_2, 3.0));
    }
    let target = m.target(Point2::new(0.0, 3.0)).unwrap();
    assert!((target.position.0.y - 3.0).abs() < 1e-9);
    m.dismiss();
    assert!(m.news(0.3).is_empty());
}

#[test]
fn a_resumed_map_goes_on_where_the_saved_one_was() {
    let mut m = VictimMap::new(VictimMapParams::default());
    let robot = Pose2::default();
    m.next_frame();
    for _ in 0..3 {
        m.add(robot, &seen(0.0, 4.0));
        m.add(robot, &seen(std::f64::consts::FRAC_PI_2, 3.0));
    }
    m.target(robot.position()).unwrap();
    m.report().unwrap();
    let told = m.news(0.3);
    // A snapshot is read back through RON's dynamic values.
    let saved: VictimMap = crate::test_support::through_ron_values(&m);
    let mut back = VictimMap::resume(VictimMapParams::default(), &saved);
    assert_eq!(back, m);
    assert_eq!(back.reported(), m.reported());
    assert!(back.news(0.3).is_empty(), "told before: {told:?}");
    // The same ids, the same victims: a fourth sighting joins the first candidate.
    assert_eq!(back.add(robot, &seen(0.0, 4.0)), None);
    assert_eq!((back.seen().len(), back.pending()), (2, 1));
    assert!(VictimMap::default().is_empty() && !back.is_empty());
}
