//! `petrel get` and `petrel set` as real processes against agents of a running team.

use std::process::Command;

use crate::support::*;

fn petrel(args: &[&str]) -> (i32, String, String) {
    let out = crate::bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel")).args(args),
    );
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (
        out.status.code().unwrap_or(-1),
        text(&out.stdout),
        text(&out.stderr),
    )
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn get_and_set_reach_a_running_agent_and_refusals_exit_1() {
    let dir = tempfile::tempdir().unwrap();
    let team = team_name("cli");
    let port = free_port();
    let config = agent_config(
        "filter",
        &team,
        port,
        &[],
        r#"remote_write: ["scale/params/*"]"#,
        r#"
        (name: "scale", type: "demo.scale", values: {"params/factor": 2.0}),"#,
    );
    let via = dir.path().join("filter.ron");
    std::fs::write(&via, &config).unwrap();
    let filter = start(&config).await;
    let via = via.to_str().unwrap();

    let (code, out, err) = petrel(&[
        "set",
        "petrel://filter/scale/params/factor",
        "3.5",
        "--via",
        via,
    ]);
    assert_eq!(code, 0, "{out}{err}");
    assert_eq!(
        filter.handle::<f64>("scale/params/factor").await.value(),
        3.5
    );

    let (code, out, err) = petrel(&["get", "petrel://filter/scale/params/factor", "--via", via]);
    assert_eq!((code, out.trim()), (0, "3.5 (f64)"), "{err}");

    let (code, _, err) = petrel(&[
        "set",
        "petrel://filter/scale/out/value",
        "1.0",
        "--via",
        via,
    ]);
    assert_eq!(code, 1);
    assert!(
        err.starts_with("error: ") && err.contains("only params/ and control/"),
        "{err}"
    );
    let (code, _, err) = petrel(&[
        "set",
        "petrel://filter/scale/params/factor",
        "(x: 1)",
        "--via",
        via,
    ]);
    assert_eq!(code, 1);
    assert!(err.contains("scale/params/factor"), "{err}");
    let (code, _, err) = petrel(&["set", "scale/params/factor", "1.0", "--via", via]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(
        filter.handle::<f64>("scale/params/factor").await.value(),
        3.5
    );
    filter.stop().await;
}

/// A member started before the peer it connects to (the team demos start in any order) runs
/// without zenoh's warning about its start conditions: the peer is expected to come later.
#[test]
fn a_member_started_before_its_peer_logs_no_zenoh_start_warning() {
    let dir = tempfile::tempdir().unwrap();
    let team = team_name("early");
    // Nothing listens on `absent`: the peer this member connects to has not started.
    let (port, absent) = (free_port(), free_port());
    let config = agent_config(
        "early",
        &team,
        port,
        &[absent],
        "",
        r#"
        (name: "scale", type: "demo.scale"),"#,
    );
    let path = dir.path().join("early.ron");
    std::fs::write(&path, &config).unwrap();
    let runtime = dir.path().join("runtime");
    std::fs::create_dir(&runtime).unwrap();
    let out = crate::bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(["run", path.to_str().unwrap(), "--for", "1s"])
            .env("PETREL_RUNTIME_DIR", &runtime)
            .env_remove("RUST_LOG"),
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(err.contains("joined the team"), "{err}");
    assert!(!err.contains("Scouting delay"), "{err}");
}
