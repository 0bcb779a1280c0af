//! Rules on parameters beyond their type and range. Parameters a module reads only when it
//! starts (`Ports::read_at_start`): a config sets them; a running agent refuses new values
//! from a person, a plan binding or a context rule (they were taken and did nothing, or made
//! the module's next restart fail); `petrel check` refuses rules that would set them. Values
//! whose numbers must fit together (`Ports::accept_last`): refused wherever a range is.

use std::sync::Arc;

use petrel::actors::types::Path2;
use petrel::actors::{AnyValue, BlackboardError, ConfigFile, FilePath, DEFAULT_STOP_TIMEOUT};

use crate::support::{registry, start};

const GOALS: &str = r#"Agent(name: "r1", modules: [
    (name: "goals", type: "nav.goal_sequencer", values: {"params/goals": [(x: 1.0, y: 2.0)], "params/tolerance": 0.5}),
])"#;

#[tokio::test(start_paused = true)]
async fn a_running_agent_refuses_a_parameter_read_at_start_and_keeps_it() {
    let agent = start(GOALS).await;
    let bb = agent.blackboard();

    // A person's `petrel set` (RON text), even of a value init would refuse.
    for text in ["[]", "[(x: 3.0, y: 4.0)]"] {
        let refused = bb.set_text("goals/params/goals", text).await.unwrap_err();
        assert!(
            matches!(&refused, BlackboardError::ReadAtStart { key } if key == "goals/params/goals"),
            "{refused}"
        );
        assert!(
            refused
                .to_string()
                .contains("read once, when its module starts"),
            "{refused}"
        );
    }
    // A binding's or rule's write, through an untyped handle.
    let tolerance = bb.any_handle("goals/params/tolerance").await.unwrap();
    let value: AnyValue = Arc::new(1.0_f64);
    assert!(matches!(
        tolerance.set(value),
        Err(BlackboardError::ReadAtStart { .. })
    ));
    // Nothing changed; a parameter read at every step is still set as before.
    let goals = bb.get::<Path2>("goals/params/goals").await.unwrap();
    let points: Vec<(f64, f64)> = goals.points().iter().map(|p| (p.0.x, p.0.y)).collect();
    assert_eq!(points, [(1.0, 2.0)]);
    assert_eq!(*bb.get::<f64>("goals/params/tolerance").await.unwrap(), 0.5);
    bb.set_text("goals/params/report_every_s", "5.0")
        .await
        .unwrap();
    assert_eq!(
        *bb.get::<f64>("goals/params/report_every_s").await.unwrap(),
        5.0
    );
    // What a person typed wrong is said in their words, not the RON library's.
    let bare = bb
        .set_text("goals/params/report_every_s", "abc")
        .await
        .unwrap_err();
    assert!(
        bare.to_string()
            .contains("`abc` is a bare word, which is no value (text takes double quotes"),
        "{bare}"
    );
    // A path or words without their quotes: the quoting said too.
    for unquoted in ["/no/such/rules.ron", "fast mode", "./rules.ron"] {
        let error = bb
            .set_text("goals/params/report_every_s", unquoted)
            .await
            .unwrap_err();
        assert!(
            error
                .to_string()
                .contains(&format!("text takes double quotes: `\"{unquoted}\"`")),
            "{error}"
        );
    }
    let deep = format!("{}{}", "[".repeat(5000), "]".repeat(5000));
    let deep = bb
        .set_text("goals/params/report_every_s", &deep)
        .await
        .unwrap_err();
    assert!(deep.to_string().contains("nested too deeply"), "{deep}");
    assert!(!deep.to_string().contains("serde_stacker"), "{deep}");
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[test]
fn check_refuses_a_context_rule_that_sets_a_parameter_read_at_start() {
    let dir = tempfile::tempdir().unwrap();
    let rules = dir.path().join("rules.ron");
    std::fs::write(
        &rules,
        r#"Contexts(contexts: [(name: "near", when: "goals/out/reached > 0", set: {"goals/params/tolerance": "1.0"})])"#,
    )
    .unwrap();
    let config = dir.path().join("agent.ron");
    let contexts = format!(
        r#"(name: "contexts", type: "context.manager", values: {{"params/rules": {:?}}}),
    (name: "goals""#,
        rules.display().to_string()
    );
    std::fs::write(&config, GOALS.replace(r#"(name: "goals""#, &contexts)).unwrap();
    let file = ConfigFile::load(&config).unwrap();
    let errors = petrel::check(&file, &registry()).unwrap_err().to_string();
    assert!(
        errors.contains(
            "context `near`: `goals/params/tolerance` is read once, when its module starts"
        ),
        "{errors}"
    );
}

/// A parameter whose numbers are each fine but do not fit together (a box with x0 > x1) is
/// refused where a range is: in the config, and from a tool while running (it failed the
/// explorer's step, then its restarts, until the agent was given up).
#[tokio::test(start_paused = true)]
async fn a_value_that_does_not_fit_its_rule_is_refused_in_the_config_and_while_running() {
    let config = |area: &str| {
        format!(
            r#"Agent(name: "r1", modules: [(name: "explorer", type: "nav.explorer", values: {{"params/area": {area}}})])"#
        )
    };
    for bad in ["[10.0, 10.0, 0.0, 0.0]", "[1.0, 2.0]"] {
        let errors = crate::support::refused(&config(bad));
        assert!(
            errors.contains("expected `[]` or `[x0, y0, x1, y1]` with x0 < x1 and y0 < y1"),
            "{bad}: {errors}"
        );
    }
    // A map's corner as a world's: within a thousand kilometres, shown short when refused.
    let far = crate::support::refused(
        r#"Agent(name: "r1", modules: [(name: "mapper", type: "nav.mapper", values: {"params/origin": (x: 1e308, y: 0.0)})])"#,
    );
    assert!(
        far.contains("= Point2(x: 1.000e308, y: 0.000): expected `(x: .., y: ..)` in metres, each within -1e6..=1e6"),
        "{far}"
    );
    let agent = start(&config("[0.0, 0.0, 5.0, 5.0]")).await;
    let bb = agent.blackboard();
    let refused = bb
        .set_text("explorer/params/area", "[5.0, 0.0, 1.0, 5.0]")
        .await
        .unwrap_err();
    assert!(
        matches!(refused, BlackboardError::OutOfRange { .. }),
        "{refused}"
    );
    bb.set_text("explorer/params/area", "[]").await.unwrap();
    bb.set_text("explorer/params/area", "[1.0, 1.0, 2.0, 2.0]")
        .await
        .unwrap();
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

/// A file path set while the agent runs names a file that exists, or is refused and the old
/// one stays: a typo in `petrel set .../params/rules` was taken in silence, and the manager's
/// next restart (a crash) then failed on it again and again. A relative path is taken from
/// the agent's working directory and kept absolute.
#[tokio::test(start_paused = true)]
async fn a_file_path_set_while_running_must_name_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let rules = dir.path().join("rules.ron");
    std::fs::write(&rules, r#"Contexts(contexts: [])"#).unwrap();
    let config = format!(
        r#"Agent(name: "r1", modules: [(name: "contexts", type: "context.manager", values: {{"params/rules": {:?}}})])"#,
        rules.display().to_string()
    );
    let agent = start(&config).await;
    let bb = agent.blackboard();
    let key = "contexts/params/rules";
    let missing = dir.path().join("nope.ron");
    for text in [
        format!("{:?}", missing.display().to_string()),
        "\"nope.ron\"".into(),
    ] {
        let refused = bb.set_text(key, &text).await.unwrap_err().to_string();
        assert!(
            refused.contains("nope.ron`: it does not exist"),
            "{refused}"
        );
        assert!(refused.contains("expected the path of a file"), "{refused}");
    }
    let dir_refused = bb
        .set_text(key, &format!("{:?}", dir.path().display().to_string()))
        .await
        .unwrap_err();
    assert!(
        dir_refused.to_string().contains("it is a directory"),
        "{dir_refused}"
    );
    assert_eq!(bb.get::<FilePath>(key).await.unwrap().as_path(), rules);

    // Integration tests run in the package's directory.
    bb.set_text(key, "\"configs/contexts-demo.rules.ron\"")
        .await
        .unwrap();
    let set = bb.get::<FilePath>(key).await.unwrap();
    let expected = std::env::current_dir()
        .unwrap()
        .join("configs/contexts-demo.rules.ron");
    assert_eq!(set.as_path(), expected);
    // None at all is a value the manager reports itself, as in a config.
    bb.set_text(key, "\"\"").await.unwrap();
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}
