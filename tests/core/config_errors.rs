//! Every config error is found before anything starts, located, and says what was expected.

use std::path::Path;

use petrel::actors::{ConfigFile, FilePath};

use crate::support::registry;

/// The errors of config `text`, one string per error.
fn errors(text: &str) -> Vec<String> {
    match ConfigFile::parse("bad.ron", text).and_then(|f| f.build(&registry()).map(|_| ())) {
        Ok(()) => panic!("config should be rejected"),
        Err(e) => e.0.iter().map(ToString::to_string).collect(),
    }
}

#[test]
fn ron_syntax_errors_give_file_line_and_column() {
    let e = errors(
        "Agent(\n    name: \"r1\",\n    modules: [ (name: \"a\" type: \"demo.counter\") ],\n)",
    );
    assert_eq!(e.len(), 1);
    assert!(e[0].starts_with("bad.ron:3:"), "{}", e[0]);
    assert!(e[0].contains("RON syntax"), "{}", e[0]);
    let unknown_field = errors("Agent(name: \"r1\", modulez: [])");
    assert!(unknown_field[0].contains("modulez"), "{}", unknown_field[0]);
}

#[test]
fn a_whole_number_out_of_range_names_its_field() {
    let e = errors(
        "Agent(name: \"r\", modules: [\n  (name: \"c\", type: \"demo.counter\", shutdown_timeout_ms:  99999999999999999999999),\n])",
    );
    assert_eq!(
        e,
        ["bad.ron:2:59: error: `shutdown_timeout_ms`: a whole number out of range for this field (counts and times in ms take 0 or more; see the field's documentation for its limit) (RON syntax of an agent config; see the example in the README)"]
    );
}

#[test]
fn a_negative_whole_number_names_its_field_too() {
    let e = errors("Agent(name: \"r\", step_budget: (mean_us: -1), modules: [])");
    assert_eq!(e.len(), 1, "{e:?}");
    assert!(
        e[0].contains("error: `mean_us`: a whole number out of range"),
        "{}",
        e[0]
    );
}

#[test]
fn names_written_with_escapes_are_located_and_shown_escaped() {
    let e = errors(r#"Agent(name: "a\u{2f}b", modules: [(name: "c\td", type: "demo.counter")])"#);
    assert_eq!(e.len(), 2, "{e:?}");
    assert!(
        e[0].starts_with("bad.ron:1:7: error: agent name `a/b`:"),
        "{}",
        e[0]
    );
    assert!(
        e[1].starts_with("bad.ron:1:42: error: module name `c\\td`:"),
        "{}",
        e[1]
    );
}

#[test]
fn a_name_longer_than_an_address_can_carry_is_refused_and_shown_short() {
    let (fine, long) = ("m".repeat(128), "m".repeat(60_000));
    let config = |agent: &str| {
        format!(r#"Agent(name: "{agent}", modules: [(name: "{fine}", type: "demo.counter")])"#)
    };
    let fine = ConfigFile::parse("fine.ron", &config(&fine)).unwrap();
    assert!(fine.build(&registry()).is_ok(), "128 characters are a name");
    let e = errors(&config(&long));
    assert_eq!(e.len(), 1, "{e:?}");
    assert!(
        e[0].starts_with(&format!(
            "bad.ron:1:13: error: agent name `{}…` (60000 characters): expected 1 to 128 letters",
            "m".repeat(48)
        )),
        "{}",
        e[0]
    );
}

#[test]
fn a_snapshot_clock_that_no_clock_reads_is_refused_at_its_field() {
    for bad in ["-1.0", "1e300", "NaN"] {
        let e = errors(&format!(
            "Agent(name: \"r\",\n    clock_s: {bad},\n    modules: [])"
        ));
        assert_eq!(e.len(), 1, "{e:?}");
        assert!(
            e[0].starts_with("bad.ron:2:5: error: clock_s is ")
                && e[0].ends_with("expected the seconds of a snapshot's clock, 0..=1e12"),
            "{}",
            e[0]
        );
    }
}

#[test]
fn an_empty_or_cut_short_config_says_so() {
    assert_eq!(
        errors("\n   \n"),
        ["bad.ron:1:1: error: the file is empty (nothing but whitespace); expected an agent config; see the example in the README"]
    );
    let e = errors("Agent(name: \"r\", modules: [\n");
    assert_eq!(e.len(), 1, "{e:?}");
    assert!(
        e[0].starts_with("bad.ron:1:28: error: the file ends too early: "),
        "{}",
        e[0]
    );
    // An error in the middle is no end of file.
    let e = errors("Agent(name: \"r\" modules: [])\n");
    assert!(!e[0].contains("ends too early"), "{}", e[0]);
}

#[test]
fn a_missing_file_is_named() {
    let e = ConfigFile::load("no/such/config.ron")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("no/such/config.ron: error: cannot read config:"),
        "{e}"
    );
}

#[test]
fn an_unknown_module_type_suggests_the_nearest_names() {
    let e = errors("Agent(name: \"r1\", modules: [\n  (name: \"c\", type: \"demo.conter\"),\n])");
    assert_eq!(e, ["bad.ron:2:21: error: module `c`: unknown module type `demo.conter`; did you mean `demo.counter`?"]);
}

#[test]
fn an_unknown_property_lists_the_module_properties() {
    let e = errors(
        r#"Agent(name: "r1", modules: [(name: "s", type: "demo.scale", values: {"params/factr": 2.0})])"#,
    );
    assert_eq!(e.len(), 1);
    assert!(
        e[0].starts_with(
            "bad.ron:1:70: error: module `s` has no property `params/factr`; it has: "
        ),
        "{}",
        e[0]
    );
    assert!(
        e[0].ends_with(
            "it has: enabled, in/value, out/value, params/factor, params/offset, params/smoothing"
        ),
        "{}",
        e[0]
    );
    let link = errors(
        r#"Agent(name: "r1", modules: [(name: "s", type: "demo.scale", links: {"in/valeu": "s/out/value"})])"#,
    );
    assert!(
        link[0].contains("module `s` has no property `in/valeu`; it has: enabled, in/value,"),
        "{}",
        link[0]
    );
    let target = errors(
        r#"Agent(name: "r1", modules: [(name: "s", type: "demo.scale", links: {"in/value": "x/out/value"})])"#,
    );
    assert!(
        target[0].ends_with("module `s`, `in/value`: no module `x` in agent `r1` (modules: s)"),
        "{}",
        target[0]
    );
}

#[test]
fn a_wrong_value_type_says_expected_and_found() {
    let e = errors(
        r#"Agent(name: "r1", modules: [(name: "s", type: "demo.scale", values: {"params/factor": "big"})])"#,
    );
    assert_eq!(e.len(), 1);
    assert!(
        e[0].contains("module `s`, `params/factor` (f64): "),
        "{}",
        e[0]
    );
    assert!(
        e[0].to_lowercase().contains("found the string \"big\""),
        "{}",
        e[0]
    );
}

#[test]
fn link_cycles_and_type_mismatches_are_rejected() {
    let cycle = errors(
        r#"Agent(name: "r1", modules: [
            (name: "a", type: "test.echo", links: {"in/value": "b/in/value"}),
            (name: "b", type: "test.echo", links: {"in/value": "a/in/value"}),
        ])"#,
    );
    assert_eq!(cycle.len(), 1);
    assert!(cycle[0].starts_with("bad.ron:3:"), "{}", cycle[0]);
    assert!(
        cycle[0].ends_with("link cycle: b/in/value -> a/in/value -> b/in/value"),
        "{}",
        cycle[0]
    );
    let types = errors(
        r#"Agent(name: "r1", modules: [
            (name: "c", type: "demo.counter"),
            (name: "s", type: "demo.scale", links: {"in/value": "c/params/period_ms"}),
        ])"#,
    );
    assert!(
        types[0].ends_with(
            "cannot link `s/in/value` (f64) to `c/params/period_ms` (i64): the types differ"
        ),
        "{}",
        types[0]
    );
    let queue = errors(
        r#"Agent(name: "r1", modules: [
            (name: "c", type: "demo.counter"),
            (name: "q", type: "demo.consumer", links: {"in/items": "c/out/value"}),
        ])"#,
    );
    assert!(
        queue[0].contains("a queue input links to a queue"),
        "{}",
        queue[0]
    );
}

#[test]
fn duplicate_module_names_are_rejected() {
    let e = errors(
        r#"Agent(name: "r1", modules: [(name: "a", type: "demo.counter"), (name: "a", type: "demo.scale")])"#,
    );
    assert_eq!(
        e,
        ["bad.ron:1:71: error: duplicate module name `a`: each module needs its own name"]
    );
}

#[test]
fn all_errors_are_reported_in_one_pass() {
    let e = errors(
        r#"Agent(name: "r1", modules: [
            (name: "a", type: "demo.nope"),
            (name: "b", type: "demo.scale", values: {"params/factor": true, "params/gain": 1.0},
             links: {"in/value": "a/out/value"}),
        ])"#,
    );
    assert_eq!(e.len(), 4, "{e:#?}");
    // Which four: each at its place, in petrel's words (what follows a dependency's wording
    // is not pinned).
    let expected = [
        "bad.ron:2:31: error: module `a`: unknown module type `demo.nope`",
        "bad.ron:3:54: error: module `b`, `params/factor`",
        "bad.ron:3:77: error: module `b` has no property `params/gain`; it has: enabled, in/value,",
        "bad.ron:4:22: error: module `b`, `in/value`: no module `a` in agent `r1`",
    ];
    for (error, start) in e.iter().zip(expected) {
        assert!(error.starts_with(start), "{error}\n(expected {start}...)");
    }
}

#[test]
fn supervision_settings_are_checked() {
    let e = errors(
        r#"Agent(name: "r1",
    supervision: (max_restarts: 1000000, within_s: 1e300, backoff: (min_ms: 50, max_ms: 10)),
    groups: [(name: "g"), (name: "g"), (name: "bad name/x")],
    modules: [(name: "a", type: "demo.counter", group: "nav"), (name: "_b", type: "demo.counter", watchdog_ms: 0)],
)"#,
    );
    let expected = [
        "bad.ron:3:47: error: group name `bad name/x`: expected 1 to 128 letters, digits, `_`, `-` or `.` (a name is part of every property address, `petrel://agent/module/path`)",
        "bad.ron:2:19: error: supervision: max_restarts is 1000000; expected 0..=100000",
        "bad.ron:2:42: error: supervision: within_s is 1e300; expected a number of seconds in (0, 86400]",
        "bad.ron:2:59: error: supervision backoff: min_ms (50) is above max_ms (10)",
        "bad.ron:3:21: error: duplicate group name `g`",
        "bad.ron:4:56: error: module `a`: unknown group `nav` (groups: g, bad name/x)",
        "bad.ron:4:71: error: module name `_b`: names starting with `_` are reserved for the runtime",
        "bad.ron:4:99: error: module `_b`: watchdog_ms must be above 0",
    ];
    assert_eq!(e, expected);
    // A group's field, in that group.
    let group = errors(
        r#"Agent(name: "r1", groups: [(name: "a", within_s: 5.0), (name: "b", within_s: 0.0)])"#,
    );
    assert_eq!(
        group,
        ["bad.ron:1:68: error: group `b`: within_s is 0; expected a number of seconds in (0, 86400]"]
    );
    let strategy = errors(r#"Agent(name: "r1", supervision: (strategy: one_for_none))"#);
    assert!(
        strategy[0].starts_with("bad.ron:1:43: error: Unexpected variant named `one_for_none`"),
        "{}",
        strategy[0]
    );
}

#[test]
fn file_paths_are_relative_to_the_config_file_that_names_them() {
    let mut file = ConfigFile::parse(
        "robots/base.ron",
        r#"Agent(name: "r1", modules: [(name: "m", type: "mission.pnp",
            values: {"params/plan": "plans/go.plan", "params/rules": "/etc/abs.er"})])"#,
    )
    .unwrap();
    let overlay = ConfigFile::parse(
        "tuning/over.ron",
        r#"Agent(name: "r1", modules: [(name: "m", type: "mission.pnp",
            values: {"params/rules": "go.er"})])"#,
    )
    .unwrap();
    let built = file.build(&registry()).unwrap();
    let path = |r: &petrel::actors::Registry, p: &str| {
        let (_, value) = r.get(p).unwrap();
        value
            .downcast_ref::<FilePath>()
            .unwrap()
            .as_path()
            .to_path_buf()
    };
    let cwd = std::env::current_dir().unwrap();
    assert_eq!(
        path(&built, "m/params/plan"),
        cwd.join("robots/plans/go.plan")
    );
    assert_eq!(
        path(&built, "m/params/rules"),
        Path::new("/etc/abs.er"),
        "absolute stays"
    );

    file.overlay(overlay);
    let built = file.build(&registry()).unwrap();
    assert_eq!(
        path(&built, "m/params/plan"),
        cwd.join("robots/plans/go.plan")
    );
    assert_eq!(
        path(&built, "m/params/rules"),
        cwd.join("tuning/go.er"),
        "an overlay's paths are relative to the overlay"
    );
}

#[test]
fn every_field_an_overlay_writes_replaces_the_base_and_nothing_else_does() {
    let mut base = ConfigFile::parse(
        "base.ron",
        r#"Agent(name: "r1", supervision: (max_restarts: 5, within_s: 10.0),
            modules: [(name: "c", type: "demo.counter", restart: permanent, watchdog_ms: 100,
                       values: {"params/period_ms": 10})])"#,
    )
    .unwrap();
    let overlay = ConfigFile::parse(
        "overlay.ron",
        r#"Agent(name: "r1", supervision: (max_restarts: 50, within_s: 2.0, on_give_up: disable_module),
            groups: [(name: "g", strategy: one_for_all)],
            modules: [(name: "c", type: "demo.counter", restart: temporary, group: "g",
                       values: {"params/start": 5.0})])"#,
    )
    .unwrap();
    base.overlay(overlay);
    let c = &base.config;
    assert_eq!(
        (c.supervision.max_restarts, c.supervision.within_s),
        (50, 2.0)
    );
    assert_eq!(c.groups.len(), 1);
    let m = &c.modules[0];
    assert_eq!(
        m.restart,
        petrel::actors::supervision::RestartPolicy::Temporary
    );
    assert_eq!(m.group.as_deref(), Some("g"));
    assert_eq!(m.watchdog_ms, Some(100), "not written by the overlay: kept");
    assert_eq!(m.values.len(), 2, "values merge key by key");
    // An overlay that writes no supervision leaves the base's.
    let mut again = base.clone();
    again.overlay(ConfigFile::parse("o.ron", r#"Agent(name: "r1", modules: [])"#).unwrap());
    assert_eq!(again.config.supervision.max_restarts, 50);
}

/// A word parameter (`demo.signal`'s waveform) takes only its words, at load and at run time:
/// an unknown waveform set while running had made the signal a silent 0.
#[tokio::test(start_paused = true)]
async fn a_word_parameter_refuses_other_words_at_load_and_at_run_time() {
    let loaded = errors(
        "Agent(name: \"r1\", modules: [\n  (name: \"s\", type: \"demo.signal\", values: {\"params/waveform\": \"squiggle\"}),\n])",
    );
    assert_eq!(loaded.len(), 1, "{loaded:?}");
    assert!(
        loaded[0].starts_with("bad.ron:2:")
            && loaded[0]
                .contains("expected one of \"sine\", \"square\", \"triangle\", \"sawtooth\""),
        "{}",
        loaded[0]
    );
    let agent = crate::support::start(
        "Agent(name: \"r1\", modules: [(name: \"s\", type: \"demo.signal\")])",
    )
    .await;
    let bb = agent.blackboard();
    let refused = bb
        .set("s/params/waveform", "squiggle".to_string())
        .await
        .unwrap_err()
        .to_string();
    assert_eq!(
        refused,
        "`s/params/waveform` = \"squiggle\": expected one of \"sine\", \"square\", \"triangle\", \"sawtooth\" (sine, square, triangle or sawtooth)"
    );
    bb.set("s/params/waveform", "square".to_string())
        .await
        .unwrap();
    assert_eq!(
        *bb.get::<String>("s/params/waveform").await.unwrap(),
        "square"
    );
    agent.stop(petrel::actors::DEFAULT_STOP_TIMEOUT).await;
}

/// A value beside a link of the same property would never be read: in one file it is an
/// error at the value; an overlay's value replaces the base's link (and its link the base's
/// value), so a snapshot taken after `petrel unlink` resumes with the value.
#[test]
fn a_value_and_a_link_on_one_property_are_an_error_in_one_file_and_the_last_word_across_overlays() {
    let both = errors(
        "Agent(name: \"r1\", modules: [\n  (name: \"src\", type: \"demo.counter\"),\n  (name: \"e\", type: \"demo.scale\",\n   values: {\"in/value\": 2.0},\n   links: {\"in/value\": \"src/out/value\"}),\n])",
    );
    assert_eq!(both.len(), 1, "{both:?}");
    assert!(
        both[0].starts_with("bad.ron:4:")
            && both[0].contains("`e/in/value` has both a value and a link (to `src/out/value`)"),
        "{}",
        both[0]
    );
    let base = || {
        ConfigFile::parse(
            "base.ron",
            r#"Agent(name: "r1", modules: [(name: "src", type: "demo.counter"),
                (name: "e", type: "demo.scale", values: {"params/factor": 2.0},
                 links: {"in/value": "src/out/value"})])"#,
        )
        .unwrap()
    };
    let mut unlinked = base();
    unlinked.overlay(
        ConfigFile::parse(
            "snap.ron",
            r#"Agent(name: "r1", modules: [(name: "e", values: {"in/value": 7.0})])"#,
        )
        .unwrap(),
    );
    let e = &unlinked.config.modules[1];
    assert!(e.links.is_empty() && e.values.len() == 2, "{e:?}");
    assert!(unlinked.build(&registry()).is_ok());
    let mut relinked = base();
    relinked.overlay(
        ConfigFile::parse(
            "o.ron",
            r#"Agent(name: "r1", modules: [(name: "e", links: {"params/factor": "src/out/value"})])"#,
        )
        .unwrap(),
    );
    let e = &relinked.config.modules[1];
    assert!(
        e.values.is_empty() && e.links.len() == 2,
        "the overlay's link replaces the base's value: {e:?}"
    );
}

/// Beside a link to another agent, a value is what the input holds until the first sample
/// arrives (and keeps if the link breaks): not an error.
#[test]
fn a_value_beside_a_link_to_another_agent_is_the_input_until_the_first_sample() {
    let file = ConfigFile::parse(
        "remote.ron",
        r#"Agent(name: "b", team: (name: "t", connect: ["tcp/127.0.0.1:7447"]), modules: [
            (name: "scale", type: "demo.scale", values: {"in/value": 7.0},
             links: {"in/value": "petrel://a/count/out/value"})])"#,
    )
    .unwrap();
    assert!(file.build(&registry()).is_ok());
}

/// A value megabytes long is not echoed whole in its error: the message is cut at 2,000
/// characters, saying how many more there were.
#[test]
fn a_huge_value_is_cut_short_in_its_error() {
    let long = "a".repeat(100_000);
    let errors = crate::support::refused(&format!(
        r#"Agent(name: "r1", modules: [(name: "s", type: "demo.scale", values: {{"params/factor": "{long}"}})])"#
    ));
    assert!(errors.starts_with("bad.ron:1:"), "{errors}");
    assert!(errors.contains("`params/factor` (f64)"), "{errors}");
    assert!(
        errors.chars().count() < 2_200,
        "{} characters",
        errors.len()
    );
    let tail = errors.rsplit('…').next().unwrap();
    let more: usize = tail
        .trim_start_matches(" (")
        .trim_end_matches(" more characters)")
        .parse()
        .unwrap_or_else(|_| panic!("{tail}"));
    assert!(more > 97_000, "{more}");
}
