//! `sim.world` hosting several `sim.body` robots, as a real agent on tokio's paused clock.

use std::time::Duration;

use petrel_actors::{status, Agent, ConfigFile, LaserScan, Pose2, Twist2, DEFAULT_STOP_TIMEOUT};

const WORLD: &str = "../configs/worlds/cluttered.txt";

async fn start(modules: &str) -> Agent {
    let text = format!(r#"Agent(name: "sim", modules: [{modules}])"#);
    let file = ConfigFile::parse("test.ron", &text).unwrap_or_else(|e| panic!("{e}"));
    Agent::start(&file, &crate::builtin())
        .await
        .unwrap_or_else(|e| panic!("{e}"))
}

/// A world with bodies `a` and `b` facing each other 2 m apart along the top wall.
fn two_bodies(extra: &str) -> String {
    format!(
        r#"(name: "world", type: "sim.world",
            values: {{"params/world": "{WORLD}", "params/bodies": ["a", "b"],
                      "params/command_timeout_s": 0.0, "params/laser/rate_hz": 0.0 {extra}}}),
           (name: "a", type: "sim.body", values: {{"params/start": [1.0, 19.4, 0.0]}}),
           (name: "b", type: "sim.body", values: {{"params/start": [3.0, 19.4, 180.0]}})"#
    )
}

/// A handle on the latest scan of `body` (it sees the items pushed from now on).
async fn scans(agent: &Agent, body: &str) -> petrel_actors::AnyHandle {
    let address = format!("{body}/out/laserScan");
    agent.blackboard().expr_handle(&address).await.unwrap()
}

fn latest(scans: &petrel_actors::AnyHandle) -> LaserScan {
    (*scans.get::<LaserScan>().unwrap()).clone()
}

async fn get<T: petrel_actors::PropertyType>(agent: &Agent, address: &str) -> T {
    (*agent.blackboard().get::<T>(address).await.unwrap()).clone()
}

#[tokio::test(start_paused = true)]
async fn bodies_see_each_other_and_a_robot_driving_into_another_collides() {
    let agent = start(&two_bodies("")).await;
    let handles = [scans(&agent, "a").await, scans(&agent, "b").await];
    tokio::time::sleep(Duration::from_millis(100)).await;
    // Each sees the other's near side straight ahead: 2 m between centres, radius 0.2.
    for (body, h) in ["a", "b"].iter().zip(&handles) {
        let scan = latest(h);
        let ahead = scan.ranges[scan.ranges.len() / 2];
        assert!((ahead - 1.8).abs() < 1e-6, "{body} sees {ahead} m ahead");
    }
    agent
        .blackboard()
        .set("a/in/controlSpeed", Twist2::new(0.5, 0.0))
        .await
        .unwrap();
    tokio::time::sleep(Duration::from_secs(6)).await;
    let (pa, pb) = (
        get::<Pose2>(&agent, "a/out/pose").await,
        get::<Pose2>(&agent, "b/out/pose").await,
    );
    let (ca, cb) = (
        get::<i64>(&agent, "a/out/collisions").await,
        get::<i64>(&agent, "b/out/collisions").await,
    );
    let (ta, tb) = (
        get::<f64>(&agent, "a/out/simTime").await,
        get::<f64>(&agent, "b/out/simTime").await,
    );
    let world_time = get::<f64>(&agent, "world/out/simTime").await;
    let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
    // a drove 1.6 m into b and stopped against it; b, standing, was pushed nowhere.
    let gap = (pb.x() - pa.x()).hypot(pb.y() - pa.y());
    assert!((0.4 - 1e-9..0.45).contains(&gap), "centres {gap} m apart");
    assert_eq!((pb.x(), pb.y()), (3.0, 19.4));
    assert_eq!((ca, cb), (1, 0), "a hit b once; b did not move");
    assert!(
        ta > 5.0 && ta == tb && tb == world_time,
        "{ta} {tb} {world_time}"
    );
    assert_eq!(summary.module("a").unwrap().status, status::STOPPED);
}

#[tokio::test(start_paused = true)]
async fn a_single_robot_world_keeps_its_own_ports() {
    let agent = start(&format!(
        r#"(name: "robot", type: "sim.world", values: {{"params/world": "{WORLD}",
            "params/start": [1.0, 19.4, 0.0], "params/command_timeout_s": 0.0}})"#
    ))
    .await;
    let scan = scans(&agent, "robot").await;
    agent
        .blackboard()
        .set("robot/in/controlSpeed", Twist2::new(0.5, 0.0))
        .await
        .unwrap();
    tokio::time::sleep(Duration::from_secs(2)).await;
    let pose = get::<Pose2>(&agent, "robot/out/pose").await;
    let t = get::<f64>(&agent, "robot/out/simTime").await;
    let scan = latest(&scan);
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
    assert!(
        pose.x() > 1.5 && t > 1.9 && scan.ranges.len() == 181,
        "{pose:?} {t}"
    );
}

#[tokio::test(start_paused = true)]
async fn bad_bodies_are_refused_at_init_with_what_was_expected() {
    let cases = [
        (
            r#"["a", "nobody"]"#,
            "this agent has no module `nobody`; expected the names of sim.body modules",
        ),
        (
            r#"["a", "m"]"#,
            "`m` is a nav.mapper, expected a sim.body module",
        ),
        (r#"["a", "a"]"#, "`a` is named twice"),
        (r#"["a", "b"]"#, "placing body `b`"),
    ];
    for (bodies, expected) in cases {
        let agent = start(&format!(
            r#"(name: "world", type: "sim.world", values: {{"params/world": "{WORLD}", "params/bodies": {bodies}}}),
               (name: "a", type: "sim.body", values: {{"params/start": [1.0, 19.4, 0.0]}}),
               (name: "b", type: "sim.body", values: {{"params/start": [1.1, 19.4, 0.0]}}),
               (name: "m", type: "nav.mapper")"#
        ))
        .await;
        tokio::time::sleep(Duration::from_millis(50)).await;
        let summary = agent.stop(DEFAULT_STOP_TIMEOUT).await;
        let report = summary.module("world").unwrap();
        let error = report.last_error.clone().unwrap_or_default();
        assert_eq!(report.status, status::FAILED, "{bodies}");
        assert!(error.contains(expected), "{bodies}: {error}");
    }
}
