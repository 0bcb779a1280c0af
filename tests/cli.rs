//! The `petrel` binary as a user runs it.

#[path = "common/bounded.rs"]
mod bounded;

use std::process::{Command, Output};

fn petrel(args: &[&str]) -> Output {
    bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(args)
            .env("RUST_LOG", "warn"),
    )
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

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
])"#,
    )
    .unwrap();
    let out = petrel(&["check", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    let p = path.display();
    assert!(err.contains(&format!("{p}:2:23: error: module `c`: unknown module type `demo.countr`; did you mean `demo.counter`?")), "{err}");
    assert!(err.contains(&format!("{p}:3:46: error: module `s`, `params/factor` (f64): expected a number but found the string \"x\" instead; a value looks like 1.0")), "{err}");
    assert!(
        err.contains("link cycle: s/in/value -> s/in/value"),
        "{err}"
    );
    assert!(
        err.ends_with("3 errors found; nothing was started\n"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn modules_lists_and_describes_types() {
    let list = text(&petrel(&["modules"]).stdout);
    assert!(
        list.contains("demo.scale") && list.contains("demo.consumer"),
        "{list}"
    );
    let out = petrel(&["modules", "describe", "demo.scale"]);
    let described = text(&out.stdout);
    assert!(
        described.lines().any(|l| l.split_whitespace().take(4).eq([
            "params/factor",
            "param",
            "f64",
            "1.0"
        ])),
        "{described}"
    );
    let unknown = petrel(&["modules", "describe", "demo.scal"]);
    assert_eq!(unknown.status.code(), Some(2));
    assert!(text(&unknown.stderr).contains("did you mean demo.scale?"));
}

#[test]
fn run_for_a_while_prints_a_summary_and_writes_a_runnable_snapshot() {
    let dir = tempfile::tempdir().unwrap();
    let snap = dir.path().join("snap.ron");
    let out = petrel(&[
        "run",
        "configs/pipeline.ron",
        "--for",
        "300ms",
        "--snapshot-out",
        snap.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("ran for 300ms"), "{stdout}");
    assert!(
        stdout.contains("agent robot1: 5 modules, 0 failures"),
        "{stdout}"
    );
    assert!(
        stdout
            .lines()
            .any(|l| l.trim_start().starts_with("consumer") && l.contains("stopped")),
        "{stdout}"
    );
    let check = petrel(&["check", snap.to_str().unwrap()]);
    assert!(
        check.status.success(),
        "the snapshot is a valid config: {}",
        text(&check.stderr)
    );
    let overlay = petrel(&[
        "check",
        "configs/pipeline.ron",
        "--overlay",
        snap.to_str().unwrap(),
    ]);
    assert!(
        overlay.status.success(),
        "and a valid overlay: {}",
        text(&overlay.stderr)
    );
}

#[test]
fn bad_arguments_are_explained() {
    let out = petrel(&["run", "configs/pipeline.ron", "--for", "soon"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("invalid value 'soon' for '--for <DURATION>'"),
        "{}",
        text(&out.stderr)
    );
    let missing = petrel(&["run", "configs/nope.ron"]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(text(&missing.stderr).starts_with("configs/nope.ron: error: cannot read config:"));
}

#[test]
fn plan_simulate_prints_one_json_line_per_step() {
    let out = petrel(&["plan", "simulate", "plans/tests/fixtures/editor_three.pnml"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(
        text(&out.stdout),
        concat!(
            "{\"step\":0,\"marking\":{\"P\":1}}\n",
            "{\"step\":1,\"calls\":[\"azione1.start\"],\"marking\":{\"azione1.ex\":1}}\n",
            "{\"step\":2,\"calls\":[],\"marking\":{\"azione1.ex\":1}}\n",
            "{\"step\":3,\"calls\":[\"azione1.end\"],\"marking\":{\"goal\":1}}\n",
            "{\"result\":\"goal\",\"step\":3}\n",
        )
    );
    let broken = petrel(&["plan", "check", "plans/tests/fixtures/malformed.pnml"]);
    assert_eq!(broken.status.code(), Some(2));
    assert!(
        text(&broken.stderr).starts_with("error: "),
        "{}",
        text(&broken.stderr)
    );
}

#[test]
fn the_chaos_demo_keeps_going_and_loses_nothing() {
    let out = petrel(&["run", "configs/chaos.ron", "--for", "3s"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let summary = stdout
        .lines()
        .find(|l| l.starts_with("agent robot1:"))
        .expect("a summary");
    let restarts: u64 = summary
        .split(", ")
        .find_map(|p| p.strip_suffix(" restarts")?.parse().ok())
        .unwrap();
    assert!(restarts > 0, "{stdout}");
    let last = stdout
        .lines()
        .rfind(|l| l.starts_with("[consumer]"))
        .expect("the consumer reports");
    assert!(last.ends_with("gaps 0, duplicates 0"), "{last}");
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
    assert!(
        err.contains(&format!(
            "{}:2:24: error: context `fast`: in `s/out/value > \"x\"`",
            rules.display()
        )),
        "{err}"
    );
    assert!(
        err.contains("context `fast`: in `1`:"),
        "a number cannot set a bool: {err}"
    );
}

/// Runs `petrel run` in the background, reading its log line by line.
#[cfg(unix)]
struct Running {
    child: std::process::Child,
    log: std::io::Lines<std::io::BufReader<std::process::ChildStderr>>,
}

#[cfg(unix)]
impl Running {
    fn start(config: &std::path::Path) -> Self {
        use std::io::BufRead;
        let mut child = Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(["run", config.to_str().unwrap(), "--for", "120s"])
            .env("RUST_LOG", "info")
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("petrel runs");
        let log = std::io::BufReader::new(child.stderr.take().unwrap()).lines();
        Running { child, log }
    }

    /// Reads the log up to the first line containing `needle` and returns it.
    fn wait_for(&mut self, needle: &str) -> String {
        for line in self.log.by_ref() {
            let line = line.expect("the log is text");
            if line.contains(needle) {
                return line;
            }
        }
        panic!("petrel's log ended without `{needle}`");
    }

    fn signal(&self, name: &str) {
        let sent = Command::new("kill")
            .args([&format!("-{name}"), &self.child.id().to_string()])
            .status()
            .expect("kill runs");
        assert!(sent.success());
    }
}

#[cfg(unix)]
#[test]
fn sighup_reloads_context_rules_and_a_broken_file_keeps_the_running_ones() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("agent.ron");
    let rules = dir.path().join("rules.ron");
    std::fs::write(
        &config,
        r#"Agent(name: "r1", contexts: "rules.ron", modules: [(name: "s", type: "demo.signal"), (name: "c", type: "demo.camera")])"#,
    )
    .unwrap();
    let fast = |threshold: &str| {
        format!(
            "Contexts(contexts: [\n  (name: \"fast\", when: \"s/out/value > {threshold}\", set: {{\"c/params/deblur\": \"true\"}}),\n])"
        )
    };
    std::fs::write(&rules, fast("0.5")).unwrap();
    let mut petrel = Running::start(&config);
    petrel.wait_for("context rules loaded");

    std::fs::write(&rules, fast("")).unwrap();
    petrel.signal("HUP");
    petrel.wait_for("context rules not reloaded; the running rules stay");
    let error = petrel.wait_for("error:");
    assert!(
        error.contains(&format!(
            "{}:2:39: error: context `fast`: in `s/out/value > `: expected a value",
            rules.display()
        )),
        "{error}"
    );

    std::fs::write(&rules, fast("0.9")).unwrap();
    petrel.signal("HUP");
    petrel.wait_for("context rules reloaded");

    petrel.signal("INT");
    petrel.wait_for("stopping: interrupted");
    assert!(petrel.child.wait().unwrap().success());
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
        "{}:2:47: error: module `robot`: `params/world` names {}, which does not exist",
        config.display(),
        dir.path().join("maps/nowhere.txt").display()
    );
    assert!(err.contains(&expected), "{err}");
}

#[test]
fn a_mission_runs_to_its_goal_on_one_worker_thread() {
    let out = petrel(&["run", "configs/mission-demo.ron", "--workers", "1"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let refused = petrel(&["run", "configs/mission-demo.ron", "--workers", "0"]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(text(&refused.stderr).contains("'--workers <WORKERS>'"));
}

#[test]
fn plan_check_stops_at_max_states_and_says_how_to_go_further() {
    let out = petrel(&[
        "plan",
        "check",
        "plans/tests/fixtures/delivery.plan",
        "--max-states",
        "3",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("(3 markings explored, incomplete)")
            && stdout.contains("warning[incomplete]: stopped after exploring 3 markings (the limit); raise --max-states"),
        "{stdout}"
    );
    let full = petrel(&["plan", "check", "plans/tests/fixtures/delivery.plan"]);
    assert!(
        !text(&full.stdout).contains("incomplete"),
        "{}",
        text(&full.stdout)
    );
}
