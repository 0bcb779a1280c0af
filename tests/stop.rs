//! A stop always stops: `--for`, Ctrl-C and SIGTERM end `petrel run` even when a module's step
//! never yields its thread, and the summary or the last message names the modules killed.
#![cfg(unix)]

#[path = "common/bounded.rs"]
mod bounded;
#[path = "common/running.rs"]
mod running;

use std::process::Command;

use running::Running;

/// A config whose module `stuck` fails its first step with `fault` (`spin`: a CPU loop that
/// never yields; `block`: a call that never returns), beside a periodic module that is fine.
fn config(dir: &std::path::Path, fault: &str) -> std::path::PathBuf {
    let path = dir.join("stuck.ron");
    std::fs::write(
        &path,
        format!(
            r#"Agent(name: "r", modules: [
    (name: "fine", type: "demo.counter", values: {{"params/period_ms": 20}}),
    (name: "stuck", type: "demo.counter", values: {{"params/period_ms": 20, "control/fault": "{fault}"}}),
])"#
        ),
    )
    .unwrap();
    path
}

/// `petrel run` on one worker with a module whose first step blocks for good, once that step
/// is seen blocking.
fn blocked_on_one_worker(dir: &std::path::Path, stop_timeout: &str) -> Running {
    let config = config(dir, "block");
    let mut petrel = Running::start(
        &[
            "run",
            config.to_str().unwrap(),
            "--workers",
            "1",
            "--stop-timeout",
            stop_timeout,
            "--no-remote",
        ],
        dir,
    );
    petrel.wait_for("agent started");
    // The agent has started before its modules' first steps: a stop asked now can reach
    // `stuck` before its step blocks, and it then stops like any module (a run that ended 0
    // in CI). The thread-hold watcher's warning says the step is holding the thread.
    let (held, _) = petrel.wait_for("has held the agent's thread");
    assert!(held.contains("module=stuck"), "{held}");
    petrel
}

/// `petrel run` of the config with `fault` for 1 s on `workers` threads, 300 ms stop timeout:
/// exit code, standard output, log.
fn run_for_1s(dir: &std::path::Path, fault: &str, workers: &str) -> (Option<i32>, String, String) {
    let config = config(dir, fault);
    let out = bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args([
                "run",
                config.to_str().unwrap(),
                "--for",
                "1s",
                "--workers",
                workers,
            ])
            .args(["--stop-timeout", "300ms", "--no-remote"])
            .env("RUST_LOG", "info")
            .env("PETREL_RUNTIME_DIR", dir),
    );
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn run_for_ends_the_process_when_a_spinning_step_holds_the_only_worker() {
    let dir = tempfile::tempdir().unwrap();
    let (code, _, log) = run_for_1s(dir.path(), "spin", "1");
    assert_eq!(code, Some(1), "{log}");
    assert!(
        log.contains(
            "the modules did not stop within 800ms: ending the process, which kills r/stuck"
        ),
        "{log}"
    );
    assert!(
        !log.contains("r/fine"),
        "only the stuck module is named: {log}"
    );
}

#[test]
fn a_module_that_does_not_stop_in_time_is_killed_and_the_summary_says_so() {
    let dir = tempfile::tempdir().unwrap();
    // `hang`: a step that awaits forever, which the runtime can kill. (A step that blocks its
    // thread may strand tasks tokio queued on that worker, so only the watchdog can end it.)
    let (code, summary, log) = run_for_1s(dir.path(), "hang", "2");
    assert_eq!(code, Some(1), "{log}");
    let status = |module: &str| {
        summary
            .lines()
            .find(|l| l.split_whitespace().next() == Some(module))
            .and_then(|l| l.split_whitespace().nth(2))
            .unwrap_or_else(|| panic!("no summary line for {module}: {summary}"))
            .to_string()
    };
    assert_eq!(status("stuck"), "killed", "{summary}");
    assert_eq!(status("fine"), "stopped", "{summary}");
    assert!(log.contains("module did not stop in time: killed"), "{log}");
}

#[test]
fn sigterm_ends_the_process_when_a_step_blocks_forever() {
    let dir = tempfile::tempdir().unwrap();
    let petrel = blocked_on_one_worker(dir.path(), "300ms");
    petrel.signal("TERM");
    let (status, _, log) = petrel.finish();
    assert_eq!(status.code(), Some(1), "{log}");
    assert!(log.contains("which kills r/stuck"), "{log}");
}

#[test]
fn a_second_ctrl_c_exits_at_once_without_waiting_for_the_stop_timeout() {
    let dir = tempfile::tempdir().unwrap();
    // Far longer than the test's deadline: only the second Ctrl-C can end this run in time.
    let mut petrel = blocked_on_one_worker(dir.path(), "1h");
    petrel.signal("INT");
    petrel.wait_for("Ctrl-C again to exit at once");
    petrel.signal("INT");
    let (status, _, log) = petrel.finish();
    assert_eq!(status.code(), Some(130), "{log}");
    assert!(
        log.contains("interrupted again: exiting without waiting for the modules"),
        "{log}"
    );
}
