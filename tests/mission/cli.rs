//! The shipped mission demo, run by the real binary from the repository root.

use std::process::Command;

#[test]
fn the_mission_demo_ends_by_itself_at_the_goal_with_exit_0() {
    let out = Command::new(env!("CARGO_BIN_EXE_petrel"))
        .args(["run", "configs/mission-demo.ron"])
        .env("RUST_LOG", "warn")
        .output()
        .expect("petrel runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{:?}\n{stdout}\n{stderr}",
        out.status
    );
    assert!(stdout.contains("mission `demo` ended: goal"), "{stdout}");
    assert!(
        stdout.contains("agent robot1: 7 modules, 0 failures"),
        "{stdout}"
    );
    let row = stdout
        .lines()
        .find(|l| l.contains("mission.pnp"))
        .unwrap_or("");
    assert!(row.contains("stopped"), "{stdout}");
    assert!(
        !stderr.contains("WARN") && !stderr.contains("ERROR"),
        "{stderr}"
    );
}

#[test]
fn check_accepts_the_mission_demo() {
    let out = Command::new(env!("CARGO_BIN_EXE_petrel"))
        .args(["check", "configs/mission-demo.ron"])
        .output()
        .expect("petrel runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
