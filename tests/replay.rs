//! Replay equivalence: the mapper fed by a replay of the simulator's recorded outputs builds
//! the very map it built live (deterministic simulation, paused clock).

use std::path::Path;
use std::time::Duration;

use petrel::actors::{Agent, ConfigFile, OccupancyGrid, DEFAULT_STOP_TIMEOUT};
use petrel::record::{Format, RecordOptions, Recorder, Selection};

/// Time (virtual, or wall time on the wall clock) after which a test gives up waiting for a
/// replay of two recorded seconds.
const GUARD: Duration = Duration::from_secs(120);

fn navigate(overlay: &str) -> ConfigFile {
    let mut file = ConfigFile::load(Path::new("configs/navigate.ron")).unwrap();
    let overlay = ConfigFile::parse(
        "overlay.ron",
        // No module is moved off the agent's thread for a slow mean step (a debug build's
        // mapper): only there is every step a replayed instant woke sure to run before the next
        // (`Context::settle_agent`). The mapper publishes every change, so the map read is all
        // it mapped, not its last publication (`params/publish_every_scans`).
        &format!(r#"Agent(name: "robot1", step_budget: (mean_us: 0, steps: 20), modules: [(name: "recorder", type: "sim.recorder", values: {{"params/png": ""}}), (name: "mapper", type: "nav.mapper", values: {{"params/publish_every_scans": 1}}), {overlay}])"#),
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

/// Replays the simulator's recorded outputs at `rate` (0: as fast as possible) into the
/// mission without its simulator; returns the map once the replay says it is done. Nothing
/// waits after that: each recorded instant reached the mapper before the next was published.
async fn replayed(path: &Path, rate: f64) -> OccupancyGrid {
    let overlay = format!(
        r#"(name: "robot", type: "sim.world", values: {{"enabled": false}}),
           (name: "replay", type: "record.replay",
            values: {{"params/file": {:?}, "params/modules": "robot", "params/rate": {rate:?}}})"#,
        path.display().to_string()
    );
    let file = navigate(&overlay);
    let agent = Agent::start_without(&file, &registry(), &["robot".to_string()])
        .await
        .unwrap();
    let done = agent
        .blackboard()
        .handle::<bool>("replay/out/done")
        .await
        .unwrap();
    let ended = tokio::time::timeout(GUARD, async {
        while !*done.get() {
            done.changed().await;
        }
    })
    .await;
    assert!(ended.is_ok(), "the replay should end");
    let map = map_of(&agent).await;
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    assert_eq!(summary.failures(), 0, "{summary}");
    map
}

fn known(map: &OccupancyGrid) -> usize {
    map.data.iter().filter(|&&c| c >= 0).count()
}

fn assert_same_map(live: &OccupancyGrid, replayed: &OccupancyGrid) {
    assert!(
        known(live) > 1000,
        "the robot mapped something: {}",
        known(live)
    );
    let differ = live
        .data
        .iter()
        .zip(replayed.data.iter())
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(differ, 0, "cells that differ (of {} known)", known(live));
    assert_eq!(live, replayed);
}

#[tokio::test(start_paused = true)]
async fn mapping_replayed_from_a_recording_gives_the_live_map() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nav.mcap");
    let live_map = live(&path, Format::Foxglove, Duration::from_secs(2)).await;
    assert_same_map(&live_map, &replayed(&path, 1.0).await);
}

/// On the wall clock, as `petrel replay` runs it (a multi-thread runtime, the agent on its own
/// thread, wake-ups as late as the machine makes them), as fast as possible and faster than
/// recorded. Before each recorded instant waited for the modules downstream, several were
/// written over one another before the localizer ran, and the mapper put scans at later
/// poses (529 of 13,141 cells differed as fast as possible). On a paused clock a whole replay
/// step happens at one instant, so write times cannot order a scan and its pose there; rate
/// 1 is as fast as the CPU allows on that clock anyway.
#[test]
fn mapping_replayed_on_the_wall_clock_gives_the_live_map() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nav.mcap");
    let paused = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .start_paused(true)
        .build()
        .unwrap();
    let live_map = paused.block_on(live(&path, Format::Foxglove, Duration::from_secs(2)));
    let wall = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    for rate in [0.0, 4.0] {
        let replay_map = wall.block_on(replayed(&path, rate));
        assert_same_map(&live_map, &replay_map);
    }
}
