//! `nav.mapper` publishing its map at a rate of its own (`params/publish_every_scans`).

use std::time::Duration;

use petrel_actors::{OccupancyGrid, DEFAULT_STOP_TIMEOUT};

use super::tests::{start, WORLD};

/// Two mappers on the same scans, one publishing every change and one at most every 10 scans:
/// the second publishes a few maps, never a newer one than the first, and when it stops it
/// publishes what it held back, so its last map is the first one's.
#[tokio::test(start_paused = true)]
async fn a_mapper_with_a_publishing_period_publishes_less_and_loses_nothing() {
    let mapper = |name: &str, every: u32| {
        format!(
            r#"(name: "{name}", type: "nav.mapper", values: {{"params/publish_every_scans": {every}, "params/fov_deg": 60.0}},
                links: {{"in/laserScan": "robot/out/laserScan", "in/pose": "robot/out/pose"}})"#
        )
    };
    let agent = start(&format!(
        r#"(name: "robot", type: "sim.world", values: {{"params/world": "{WORLD}",
            "params/command_timeout_s": 0.0, "in/controlSpeed": (v: 0.0, omega: 0.5)}}), {}, {}"#,
        mapper("every", 1),
        mapper("gated", 10)
    ))
    .await;
    let bb = agent.blackboard();
    let every = bb.handle::<OccupancyGrid>("every/out/map").await.unwrap();
    let gated = bb.handle::<OccupancyGrid>("gated/out/map").await.unwrap();
    tokio::time::sleep(Duration::from_millis(3_500)).await;
    let (every_maps, gated_maps) = (every.version(), gated.version());
    // The robot turns in place, mapping a 60° view: new cells come into view at every scan.
    assert!(every_maps > 50, "{every_maps} maps published");
    // The default map from init, then one per 10 of the 20 scans a second: about 8.
    assert!(
        (5..=9).contains(&gated_maps),
        "{gated_maps} maps published (every change: {every_maps})"
    );
    let known = |map: &OccupancyGrid| map.data.iter().filter(|&&c| c >= 0).count();
    assert!(
        known(&gated.get()) < known(&every.get()),
        "the scans since the last publication are held back"
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
    let (gated, every) = (gated.get(), every.get());
    assert!(
        gated == every,
        "the map held back is published when the mapper stops: {} cells known of {}",
        known(&gated),
        known(&every)
    );
}
