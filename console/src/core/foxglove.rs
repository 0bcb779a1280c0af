//! The server side of the Foxglove WebSocket protocol (`foxglove.websocket.v1`, as its
//! specification describes it), as pure functions: the JSON messages the server sends
//! (`serverInfo`, `advertise`, `status`), the client's `subscribe`/`unsubscribe` read, and
//! the binary Message Data frame. Only what a live view needs: no client publishing, no
//! parameters, no services.

use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

/// The WebSocket subprotocol a Foxglove client asks for.
pub const SUBPROTOCOL: &str = "foxglove.websocket.v1";

/// The opcode of a Message Data frame.
pub const MESSAGE_DATA: u8 = 0x01;

/// A channel as `advertise` lists it.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Channel {
    /// The server's id for it.
    pub id: u32,
    /// The topic (`/agent/module/path`, as in a recording).
    pub topic: String,
    /// Message encoding: `protobuf`, `json` or `cdr`.
    pub encoding: String,
    /// Schema name, e.g. `foxglove.LaserScan`.
    pub schema_name: String,
    /// The schema as text: a JSON schema or a `ros2msg` definition as it is, a binary protobuf
    /// `FileDescriptorSet` base64-encoded (as the protocol carries binary schemas).
    pub schema: String,
    /// `protobuf`, `jsonschema` or `ros2msg`.
    pub schema_encoding: String,
}

/// The first message of every connection.
pub fn server_info(name: &str, session_id: &str) -> Value {
    json!({
        "op": "serverInfo",
        "name": name,
        "capabilities": [],
        "metadata": {},
        "sessionId": session_id,
    })
}

/// Announces `channels`.
pub fn advertise(channels: &[Channel]) -> Value {
    json!({ "op": "advertise", "channels": channels })
}

/// How serious a status message is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// 0.
    Info = 0,
    /// 1.
    Warning = 1,
    /// 2.
    Error = 2,
}

/// A status message the client may show.
pub fn status(level: Level, message: &str) -> Value {
    json!({ "op": "status", "level": level as u8, "message": message })
}

/// One subscription a client asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Subscription {
    /// The client's id for it (in every Message Data frame).
    pub id: u32,
    /// The advertised channel.
    pub channel_id: u32,
}

/// What a client asked for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ClientOp {
    /// Start streaming these channels.
    Subscribe(Vec<Subscription>),
    /// Stop these subscriptions.
    Unsubscribe(Vec<u32>),
    /// An operation this server does not offer (named, so it can say so).
    Unsupported(String),
}

#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct Raw {
    op: String,
    #[serde(default)]
    subscriptions: Vec<Subscription>,
    #[serde(default)]
    subscription_ids: Vec<u32>,
}

/// Reads a client's text message.
pub fn parse_client(text: &str) -> Result<ClientOp, String> {
    let raw: Raw = serde_json::from_str(text)
        .map_err(|e| format!("expected a JSON object with an `op`: {e}"))?;
    Ok(match raw.op.as_str() {
        "subscribe" => ClientOp::Subscribe(raw.subscriptions),
        "unsubscribe" => ClientOp::Unsubscribe(raw.subscription_ids),
        _ => ClientOp::Unsupported(raw.op),
    })
}

/// A Message Data frame: opcode, subscription id, receive time (ns), payload; integers
/// little-endian.
pub fn message_data(subscription: u32, receive_ns: u64, payload: &[u8]) -> Vec<u8> {
    let mut frame = Vec::with_capacity(13 + payload.len());
    frame.push(MESSAGE_DATA);
    frame.extend_from_slice(&subscription.to_le_bytes());
    frame.extend_from_slice(&receive_ns.to_le_bytes());
    frame.extend_from_slice(payload);
    frame
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channels_are_advertised_with_the_specs_field_names() {
        let channel = Channel {
            id: 3,
            topic: "/robot1/sim/out/scan".into(),
            encoding: "json".into(),
            schema_name: "foxglove.LaserScan".into(),
            schema: "{}".into(),
            schema_encoding: "jsonschema".into(),
        };
        assert_eq!(
            advertise(&[channel]),
            json!({"op": "advertise", "channels": [{"id": 3, "topic": "/robot1/sim/out/scan",
                "encoding": "json", "schemaName": "foxglove.LaserScan", "schema": "{}",
                "schemaEncoding": "jsonschema"}]})
        );
        assert_eq!(server_info("petrel", "1")["op"], "serverInfo");
        assert_eq!(status(Level::Warning, "x")["level"], 1);
    }

    #[test]
    fn client_messages_are_read_and_unknown_ones_named() {
        assert_eq!(
            parse_client(r#"{"op":"subscribe","subscriptions":[{"id":0,"channelId":3}]}"#),
            Ok(ClientOp::Subscribe(vec![Subscription {
                id: 0,
                channel_id: 3
            }]))
        );
        assert_eq!(
            parse_client(r#"{"op":"unsubscribe","subscriptionIds":[0,2]}"#),
            Ok(ClientOp::Unsubscribe(vec![0, 2]))
        );
        assert_eq!(
            parse_client(r#"{"op":"getParameters","parameterNames":[]}"#),
            Ok(ClientOp::Unsupported("getParameters".into()))
        );
        assert!(parse_client("[1]").is_err());
    }

    #[test]
    fn a_message_frame_is_opcode_id_time_payload_little_endian() {
        let frame = message_data(7, 0x0102_0304_0506_0708, b"{}");
        assert_eq!(frame, [1, 7, 0, 0, 0, 8, 7, 6, 5, 4, 3, 2, 1, b'{', b'}']);
    }
}
