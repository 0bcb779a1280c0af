//! `petrel check`: what it accepts, and every error it reports with file and line.

use std::process::Command;

use crate::bounded::{self, petrel, text};
use crate::temp_config;

#[test]
fn check_accepts_the_shipped_demo_config() {
    let out = petrel(&["check", "configs/pipeline.ron"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(
        text(&out.stdout),
        "configs/pipeline.ron: ok: agent `robot1`, 5 modules, 3 links\n"
    );
}

#[test]
fn check_lists_every_error_of_a_broken_config_and_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.ron");
    std::fs::write(
        &path,
        r#"Agent(name: "r1", modules: [
    (name: "c", type: "demo.countr"),
    (name: "s", type: "demo.scale", values: {"params/factor": "x"}, links: {"in/value": "s/in/value"}),
    (name: "g", type: "nav.goal_sequencer", values: {"params/goals": 5}),
])"#,
    )
    .unwrap();
    let out = petrel(&["check", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    let p = path.display();
    assert!(err.contains(&format!("{p}:2:23: error: module `c`: unknown module type `demo.countr`; did you mean `demo.counter`?")), "{err}");
    assert!(err.contains(&format!("{p}:3:46: error: module `s`, `params/factor` (f64): expected a number but found the string \"x\" instead; a value looks like 1.0")), "{err}");
    // A list property empty now: the example shows what its items look like.
    assert!(err.contains(&format!("{p}:4:54: error: module `g`, `params/goals` (Path2): expected a list but found the unsigned integer `5` instead; a value looks like [(x: 1.0, y: 2.0), (x: 3.0, y: 4.0)]")), "{err}");
    assert!(
        err.contains("link cycle: s/in/value -> s/in/value"),
        "{err}"
    );
    assert!(
        err.ends_with("4 errors found; nothing was started\n"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

/// Thousands of errors (one mistake repeated by a generator) are counted, and the first 200
/// shown located: 100,000 took a minute to locate and printed megabytes.
#[test]
fn check_shows_the_first_200_errors_and_counts_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("many.ron");
    let values: Vec<String> = (0..1500).map(|i| format!("\"params/x{i}\": 1")).collect();
    std::fs::write(
        &path,
        format!(
            "Agent(name: \"r1\", modules: [\n(name: \"s\", type: \"demo.scale\", values: {{{}}})])",
            values.join(", ")
        ),
    )
    .unwrap();
    let out = petrel(&["check", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 202, "{err}");
    let p = path.display().to_string();
    assert!(
        lines[..200]
            .iter()
            .all(|l| l.starts_with(&format!("{p}:2:"))),
        "{err}"
    );
    assert!(lines[0].contains("`params/x0`"), "{}", lines[0]);
    assert_eq!(
        lines[200],
        "... and 1300 more errors, not shown (fix the first ones: often one mistake repeated)"
    );
    assert_eq!(lines[201], "1500 errors found; nothing was started");
}

#[test]
fn check_validates_context_rules_with_the_config() {
    let ok = petrel(&["check", "configs/contexts-demo.ron"]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("agent.ron"),
        r#"Agent(name: "r1", contexts: "rules.ron", modules: [(name: "s", type: "demo.signal"), (name: "c", type: "demo.camera")])"#,
    )
    .unwrap();
    std::fs::write(
        dir.path().join("rules.ron"),
        "Contexts(contexts: [\n  (name: \"fast\", when: \"s/out/value > \\\"x\\\"\", set: {\"c/params/deblur\": \"1\"}),\n])",
    )
    .unwrap();
    let out = petrel(&["check", dir.path().join("agent.ron").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    let rules = dir.path().join("rules.ron");
    // At the `\"x\"` the error is about, as written in the file (escaped).
    assert!(
        err.contains(&format!(
            "{}:2:39: error: context `fast`: in `s/out/value > \"x\"`",
            rules.display()
        )),
        "{err}"
    );
    assert!(
        err.contains("context `fast`: in `1`:"),
        "a number cannot set a bool: {err}"
    );
}

#[test]
fn check_binds_missions_and_locates_bad_bindings_in_the_config() {
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("m.plan");
    std::fs::write(&plan, "go_3; report").unwrap();
    let config = dir.path().join("agent.ron");
    let write = |actions: &str| {
        std::fs::write(
            &config,
            format!(
                "Agent(name: \"r1\", modules: [\n  (name: \"count\", type: \"demo.counter\"),\n  (name: \"m\", type: \"mission.pnp\", values: {{\"params/plan\": {:?},\n    \"params/actions\": {{{actions}}}}}),\n])",
                plan.display().to_string()
            ),
        )
        .unwrap()
    };
    write(
        r#""go": (enable: ["count"], finished: "count/out/value >= $1"), "report": (restore: true)"#,
    );
    let ok = petrel(&["check", config.to_str().unwrap()]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));

    write(r#""go": (enable: ["cnt"], finished: "count/out/valu >= $1")"#);
    let out = petrel(&["check", config.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    let at = |line_col: &str, what: &str| {
        assert!(
            err.contains(&format!("{}:{line_col}: error: {what}", config.display())),
            "{line_col} {what}:\n{err}"
        )
    };
    at(
        "4:40",
        "m/params/actions[\"go\"].enable (action `go_3`): no module `cnt`",
    );
    at(
        "4:24",
        "m/params/actions[\"go\"].finished: 1:1: unknown property `count/out/valu`",
    );
    at(
        "4:5",
        "m/params/actions: no binding for action `report` at ",
    );
    assert!(err.contains("m.plan:1 (bound: go)"), "{err}");
}

#[test]
fn check_reports_a_missing_file_where_the_config_names_it() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("agent.ron");
    std::fs::write(
        &config,
        "Agent(name: \"r1\", modules: [\n  (name: \"robot\", type: \"sim.world\", values: {\"params/world\": \"maps/nowhere.txt\"}),\n])",
    )
    .unwrap();
    let out = petrel(&["check", config.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    let expected = format!(
        "{}:2:47: error: module `robot`: `params/world` names {}, but it does not exist",
        config.display(),
        dir.path().join("maps/nowhere.txt").display()
    );
    assert!(err.contains(&expected), "{err}");

    // A missing rules file named by the agent's `contexts:` field: the field is where it is
    // named (the context manager it adds is written nowhere).
    let rules = dir.path().join("contexts.ron");
    std::fs::write(
        &rules,
        "Agent(name: \"r1\",\n  contexts: \"missing.rules.ron\",\n  modules: [])",
    )
    .unwrap();
    let out = petrel(&["check", rules.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    let expected = format!(
        "{}:2:3: error: `contexts:` names {}, but it does not exist",
        rules.display(),
        dir.path().join("missing.rules.ron").display()
    );
    assert!(err.contains(&expected), "{err}");

    // Not a regular file (a FIFO would block the start forever), a symlink loop, a map image
    // that is a device: each named for what it is, before anything runs.
    let fifo = dir.path().join("fifo.txt");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let (a, b) = (dir.path().join("a.txt"), dir.path().join("b.txt"));
    std::os::unix::fs::symlink(&b, &a).unwrap();
    std::os::unix::fs::symlink(&a, &b).unwrap();
    std::fs::write(
        dir.path().join("zero.yaml"),
        "image: /dev/zero\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.2\n",
    )
    .unwrap();
    for (world, problem) in [
        (
            "fifo.txt",
            "but it is not a regular file (a FIFO, device or socket)",
        ),
        ("a.txt", "but it is a symlink loop"),
        (
            "zero.yaml",
            "/dev/zero: cannot read map image: it is not a regular file",
        ),
    ] {
        std::fs::write(
            &config,
            format!("Agent(name: \"r1\", modules: [\n  (name: \"robot\", type: \"sim.world\", values: {{\"params/world\": \"{world}\"}}),\n])"),
        )
        .unwrap();
        let out = petrel(&["check", config.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2), "{world}");
        let err = text(&out.stderr);
        assert!(err.contains(problem), "{world}: {err}");
    }
}

#[test]
fn a_world_file_that_does_not_parse_is_refused_by_check_and_run_before_anything_starts() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("broken.txt"), "#####\n#R Z#\n#####\n").unwrap();
    let config = dir.path().join("robot.ron");
    std::fs::write(
        &config,
        r#"Agent(name: "r", modules: [
    (name: "robot", type: "sim.world", values: {"params/world": "broken.txt"}),
])"#,
    )
    .unwrap();
    for command in ["check", "run"] {
        let out = petrel(&[command, config.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2), "{command}");
        let err = text(&out.stderr);
        let at = format!("{}:2:", config.display());
        assert!(
            err.starts_with(&at),
            "{command}: located in the config: {err}"
        );
        assert!(
            err.contains("`params/world`: ")
                && err.contains("broken.txt:2:4: unexpected character 'Z'"),
            "{command}: names the world file's line: {err}"
        );
        assert!(
            err.ends_with("1 error found; nothing was started\n"),
            "{err}"
        );
    }
}

#[test]
fn check_warns_about_a_module_that_reads_its_own_output() {
    let (_dir, config) = temp_config(
        "self.ron",
        r#"Agent(name: "r", modules: [
    (name: "c", type: "demo.counter"),
    (name: "s", type: "demo.scale", links: {"in/value": "s/out/value"}),
])"#,
    );
    let out = petrel(&["check", config.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "a warning, not an error");
    let warnings = text(&out.stderr);
    assert!(
        warnings.contains(&format!(
            "{}:3:45: warning: module `s`: `in/value` reads its own `out/value`",
            config.display()
        )),
        "{warnings}"
    );
    assert!(!warnings.contains("module `c`"), "{warnings}");
}

#[test]
fn configs_work_from_any_directory() {
    let elsewhere = tempfile::tempdir().unwrap();
    let root = std::env::current_dir().unwrap();
    for config in ["mission-demo.ron", "contexts-demo.ron", "navigate.ron"] {
        let out = bounded::output_within_deadline(
            Command::new(env!("CARGO_BIN_EXE_petrel"))
                .args(["check", root.join("configs").join(config).to_str().unwrap()])
                .current_dir(elsewhere.path())
                .env("RUST_LOG", "warn"),
        );
        assert!(out.status.success(), "{config}: {}", text(&out.stderr));
    }
}

/// Configs checked together: a link to an agent of another team can never connect (links
/// reach only agents of one team), and is refused where it is written.
#[test]
fn a_link_to_an_agent_of_another_team_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let copy = |name: &str, edit: &dyn Fn(String) -> String| {
        let text = std::fs::read_to_string(format!("configs/team/{name}.ron")).unwrap();
        let path = dir.path().join(format!("{name}.ron"));
        std::fs::write(&path, edit(text)).unwrap();
        path.to_str().unwrap().to_string()
    };
    let filter = copy("filter", &|t| t);
    let sensor = copy("sensor", &|t| t);
    let display = copy("display", &|t| {
        t.replacen(r#"name: "demo""#, r#"name: "demo2""#, 1)
    });
    let same = petrel(&["check", "configs/team/display.ron", &filter, &sensor]);
    assert!(same.status.success(), "{}", text(&same.stderr));
    let out = petrel(&["check", &display, &filter, &sensor]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("but agent `filter` is in team `demo` and this agent in team `demo2`: links reach only agents of the same team"),
        "{err}"
    );
    assert!(
        err.starts_with(&format!("{display}:")),
        "located in display.ron: {err}"
    );
}
