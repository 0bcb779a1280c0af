//! Every `petrel run` is reachable from the same machine: `petrel ls|get|set` find an agent
//! that has no `team:` section through the run's record, with no config to point at.

use std::io::{BufRead, BufReader, Lines};
use std::path::Path;
use std::process::{Child, ChildStderr, Command, Stdio};

/// A `petrel run` whose log the test reads; killed (SIGKILL) when dropped.
struct Run {
    child: Child,
    log: Lines<BufReader<ChildStderr>>,
}

impl Run {
    fn start(config: &Path, records: &Path) -> Run {
        let mut child = Command::new(env!("CARGO_BIN_EXE_petrel"))
            .arg("run")
            .arg(config)
            .args(["--for", "120s"])
            .env("PETREL_RUNTIME_DIR", records)
            .env("RUST_LOG", "info")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("petrel starts");
        let log = BufReader::new(child.stderr.take().unwrap()).lines();
        Run { child, log }
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

    fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
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

#[test]
fn tools_find_a_run_without_a_team_section_and_forget_it_once_killed() {
    let dir = tempfile::tempdir().unwrap();
    let records = dir.path().join("records");
    let config = dir.path().join("lonely.ron");
    std::fs::write(
        &config,
        r#"Agent(name: "lonely", modules: [
            (name: "signal", type: "demo.signal"),
            (name: "scale", type: "demo.scale", values: {"params/factor": 2.0},
             links: {"in/value": "signal/out/value"}),
        ])"#,
    )
    .unwrap();
    let mut run = Run::start(&config, &records);
    run.wait_for("reachable by tools");
    let pid = run.child.id().to_string();

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
