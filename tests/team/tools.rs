//! Every `petrel run` is reachable from the same machine: `petrel ls|get|set|echo|hz` find an
//! agent that has no `team:` section through the run's record, with no config to point at.

use std::io::{BufRead, BufReader, Lines};
use std::path::Path;
use std::process::{Child, ChildStderr, Command, Stdio};

/// A `petrel run` whose log the test reads; killed (SIGKILL) when dropped.
struct Run {
    /// Taken when the run is waited for.
    child: Option<Child>,
    log: Lines<BufReader<ChildStderr>>,
}

impl Run {
    fn start(config: &Path, records: &Path) -> Run {
        Run::start_with(config, records, &[])
    }

    fn start_with(config: &Path, records: &Path, args: &[&str]) -> Run {
        let mut child = Command::new(env!("CARGO_BIN_EXE_petrel"))
            .arg("run")
            .arg(config)
            .args(["--for", "120s"])
            .args(args)
            .env("PETREL_RUNTIME_DIR", records)
            .env("RUST_LOG", "info")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("petrel starts");
        let log = BufReader::new(child.stderr.take().unwrap()).lines();
        Run {
            child: Some(child),
            log,
        }
    }

    /// Reads the log up to a line containing `needle` (the run ends by itself after `--for`,
    /// which bounds the wait).
    fn wait_for(&mut self, needle: &str) {
        for line in self.log.by_ref() {
            if line.expect("the log is text").contains(needle) {
                return;
            }
        }
        panic!("the log ended without `{needle}`");
    }

    /// Ctrl-C, then waits (bounded) for the run to end cleanly.
    fn interrupt(mut self) {
        let child = self.child.take().expect("a running child");
        unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
        // The log must be read to its end, or the run could block writing it.
        for _ in self.log.by_ref() {}
        let out = crate::bounded::wait_within_deadline(child, "petrel run");
        assert!(out.status.success(), "{:?}", out.status);
    }

    fn kill(&mut self) {
        if let Some(mut child) = self.child.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }

    fn pid(&self) -> u32 {
        self.child.as_ref().map_or(0, Child::id)
    }
}

impl Drop for Run {
    fn drop(&mut self) {
        self.kill();
    }
}

fn petrel(records: &Path, args: &[&str]) -> (i32, String, String) {
    let out = crate::bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(args)
            .env("PETREL_RUNTIME_DIR", records),
    );
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (
        out.status.code().unwrap_or(-1),
        text(&out.stdout),
        text(&out.stderr),
    )
}

/// Starts a run of agent `lonely` (no `team:` section) recording itself in `dir/records`.
fn lonely(dir: &Path) -> (Run, std::path::PathBuf) {
    agent_run(dir, "lonely")
}

/// Starts a run of agent `name` (no `team:` section) recording itself in `dir/records`.
fn agent_run(dir: &Path, name: &str) -> (Run, std::path::PathBuf) {
    let records = dir.join("records");
    let config = dir.join(format!("{name}.ron"));
    std::fs::write(
        &config,
        r#"Agent(name: "NAME", modules: [
            (name: "signal", type: "demo.signal", values: {"params/sample_ms": 5}),
            (name: "scale", type: "demo.scale", values: {"params/factor": 2.0},
             links: {"in/value": "signal/out/value"}),
            (name: "producer", type: "demo.producer", values: {"params/period_ms": 5, "params/batch": 3}),
        ])"#
        .replace("NAME", name),
    )
    .unwrap();
    let mut run = Run::start(&config, &records);
    run.wait_for("reachable by tools");
    (run, records)
}

#[test]
fn tools_find_a_run_without_a_team_section_and_forget_it_once_killed() {
    let dir = tempfile::tempdir().unwrap();
    let (mut run, records) = lonely(dir.path());
    let pid = run.pid().to_string();

    let (code, out, err) = petrel(&records, &["ls"]);
    assert_eq!(code, 0, "{err}");
    let row = out.lines().nth(1).unwrap_or_default();
    let cells: Vec<&str> = row.split_whitespace().collect();
    assert_eq!(cells[0], "lonely", "{out}");
    assert_eq!(cells[2], pid, "{out}");
    assert!(cells[3].starts_with("tcp/127.0.0.1:"), "{out}");

    let (code, out, err) = petrel(&records, &["ls", "lonely"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("\nscale (demo.scale)\n"), "{out}");
    assert!(
        out.lines().any(|l| l.split_whitespace().collect::<Vec<_>>()
            == ["in/value", "input", "f64", "<-", "signal/out/value"]),
        "{out}"
    );

    let url = "petrel://lonely/scale/params/factor";
    let (code, out, err) = petrel(&records, &["get", url]);
    assert_eq!((code, out.trim()), (0, "2.0 (f64)"), "{err}");
    let (code, _, err) = petrel(&records, &["set", url, "4.5"]);
    assert_eq!(code, 0, "{err}");
    let (code, out, err) = petrel(&records, &["get", url]);
    assert_eq!((code, out.trim()), (0, "4.5 (f64)"), "{err}");
    let (code, _, err) = petrel(&records, &["set", "petrel://lonely/scale/out/value", "1.0"]);
    assert_eq!(code, 1);
    assert!(err.contains("only params/ and control/"), "{err}");
    let (code, _, err) = petrel(&records, &["get", "petrel://lonley/scale/params/factor"]);
    assert_eq!(code, 1);
    assert_eq!(
        err.trim(),
        "error: no running agent `lonley`; running: `lonely` (nearest: `lonely`)"
    );

    run.kill();
    let (code, out, _) = petrel(&records, &["ls"]);
    assert_eq!(code, 0);
    assert!(out.starts_with("no `petrel run` is running"), "{out}");
    let (code, _, err) = petrel(&records, &["get", url]);
    assert_eq!(code, 1);
    assert!(err.contains("no running agent `lonely`"), "{err}");
}

#[test]
fn echo_follows_values_and_queue_items_and_hz_reports_a_rate() {
    let dir = tempfile::tempdir().unwrap();
    let (_run, records) = lonely(dir.path());

    let (code, out, err) = petrel(
        &records,
        &[
            "echo",
            "petrel://lonely/signal/out/value",
            "-n",
            "3",
            "--json",
        ],
    );
    assert_eq!(code, 0, "{err}");
    let lines: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect();
    assert_eq!(lines.len(), 3, "{out}");
    for pair in lines.windows(2) {
        assert!(pair[1]["seq"].as_u64() > pair[0]["seq"].as_u64(), "{out}");
        assert!(
            pair[1]["stamp_ns"].as_u64() >= pair[0]["stamp_ns"].as_u64(),
            "{out}"
        );
    }
    assert!(
        lines
            .iter()
            .all(|l| l["type"] == "f64" && l["value"].is_f64()),
        "{out}"
    );

    // Queue items come in order, none skipped: consecutive numbers.
    let (code, out, err) = petrel(
        &records,
        &["echo", "petrel://lonely/producer/out/items", "-n", "12"],
    );
    assert_eq!(code, 0, "{err}");
    let items: Vec<i64> = out.lines().map(|l| l.parse().expect("a number")).collect();
    assert_eq!(items.len(), 12, "{out}");
    assert!(items.windows(2).all(|w| w[1] == w[0] + 1), "{items:?}");

    let (code, out, err) = petrel(
        &records,
        &["hz", "petrel://lonely/signal/out/value", "-n", "20"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        out.starts_with("rate ") && out.contains(" Hz over 20 samples: interval mean "),
        "{out}"
    );

    // Every module once, with its stats: the producer has stepped, so its row says so.
    let (code, out, err) = petrel(&records, &["top", "--once"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("AGENT   MODULE    TYPE"), "{out}");
    let producer: Vec<&str> = out
        .lines()
        .find(|l| l.contains(" producer "))
        .unwrap_or_else(|| panic!("no producer row: {out}"))
        .split_whitespace()
        .collect();
    assert_eq!(
        producer[..4],
        ["lonely", "producer", "demo.producer", "running"],
        "{out}"
    );
    assert!(producer[4].parse::<i64>().unwrap() > 0, "{out}");
    assert_eq!(out.lines().count(), 4, "a header and 3 modules: {out}");

    let (code, _, err) = petrel(
        &records,
        &["echo", "petrel://lonely/signal/out/nope", "-n", "1"],
    );
    assert_eq!(code, 1);
    assert!(err.contains("has no property `out/nope`"), "{err}");
}

/// Two runs of one config: `top` tells their agents apart by pid; one of them stopped
/// (`kill -STOP`) shows as not answering while the other is still shown.
#[test]
fn top_labels_twin_agents_by_pid_and_shows_a_stopped_one_beside_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let (first, records) = agent_run(dir.path(), "twin");
    let (second, _) = agent_run(dir.path(), "twin");
    let label = |run: &Run| format!("twin (pid {})", run.pid());
    let (code, out, err) = petrel(&records, &["top", "--once"]);
    assert_eq!(code, 0, "{err}");
    for run in [&first, &second] {
        let rows = out.lines().filter(|l| l.starts_with(&label(run))).count();
        assert_eq!(rows, 3, "three modules of {}: {out}", label(run));
    }

    let signal = |sig: &str| {
        let status = Command::new("kill")
            .args([sig, &second.pid().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
    };
    signal("-STOP");
    let (code, out, err) = petrel(&records, &["top", "--once"]);
    signal("-CONT");
    assert_eq!(code, 0, "the other agent is still shown: {err}");
    let stopped: Vec<&str> = out
        .lines()
        .filter(|l| l.starts_with(&label(&second)))
        .collect();
    assert_eq!(stopped.len(), 1, "{out}");
    assert!(stopped[0].contains(" no answer "), "{out}");
    let running = out
        .lines()
        .filter(|l| l.starts_with(&label(&first)) && l.contains(" running "))
        .count();
    assert_eq!(running, 3, "{out}");
}

/// `set` of a value an active context holds is done, with a note that the context puts its own
/// original back when it ends (it did so in silence); a value no context holds gets none.
#[test]
fn set_of_a_value_a_context_holds_says_the_context_will_put_its_original_back() {
    let dir = tempfile::tempdir().unwrap();
    let records = dir.path().join("records");
    let rules = dir.path().join("hold.rules.ron");
    std::fs::write(
        &rules,
        r#"Contexts(contexts: [(name: "hold", when: "signal/out/value > -10", set: {"scale/params/factor": "3.0"})])"#,
    )
    .unwrap();
    let config = dir.path().join("held.ron");
    std::fs::write(
        &config,
        format!(
            r#"Agent(name: "held", modules: [
                (name: "signal", type: "demo.signal", values: {{"params/sample_ms": 5}}),
                (name: "scale", type: "demo.scale", links: {{"in/value": "signal/out/value"}}),
                (name: "contexts", type: "context.manager", values: {{"params/rules": {:?}}}),
            ])"#,
            rules.display().to_string()
        ),
    )
    .unwrap();
    let mut run = Run::start(&config, &records);
    // Both lines, in whichever order they come.
    let (mut reachable, mut active) = (false, false);
    for line in run.log.by_ref() {
        let line = line.expect("the log is text");
        reachable |= line.contains("reachable by tools");
        active |= line.contains("context activated");
        if reachable && active {
            break;
        }
    }
    assert!(reachable && active, "the log ended first");
    let (code, out, err) = petrel(&records, &["set", "held/scale/params/factor", "7.0"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(out.trim(), "petrel://held/scale/params/factor = 7.0");
    assert!(
        err.contains("note: a context of `contexts` holds `scale/params/factor`"),
        "{err}"
    );
    let (code, _, err) = petrel(&records, &["set", "held/signal/params/period_s", "3.0"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("note:"), "no context holds it: {err}");
}

/// A follower of a run that ends (here killed) says so and exits 1, rather than wait without
/// end for an agent that cannot come back; hz too while it reports every second.
#[test]
fn followers_end_with_an_error_once_the_agent_is_gone() {
    // Said as such: the run is gone (its record is a dead process's), not "did not answer ...
    // is it a member of the team?".
    let dir = tempfile::tempdir().unwrap();
    let (mut run, records) = lonely(dir.path());
    let follower = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(args)
            .env("PETREL_RUNTIME_DIR", &records)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("petrel starts")
    };
    let mut echo = follower(&[
        "echo",
        "petrel://lonely/signal/out/value",
        "-n",
        "100000000",
    ]);
    let mut events = follower(&["events", "lonely", "-n", "100000000"]);
    // hz without a count reports each second, as long as it runs.
    let mut hz = follower(&["hz", "petrel://lonely/signal/out/value"]);
    // All follow once echo printed a value, hz a rate, and events said its streams are open.
    let mut echo_out = BufReader::new(echo.stdout.take().unwrap()).lines();
    assert!(echo_out.next().is_some(), "echo printed a value");
    let mut hz_out = BufReader::new(hz.stdout.take().unwrap()).lines();
    assert!(hz_out.next().is_some(), "hz reported");
    let mut events_err = BufReader::new(events.stderr.take().unwrap()).lines();
    let opened = events_err.next().and_then(Result::ok).unwrap_or_default();
    assert!(opened.starts_with("following "), "{opened}");

    run.kill();
    // Read what is left, so neither blocks writing it; bounded by the followers' ends.
    let echo_rest = std::thread::spawn(move || echo_out.count());
    let hz_rest = std::thread::spawn(move || hz_out.count());
    let events_rest =
        std::thread::spawn(move || events_err.map_while(Result::ok).collect::<Vec<_>>());
    let echo = crate::bounded::wait_within_deadline(echo, "petrel echo");
    let events = crate::bounded::wait_within_deadline(events, "petrel events");
    let hz = crate::bounded::wait_within_deadline(hz, "petrel hz");
    echo_rest.join().unwrap();
    hz_rest.join().unwrap();
    let hz_said = String::from_utf8_lossy(&hz.stderr).into_owned();
    assert_eq!(hz.status.code(), Some(1), "{hz_said}");
    assert!(
        hz_said.contains("agent `lonely` left: its run ended"),
        "{hz_said}"
    );
    let events_said = events_rest.join().unwrap().join("\n");
    let echo_said = String::from_utf8_lossy(&echo.stderr).into_owned();
    assert_eq!(echo.status.code(), Some(1), "{echo_said}");
    assert!(
        echo_said.contains("agent `lonely` left: its run ended"),
        "{echo_said}"
    );
    assert_eq!(events.status.code(), Some(1), "{events_said}");
    assert!(
        events_said.contains("agent `lonely` left: its run ended"),
        "{events_said}"
    );
}

/// SIGTERM ends a follower as Ctrl-C does, cleanly (exit 0), as it ends `run` and `console`.
#[test]
fn sigterm_ends_a_follower_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let (_run, records) = lonely(dir.path());
    for args in [&["echo", "petrel://lonely/signal/out/value"][..], &["top"]] {
        let mut follower = Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(args)
            .env("PETREL_RUNTIME_DIR", &records)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("petrel starts");
        let mut out = BufReader::new(follower.stdout.take().unwrap()).lines();
        assert!(out.next().is_some(), "{args:?} printed");
        unsafe { libc::kill(follower.id() as libc::pid_t, libc::SIGTERM) };
        let rest = std::thread::spawn(move || out.count());
        let ended = crate::bounded::wait_within_deadline(follower, "a follower");
        rest.join().unwrap();
        assert_eq!(
            ended.status.code(),
            Some(0),
            "{args:?}: {}",
            String::from_utf8_lossy(&ended.stderr)
        );
    }
}

/// `petrel top` over two runs: when one ends it shows the other, and ends itself (exit 1,
/// saying so) only when both have.
#[test]
fn top_keeps_showing_the_runs_that_go_on() {
    let dir = tempfile::tempdir().unwrap();
    let (mut first, records) = agent_run(dir.path(), "lonely");
    let (mut second, _) = agent_run(dir.path(), "other");
    let mut top = Command::new(env!("CARGO_BIN_EXE_petrel"))
        .arg("top")
        .env("PETREL_RUNTIME_DIR", &records)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("petrel starts");
    // Each frame: the clear-screen sequence and the header, then a row per module. Read on a
    // thread so that a top that stopped printing fails the wait below instead of hanging.
    let (tx, frames) = std::sync::mpsc::channel::<Vec<String>>();
    let stdout = top.stdout.take().unwrap();
    std::thread::spawn(move || {
        let mut frame = Vec::new();
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if line.contains("AGENT") && !frame.is_empty() {
                let _ = tx.send(std::mem::take(&mut frame));
            }
            frame.push(line);
        }
        let _ = tx.send(frame);
    });
    let agents = |frame: &[String]| -> Vec<String> {
        let mut names: Vec<String> = frame[1..]
            .iter()
            .filter_map(|l| l.split_whitespace().next().map(str::to_string))
            .collect();
        names.dedup();
        names.sort();
        names.dedup();
        names
    };
    let wait_for = |want: &[&str]| {
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
        loop {
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            let frame = frames
                .recv_timeout(left)
                .unwrap_or_else(|_| panic!("no frame showing {want:?} within 30 s"));
            if agents(&frame) == want {
                return;
            }
        }
    };
    wait_for(&["lonely", "other"]);
    second.kill();
    wait_for(&["lonely"]);
    first.kill();
    let top = crate::bounded::wait_within_deadline(top, "petrel top");
    let said = String::from_utf8_lossy(&top.stderr).into_owned();
    assert_eq!(top.status.code(), Some(1), "{said}");
    assert!(
        said.contains("every agent shown left: their runs ended"),
        "{said}"
    );
}

#[test]
fn events_show_a_fault_and_the_restart_that_follows() {
    let dir = tempfile::tempdir().unwrap();
    let (_run, records) = lonely(dir.path());
    let mut events = Command::new(env!("CARGO_BIN_EXE_petrel"))
        .args(["events", "lonely", "-n", "2"])
        .env("PETREL_RUNTIME_DIR", &records)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("petrel events starts");
    // Its streams are open once it says so: nothing that happens later can be missed.
    let mut said = String::new();
    BufReader::new(events.stderr.take().unwrap())
        .read_line(&mut said)
        .unwrap();
    assert_eq!(
        said.trim(),
        "following 1 event stream: lonely/_supervisor/events"
    );
    let (code, _, err) = petrel(
        &records,
        &["set", "petrel://lonely/scale/control/fault", "\"error\""],
    );
    assert_eq!(code, 0, "{err}");
    let out = crate::bounded::wait_within_deadline(events, "petrel events");
    assert!(out.status.success());
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| {
            let json = l
                .strip_prefix("lonely/_supervisor/events  ")
                .expect("the source first");
            serde_json::from_str(json).expect("an event as JSON")
        })
        .collect();
    let kinds: Vec<(&str, &str)> = lines
        .iter()
        .map(|e| (e["module"].as_str().unwrap(), e["kind"].as_str().unwrap()))
        .collect();
    assert_eq!(kinds, [("scale", "failed"), ("scale", "restarted")]);
    assert!(
        lines[0]["reason"].as_str().unwrap().contains("error"),
        "{lines:?}"
    );
}

#[test]
fn a_trace_has_a_track_per_module_with_its_steps_and_the_failure_and_restart() {
    let dir = tempfile::tempdir().unwrap();
    let records = dir.path().join("records");
    let config = dir.path().join("traced.ron");
    std::fs::write(
        &config,
        r#"Agent(name: "traced", modules: [
            (name: "signal", type: "demo.signal", values: {"params/sample_ms": 5}),
            (name: "scale", type: "demo.scale", links: {"in/value": "signal/out/value"}),
        ])"#,
    )
    .unwrap();
    let trace = dir.path().join("run.json");
    let mut run = Run::start_with(&config, &records, &["--trace-out", trace.to_str().unwrap()]);
    run.wait_for("reachable by tools");
    let (code, _, err) = petrel(
        &records,
        &["set", "petrel://traced/scale/control/fault", "\"error\""],
    );
    assert_eq!(code, 0, "{err}");
    run.wait_for("restarting module");
    run.interrupt();

    let text = std::fs::read_to_string(&trace).unwrap();
    let events: Vec<serde_json::Value> = serde_json::from_str(&text).expect("a JSON array");
    let track = |name: &str| {
        events
            .iter()
            .find(|e| e["ph"] == "M" && e["args"]["name"] == name)
            .and_then(|e| e["tid"].as_u64())
            .unwrap_or_else(|| panic!("no track {name}"))
    };
    let (signal, scale) = (track("traced/signal"), track("traced/scale"));
    let on = |tid: u64, ph: &str| -> Vec<&serde_json::Value> {
        events
            .iter()
            .filter(|e| e["tid"] == tid && e["ph"] == ph)
            .collect()
    };
    for tid in [signal, scale] {
        let steps = on(tid, "X");
        assert!(!steps.is_empty(), "no steps on track {tid}");
        assert!(steps
            .iter()
            .all(|s| s["name"] == "step" && s["dur"].as_f64().unwrap() >= 0.0));
    }
    let instants: Vec<&str> = on(scale, "i")
        .iter()
        .filter_map(|e| e["name"].as_str())
        .collect();
    let failed = instants.iter().position(|n| *n == "module failed");
    let restarted = instants.iter().position(|n| *n == "restarting module");
    assert!(
        matches!((failed, restarted), (Some(f), Some(r)) if f < r),
        "{instants:?}"
    );
}
