//! Replay equivalence: the mapper fed by a replay of the simulator's recorded outputs builds
//! the very map it built live (deterministic simulation, paused clock).

use std::path::Path;
use std::time::Duration;

use petrel::actors::{Agent, ConfigFile, OccupancyGrid, DEFAULT_STOP_TIMEOUT};
use petrel::record::{Format, RecordOptions, Recorder, Selection};

/// Virtual time after which a test gives up waiting.
const GUARD: Duration = Duration::from_secs(600);

fn navigate(overlay: &str) -> ConfigFile {
    let mut file = ConfigFile::load(Path::new("configs/navigate.ron")).unwrap();
    let overlay = ConfigFile::parse(
        "overlay.ron",
        &format!(r#"Agent(name: "robot1", modules: [(name: "recorder", type: "sim.recorder", values: {{"params/png": ""}}), {overlay}])"#),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    file.overlay(overlay);
    file
}

fn registry() -> petrel::actors::ModuleRegistry {
    petrel::Petrel::new().registry().clone()
}

async fn map_of(agent: &Agent) -> OccupancyGrid {
    (*agent
        .blackboard()
        .get::<OccupancyGrid>("mapper/out/map")
        .await
        .unwrap())
    .clone()
}

/// Runs the live mission for `run` of virtual time, recording the simulator, then stops the
/// simulator and lets the pipeline settle; returns the map.
async fn live(path: &Path, format: Format, run: Duration) -> OccupancyGrid {
    // The simulator starts disabled so the recorder is attached before its first step.
    let file = navigate(r#"(name: "robot", type: "sim.world", values: {"enabled": false})"#);
    let agent = Agent::start(&file, &registry()).await.unwrap();
    let mut options = RecordOptions::everything(path, format);
    options.selection = Selection::new(&["robot/**".into(), "mapper/out/map".into()], &[]).unwrap();
    // Nothing may be dropped here: the paused clock runs the simulation faster than the
    // debug-build writer encodes.
    options.backlog = 1 << 22;
    let mut recorder = Recorder::start(options).unwrap();
    recorder.attach("robot1", agent.blackboard()).await.unwrap();
    agent.blackboard().set("robot/enabled", true).await.unwrap();
    tokio::time::sleep(run).await;
    agent
        .blackboard()
        .set("robot/enabled", false)
        .await
        .unwrap();
    tokio::time::sleep(Duration::from_millis(200)).await;
    let map = map_of(&agent).await;
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
    let report = recorder.finish().await.unwrap();
    assert_eq!(report.dropped, 0);
    assert!(report.written > 1000, "{report:?}");
    map
}

async fn replayed(path: &Path) -> OccupancyGrid {
    let overlay = format!(
        r#"(name: "robot", type: "sim.world", values: {{"enabled": false}}),
           (name: "replay", type: "record.replay",
            values: {{"params/file": {:?}, "params/modules": "robot"}})"#,
        path.display().to_string()
    );
    let file = navigate(&overlay);
    let agent = Agent::start_without(&file, &registry(), &["robot".to_string()])
        .await
        .unwrap();
    let deadline = tokio::time::Instant::now() + GUARD;
    while !*agent
        .blackboard()
        .get::<bool>("replay/out/done")
        .await
        .unwrap()
    {
        assert!(
            tokio::time::Instant::now() < deadline,
            "the replay should end"
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    tokio::time::sleep(Duration::from_millis(200)).await;
    let map = map_of(&agent).await;
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    assert_eq!(summary.failures(), 0, "{summary}");
    map
}

fn known(map: &OccupancyGrid) -> usize {
    map.data.iter().filter(|&&c| c >= 0).count()
}

#[tokio::test(start_paused = true)]
async fn mapping_replayed_from_a_recording_gives_the_live_map() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nav.mcap");
    let live_map = live(&path, Format::Foxglove, Duration::from_secs(2)).await;
    assert!(
        known(&live_map) > 1000,
        "the robot mapped something: {}",
        known(&live_map)
    );
    let replay_map = replayed(&path).await;
    let differ = live_map
        .data
        .iter()
        .zip(replay_map.data.iter())
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(
        differ,
        0,
        "cells that differ (of {} known)",
        known(&live_map)
    );
    assert_eq!(live_map, replay_map);
}
