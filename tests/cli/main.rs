//! The `petrel` binary as a user runs it: `check` (check.rs), `run` (run.rs), and the other
//! tools — `modules`, `plan`, `graph`, bad arguments, a closed pipe (tools.rs).

#[path = "../common/bounded.rs"]
mod bounded;
mod check;
mod run;
#[path = "../common/running.rs"]
mod running;
mod tools;

/// Writes config `text` as `name` in a fresh temporary directory (alive as long as the returned
/// guard) and returns its path.
fn temp_config(name: &str, text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    (dir, path)
}
