//! The JSON schemas of the Foxglove messages petrel writes (with petrel's own additions
//! described in them).

use serde_json::json;

fn time_schema() -> serde_json::Value {
    json!({"type": "object", "properties": {
        "sec": {"type": "integer", "minimum": 0},
        "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}}})
}

fn pose_schema() -> serde_json::Value {
    let xyz = json!({"type": "object", "properties": {
        "x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}});
    json!({"type": "object", "properties": {
        "position": xyz,
        "orientation": {"type": "object", "properties": {
            "x": {"type": "number"}, "y": {"type": "number"},
            "z": {"type": "number"}, "w": {"type": "number"}}},
        "theta": {"type": "number", "description": "petrel: exact heading, radians"}}})
}

fn schema(title: &str, properties: serde_json::Value) -> Vec<u8> {
    let text = json!({"title": title, "type": "object", "properties": properties});
    serde_json::to_vec_pretty(&text).expect("a JSON value serializes")
}

/// `foxglove.LaserScan`'s JSON schema.
pub fn laser_scan_schema() -> Vec<u8> {
    let numbers = json!({"type": "array", "items": {"type": "number"}});
    schema(
        "foxglove.LaserScan",
        json!({"timestamp": time_schema(), "frame_id": {"type": "string"}, "pose": pose_schema(),
            "start_angle": {"type": "number"}, "end_angle": {"type": "number"},
            "ranges": numbers, "intensities": numbers,
            "range_max": {"type": "number", "description": "petrel: maximum range, m"}}),
    )
}

/// `foxglove.PoseInFrame`'s JSON schema.
pub fn pose_in_frame_schema() -> Vec<u8> {
    schema(
        "foxglove.PoseInFrame",
        json!({"timestamp": time_schema(), "frame_id": {"type": "string"}, "pose": pose_schema()}),
    )
}

/// `foxglove.Grid`'s JSON schema.
pub fn grid_schema() -> Vec<u8> {
    let field = json!({"type": "object", "properties": {
        "name": {"type": "string"}, "offset": {"type": "integer"}, "type": {"type": "integer"}}});
    schema(
        "foxglove.Grid",
        json!({"timestamp": time_schema(), "frame_id": {"type": "string"}, "pose": pose_schema(),
            "column_count": {"type": "integer"},
            "cell_size": {"type": "object", "properties": {
                "x": {"type": "number"}, "y": {"type": "number"}}},
            "row_stride": {"type": "integer"}, "cell_stride": {"type": "integer"},
            "fields": {"type": "array", "items": field},
            "data": {"type": "string", "contentEncoding": "base64"}}),
    )
}

/// `foxglove.RawImage`'s JSON schema.
pub fn raw_image_schema() -> Vec<u8> {
    schema(
        "foxglove.RawImage",
        json!({"timestamp": time_schema(), "frame_id": {"type": "string"},
            "width": {"type": "integer"}, "height": {"type": "integer"},
            "encoding": {"type": "string"}, "step": {"type": "integer"},
            "data": {"type": "string", "contentEncoding": "base64"}}),
    )
}

/// `foxglove.Log`'s JSON schema.
pub fn log_schema() -> Vec<u8> {
    schema(
        "foxglove.Log",
        json!({"timestamp": time_schema(),
            "level": {"type": "integer", "description": "0 unknown, 1 debug, 2 info, 3 warning, 4 error, 5 fatal"},
            "message": {"type": "string"}, "name": {"type": "string"},
            "file": {"type": "string"}, "line": {"type": "integer"}}),
    )
}
