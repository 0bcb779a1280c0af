use super::*;

fn at(x: f64, y: f64) -> Point2 {
    Point2::new(x, y)
}

#[test]
fn reports_near_a_known_victim_are_that_victim_and_finders_are_kept() {
    let mut t = TeamVictims::new(1.0);
    assert_eq!(t.report("r2", None, at(1.0, 1.0)), Report::New(0));
    assert_eq!(t.report("r1", None, at(1.5, 1.2)), Report::Known(0));
    assert_eq!(t.report("r1", None, at(1.4, 0.9)), Report::Known(0));
    assert_eq!(t.report("r2", None, at(1.1, 0.9)), Report::Known(0));
    assert_eq!(t.report("r1", None, at(5.0, 1.0)), Report::New(1));
    assert_eq!(t.victims()[0].also_by(), ["r1"]);
    // The mean of the four reports.
    assert_eq!(t.victims()[0].reports(), 4);
    assert_eq!(
        t.summary(),
        "team victims: 2\n  1 (1.25, 1.00) found by r2, also r1\n  2 (5.00, 1.00) found by r1\n  first found: r1: 1, r2: 1\n"
    );
    assert_eq!(TeamVictims::new(1.0).summary(), "team victims: 0\n");
}

#[test]
fn a_revised_report_replaces_the_robots_earlier_estimate() {
    let mut t = TeamVictims::new(1.0);
    // r2 first places a victim at (12.4, 2.0), 1.6 m from where it is, (13.9, 1.3).
    assert_eq!(t.report("r2", Some(4), at(12.4, 2.0)), Report::New(0));
    // Closer, its estimate moves: the entry follows (not a second report, not a new victim).
    assert_eq!(t.report("r2", Some(4), at(13.2, 1.6)), Report::Revised(0));
    assert_eq!(t.report("r2", Some(4), at(13.8, 1.3)), Report::Revised(0));
    assert_eq!(t.victims().len(), 1);
    assert_eq!(t.victims()[0].reports(), 1);
    assert_eq!(t.victims()[0].position(), at(13.8, 1.3));
    // Ids are per robot: r3's id 4 is another report.
    assert_eq!(t.report("r3", Some(4), at(14.0, 1.3)), Report::Known(0));
    assert_eq!(t.victims()[0].position(), at(13.9, 1.3));
    assert_eq!(t.victims()[0].also_by(), ["r3"]);
    // A revision of r3's keeps r2's estimate in the mean.
    assert_eq!(t.report("r3", Some(4), at(14.2, 1.3)), Report::Revised(0));
    assert!((t.victims()[0].position().0.x - 14.0).abs() < 1e-9);
}

#[test]
fn a_revision_that_brings_two_entries_together_merges_them_into_the_earlier() {
    let mut t = TeamVictims::new(1.0);
    assert_eq!(t.report("r1", Some(0), at(1.0, 1.0)), Report::New(0));
    // r2's first estimate of the same victim lands 1.6 m off: a second entry, for now.
    assert_eq!(t.report("r2", Some(7), at(2.6, 1.0)), Report::New(1));
    assert_eq!(t.report("r3", None, at(8.0, 8.0)), Report::New(2));
    assert_eq!(
        t.report("r2", Some(7), at(1.2, 1.0)),
        Report::Merged { kept: 0, gone: 1 }
    );
    let v = t.victims();
    assert_eq!(v.len(), 2, "{v:?}");
    assert_eq!((v[0].found_by.as_str(), v[0].reports()), ("r1", 2));
    assert_eq!(v[0].also_by(), ["r2"]);
    assert!((v[0].position().0.x - 1.1).abs() < 1e-9);
    // The entries after the one merged moved up.
    assert_eq!(v[1].position(), at(8.0, 8.0));
    // And r2's report goes on being revised where it now is.
    assert_eq!(t.report("r2", Some(7), at(1.0, 1.0)), Report::Revised(0));
}

#[test]
fn a_revision_far_from_the_others_reports_is_another_victim() {
    let mut t = TeamVictims::new(1.0);
    t.report("r1", Some(0), at(1.0, 1.0));
    // r2's first estimate joined r1's victim, but it was of another one, 3 m away.
    assert_eq!(t.report("r2", Some(3), at(1.8, 1.0)), Report::Known(0));
    assert_eq!(t.report("r2", Some(3), at(4.0, 1.0)), Report::New(1));
    let v = t.victims();
    assert_eq!((v[0].reports(), v[0].position()), (1, at(1.0, 1.0)));
    assert!(v[0].also_by().is_empty(), "r2's report left it");
    assert_eq!(
        (v[1].found_by.as_str(), v[1].position()),
        ("r2", at(4.0, 1.0))
    );
}

#[test]
fn the_list_survives_a_round_trip_through_rons_dynamic_values() {
    let mut t = TeamVictims::new(1.0);
    t.report("r1", Some(0), at(1.0, 1.0));
    t.report("r2", Some(2), at(1.5, 1.0));
    let mut back: TeamVictims = crate::test_support::through_ron_values(&t);
    assert_eq!(back.summary(), t.summary());
    // Ids survive too: r2 revises its report rather than adding one.
    assert_eq!(back.report("r2", Some(2), at(1.1, 1.0)), Report::Revised(0));
}
