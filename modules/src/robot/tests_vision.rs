//! The vision side of the robot modules as real agents on tokio's paused clock: the searched
//! floor and the victim mapper.

use std::time::Duration;

use petrel_actors::{Agent, DEFAULT_STOP_TIMEOUT};

use super::tests::start;

/// A 10 m x 10 m free map of 1 m cells, its origin at (0, 0).
fn free_map() -> petrel_actors::OccupancyGrid {
    petrel_actors::OccupancyGrid {
        width: 10,
        height: 10,
        resolution: 1.0,
        origin: petrel_actors::Pose2::default(),
        data: vec![0i8; 100].into(),
    }
}

/// Waits (bounded, on the paused clock) until `path` holds `want`.
async fn wait_for(agent: &Agent, path: &str, want: i64) {
    for _ in 0..500 {
        if *agent.blackboard().get::<i64>(path).await.unwrap() == want {
            return;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    let got = *agent.blackboard().get::<i64>(path).await.unwrap();
    panic!("{path} never became {want} (it is {got})");
}

#[tokio::test(start_paused = true)]
async fn nav_searched_counts_bright_frames_and_skips_dark_ones() {
    use petrel_actors::{OccupancyGrid, Pose2};
    let agent = start(
        r#"(name: "searched", type: "nav.searched",
            values: {"params/min_views": 1, "params/min_range": 1.0, "params/max_range": 2.5,
                     "params/fov_deg": 102.0, "params/victim_radius": 0.0})"#,
    )
    .await;
    let bb = agent.blackboard();
    // The camera in cell (0, 5) facing +x.
    bb.set("searched/in/map", free_map()).await.unwrap();
    bb.set("searched/in/robotPose", Pose2::new(0.5, 5.5, 0.0))
        .await
        .unwrap();
    // Too dark: nothing searched.
    bb.set("searched/in/brightness", 0.05).await.unwrap();
    bb.set("searched/in/frames", 1i64).await.unwrap();
    wait_for(&agent, "searched/out/skipped", 1).await;
    assert_eq!(*bb.get::<f64>("searched/out/area").await.unwrap(), 0.0);
    // Bright enough: the six cells ahead (as the core's test), 6 m².
    bb.set("searched/in/brightness", 0.5).await.unwrap();
    bb.set("searched/in/frames", 2i64).await.unwrap();
    wait_for(&agent, "searched/out/frames", 1).await;
    assert_eq!(*bb.get::<f64>("searched/out/area").await.unwrap(), 6.0);
    let grid = bb
        .get::<OccupancyGrid>("searched/out/searched")
        .await
        .unwrap();
    assert_eq!(grid.get(1, 5), Some(0));
    assert_eq!(grid.get(0, 5), Some(-1));
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_restarted_victim_mapper_goes_on_with_its_candidates() {
    use crate::robot::victim_mapper::MapperMemory;
    use crate::vision::{Detection, Detections};
    let agent = start(
        r#"(name: "victims", type: "vision.victim_mapper", values: {"params/confirm_hits": 2})"#,
    )
    .await;
    let bb = agent.blackboard();
    let sighting = || {
        Detections(vec![Detection {
            bearing: 0.0,
            range: 2.0,
            confidence: 1.0,
        }])
    };
    // Sightings are placed only once the localizer gave a pose.
    bb.set(
        "victims/in/robotPose",
        petrel_actors::Pose2::new(0.0, 0.0, 0.0),
    )
    .await
    .unwrap();
    // One sighting: a candidate, not yet a victim (two confirm one).
    bb.set("victims/in/detections", sighting()).await.unwrap();
    for _ in 0..500 {
        let memory = bb.get::<MapperMemory>("victims/state/map").await.unwrap();
        if !memory.map.is_empty() {
            break;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    assert_eq!(*bb.get::<i64>("victims/out/pending").await.unwrap(), 0);
    agent.modules().restart("victims").await.unwrap();
    // The second sighting, seen by the new instance, confirms the first one's candidate
    // (which the new instance does not count twice).
    bb.set("victims/in/detections", sighting()).await.unwrap();
    wait_for(&agent, "victims/out/pending", 1).await;
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

/// Before the localizer's first estimate the pose input reads (0, 0, 0): a frame seen then is
/// neither placed as a sighting nor counted as searched floor (a team robot placed a victim
/// metres off from there at start).
#[tokio::test(start_paused = true)]
async fn frames_before_the_first_pose_place_nothing() {
    use crate::vision::{Detection, Detections};
    use petrel_actors::Pose2;
    let agent = start(
        r#"(name: "victims", type: "vision.victim_mapper", values: {"params/confirm_hits": 1}),
           (name: "searched", type: "nav.searched", values: {"params/min_views": 1})"#,
    )
    .await;
    let bb = agent.blackboard();
    bb.set("searched/in/map", free_map()).await.unwrap();
    let sighting = Detections(vec![Detection {
        bearing: 0.0,
        range: 2.0,
        confidence: 1.0,
    }]);
    bb.set("victims/in/detections", sighting.clone())
        .await
        .unwrap();
    bb.set("searched/in/frames", 1i64).await.unwrap();
    tokio::time::sleep(Duration::from_millis(100)).await;
    assert_eq!(*bb.get::<i64>("victims/out/pending").await.unwrap(), 0);
    assert_eq!(*bb.get::<i64>("searched/out/frames").await.unwrap(), 0);
    // The first estimate: frames count from now on.
    for target in ["victims", "searched"] {
        bb.set(&format!("{target}/in/robotPose"), Pose2::new(2.5, 5.5, 0.0))
            .await
            .unwrap();
    }
    bb.set("victims/in/detections", sighting).await.unwrap();
    bb.set("searched/in/frames", 2i64).await.unwrap();
    wait_for(&agent, "victims/out/pending", 1).await;
    wait_for(&agent, "searched/out/frames", 1).await;
    assert!(*bb.get::<f64>("searched/out/area").await.unwrap() > 0.0);
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}
