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
    /// Reads lines until each of `needles` was in one, in any order, within the deadline.
    pub(crate) fn wait_for_all(&self, needles: &[&str]) {
        let deadline = std::time::Instant::now() + DEADLINE;
        let mut missing: Vec<&str> = needles.to_vec();
        while !missing.is_empty() {
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) => missing.retain(|n| !line.contains(n)),
                Err(_) => panic!("no lines with {missing:?} in time"),
            }
        }
    }

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

/// An agent of team `team` listening on `port` (and connecting to `peer`), with a sine wave.
fn team_agent(dir: &Path, name: &str, team: &str, port: u16, peer: Option<u16>) -> String {
    let connect = peer.map_or(String::new(), |p| {
        format!("connect: [\"tcp/127.0.0.1:{p}\"],")
    });
    let text = format!(
        r#"Agent(name: "{name}", team: (name: "{team}", listen: ["tcp/127.0.0.1:{port}"], {connect} lease_ms: 1000),
            modules: [(name: "signal", type: "demo.signal", values: {{"params/sample_ms": 50}})])"#
    );
    let path = dir.join(format!("{name}.ron"));
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_string()
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .unwrap()
        .port()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn with_via_the_console_shows_a_teams_members_as_they_join_and_leave() {
    let dir = tempfile::tempdir().unwrap();
    let records = tempfile::tempdir().unwrap();
    let team = format!("console-via-{}", std::process::id());
    let (a, b) = (free_port(), free_port());
    let first = team_agent(dir.path(), "scout", &team, a, None);
    let second = team_agent(dir.path(), "relay", &team, b, Some(a));
    let mut run = Proc::start(&["run", &first, &second, "--for", "120s"], records.path());
    run.wait_for("reachable by tools");
    let console = Proc::start(
        &["console", "--via", &first, "--listen", "127.0.0.1:0"],
        records.path(),
    );
    let url = console.wait_for("console: http://");
    let addr: SocketAddr = url
        .trim_start_matches("console: http://")
        .trim_end_matches('/')
        .parse()
        .unwrap();
    console.wait_for_all(&[
        "console: showing agent `scout`",
        "console: showing agent `relay`",
    ]);
    let agents = get(addr, "/api/agents").await.json();
    let mut live: Vec<&str> = agents["agents"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|a| a["state"] == "live")
        .map(|a| a["name"].as_str().unwrap())
        .collect();
    live.sort();
    assert_eq!(live, ["relay", "scout"], "{agents}");
    let value = get(addr, "/api/agents/relay/value?key=signal/params/sample_ms")
        .await
        .json();
    assert_eq!(value["json"], 50, "{value}");

    // Their process is killed: the team's tokens go, and the console shows both left.
    run.child().kill().unwrap();
    run.child().wait().unwrap();
    console.wait_for_all(&["console: agent `scout` left", "console: agent `relay` left"]);
    let agents = get(addr, "/api/agents").await.json();
    assert!(
        agents["agents"]
            .as_array()
            .unwrap()
            .iter()
            .all(|a| a["state"] == "left"),
        "{agents}"
    );
}
