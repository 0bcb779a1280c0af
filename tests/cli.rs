//! The `petrel` binary as a user runs it.

#[path = "common/bounded.rs"]
mod bounded;
#[path = "common/running.rs"]
mod running;

use std::process::{Command, Output};

use bounded::{petrel, text};

/// Writes config `text` as `name` in a fresh temporary directory (alive as long as the returned
/// guard) and returns its path.
fn temp_config(name: &str, text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    (dir, path)
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
        described.lines().any(|l| l.split_whitespace().take(5).eq([
            "params/factor",
            "param",
            "f64",
            "finite",
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
    // The wording is clap's: only that it names the option and the value is ours to hold.
    let said = text(&out.stderr);
    assert!(said.contains("'soon'") && said.contains("--for"), "{said}");
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
    // Always true (the signal stays within ±1), so a context is active from the start.
    let rule = |name: &str, when: &str, deblur: bool| {
        format!(
            "Contexts(contexts: [\n  (name: \"{name}\", when: \"{when}\", set: {{\"c/params/deblur\": \"{deblur}\"}}),\n])"
        )
    };
    std::fs::write(&rules, rule("fast", "s/out/value > -1000", true)).unwrap();
    let mut petrel = running::Running::start(
        &["run", config.to_str().unwrap(), "--for", "120s"],
        dir.path(),
    );
    petrel.wait_for("context rules loaded");
    let (set, _) = petrel.wait_for("context sets");
    assert!(
        set.contains("context=fast") && set.contains("new=true"),
        "{set}"
    );

    std::fs::write(&rules, rule("fast", "s/out/value > ", true)).unwrap();
    petrel.signal("HUP");
    petrel.wait_for("context rules not reloaded; the running rules stay");
    let (error, _) = petrel.wait_for("error:");
    assert!(
        error.contains(&format!(
            "{}:2:39: error: context `fast`: in `s/out/value > `: expected a value",
            rules.display()
        )),
        "{error}"
    );

    // The running rules still act: `fast` is still the active context.
    let active = || {
        let out = bounded::output_within_deadline(
            Command::new(env!("CARGO_BIN_EXE_petrel"))
                .args(["get", "petrel://r1/contexts/out/active"])
                .env("PETREL_RUNTIME_DIR", dir.path()),
        );
        assert!(out.status.success(), "{}", text(&out.stderr));
        text(&out.stdout)
    };
    assert!(active().contains("fast"), "{}", active());

    // The new rules are in force: `fast` ends (its setting restored), `slow` is active.
    std::fs::write(&rules, rule("slow", "s/out/value > -1000", false)).unwrap();
    petrel.signal("HUP");
    let (_, before) = petrel.wait_for("context activated context=slow");
    for needle in ["context rules reloaded", "context deactivated context=fast"] {
        assert!(
            before.iter().any(|l| l.contains(needle)),
            "{needle}: {before:#?}"
        );
    }
    let now = active();
    assert!(now.contains("slow") && !now.contains("fast"), "{now}");

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
        "{}:2:47: error: module `robot`: `params/world` names {}, but it does not exist",
        config.display(),
        dir.path().join("maps/nowhere.txt").display()
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
fn a_mission_runs_to_its_goal_on_one_worker_thread() {
    let out = bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args([
                "run",
                "configs/mission-demo.ron",
                "--workers",
                "1",
                "--no-remote",
            ])
            .env("RUST_LOG", "petrel=info"),
    );
    let err = text(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("modules run on 1 worker thread(s)"),
        "the worker count in effect: {err}"
    );
    for bad in ["0", "257", "3000"] {
        let refused = petrel(&["run", "configs/mission-demo.ron", "--workers", bad]);
        assert_eq!(refused.status.code(), Some(2), "--workers {bad}");
        assert!(text(&refused.stderr).contains("'--workers <WORKERS>'"));
    }
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

#[test]
fn graph_draws_modules_and_links_as_dot() {
    let out = petrel(&["graph", "configs/team/filter.ron"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let dot = text(&out.stdout);
    assert!(dot.starts_with("digraph \"filter\" {"), "{dot}");
    // One box per module, one dashed box per module of another agent that a link reads.
    assert!(dot.contains("[ label = \"scale\\ndemo.scale\"]"), "{dot}");
    assert!(
        dot.contains("[ label = \"sensor/producer\", style = dashed]"),
        "{dot}"
    );
    // A remote queue link is bold (a queue) and dashed (remote).
    assert!(
        dot.contains("label = \"out/items → in/items\", style = \"bold,dashed\""),
        "{dot}"
    );
    assert_eq!(dot.matches(" -> ").count(), 2, "{dot}");

    let local = text(&petrel(&["graph", "configs/pipeline.ron"]).stdout);
    assert_eq!(local.matches(" -> ").count(), 3, "3 links: {local}");
    assert!(!local.contains("dashed"), "no remote link: {local}");

    let out = petrel(&["graph", "configs/does-not-exist.ron"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("does-not-exist.ron"));
}

#[test]
fn a_module_panic_is_one_error_event_in_its_span_and_nothing_beside_the_log() {
    let (_dir, config) = temp_config(
        "panics.ron",
        r#"Agent(name: "r", modules: [
    (name: "c", type: "demo.counter", restart: temporary, values: {"params/period_ms": 10}),
    (name: "chaos", type: "demo.chaos",
     values: {"params/targets": "c", "params/faults": "panic", "params/mean_interval_ms": 20}),
])"#,
    );
    let out = bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(["run", config.to_str().unwrap(), "--for", "3s"])
            .args(["--log-format", "json", "--no-remote"])
            .env("RUST_LOG", "info")
            .env("RUST_BACKTRACE", "1"),
    );
    // `c` is temporary: it stays failed, and the run says so with exit code 1.
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    let lines: Vec<serde_json::Value> = text(&out.stderr)
        .lines()
        .map(|l| {
            serde_json::from_str(l).unwrap_or_else(|e| panic!("not a JSON log line ({e}): {l}"))
        })
        .collect();
    let panics: Vec<&serde_json::Value> = lines
        .iter()
        .filter(|l| {
            l["fields"]["message"]
                .as_str()
                .is_some_and(|m| m.starts_with("panicked: "))
        })
        .collect();
    assert_eq!(panics.len(), 1, "one report for one panic: {panics:?}");
    let panic = panics[0];
    assert_eq!(panic["level"], "ERROR");
    assert_eq!(panic["span"]["module"], "c", "{panic}");
    assert_eq!(
        panic["fields"]["message"],
        "panicked: fault injected through control/fault: panic"
    );
    let location = panic["fields"]["panic.location"].as_str().unwrap();
    assert!(location.contains("module_actor"), "{location}");
    assert!(
        panic["fields"]["backtrace"]
            .as_str()
            .is_some_and(|b| !b.is_empty()),
        "RUST_BACKTRACE asks for a backtrace field: {panic}"
    );
    let failed = lines
        .iter()
        .find(|l| l["fields"]["message"] == "module failed")
        .expect("the supervisor reports the failure");
    let error = failed["fields"]["error"].as_str().unwrap();
    assert!(
        error.starts_with(&format!("panicked at {location}: ")),
        "the failure names where the panic was: {error}"
    );
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

/// Runs petrel with its standard output a pipe whose reading end is already closed, so every
/// write to it fails (as `petrel … | head -1` after `head` has exited).
fn petrel_into_a_closed_pipe(args: &[&str]) -> Output {
    use std::os::fd::{FromRawFd, OwnedFd};
    let mut fds = [0; 2];
    // SAFETY: `pipe` fills two fresh descriptors; the reading one is closed at once and the
    // writing one is owned by the `Stdio` handed to the child.
    let stdout = unsafe {
        assert_eq!(libc::pipe(fds.as_mut_ptr()), 0, "pipe");
        libc::close(fds[0]);
        std::process::Stdio::from(OwnedFd::from_raw_fd(fds[1]))
    };
    let child = Command::new(env!("CARGO_BIN_EXE_petrel"))
        .args(args)
        .env("RUST_LOG", "info")
        .stdin(std::process::Stdio::null())
        .stdout(stdout)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    bounded::wait_within_deadline(child, &format!("petrel {args:?}"))
}

#[test]
fn a_closed_standard_output_ends_tools_quietly_and_a_run_goes_on() {
    use std::os::unix::process::ExitStatusExt;
    for args in [
        &["check", "configs/pipeline.ron"][..],
        &["plan", "dot", "plans/tests/fixtures/delivery.plan"],
        &["plan", "check", "plans/tests/fixtures/delivery.plan"],
        &["graph", "configs/navigate.ron"],
        &["modules"],
    ] {
        let out = petrel_into_a_closed_pipe(args);
        let err = text(&out.stderr);
        assert_eq!(
            out.status.signal(),
            Some(libc::SIGPIPE),
            "{args:?} ends by SIGPIPE like other Unix tools: {:?} {err}",
            out.status
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    // A run keeps going to its end (cleanup, summary attempt) with its printer quiet.
    let out =
        petrel_into_a_closed_pipe(&["run", "configs/pipeline.ron", "--for", "1s", "--no-remote"]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert_eq!(
        err.matches("standard output was closed: nothing more is printed")
            .count(),
        1,
        "said once: {err}"
    );
    assert!(
        !err.contains("panicked") && !err.contains("module failed"),
        "{err}"
    );
}

#[test]
fn outputs_never_replace_inputs_and_bad_destinations_are_refused_before_running() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("pipeline.ron");
    let original = std::fs::read_to_string("configs/pipeline.ron").unwrap();
    std::fs::write(&config, &original).unwrap();
    let config_arg = config.to_str().unwrap();

    // The snapshot would replace the config (named another way): refused, nothing run.
    // Both refusals come before the 30 s run would start.
    let snapshot_to = |out: &std::path::Path| {
        petrel(&[
            "run",
            config_arg,
            "--for",
            "30s",
            "--snapshot-out",
            out.to_str().unwrap(),
        ])
    };
    let out = snapshot_to(&dir.path().join(".").join("pipeline.ron"));
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("which this run reads"),
        "{}",
        text(&out.stderr)
    );
    assert!(
        !text(&out.stdout).contains("ran for"),
        "refused before running"
    );
    assert_eq!(std::fs::read_to_string(&config).unwrap(), original);

    // A destination that cannot be written is found before the run, not after it.
    let out = snapshot_to(&dir.path().join("no/such/dir/snap.ron"));
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).starts_with("error: --snapshot-out "),
        "{}",
        text(&out.stderr)
    );

    // A good destination gets a whole snapshot, and no temporary file stays beside it.
    let snap = dir.path().join("snap.ron");
    let out = petrel(&[
        "run",
        config_arg,
        "--for",
        "1s",
        "--no-remote",
        "--snapshot-out",
        snap.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(std::fs::read_to_string(&snap)
        .unwrap()
        .starts_with("// Snapshot of agent"));
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["pipeline.ron", "snap.ron"]);

    // plan compile -o onto its own input: refused, the text plan kept.
    let plan = dir.path().join("p.plan");
    std::fs::write(&plan, "a; b\n").unwrap();
    let out = petrel(&[
        "plan",
        "compile",
        plan.to_str().unwrap(),
        "-o",
        plan.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
    assert_eq!(std::fs::read_to_string(&plan).unwrap(), "a; b\n");
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
