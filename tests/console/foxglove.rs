//! `petrel run --foxglove`: a Foxglove WebSocket client (subprotocol `foxglove.websocket.v1`)
//! against the running robot config: server info, the advertised channels, subscriptions to
//! the laser and the log, and Message Data frames that decode with the advertised schema (and
//! with the recorder's own decoder). Every read has a deadline; the run is killed when the
//! test ends.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;

use futures_util::StreamExt;
use petrel::actors::{LaserScan, TypeInfo};
use petrel::record::Codec;
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
    assert_eq!(
        (&laser["encoding"], &laser["schemaEncoding"]),
        (&json!("json"), &json!("jsonschema"))
    );
    let laser_topic = laser["topic"].as_str().unwrap();
    assert!(
        laser_topic.starts_with("/robot1/"),
        "topics as a recording names them: {laser}"
    );
    let schema: Value = serde_json::from_str(laser["schema"].as_str().unwrap()).unwrap();
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
            {"id": 3, "channelId": log["id"]}, {"id": 7, "channelId": laser["id"]}]}),
    )
    .await;
    let (mut frame, mut logged) = (None, None);
    while frame.is_none() || logged.is_none() {
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
    let payload = &frame[13..];
    let message: Value = serde_json::from_slice(payload).expect("a JSON message");
    fits(&schema, &message).unwrap();
    let codec = Codec::from_channel("foxglove.LaserScan", "json", false).unwrap();
    let scan = codec
        .decode(&TypeInfo::of::<LaserScan>(), payload)
        .expect("the recorder's decoder reads it");
    let scan = scan.downcast_ref::<LaserScan>().unwrap();
    assert!(!scan.ranges.is_empty(), "a scan with rays");

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
