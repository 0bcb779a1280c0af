//! Tests of the team config: link target forms, patterns, checks.

use super::*;

fn target(text: &str) -> Result<LinkTarget, String> {
    ron::from_str::<LinkTarget>(text).map_err(|e| e.to_string())
}

#[test]
fn link_targets_read_both_forms_and_round_trip() {
    assert_eq!(target(r#""a/out/x""#).unwrap(), LinkTarget::new("a/out/x"));
    let long = target(
        r#"(from: "petrel://r2/a/out/x", mode: on_change(min_interval_ms: 50), reliability: best_effort, lossy: true)"#,
    )
    .unwrap();
    let qos = long.qos.unwrap();
    assert_eq!(
        qos.mode,
        Mode::OnChange {
            min_interval_ms: 50
        }
    );
    assert_eq!(qos.reliability, Reliability::BestEffort);
    assert!(qos.lossy);
    assert_eq!(target(&long.to_ron()).unwrap(), long);
    let periodic = target(r#"(from: "petrel://r2/a/out/x", mode: periodic(ms: 200))"#).unwrap();
    for (mode, says) in [
        ("periodic(ms: 0)", "ms is 0; expected 1..=86400000 ms"),
        (
            "periodic(ms: 99999999999)",
            "ms is 99999999999; expected 1..=86400000 ms",
        ),
        (
            "on_change(min_interval_ms: 99999999999)",
            "min_interval_ms is 99999999999",
        ),
    ] {
        let e = target(&format!(r#"(from: "petrel://r2/a/out/x", mode: {mode})"#)).unwrap_err();
        assert!(e.contains(says), "{mode}: {e}");
    }
    assert_eq!(periodic.qos.unwrap().mode, Mode::Periodic { ms: 200 });
    assert_eq!(target(&periodic.to_ron()).unwrap(), periodic);
    let plain = target(r#"(from: "petrel://r2/a/out/x", mode: on_change)"#).unwrap();
    assert_eq!(plain.qos.unwrap(), Qos::default());
}

#[test]
fn bad_link_targets_say_what_was_expected() {
    let e = target(r#"(from: "x", mode: periodc(ms: 2))"#).unwrap_err();
    assert!(
        e.contains("periodic(ms: N)") && e.contains("periodc"),
        "{e}"
    );
    let e = target(r#"(fro: "x")"#).unwrap_err();
    assert!(e.contains("fro"), "{e}");
    let e = target(r#"(from: "x", reliability: sometimes)"#).unwrap_err();
    assert!(e.contains("sometimes"), "{e}");
}

#[test]
fn team_sections_round_trip() {
    let text = r#"(name: "r", mode: client, listen: ["tcp/127.0.0.1:1"], connect: ["tcp/127.0.0.1:2"], lease_ms: 500, remote_write: ["a/params/*"], scouting: true)"#;
    let team: TeamConfig = ron::from_str(text).unwrap();
    assert_eq!(ron::from_str::<TeamConfig>(&team.to_ron()).unwrap(), team);
}

#[test]
fn patterns_match_segments() {
    assert!(pattern_matches("planner/params/**", "planner/params/a/b"));
    assert!(pattern_matches("planner/params/**", "planner/params/x"));
    assert!(!pattern_matches("planner/params/*", "planner/params/a/b"));
    assert!(pattern_matches("*/control/*", "scale/control/fault"));
    assert!(!pattern_matches("*/control/*", "scale/params/factor"));
    assert!(pattern_matches("**", "a/b/c"));
    assert!(pattern_error("a/b*/c").is_some());
    assert!(pattern_error("a/**/c").is_none());
}

#[test]
fn team_checks_name_what_is_wrong() {
    let mut t: TeamConfig = ron::from_str(r#"(name: "rescue")"#).unwrap();
    assert!(check(&t).is_empty());
    assert_eq!(t.lease_ms, DEFAULT_LEASE_MS);
    t.lease_ms = 5;
    t.listen = vec!["udp/1.2.3.4:5".into(), "tcp/127.0.0.1:x".into()];
    t.connect = vec!["tcp/127.0.0.1:7448".into()];
    let errors = check(&t).join("\n");
    assert!(errors.contains("lease_ms is 5"), "{errors}");
    assert!(errors.contains("`udp/1.2.3.4:5`"), "{errors}");
    assert!(errors.contains("`tcp/127.0.0.1:x`"), "{errors}");
    assert!(!errors.contains("7448"), "{errors}");
}

#[test]
fn an_endpoint_listened_on_twice_is_refused() {
    let team = TeamConfig {
        name: "t".into(),
        listen: vec!["tcp/127.0.0.1:7998".into(), "tcp/127.0.0.1:7998".into()],
        ..TeamConfig::default()
    };
    assert_eq!(
        check(&team),
        ["team listen has `tcp/127.0.0.1:7998` twice; expected each endpoint once"]
    );
}
