//! `petrel run --console` as a user runs it: the address it prints, the token rules at the
//! command line.

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::sync::mpsc;

use crate::support::*;

#[path = "../common/bounded.rs"]
pub(crate) mod bounded;

fn petrel() -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_petrel"));
    cmd.env("RUST_LOG", "info");
    cmd
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn run_prints_the_console_address_and_serves_the_agents_and_its_log() {
    let mut child = petrel()
        .args(["run", "configs/pipeline.ron", "--for", "60s", "--no-remote"])
        .args(["--console", "127.0.0.1:0"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let (lines, url) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if let Some(url) = line.strip_prefix("console: ") {
                let _ = lines.send(url.to_string());
            }
        }
    });
    let url = match url.recv_timeout(DEADLINE) {
        Ok(url) => url,
        Err(_) => {
            let _ = child.kill();
            panic!("no `console: URL` line in time");
        }
    };
    let addr = url
        .strip_prefix("http://")
        .and_then(|u| u.strip_suffix('/'))
        .and_then(|a| a.parse().ok())
        .unwrap_or_else(|| panic!("a loopback URL without a token: {url}"));
    let agents = get(addr, "/api/agents").await.json();
    assert_eq!(agents["agents"][0]["name"], "robot1");
    assert_eq!(agents["agents"][0]["modules"].as_array().unwrap().len(), 5);
    let logs = get(addr, "/api/logs").await.json();
    assert!(
        logs["lines"]
            .as_array()
            .unwrap()
            .iter()
            .any(|l| l["message"]
                .as_str()
                .unwrap_or_default()
                .contains("console listening")),
        "{logs}"
    );
    // Ctrl-C: the run stops cleanly, the console with it.
    unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
    let out = bounded::wait_within_deadline(child, "petrel run --console");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn a_short_token_or_a_taken_address_is_refused_before_anything_is_served() {
    let out = bounded::output_within_deadline(petrel().args([
        "run",
        "configs/pipeline.ron",
        "--for",
        "5s",
        "--no-remote",
        "--console",
        "127.0.0.1:0",
        "--console-token",
        "short",
    ]));
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(
            "--console 127.0.0.1:0: the console token is 5 characters long; give at least 16"
        ),
        "{err}"
    );

    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    let out = bounded::output_within_deadline(petrel().args([
        "run",
        "configs/pipeline.ron",
        "--for",
        "5s",
        "--no-remote",
        "--console",
        &addr,
    ]));
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!("--console {addr}: cannot listen there")),
        "{err}"
    );
}

#[test]
fn the_token_needs_a_console() {
    let out = bounded::output_within_deadline(petrel().args([
        "run",
        "configs/pipeline.ron",
        "--console-token",
        "0123456789abcdef",
    ]));
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--console"));
}
