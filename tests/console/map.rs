//! The map view and the camera of a robot: `configs/navigate.ron` (with its camera on) behind a
//! console; the API serves the grid being built, the poses, path, goals, laser and the frame.

use base64::Engine as _;
use serde_json::json;

use crate::support::*;

fn decoded(b64: &serde_json::Value) -> Vec<u8> {
    base64::engine::general_purpose::STANDARD
        .decode(b64.as_str().expect("base64 text"))
        .expect("valid base64")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_robot_s_map_and_camera_are_served() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/navigate.ron");
    let mut file = petrel::actors::ConfigFile::load(&path).unwrap();
    file.overlay(
        petrel::actors::ConfigFile::parse(
            "overlay.ron",
            r#"Agent(name: "robot1", modules: [
                (name: "robot", type: "sim.world", values: {"params/camera/enabled": true}),
                (name: "recorder", type: "sim.recorder", values: {"params/png": ""}),
            ])"#,
        )
        .unwrap(),
    );
    let agent = petrel::actors::Agent::start(&file, petrel::Petrel::new().registry())
        .await
        .unwrap();
    let console = console_for(&agent, None).await;
    let addr = console.local_addr();

    // Wait, over the WebSocket, for the first grid, scan and camera frame (a queue's latest
    // item is followed from when it is first asked for: until the next push, its default).
    let mut socket = websocket(addr, "/api/ws?agent=robot1", &[]).await.unwrap();
    let watch = ["mapper/out/map", "robot/out/image", "robot/out/laserScan"];
    send(&mut socket, json!({ "watch": watch })).await;
    let (mut grid, mut frame, mut scan) = (false, false, false);
    while !(grid && frame && scan) {
        for v in next(&mut socket).await["values"]
            .as_array()
            .into_iter()
            .flatten()
        {
            let text = v["text"].as_str().unwrap();
            grid |= v["key"] == "mapper/out/map" && !text.starts_with("OccupancyGrid 0×0");
            frame |= v["key"] == "robot/out/image" && text == "Image 160×120 mono8";
            scan |= v["key"] == "robot/out/laserScan" && text == "LaserScan 181 rays";
        }
    }

    let map = get(addr, "/api/agents/robot1/map").await.json();
    assert_eq!(map["sources"]["grid"], "mapper/out/map");
    let g = &map["grid"];
    let (w, h) = (g["width"].as_u64().unwrap(), g["height"].as_u64().unwrap());
    assert!(w > 0 && h > 0, "{g}");
    assert_eq!(decoded(&g["cells"]).len() as u64, w * h);
    assert!(
        map["pose"]["x"].is_f64() && map["true_pose"]["theta"].is_f64(),
        "{map}"
    );
    assert_eq!(
        map["goals"].as_array().unwrap().len(),
        3,
        "navigate's three goals"
    );
    assert_eq!(map["laser"]["ranges"].as_array().unwrap().len(), 181);
    // The page asks again with the grid version it has: an unchanged grid is not resent.
    let version = map["grid_version"].as_u64().unwrap();
    let again = get(
        addr,
        &format!("/api/agents/robot1/map?grid_version={version}"),
    )
    .await
    .json();
    if again["grid_version"] == version {
        assert!(again["grid"].is_null(), "the same grid is not sent twice");
    }

    let camera = get(addr, "/api/agents/robot1/camera").await.json();
    assert_eq!(camera["key"], "robot/out/image");
    let image = &camera["image"];
    assert_eq!(
        (image["width"].as_u64(), image["height"].as_u64()),
        (Some(160), Some(120))
    );
    assert_eq!(decoded(&image["data"]).len(), 160 * 120);
    console.stop().await;
    agent.stop(None).await;
}
