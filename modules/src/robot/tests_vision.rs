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

/// One victim straight ahead, 2 m away, surely seen.
fn straight_ahead() -> crate::vision::Detections {
    crate::vision::Detections(vec![crate::vision::Detection {
        bearing: 0.0,
        range: 2.0,
        confidence: 1.0,
    }])
}

/// `vision.victim_mapper` seeing a victim in `confirm_hits` sightings.
async fn victim_mapper(confirm_hits: i64) -> Agent {
    start(&format!(
        r#"(name: "victims", type: "vision.victim_mapper", values: {{"params/confirm_hits": {confirm_hits}}})"#
    ))
    .await
}

/// What `nav.searched` searched.
const SEARCHED: &str = "searched/out/searched";

/// `nav.searched` searching from 0.5 m ahead to 2.5 m away in one frame, on [`free_map`], the
/// camera in cell (0, 5) facing +x: (1, 5) and the three cells of column 2 (as the core's test).
async fn searched_facing_x() -> Agent {
    let agent = start(
        r#"(name: "searched", type: "nav.searched",
            values: {"params/min_views": 1, "params/min_range": 0.5, "params/max_range": 2.5,
                     "params/fov_deg": 102.0, "params/victim_radius": 0.0})"#,
    )
    .await;
    let bb = agent.blackboard();
    bb.set("searched/in/map", free_map()).await.unwrap();
    bb.set(
        "searched/in/robotPose",
        petrel_actors::Pose2::new(0.5, 5.5, 0.0),
    )
    .await
    .unwrap();
    agent
}

#[tokio::test(start_paused = true)]
async fn nav_searched_counts_bright_frames_and_skips_dark_ones() {
    use petrel_actors::OccupancyGrid;
    let agent = searched_facing_x().await;
    let bb = agent.blackboard();
    // Too dark: nothing searched.
    bb.set("searched/in/brightness", 0.05).await.unwrap();
    bb.set("searched/in/frames", 1i64).await.unwrap();
    wait_for(&agent, "searched/out/skipped", 1).await;
    assert_eq!(*bb.get::<f64>("searched/out/area").await.unwrap(), 0.0);
    // Bright enough: the four cells ahead, 4 m².
    bb.set("searched/in/brightness", 0.5).await.unwrap();
    bb.set("searched/in/frames", 2i64).await.unwrap();
    wait_for(&agent, "searched/out/frames", 1).await;
    assert_eq!(*bb.get::<f64>("searched/out/area").await.unwrap(), 4.0);
    let grid = bb.get::<OccupancyGrid>(SEARCHED).await.unwrap();
    assert_eq!(grid.get(1, 5), Some(0));
    assert_eq!(grid.get(0, 5), Some(-1));
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

/// A frame taken after the robot turned fast searches nothing: the turn smeared a victim's
/// pattern over the exposure, and the detector would not have found it.
#[tokio::test(start_paused = true)]
async fn nav_searched_skips_frames_taken_while_turning_fast() {
    use petrel_actors::{OccupancyGrid, Pose2};
    let agent = searched_facing_x().await;
    let bb = agent.blackboard();
    bb.set("searched/in/brightness", 0.5).await.unwrap();
    let frame_at = |heading: f64, frame: i64| {
        let bb = bb.clone();
        async move {
            // Each frame later than the pose before: it is placed from the pose written with it.
            tokio::time::sleep(Duration::from_millis(10)).await;
            bb.set("searched/in/robotPose", Pose2::new(0.5, 5.5, heading))
                .await
                .unwrap();
            bb.set("searched/in/frames", frame).await.unwrap();
        }
    };
    // Facing +y: searched.
    frame_at(std::f64::consts::FRAC_PI_2, 1).await;
    wait_for(&agent, "searched/out/frames", 1).await;
    // A quarter turn later, facing +x: smeared, the floor ahead stays unsearched.
    frame_at(0.0, 2).await;
    wait_for(&agent, "searched/out/skipped", 1).await;
    let grid = bb.get::<OccupancyGrid>(SEARCHED).await.unwrap();
    assert_eq!(grid.get(1, 5), Some(-1), "seen only while turning");
    // Still facing +x, no turn since: searched.
    frame_at(0.0, 3).await;
    wait_for(&agent, "searched/out/frames", 2).await;
    let grid = bb.get::<OccupancyGrid>(SEARCHED).await.unwrap();
    assert_eq!(grid.get(1, 5), Some(0), "seen standing");
    assert_eq!(*bb.get::<i64>("searched/out/skipped").await.unwrap(), 1);
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_restarted_victim_mapper_goes_on_with_its_candidates() {
    use crate::robot::victim_mapper::MapperMemory;
    let agent = victim_mapper(2).await;
    let bb = agent.blackboard();
    let sighting = straight_ahead;
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
    use petrel_actors::Pose2;
    let agent = start(
        r#"(name: "victims", type: "vision.victim_mapper", values: {"params/confirm_hits": 1}),
           (name: "searched", type: "nav.searched", values: {"params/min_views": 1})"#,
    )
    .await;
    let bb = agent.blackboard();
    bb.set("searched/in/map", free_map()).await.unwrap();
    let sighting = straight_ahead();
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

/// Writes `value` to `address` stamped `taken`, as the detector writes a frame's results.
async fn set_taken_at<T: petrel_actors::PropertyType>(
    agent: &Agent,
    address: &str,
    value: T,
    taken: tokio::time::Instant,
) {
    let handle = agent.blackboard().any_handle(address).await.unwrap();
    handle
        .set_at(std::sync::Arc::new(value), taken)
        .unwrap_or_else(|e| panic!("{address}: {e}"));
}

/// A frame reaches the modules that place it after the robot has moved on: the floor it shows is
/// the floor ahead of the pose the robot had when the camera took it, not of the current one.
#[tokio::test(start_paused = true)]
async fn the_searched_floor_is_the_floor_ahead_of_the_pose_when_the_frame_was_taken() {
    use petrel_actors::{OccupancyGrid, Pose2};
    let agent = searched_facing_x().await;
    let bb = agent.blackboard();
    // Facing +x when the frame is taken; facing +y 100 ms later, when it has been processed.
    let taken = tokio::time::Instant::now();
    tokio::time::sleep(Duration::from_millis(100)).await;
    bb.set(
        "searched/in/robotPose",
        Pose2::new(0.5, 5.5, std::f64::consts::FRAC_PI_2),
    )
    .await
    .unwrap();
    set_taken_at(&agent, "searched/in/brightness", 0.5, taken).await;
    set_taken_at(&agent, "searched/in/frames", 1i64, taken).await;
    wait_for(&agent, "searched/out/frames", 1).await;
    let grid = bb.get::<OccupancyGrid>(SEARCHED).await.unwrap();
    assert_eq!(grid.get(1, 5), Some(0), "ahead along +x: searched");
    assert_eq!(grid.get(0, 7), Some(-1), "ahead along +y: not seen");
    assert_eq!(*bb.get::<f64>("searched/out/area").await.unwrap(), 4.0);
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

/// Likewise a sighting: 2 m straight ahead of where the camera looked when it took the frame.
#[tokio::test(start_paused = true)]
async fn a_sighting_is_placed_from_the_pose_when_the_frame_was_taken() {
    use petrel_actors::types::Path2;
    use petrel_actors::Pose2;
    let agent = victim_mapper(1).await;
    let bb = agent.blackboard();
    bb.set("victims/in/robotPose", Pose2::new(1.0, 1.0, 0.0))
        .await
        .unwrap();
    let taken = tokio::time::Instant::now();
    // The robot turns left and drives on while the frame is processed.
    for i in 1..=3 {
        tokio::time::sleep(Duration::from_millis(30)).await;
        let turned = Pose2::new(1.0, 1.0 + 0.1 * i as f64, 0.5 * i as f64);
        bb.set("victims/in/robotPose", turned).await.unwrap();
    }
    set_taken_at(&agent, "victims/in/detections", straight_ahead(), taken).await;
    wait_for(&agent, "victims/out/pending", 1).await;
    let seen = bb.get::<Path2>("victims/out/seen").await.unwrap();
    let victim = seen.points()[0];
    assert!(
        (victim.0.x - 3.0).abs() < 0.05 && (victim.0.y - 1.0).abs() < 0.05,
        "placed at {victim:?}, expected (3, 1)"
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

/// The detector stamps what it found in a frame with the time the frame was taken: here frames
/// wait in its queue while it is disabled, and the one it processes when enabled keeps its time;
/// `out/latency` says how long it waited.
#[tokio::test(start_paused = true)]
async fn the_detector_stamps_its_results_with_the_frame_time_and_says_how_late_it_is() {
    let agent = start(&format!(
        r#"(name: "robot", type: "sim.world",
            values: {{"params/world": "{}", "params/camera/enabled": true, "params/deterministic": true}}),
           (name: "detector", type: "vision.victim_detector", values: {{"enabled": false}},
            links: {{"in/image": "robot/out/image"}})"#,
        super::tests::WORLD
    ))
    .await;
    let bb = agent.blackboard();
    tokio::time::sleep(Duration::from_millis(500)).await;
    bb.set("robot/enabled", false).await.unwrap();
    tokio::time::sleep(Duration::from_millis(100)).await;
    let enabled_at = tokio::time::Instant::now();
    bb.set("detector/enabled", true).await.unwrap();
    wait_for(&agent, "detector/out/frames", 1).await;
    let latency = *bb.get::<f64>("detector/out/latency").await.unwrap();
    assert!(
        latency >= 0.1,
        "the frame waited 100 ms or more, out/latency says {latency} s"
    );
    for output in ["frames", "detections", "brightness"] {
        let written = bb
            .any_handle(&format!("detector/out/{output}"))
            .await
            .unwrap()
            .read()
            .written;
        assert!(
            written + Duration::from_millis(100) <= enabled_at,
            "out/{output} is stamped {:?} before it was written: the frame's time, taken before the world stopped",
            enabled_at - written
        );
    }
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}
