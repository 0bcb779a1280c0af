//! Modules, contexts and plans that re-trigger themselves without progress (issue 19): they
//! neither starve the agent nor flood the log, and each loop is reported once, by name.

#[path = "common/bounded.rs"]
mod bounded;
#[path = "common/running.rs"]
mod running;

use std::process::Command;

use bounded::text;

/// How a run ended: exit code, standard output (the summary), the whole log.
struct Ended {
    code: Option<i32>,
    summary: String,
    log: String,
}

/// Runs `petrel run CONFIG` (log at `info`, `extra` arguments) until its log names a loop
/// (a line containing `needle`, within the process deadline), then stops it with Ctrl-C.
/// Waiting for the report rather than for a fixed time keeps the test meaningful on a loaded
/// machine, where a loop may take longer than a second to show. The configs turn the step
/// budget off (`mean_us: 0`, `held_ms: 0`): a loop's steps may average over it there, and a
/// module moved off its agent's thread is restarted, which may end its loop (a restarted
/// context manager has no context active) or make it named again by the new instance.
fn run_until_reported(config: &std::path::Path, extra: &[&str], needle: &str) -> Ended {
    let records = tempfile::tempdir().unwrap();
    let mut args = vec!["run", config.to_str().unwrap(), "--no-remote"];
    args.extend(extra);
    let mut petrel = running::Running::start(&args, records.path());
    let (line, before) = petrel.wait_for(needle);
    petrel.signal("INT");
    let (status, summary, rest) = petrel.finish();
    let log = [before.join("\n"), line, rest].join("\n");
    Ended {
        code: status.code(),
        summary,
        log,
    }
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
        r#"Agent(name: "r", step_budget: (mean_us: 0, steps: 20, held_ms: 0), modules: [
    (name: "s", type: "demo.scale", links: {"in/value": "s/out/value"}, values: {"params/factor": 1.0001}),
    (name: "c", type: "demo.counter", values: {"params/period_ms": 100}),
    (name: "after", type: "demo.scale", links: {"in/value": "s/out/value"}),
])"#,
    )]);
    let Ended { code, summary, log } =
        run_until_reported(&config, &["--workers", "1"], "re-triggers itself");
    assert_eq!(code, Some(0), "{log}");
    assert!(
        steps(&summary, "s") >= 1000,
        "the busy module ran: {summary}"
    );
    assert!(
        steps(&summary, "c") >= 1,
        "the periodic module ran: {summary}"
    );
    let reports = lines_with(&log, "re-triggers itself");
    assert_eq!(reports.len(), 1, "one report, for `s` only: {log}");
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
        r#"Agent(name: "r", step_budget: (mean_us: 0, steps: 20, held_ms: 0), modules: [
    (name: "a", type: "demo.scale", links: {"in/value": "b/out/value"}),
    (name: "b", type: "demo.scale", links: {"in/value": "a/out/value"}, values: {"params/factor": 1.0001}),
])"#,
    )]);
    let Ended { code, log, .. } = run_until_reported(&config, &[], "re-triggers itself");
    assert_eq!(code, Some(0), "{log}");
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
            r#"Agent(name: "r", contexts: "ctx.rules.ron", step_budget: (mean_us: 0, steps: 20, held_ms: 0), modules: [
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
    // Said to be on purpose, the warning goes; the run below still names a real loop.
    let quiet = config.with_file_name("quiet.rules.ron");
    let original = std::fs::read_to_string(&rules).unwrap();
    let marked = original.replace("set:", "reads_own_changes: true, set:");
    std::fs::write(&quiet, marked).unwrap();
    let quiet_config = config.with_file_name("quiet.ron");
    let original = std::fs::read_to_string(&config).unwrap();
    let pointed = original.replace("ctx.rules.ron", "quiet.rules.ron");
    std::fs::write(&quiet_config, pointed).unwrap();
    let check = bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel")).args(["check", quiet_config.to_str().unwrap()]),
    );
    let quiet_err = text(&check.stderr);
    assert!(
        check.status.success() && !quiet_err.contains("warning"),
        "{quiet_err}"
    );

    let Ended { code, summary, log } = run_until_reported(&config, &[], "re-triggers itself");
    assert_eq!(code, Some(0), "{log}");
    assert!(
        steps(&summary, "contexts") >= 1000,
        "it did loop: {summary}\n{log}"
    );
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
            r#"Agent(name: "r", step_budget: (mean_us: 0, steps: 20, held_ms: 0), modules: [
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
    let Ended { code, summary, log } = run_until_reported(&config, &[], "fires in a circle");
    assert_eq!(code, Some(0), "{log}");
    assert!(steps(&summary, "c") >= 1, "the others ran: {summary}");
    let reports = lines_with(&log, "fires in a circle");
    assert_eq!(reports.len(), 1, "{reports:?}");
    assert!(
        reports[0].contains("plan `spin`") && reports[0].contains(r#""ping.start", "ping.end""#),
        "the cycle is named: {}",
        reports[0]
    );
    // It used to log ~110,000 lines a second: a firing and an "unbound action" warning each.
    let firings = lines_with(&log, "plan step").len();
    assert!(firings <= 1_100, "{firings} firings logged");
    assert_eq!(lines_with(&log, "unbound action").len(), 1, "said once");
}

#[test]
fn a_plan_that_says_something_in_a_circle_says_it_only_until_the_circle_is_named() {
    let (_dir, config) = temp_files(&[
        (
            "chatty.ron",
            r#"Agent(name: "r", step_budget: (mean_us: 0, steps: 20, held_ms: 0), modules: [
    (name: "mission", type: "mission.pnp", values: {"params/plan": "chatty.plan", "params/is_mission": true,
        "params/conditions": {"done": "c/out/value >= 3"}}),
    (name: "c", type: "demo.counter", values: {"params/period_ms": 100}),
])"#,
        ),
        // It circles until the counter reaches 3 (0.3 s), hundreds of thousands of times.
        (
            "chatty.plan",
            "LABEL_top;\n< done ? log_bye : (not done) ? say_again; GOTO_LABEL_top >\n",
        ),
    ]);
    let records = tempfile::tempdir().unwrap();
    let args = ["run", config.to_str().unwrap(), "--no-remote"];
    let (status, _summary, log) = running::Running::start(&args, records.path()).finish();
    assert_eq!(status.code(), Some(0), "the plan reached its goal: {log}");
    // Each circle said it once, a log line each (~2 million lines a second before): now only
    // until the mission's loop finder sees the circle.
    let said = lines_with(&log, " again ").len();
    assert!((1..=1_100).contains(&said), "said {said} times");
    assert_eq!(lines_with(&log, " bye ").len(), 1);
}

#[test]
fn a_plan_that_makes_tokens_without_end_is_stopped_with_the_place_named() {
    let (_dir, config) = temp_files(&[
        (
            "fork.ron",
            r#"Agent(name: "r", modules: [
    (name: "mission", type: "mission.pnp", values: {"params/plan": "fork.plan", "params/is_mission": true,
        "params/actions": {"hold": (finished: "false")}}),
])"#,
        ),
        // Each time round, a new `hold` starts beside the loop and never ends.
        (
            "fork.plan",
            "LABEL_x; { log_again; GOTO_LABEL_x } || { hold }\n",
        ),
    ]);
    let records = tempfile::tempdir().unwrap();
    let args = ["run", config.to_str().unwrap(), "--no-remote"];
    let (status, summary, log) = running::Running::start(&args, records.path()).finish();
    assert_eq!(
        status.code(),
        Some(1),
        "the mission failed: {summary}\n{log}"
    );
    assert!(
        summary.contains("place 'hold.exec' holds 10")
            && summary.contains("tokens (more than 1000)")
            && summary.contains("plan `fork`: fail"),
        "{summary}"
    );
}
