//! `petrel console` attached over the team to a `petrel run` in another process: the same API
//! and WebSocket, fed by the team client; edits through the remote `set` path; a SIGKILLed run
//! shown gone. Every wait reads a line or an answer within a deadline; both processes are
//! killed when the test ends, passed or not.

use std::io::{BufRead, BufReader, Read};
use std::net::SocketAddr;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{self, Receiver};

use serde_json::json;

use crate::support::*;

/// A child process whose output lines (stdout and stderr) the test reads; killed when dropped.
pub(crate) struct Proc {
    /// Taken when the test waits for it to end.
    child: Option<Child>,
    lines: Receiver<String>,
}

impl Proc {
    pub(crate) fn start(args: &[&str], records: &Path) -> Proc {
        let mut child = Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(args)
            .env("PETREL_RUNTIME_DIR", records)
            .env("RUST_LOG", "info")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("petrel starts");
        let (tx, lines) = mpsc::channel();
        let pipes: [Box<dyn Read + Send>; 2] = [
            Box::new(child.stdout.take().unwrap()),
            Box::new(child.stderr.take().unwrap()),
        ];
        for pipe in pipes {
            let tx = tx.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(pipe).lines().map_while(Result::ok) {
                    let _ = tx.send(line);
                }
            });
        }
        Proc {
            child: Some(child),
            lines,
        }
    }

    /// The first line (from now) containing `needle`, within the deadline.
    pub(crate) fn wait_for(&self, needle: &str) -> String {
        let deadline = std::time::Instant::now() + DEADLINE;
        loop {
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) if line.contains(needle) => return line,
                Ok(_) => continue,
                Err(_) => panic!("no line with `{needle}` in time"),
            }
        }
    }
}

impl Proc {
    pub(crate) fn child(&mut self) -> &mut Child {
        self.child.as_mut().expect("a running child")
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        if let Some(mut child) = self.child.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

async fn set(addr: SocketAddr, key: &str, value: &str) -> Answer {
    let body = json!({"key": key, "value": value}).to_string();
    http(addr, "POST", "/api/agents/robot1/set", &[], Some(&body)).await
}

/// `configs/pipeline.ron` run as robot1, and `petrel console` showing it (both using the
/// discovery records in `records`), with the console's address.
pub(crate) fn run_and_attach(records: &Path) -> (Proc, Proc, SocketAddr) {
    let run = Proc::start(&["run", "configs/pipeline.ron", "--for", "120s"], records);
    // The run's record is written (tools can find it) when it says so.
    run.wait_for("reachable by tools");
    let console = Proc::start(&["console", "--listen", "127.0.0.1:0"], records);
    let url = console.wait_for("console: http://");
    let addr: SocketAddr = url
        .trim_start_matches("console: http://")
        .trim_end_matches('/')
        .parse()
        .unwrap_or_else(|_| panic!("a loopback address: {url}"));
    console.wait_for("console: showing agent `robot1`");
    (run, console, addr)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_console_attaches_to_a_running_agent_over_its_team() {
    let records = tempfile::tempdir().unwrap();
    let (mut run, console, addr) = run_and_attach(records.path());

    // The remote agent's modules, with their step figures read over the team.
    let agents = get(addr, "/api/agents").await.json();
    let robot = &agents["agents"][0];
    assert_eq!(
        (&robot["name"], &robot["state"]),
        (&json!("robot1"), &json!("live"))
    );
    let modules: Vec<&str> = robot["modules"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        modules,
        ["sensor", "filter", "printer", "producer", "consumer"]
    );
    let props = get(addr, "/api/agents/robot1/properties").await.json();
    assert!(
        props["properties"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p["key"] == "filter/params/factor" && p["writable"] == true),
        "{props}"
    );

    // A changing value arrives over the WebSocket: the current one, then a newer version.
    let mut socket = websocket(addr, "/api/ws?agent=robot1", &[]).await.unwrap();
    send(&mut socket, json!({"watch": ["sensor/out/value"]})).await;
    let first = next(&mut socket).await;
    let first = &first["values"][0];
    assert_eq!(first["key"], "sensor/out/value", "{first}");
    let later = next(&mut socket).await;
    let later = &later["values"][0];
    assert!(
        later["version"].as_u64() > first["version"].as_u64(),
        "{first} then {later}"
    );

    // A parameter set through the console is read back from the agent itself (`petrel get`).
    let answer = set(addr, "filter/params/factor", "3.5").await;
    assert_eq!(answer.status, 200, "{}", answer.body);
    assert_eq!(answer.json()["text"], "3.5", "the answer is the value set");
    let got = crate::cli::bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(["get", "petrel://robot1/filter/params/factor"])
            .env("PETREL_RUNTIME_DIR", records.path()),
    );
    assert_eq!(String::from_utf8_lossy(&got.stdout).trim(), "3.5 (f64)");

    // Refused: an output (the console's rule), and a bad value (the owner's check, its words
    // passed on for the field).
    let forbidden = set(addr, "filter/out/value", "1.0").await;
    assert_eq!(forbidden.status, 403, "{}", forbidden.body);
    assert!(
        forbidden.body.contains("only params/ and control/"),
        "{}",
        forbidden.body
    );
    let bad = set(addr, "filter/params/factor", "\"x\"").await;
    assert_eq!(bad.status, 400, "{}", bad.body);
    assert!(bad.body.contains("expected f64"), "{}", bad.body);

    // SIGKILL: no goodbye; the console sees the run gone and shows the agent left.
    run.child().kill().unwrap();
    run.child().wait().unwrap();
    console.wait_for("console: agent `robot1` left");
    let agents = get(addr, "/api/agents").await.json();
    assert_eq!(agents["agents"][0]["state"], "left", "{agents}");
    assert_eq!(get(addr, "/api/agents/robot1/properties").await.status, 404);

    // SIGTERM ends the console cleanly (exit 0).
    let mut console = console;
    let child = console.child.take().unwrap();
    unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) };
    let out = crate::cli::bounded::wait_within_deadline(child, "petrel console");
    assert!(out.status.success(), "{:?}", out.status);
}
