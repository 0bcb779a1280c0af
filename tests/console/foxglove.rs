//! `petrel run --foxglove`: a Foxglove WebSocket client (subprotocol `foxglove.websocket.v1`)
//! against the running robot config: server info, the advertised channels, subscriptions to
//! the laser, the map, a pose and the log, and Message Data frames that decode with the
//! advertised schema alone (protobuf through `prost-reflect`, an independent implementation,
//! from the base64 `FileDescriptorSet` of `advertise`; the log's JSON schema) and with the
//! recorder's own decoder. Every read has a deadline; the run is killed when the test ends.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;

use base64::Engine;
use futures_util::StreamExt;
use petrel::actors::{LaserScan, OccupancyGrid, Pose2, TypeInfo};
use petrel::record::Codec;
use prost_reflect::{DescriptorPool, DynamicMessage};
use serde_json::{json, Value};
use tokio_tungstenite::tungstenite::Message;

use crate::support::*;

struct Killed(Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Whether `value` has every property `schema` (a JSON schema) lists, each of the JSON type
/// it names: what decoding "with the advertised schema" takes.
fn fits(schema: &Value, value: &Value) -> Result<(), String> {
    let Some(properties) = schema["properties"].as_object() else {
        return Ok(());
    };
    for (name, property) in properties {
        let field = value
            .get(name)
            .ok_or_else(|| format!("no `{name}` in {value}"))?;
        let fits_type = match property["type"].as_str() {
            Some("number") | Some("integer") => field.is_number(),
            Some("string") => field.is_string(),
            Some("array") => field.is_array(),
            Some("object") => field.is_object(),
            _ => true,
        };
        if !fits_type {
            return Err(format!("`{name}` is not a {}: {field}", property["type"]));
        }
        if field.is_object() {
            fits(property, field)?;
        }
    }
    Ok(())
}

/// Decodes `payload` with the protobuf schema `channel` advertises (base64 of a binary
/// `FileDescriptorSet`), as a Foxglove client does.
fn decode_advertised(channel: &Value, payload: &[u8]) -> DynamicMessage {
    assert_eq!(
        (&channel["encoding"], &channel["schemaEncoding"]),
        (&json!("protobuf"), &json!("protobuf")),
        "{channel}"
    );
    let schema = base64::engine::general_purpose::STANDARD
        .decode(channel["schema"].as_str().unwrap())
        .expect("a base64 schema");
    let pool = DescriptorPool::decode(&schema[..]).expect("a FileDescriptorSet");
    let name = channel["schemaName"].as_str().unwrap();
    let desc = pool
        .get_message_by_name(name)
        .unwrap_or_else(|| panic!("{name} in its own schema"));
    DynamicMessage::decode(desc, payload).expect("a message of the advertised schema")
}

/// A field of a decoded message.
fn field(m: &DynamicMessage, name: &str) -> prost_reflect::Value {
    m.get_field_by_name(name)
        .unwrap_or_else(|| panic!("no `{name}` in {m:?}"))
        .into_owned()
}

async fn text(socket: &mut Socket) -> Value {
    next(socket).await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn foxglove_subscribes_to_the_laser_and_gets_messages_of_its_schema() {
    let records = tempfile::tempdir().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_petrel"))
        .args([
            "run",
            "configs/navigate.ron",
            "--for",
            "120s",
            "--no-remote",
        ])
        .args(["--foxglove", "127.0.0.1:0"])
        .env("PETREL_RUNTIME_DIR", records.path())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let run = Killed(child);
    let (tx, url) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if let Some(url) = line.strip_prefix("foxglove: ") {
                let _ = tx.send(url.to_string());
            }
        }
    });
    let url = url
        .recv_timeout(DEADLINE)
        .expect("a `foxglove: URL` line in time");
    let addr = url
        .strip_prefix("ws://")
        .and_then(|u| u.strip_suffix('/'))
        .and_then(|a| a.parse().ok())
        .unwrap_or_else(|| panic!("a loopback ws:// address without a token: {url}"));

    // The handshake fails unless the server picks the subprotocol asked for.
    let mut socket = websocket(
        addr,
        "/",
        &[("Sec-WebSocket-Protocol", "foxglove.websocket.v1")],
    )
    .await
    .expect("the Foxglove subprotocol is accepted");
    let info = text(&mut socket).await;
    assert_eq!(info["op"], "serverInfo", "{info}");
    let advertise = text(&mut socket).await;
    assert_eq!(advertise["op"], "advertise", "{advertise}");
    let channels = advertise["channels"].as_array().unwrap();
    let laser = channels
        .iter()
        .find(|c| c["schemaName"] == "foxglove.LaserScan")
        .unwrap_or_else(|| panic!("a laser channel: {advertise}"));
    let laser_topic = laser["topic"].as_str().unwrap();
    assert!(
        laser_topic.starts_with("/robot1/"),
        "topics as a recording names them: {laser}"
    );
    let by_topic = |topic: &str| {
        channels
            .iter()
            .find(|c| c["topic"] == topic)
            .unwrap_or_else(|| panic!("channel {topic}: {advertise}"))
    };
    let map = by_topic("/robot1/mapper/out/map");
    assert_eq!(map["schemaName"], "foxglove.Grid", "{map}");
    let pose = by_topic("/robot1/localizer/out/estimatedPose");
    assert_eq!(pose["schemaName"], "foxglove.PoseInFrame", "{pose}");
    let log = channels
        .iter()
        .find(|c| c["topic"] == "/log")
        .unwrap_or_else(|| panic!("the log channel, as a recording has it: {advertise}"));
    assert_eq!(log["schemaName"], "foxglove.Log", "{log}");
    let log_schema: Value = serde_json::from_str(log["schema"].as_str().unwrap()).unwrap();

    // The log first: the run logs the laser's subscription, which then comes on the log.
    send(
        &mut socket,
        json!({"op": "subscribe", "subscriptions": [
            {"id": 3, "channelId": log["id"]}, {"id": 7, "channelId": laser["id"]},
            {"id": 8, "channelId": map["id"]}, {"id": 9, "channelId": pose["id"]}]}),
    )
    .await;
    let (mut frame, mut logged) = (None, None);
    let (mut map_frame, mut pose_frame) = (None, None);
    while frame.is_none() || logged.is_none() || map_frame.is_none() || pose_frame.is_none() {
        let message = tokio::time::timeout(DEADLINE, socket.next())
            .await
            .expect("a message in time")
            .expect("the socket stays open")
            .expect("a readable message");
        let Message::Binary(data) = message else {
            continue;
        };
        assert_eq!(data[0], 0x01, "Message Data");
        match u32::from_le_bytes(data[1..5].try_into().unwrap()) {
            7 => frame = Some(data),
            8 => map_frame = Some(data),
            9 => pose_frame = Some(data),
            3 => {
                let line: Value = serde_json::from_slice(&data[13..]).expect("a JSON log line");
                fits(&log_schema, &line).unwrap();
                let text = line["message"].as_str().unwrap_or_default();
                if text.contains("a Foxglove client subscribed") && text.contains(laser_topic) {
                    logged = Some(line);
                }
            }
            other => panic!("a frame of subscription {other}, never asked for"),
        }
    }
    let frame = frame.unwrap();
    assert!(
        u64::from_le_bytes(frame[5..13].try_into().unwrap()) > 0,
        "a receive time"
    );
    // The laser: ranges as packed doubles, read from the advertised schema alone and by the
    // recorder's decoder, the same.
    let payload = &frame[13..];
    let message = decode_advertised(laser, payload);
    let ranges = field(&message, "ranges");
    let ranges = ranges.as_list().expect("ranges, a list");
    assert!(!ranges.is_empty(), "a scan with rays");
    assert_eq!(field(&message, "frame_id").as_str(), Some("laser"));
    let codec = Codec::from_channel("foxglove.LaserScan", "protobuf", false).unwrap();
    let scan = codec
        .decode(&TypeInfo::of::<LaserScan>(), payload)
        .expect("the recorder's decoder reads it");
    let scan = scan.downcast_ref::<LaserScan>().unwrap();
    let doubles: Vec<f64> = ranges.iter().map(|r| r.as_f64().unwrap()).collect();
    assert_eq!(doubles, scan.ranges.to_vec());

    // The map: its cells as raw bytes (one INT8 field), as many as the grid has.
    let payload = &map_frame.unwrap()[13..];
    let message = decode_advertised(map, payload);
    let cells = field(&message, "data");
    let cells = cells.as_bytes().expect("the cells as bytes");
    let columns = field(&message, "column_count").as_u32().unwrap();
    let grid = Codec::from_channel("foxglove.Grid", "protobuf", false)
        .unwrap()
        .decode(&TypeInfo::of::<OccupancyGrid>(), payload)
        .expect("the recorder's decoder reads it");
    let grid = grid.downcast_ref::<OccupancyGrid>().unwrap();
    assert_eq!(columns, grid.width);
    assert_eq!(cells.len(), (grid.width * grid.height) as usize);
    assert_eq!(signed(cells), &grid.data[..]);

    // A pose: the position as the recorder's decoder reads it.
    let payload = &pose_frame.unwrap()[13..];
    let message = decode_advertised(pose, payload);
    let position = field(field(&message, "pose").as_message().unwrap(), "position");
    let x = field(position.as_message().unwrap(), "x").as_f64().unwrap();
    let decoded = Codec::from_channel("foxglove.PoseInFrame", "protobuf", false)
        .unwrap()
        .decode(&TypeInfo::of::<Pose2>(), payload)
        .expect("the recorder's decoder reads it");
    assert_eq!(x, decoded.downcast_ref::<Pose2>().unwrap().x());

    send(
        &mut socket,
        json!({"op": "getParameters", "parameterNames": []}),
    )
    .await;
    let status = text(&mut socket).await;
    assert_eq!(
        (&status["op"], &status["level"]),
        (&json!("status"), &json!(1)),
        "{status}"
    );
    drop(run);
}

/// Grid cells as the signed values petrel holds.
fn signed(bytes: &[u8]) -> Vec<i8> {
    bytes.iter().map(|&b| b as i8).collect()
}
