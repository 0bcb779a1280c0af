//! Modules, contexts and plans that re-trigger themselves without progress (issue 19): they
//! neither starve the agent nor flood the log, and each loop is reported once, by name.

#[path = "common/bounded.rs"]
mod bounded;

use std::process::{Command, Output};

use bounded::text;

/// Runs `petrel run CONFIG --for 1s` at log level `level`, with `extra` arguments.
fn run_for_1s(config: &std::path::Path, level: &str, extra: &[&str]) -> Output {
    let mut args = vec![
        "run",
        config.to_str().unwrap(),
        "--for",
        "1s",
        "--no-remote",
    ];
    args.extend(extra);
    bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(&args)
            .env("RUST_LOG", level),
    )
}

/// Writes `files` (name, text) into a fresh temporary directory; returns it and the first path.
fn temp_files(files: &[(&str, &str)]) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    for (name, body) in files {
        std::fs::write(dir.path().join(name), body).unwrap();
    }
    let first = dir.path().join(files[0].0);
    (dir, first)
}

/// The summary's step count of `module`.
fn steps(summary: &str, module: &str) -> u64 {
    let line = summary
        .lines()
        .find(|l| l.split_whitespace().next() == Some(module))
        .unwrap_or_else(|| panic!("no summary line for {module}: {summary}"));
    line.split_whitespace().nth(3).unwrap().parse().unwrap()
}

/// The log lines that contain `needle`.
fn lines_with<'a>(log: &'a str, needle: &str) -> Vec<&'a str> {
    log.lines().filter(|l| l.contains(needle)).collect()
}

#[test]
fn a_module_that_wakes_itself_starves_neither_the_others_nor_the_stop_and_is_named_once() {
    // `s` reads its own output: every step wakes it again, forever.
    let (_dir, config) = temp_files(&[(
        "self.ron",
        r#"Agent(name: "r", modules: [
    (name: "s", type: "demo.scale", links: {"in/value": "s/out/value"}, values: {"params/factor": 1.0001}),
    (name: "c", type: "demo.counter", values: {"params/period_ms": 100}),
    (name: "after", type: "demo.scale", links: {"in/value": "s/out/value"}),
])"#,
    )]);
    let out = run_for_1s(&config, "warn", &["--workers", "1"]);
    let (log, summary) = (text(&out.stderr), text(&out.stdout));
    assert_eq!(out.status.code(), Some(0), "{log}");
    assert!(
        steps(&summary, "s") > 1000,
        "the busy module ran: {summary}"
    );
    assert!(
        steps(&summary, "c") >= 1,
        "the periodic module ran: {summary}"
    );
    let reports = lines_with(&log, "re-triggers itself");
    // Its steps may average over the step budget on a loaded machine, so the runtime may move
    // it off the agent's thread (a restart, with a warning saying so), after which the new
    // instance names the loop again.
    let moves = lines_with(&log, "moved off the agent's thread")
        .iter()
        .filter(|l| l.ends_with("module=s"))
        .count();
    assert_eq!(
        reports.len(),
        1 + moves,
        "one report per instance, for `s` only: {log}"
    );
    assert!(
        reports.iter().all(|r| r.contains("module `s` ")),
        "for `s` only: {log}"
    );
    assert!(
        reports[0].contains(
            "module `s` re-triggers itself without progress through s/out/value → s/in/value"
        ),
        "the loop is named: {}",
        reports[0]
    );
}

#[test]
fn two_modules_feeding_each_other_name_the_cycle_of_links() {
    let (_dir, config) = temp_files(&[(
        "pair.ron",
        r#"Agent(name: "r", modules: [
    (name: "a", type: "demo.scale", links: {"in/value": "b/out/value"}),
    (name: "b", type: "demo.scale", links: {"in/value": "a/out/value"}, values: {"params/factor": 1.0001}),
])"#,
    )]);
    let out = run_for_1s(&config, "warn", &[]);
    let log = text(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{log}");
    let reports = lines_with(&log, "re-triggers itself");
    assert!(
        reports.iter().any(|r| r.contains("module `a` re-triggers itself without progress through a/out/value → b/in/value, b/out/value → a/in/value")),
        "{log}"
    );
    assert!(
        reports.len() <= 2,
        "each module of the loop once at most: {log}"
    );
}

#[test]
fn a_context_that_undoes_its_own_condition_is_warned_by_check_and_named_once_at_run() {
    let (_dir, config) = temp_files(&[
        (
            "ctx.ron",
            r#"Agent(name: "r", contexts: "ctx.rules.ron", modules: [
    (name: "m", type: "demo.scale"),
    (name: "c", type: "demo.counter", values: {"params/period_ms": 100}),
])"#,
        ),
        (
            "ctx.rules.ron",
            "Contexts(contexts: [\n    (name: \"undo\", when: \"m/params/factor > 0.5\", set: {\"m/params/factor\": \"0.0\"}),\n])",
        ),
    ]);
    let check = bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel")).args(["check", config.to_str().unwrap()]),
    );
    let err = text(&check.stderr);
    assert_eq!(
        check.status.code(),
        Some(0),
        "a warning, not an error: {err}"
    );
    let rules = config.with_file_name("ctx.rules.ron");
    assert!(
        err.contains(&format!(
            "{}:2:58: warning: context `undo` changes `m/params/factor`, which its own `when` reads",
            rules.display()
        )),
        "{err}"
    );

    let out = run_for_1s(&config, "info", &[]);
    let (log, summary) = (text(&out.stderr), text(&out.stdout));
    assert_eq!(out.status.code(), Some(0), "{log}");
    assert!(steps(&summary, "contexts") > 1000, "it did loop: {summary}");
    assert!(steps(&summary, "c") >= 1, "the others ran: {summary}");
    let reports = lines_with(&log, "re-triggers itself");
    assert_eq!(reports.len(), 1, "once, by the manager: {reports:?}");
    assert!(
        reports[0].contains("module `contexts` re-triggers")
            && reports[0].contains("context `undo` changes `m/params/factor`"),
        "{}",
        reports[0]
    );
    // Before the loop is found each switch is logged; after, none is (it used to be ~90,000
    // lines a second). The bound follows from the loop limit, not from the machine's speed.
    let switches = lines_with(&log, "context activated").len();
    assert!(switches <= 1_000, "{switches} switches logged");
}

#[test]
fn a_plan_that_fires_in_a_circle_is_named_once_and_its_firings_are_not_logged_one_by_one() {
    let (_dir, config) = temp_files(&[
        (
            "spin.ron",
            r#"Agent(name: "r", modules: [
    (name: "mission", type: "mission.pnp", values: {"params/plan": "spin.plan", "params/allow_unbound": true}),
    (name: "c", type: "demo.counter", values: {"params/period_ms": 100}),
])"#,
        ),
        // `done` never holds (nothing sets it): `ping` finishes at once, and back to the top.
        (
            "spin.plan",
            "LABEL_top;\n< done ? log_bye : (not done) ? ping; GOTO_LABEL_top >\n",
        ),
    ]);
    let out = run_for_1s(&config, "info", &[]);
    let (log, summary) = (text(&out.stderr), text(&out.stdout));
    assert_eq!(out.status.code(), Some(0), "{log}");
    assert!(steps(&summary, "c") >= 1, "the others ran: {summary}");
    let reports = lines_with(&log, "fires in a circle");
    // Its steps are long, so the runtime may move the mission off the agent's thread (a
    // restart, with a warning saying so), after which the new instance names the cycle again.
    let moves = lines_with(&log, "moved off the agent's thread")
        .iter()
        .filter(|l| l.contains("module=mission"))
        .count();
    assert_eq!(reports.len(), 1 + moves, "{reports:?}");
    assert!(
        reports[0].contains("plan `spin`") && reports[0].contains(r#""ping.start", "ping.end""#),
        "the cycle is named: {}",
        reports[0]
    );
    // It used to log ~110,000 lines a second: a firing and an "unbound action" warning each.
    let firings = lines_with(&log, "plan step").len();
    let instances = 1 + moves;
    assert!(firings <= 1_100 * instances, "{firings} firings logged");
    assert_eq!(
        lines_with(&log, "unbound action").len(),
        instances,
        "said once (by each instance)"
    );
}
