//! Every documented exit code of every subcommand (the table in docs/missions.md#exit-codes),
//! run as real processes. Ctrl-C twice (130) is in tests/stop.rs, a closed standard output (141)
//! in tests/cli.rs.

#[path = "common/bounded.rs"]
mod bounded;

use std::process::Command;

/// The files every case may use, written into one temporary directory.
const FILES: &[(&str, &str)] = &[
    ("goal.plan", "log_hello"),
    // `go` never holds here (nothing sets it), so the plan fails; it has a goal, as a mission must.
    (
        "fail.plan",
        "< go ? log_hello : (not go) ? log_hello; fail_plan >",
    ),
    ("slow.plan", "wait_60"),
    ("bad.plan", "a; ;; b("),
    (
        "nogoal.pnml",
        r#"<?xml version="1.0"?><pnml><net id="n"><place id="p"/></net></pnml>"#,
    ),
    (
        "goal.ron",
        r#"Agent(name: "r1", modules: [(name: "m", type: "mission.pnp", values: {"params/plan": "goal.plan", "params/is_mission": true})])"#,
    ),
    (
        "fail.ron",
        r#"Agent(name: "r1", modules: [(name: "m", type: "mission.pnp", values: {"params/plan": "fail.plan", "params/is_mission": true})])"#,
    ),
    (
        "slow.ron",
        r#"Agent(name: "r1", modules: [(name: "m", type: "mission.pnp", values: {"params/plan": "slow.plan", "params/is_mission": true})])"#,
    ),
    (
        "idle.ron",
        r#"Agent(name: "r1", modules: [(name: "c", type: "demo.counter")])"#,
    ),
    (
        "failed.ron",
        r#"Agent(name: "r1", modules: [(name: "c", type: "demo.counter", restart: temporary, values: {"control/fault": "error"})])"#,
    ),
    (
        "killed.ron",
        r#"Agent(name: "r1", modules: [(name: "c", type: "demo.counter", values: {"control/fault": "hang"})])"#,
    ),
    (
        "giveup.ron",
        r#"Agent(name: "r1", supervision: (max_restarts: 2, within_s: 10.0, backoff: (min_ms: 5, max_ms: 5, jitter: 0.0)),
            modules: [(name: "c", type: "demo.counter", values: {"params/period_ms": 5}),
                      (name: "chaos", type: "demo.chaos", values: {"params/targets": "c", "params/faults": "error", "params/mean_interval_ms": 20, "params/seed": 7})])"#,
    ),
    (
        "dies.ron",
        r#"Agent(name: "r1", modules: [(name: "c", type: "demo.counter", values: {"params/period_ms": 10}),
                                      (name: "fault", type: "sim.fault", values: {"params/die_at_s": 3.0}, links: {"in/clock": "c/out/value"})])"#,
    ),
    (
        "badtype.ron",
        r#"Agent(name: "r1", modules: [(name: "c", type: "demo.nope")])"#,
    ),
    (
        "badvalue.ron",
        r#"Agent(name: "r1", modules: [(name: "c", type: "demo.counter", values: {"params/period_ms": "soon"})])"#,
    ),
    ("not.mcap", "not an MCAP file"),
];

/// (arguments, expected exit code, what the code means). Runs end by themselves or by `--for`.
const CASES: &[(&[&str], i32, &str)] = &[
    (
        &["run", "idle.ron", "--for", "200ms", "--no-remote"],
        0,
        "--for with no mission",
    ),
    (
        &["run", "goal.ron", "--no-remote"],
        0,
        "the mission reached its goal",
    ),
    (&["run", "fail.ron", "--no-remote"], 1, "the mission failed"),
    (
        &["run", "failed.ron", "--for", "300ms", "--no-remote"],
        1,
        "a module failed",
    ),
    (
        &[
            "run",
            "killed.ron",
            "--for",
            "200ms",
            "--stop-timeout",
            "100ms",
            "--no-remote",
        ],
        1,
        "a module was killed at the stop",
    ),
    (&["run", "badtype.ron", "--no-remote"], 2, "bad config"),
    (&["run", "badvalue.ron", "--no-remote"], 2, "bad value"),
    (&["run", "missing.ron"], 2, "missing config"),
    (&["run", "idle.ron", "--for", "soon"], 2, "bad argument"),
    (
        &["run", "giveup.ron", "--for", "20s", "--no-remote"],
        3,
        "the supervisor gave up",
    ),
    (
        &["run", "slow.ron", "--for", "300ms", "--no-remote"],
        4,
        "--for ended with the mission running",
    ),
    (
        &["run", "dies.ron", "--for", "20s", "--no-remote"],
        137,
        "the process's only agent died (sim.fault), as under kill -9",
    ),
    (&["check", "goal.ron"], 0, "no errors"),
    (&["check", "badtype.ron"], 2, "errors"),
    (&["graph", "goal.ron"], 0, "drawn"),
    (&["graph", "badvalue.ron"], 2, "bad config"),
    (&["modules"], 0, "listed"),
    (&["modules", "describe", "demo.counter"], 0, "described"),
    (&["modules", "describe", "demo.nope"], 2, "unknown type"),
    (&["plan", "check", "goal.plan"], 0, "no errors"),
    (&["plan", "check", "nogoal.pnml"], 1, "errors found"),
    (&["plan", "check", "bad.plan"], 2, "bad input"),
    (&["plan", "dot", "goal.plan"], 0, "drawn"),
    (&["plan", "dot", "bad.plan"], 2, "bad input"),
    (
        &["plan", "compile", "goal.plan", "-o", "goal.pnml"],
        0,
        "compiled",
    ),
    (
        &["plan", "compile", "goal.plan", "-o", "goal.plan"],
        2,
        "would overwrite its input",
    ),
    (
        &["plan", "check", "goal.plan", "--max-states", "0"],
        2,
        "no marking explored",
    ),
    (&["plan", "simulate", "goal.plan"], 0, "goal"),
    (&["plan", "simulate", "fail.plan"], 1, "fail"),
    (&["plan", "simulate", "bad.plan"], 2, "bad input"),
    (
        &["plan", "simulate", "slow.plan", "--steps", "2"],
        4,
        "steps ran out",
    ),
    (&["record", "info", "not.mcap"], 2, "not a recording"),
    (&["record", "info", "missing.mcap"], 2, "missing recording"),
    (
        &["replay", "not.mcap", "goal.ron", "--replace", "m"],
        2,
        "not a recording",
    ),
    (&["ls"], 0, "nothing running is an empty listing"),
    (&["top", "--once"], 0, "nothing running is an empty table"),
    (&["ls", "--pid", "999999"], 1, "no run has that pid"),
    (
        &["top", "--once", "--pid", "999999"],
        1,
        "no run has that pid",
    ),
    (&["get", "petrel://nobody/c/out/value"], 1, "no such agent"),
    (
        &["set", "petrel://nobody/c/params/x", "1"],
        1,
        "no such agent",
    ),
    (
        &["set", "petrel://nobody/c/params/x", "big"],
        2,
        "a bare word is no value, whatever the property",
    ),
    (
        &["set", "petrel://nobody/c/params/x", "(1.0"],
        2,
        "unclosed: no value",
    ),
    (&["echo", "petrel://nobody/c/out/value"], 1, "no such agent"),
    (
        &["hz", "petrel://nobody/c/out/value", "-n", "1"],
        2,
        "a rate needs two changes",
    ),
    (
        &["hz", "petrel://nobody/c/out/value", "--window", "0"],
        2,
        "a window of no interval",
    ),
    (&["events"], 1, "nothing to follow"),
    (
        &["console", "--listen", "0.0.0.0:0", "--token", "short"],
        2,
        "a token too short",
    ),
    (
        &["console", "--listen", "127.0.0.1:0", "--pid", "999999"],
        1,
        "no run has that pid: nothing to wait for",
    ),
    (
        &["console", "--listen", "127.0.0.1:0", "--team", ""],
        2,
        "an empty team name",
    ),
    (&["get", "no-address"], 2, "bad address"),
    (&["no-such-command"], 2, "bad command"),
];

/// A temporary directory holding [`FILES`].
fn with_files() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in FILES {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    dir
}

/// Asserts that each `petrel args` run in `dir` exits 2 saying `expected`; lists every one that
/// does not.
fn assert_refused<'a>(
    dir: &std::path::Path,
    cases: impl Iterator<Item = (&'a [&'a str], &'a str)>,
) {
    let mut wrong = Vec::new();
    for (args, expected) in cases {
        let out = petrel_in(dir, args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        if out.status.code() != Some(2) || !stderr.contains(expected) {
            wrong.push(format!(
                "petrel {}: {:?}\n{stderr}",
                args.join(" "),
                out.status.code()
            ));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n\n"));
}

/// Runs `petrel args` in `dir`, where tools find no run: the directory is the test's own.
fn petrel_in(dir: &std::path::Path, args: &[&str]) -> std::process::Output {
    bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(args)
            .current_dir(dir)
            .env("PETREL_RUNTIME_DIR", dir)
            .env("RUST_LOG", "warn"),
    )
}

#[test]
fn every_subcommand_exits_with_its_documented_code() {
    let dir = with_files();
    let mut wrong = Vec::new();
    for (args, expected, meaning) in CASES {
        let out = petrel_in(dir.path(), args);
        if out.status.code() != Some(*expected) {
            wrong.push(format!(
                "petrel {}: expected {expected} ({meaning}), got {:?}\n{}",
                args.join(" "),
                out.status.code(),
                String::from_utf8_lossy(&out.stderr)
            ));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n\n"));
}

/// `petrel replay` refuses, before anything runs, what would run live instead of replayed or
/// replay at a rate nobody asked for.
#[test]
fn replay_refuses_modules_the_config_lacks_and_a_rate_of_zero() {
    let dir = with_files();
    let cases: &[(&[&str], &str)] = &[
        (
            &["--replace", "ghost"],
            "goal.ron has no module `ghost`; expected one of its modules: m",
        ),
        (&["--replace", "m,ghost"], "--replace ghost: "),
        (&["--replace", "replay"], "has no module `replay`"),
        (
            &["--replace", "m,m"],
            "--replace names `m` twice; expected each module to replace once",
        ),
        (
            &["--replace", "m", "--rate", "0"],
            "expected a factor in [0.001, 1000] or `max`, got `0`",
        ),
    ];
    for (args, says) in cases {
        let replay = [&["replay", "not.mcap", "goal.ron"], *args].concat();
        let out = petrel_in(dir.path(), &replay);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
}

/// A recording that cannot be written where it is asked to go is refused before anything runs,
/// by `check` (a config's `record.file`) and by `run` (`--record` too), and never overwrites an
/// input of the run.
#[test]
fn a_recording_is_refused_where_it_cannot_go() {
    let dir = with_files();
    let idle = r#"Agent(name: "r1", modules: [(name: "c", type: "demo.counter")])"#;
    let with_file = |file: &str| {
        format!(
            r#"Agent(name: "r1", record: (file: "{file}"), modules: [(name: "c", type: "demo.counter")])"#
        )
    };
    std::fs::write(dir.path().join("to_null.ron"), with_file("/dev/null")).unwrap();
    std::fs::write(dir.path().join("to_itself.ron"), with_file("to_itself.ron")).unwrap();
    std::fs::write(dir.path().join("to_nothing.ron"), with_file("")).unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["check", "to_null.ron"], "/dev/null is not a regular file"),
        (
            &["run", "to_null.ron", "--for", "1s"],
            "/dev/null is not a regular file",
        ),
        (
            &["run", "idle.ron", "--for", "1s", "--record", "/dev/null"],
            "/dev/null is not a regular file",
        ),
        (
            &["run", "idle.ron", "--for", "1s", "--record", "."],
            "is a directory",
        ),
        (
            &["run", "idle.ron", "--for", "1s", "--record", "idle.ron"],
            "a file this run reads or writes",
        ),
        (
            &["check", "to_itself.ron"],
            "a file this run reads or writes",
        ),
        (
            &["run", "to_itself.ron", "--for", "1s"],
            "a file this run reads or writes",
        ),
        (&["check", "to_nothing.ron"], "an empty file name"),
        (
            &[
                "run",
                "idle.ron",
                "--for",
                "1s",
                "--record",
                "idle.ron/x.mcap",
            ],
            "is not a directory",
        ),
    ];
    assert_refused(dir.path(), cases.iter().map(|(a, e)| (&a[..], *e)));
    assert_eq!(
        std::fs::read_to_string(dir.path().join("idle.ron")).unwrap(),
        idle
    );
    assert!(std::fs::read_to_string(dir.path().join("to_itself.ron"))
        .unwrap()
        .starts_with("Agent("));
}

/// What `run` and `plan compile` write (a trace, a snapshot, a recording, PNML) is refused
/// before anything is written where it would replace a file the run uses (a config, or a plan
/// it names), a FIFO or device, or another of its outputs; the files stay as they were.
#[test]
fn no_output_replaces_an_input_a_fifo_or_another_output() {
    let dir = with_files();
    let fifo = dir.path().join("fifo");
    let c = std::ffi::CString::new(fifo.as_os_str().as_encoded_bytes()).unwrap();
    // SAFETY: a NUL-terminated path, a plain mode.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let run = |extra: &[&'static str]| {
        let mut args = vec!["run", "goal.ron", "--no-remote"];
        args.extend_from_slice(extra);
        args
    };
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            run(&["--trace-out", "goal.ron"]),
            "--trace-out: goal.ron is a file this run reads or writes",
        ),
        (
            run(&["--trace-out", "goal.plan"]),
            "goal.plan) is a file this run reads or writes",
        ),
        (
            run(&["--snapshot-out", "./goal.plan"]),
            "goal.plan) is a file this run reads or writes",
        ),
        (
            run(&["--record", "goal.plan"]),
            "goal.plan) is a file this run reads or writes",
        ),
        (
            run(&["--snapshot-out", "fifo"]),
            "fifo is not a regular file",
        ),
        (
            run(&["--record", "out.mcap", "--trace-out", "./out.mcap"]),
            "--trace-out and --record both name ./out.mcap",
        ),
        (
            run(&["--snapshot-out", "out.ron", "--trace-out", "out.ron"]),
            "--trace-out and --snapshot-out both name out.ron",
        ),
        (
            vec!["plan", "compile", "goal.plan", "-o", "fifo"],
            "-o: fifo is not a regular file",
        ),
    ];
    assert_refused(dir.path(), cases.iter().map(|(a, e)| (&a[..], *e)));
    for (name, text) in FILES.iter().filter(|(n, _)| n.starts_with("goal.")) {
        assert_eq!(
            std::fs::read_to_string(dir.path().join(name)).unwrap(),
            *text,
            "{name} is untouched"
        );
    }
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    for made in ["out.mcap", "out.ron"] {
        assert!(!dir.path().join(made).exists(), "{made} was not written");
    }
}
