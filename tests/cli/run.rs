//! `petrel run`: summaries, snapshots, reloads, panics in the log, and outputs it refuses.

use std::process::Command;

use crate::bounded::{self, petrel, text};
use crate::running;
use crate::temp_config;

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
    assert!(!text(&overlay.stderr).contains("renames"));
    // A snapshot of another robot laid over: taken, and said.
    let other = dir.path().join("other.ron");
    let snapshot = std::fs::read_to_string(&snap).unwrap();
    assert!(snapshot.contains("name: \"robot1\""), "{snapshot}");
    // The agent's clock ran from its start, though nothing in it (no mission, no contexts)
    // read the clock: a run resumed from here goes on from 300 ms at least.
    let clock: f64 = snapshot
        .lines()
        .find_map(|l| l.trim().strip_prefix("clock_s: "))
        .and_then(|v| v.trim_end_matches(',').parse().ok())
        .unwrap_or_else(|| panic!("a clock_s field: {snapshot}"));
    assert!(clock >= 0.3, "the clock counts the 300 ms run: {clock}");
    std::fs::write(
        &other,
        snapshot.replace("name: \"robot1\"", "name: \"robot2\""),
    )
    .unwrap();
    let renamed = petrel(&[
        "check",
        "configs/pipeline.ron",
        "--overlay",
        other.to_str().unwrap(),
    ]);
    assert!(renamed.status.success(), "{}", text(&renamed.stderr));
    assert!(
        text(&renamed.stderr).contains(&format!(
            "note: {}: renames the agent `robot1` to `robot2`",
            other.display()
        )),
        "{}",
        text(&renamed.stderr)
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
        .find_map(|p| {
            let n = p.strip_suffix(" restarts").or(p.strip_suffix(" restart"))?;
            n.parse().ok()
        })
        .unwrap();
    assert!(restarts > 0, "{stdout}");
    let last = stdout
        .lines()
        .rfind(|l| l.starts_with("[consumer]"))
        .expect("the consumer reports");
    assert!(last.ends_with("gaps 0, duplicates 0"), "{last}");
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
    // Tools take the address with or without its scheme.
    let active = |address: &str| {
        let out = bounded::output_within_deadline(
            Command::new(env!("CARGO_BIN_EXE_petrel"))
                .args(["get", address])
                .env("PETREL_RUNTIME_DIR", dir.path()),
        );
        assert!(out.status.success(), "{}", text(&out.stderr));
        text(&out.stdout)
    };
    let now = active("petrel://r1/contexts/out/active");
    assert!(now.contains("fast"), "{now}");

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
    let now = active("r1/contexts/out/active");
    assert!(now.contains("slow") && !now.contains("fast"), "{now}");

    petrel.signal("INT");
    petrel.wait_for("stopping: interrupted");
    assert!(petrel.child.wait().unwrap().success());
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
    // Resolving the backtrace's symbols takes long the first time (the binary's debug info is
    // read): it must not hold the agent's thread, which the held watcher would report.
    let held: Vec<&serde_json::Value> = lines
        .iter()
        .filter(|l| {
            l["fields"]["message"]
                .as_str()
                .is_some_and(|m| m.contains("held the agent's thread"))
        })
        .collect();
    assert!(held.is_empty(), "a panic report holds no thread: {held:?}");
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
        text(&out.stderr).contains("a file this run reads or writes"),
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
