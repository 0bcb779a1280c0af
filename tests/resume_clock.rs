//! A run resumed from a snapshot goes on from the snapshot's clock: an action's time, a
//! context's dwell, count what ran before it. Its own test binary: resuming moves the wall
//! clock of the whole process forward (`petrel::actors::expr::continue_from`), which would
//! shift the time of tests running beside it.

use std::time::Duration;

use petrel::actors::{Agent, ConfigFile, DEFAULT_STOP_TIMEOUT};

async fn start(text: &str) -> Agent {
    let file = ConfigFile::parse("snapshot.ron", text).unwrap_or_else(|e| panic!("{e}"));
    Agent::start(&file, petrel::Petrel::new().registry())
        .await
        .unwrap_or_else(|e| panic!("{e}"))
}

/// `text` with every number after `field:` raised by `by`.
fn later(text: &str, field: &str, by: f64) -> String {
    let mut out = String::new();
    let mut rest = text;
    let needle = format!("{field}:");
    while let Some(i) = rest.find(&needle) {
        let mut start = i + needle.len();
        start += rest[start..].len() - rest[start..].trim_start().len();
        out.push_str(&rest[..start]);
        let end = rest[start..]
            .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '-'))
            .map_or(rest.len(), |e| start + e);
        let value: f64 = rest[start..end].parse().unwrap();
        out.push_str(&format!("{:?}", value + by));
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

#[tokio::test(start_paused = true)]
async fn a_wait_resumed_in_a_new_process_waits_only_what_is_left() {
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("w.plan");
    std::fs::write(&plan, "wait_6; say_done").unwrap();
    let agent = start(&format!(
        r#"Agent(name: "r1", modules: [(name: "m", type: "mission.pnp",
            values: {{"params/plan": {:?}, "params/is_mission": true}})])"#,
        plan.display().to_string()
    ))
    .await;
    tokio::time::sleep(Duration::from_secs(2)).await;
    let snapshot = agent.snapshot().await.unwrap();
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
    assert!(snapshot.contains("clock_s: "), "{snapshot}");
    // As if the first run had lasted 1000 s longer: the clock of a new process starts again
    // near 0, far below the snapshot's.
    let snapshot = later(&later(&snapshot, "clock_s", 1000.0), "started_s", 1000.0);
    let resumed = start(&snapshot).await;
    let t0 = tokio::time::Instant::now();
    let exit = tokio::time::timeout(Duration::from_secs(60), resumed.finished())
        .await
        .expect("the wait ends: it had 4 s left");
    assert_eq!(exit.code, 0, "{}", exit.reason);
    let waited = t0.elapsed();
    assert!(
        waited >= Duration::from_millis(3900) && waited <= Duration::from_millis(4200),
        "the 4 s left of wait_6, on the paused clock: {waited:?}"
    );
    resumed.stop(DEFAULT_STOP_TIMEOUT).await;
}
