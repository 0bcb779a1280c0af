//! The standard robot types as Foxglove schemas, so Foxglove shows the laser, the map, the
//! image and the logs without configuration: here as JSON (JSON schema encoding, JSON
//! messages); grids, scans and images also as protobuf ([`proto`], [`descriptor`]).
//!
//! A pose also carries petrel's exact heading (`theta`, radians) beside the quaternion, so a
//! replay gives back the very pose that was recorded.

use std::sync::Arc;

use base64::Engine;
use petrel_actors::{Image, LaserScan, OccupancyGrid, Pose2};
use serde::{Deserialize, Serialize};

mod binary;
pub mod descriptor;
pub mod proto;
mod schema;
use binary::BASE64;

pub use schema::{
    grid_schema, laser_scan_schema, log_schema, pose_in_frame_schema, raw_image_schema,
};

use super::ros2::{heading, image_step, quaternion};
use super::{LogLevel, LogRecord, Stamp};

#[derive(Serialize, Deserialize)]
struct Time {
    sec: u32,
    nsec: u32,
}

impl From<Stamp> for Time {
    fn from(s: Stamp) -> Self {
        Time {
            sec: s.sec,
            nsec: s.nsec,
        }
    }
}

#[derive(Serialize, Deserialize)]
struct Vector3 {
    x: f64,
    y: f64,
    z: f64,
}

#[derive(Serialize, Deserialize)]
struct Quaternion {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

#[derive(Serialize, Deserialize)]
struct Pose {
    position: Vector3,
    orientation: Quaternion,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    theta: Option<f64>,
}

impl Pose {
    fn of(p: &Pose2) -> Self {
        let [x, y, z, w] = quaternion(p.theta());
        Pose {
            position: Vector3 {
                x: p.x(),
                y: p.y(),
                z: 0.0,
            },
            orientation: Quaternion { x, y, z, w },
            theta: Some(p.theta()),
        }
    }

    fn pose2(&self) -> Pose2 {
        let q = &self.orientation;
        let theta = self.theta.unwrap_or_else(|| heading([q.x, q.y, q.z, q.w]));
        Pose2::new(self.position.x, self.position.y, theta)
    }
}

#[derive(Serialize, Deserialize)]
struct FoxLaserScan {
    timestamp: Time,
    frame_id: String,
    pose: Pose,
    start_angle: f64,
    end_angle: f64,
    ranges: Vec<f64>,
    intensities: Vec<f64>,
    /// petrel's maximum range (Foxglove has none).
    #[serde(default)]
    range_max: f64,
}

#[derive(Serialize, Deserialize)]
struct PoseInFrame {
    timestamp: Time,
    frame_id: String,
    pose: Pose,
}

#[derive(Serialize, Deserialize)]
struct Vector2 {
    x: f64,
    y: f64,
}

#[derive(Serialize, Deserialize)]
struct PackedElementField {
    name: String,
    offset: u32,
    #[serde(rename = "type")]
    kind: u8,
}

/// `foxglove.PackedElementField`'s `INT8`.
const INT8: u8 = 2;

/// `data` is last and written by [`write_with_data`]: base64 never needs JSON escaping, so
/// it goes straight into the message instead of through a string and serde's escaping.
#[derive(Serialize, Deserialize)]
struct Grid {
    timestamp: Time,
    frame_id: String,
    pose: Pose,
    column_count: u32,
    cell_size: Vector2,
    row_stride: u32,
    cell_stride: u32,
    fields: Vec<PackedElementField>,
    #[serde(skip_serializing)]
    data: String,
}

/// `data` is last and written by [`write_with_data`], as for [`Grid`].
#[derive(Serialize, Deserialize)]
struct RawImage {
    timestamp: Time,
    frame_id: String,
    width: u32,
    height: u32,
    encoding: String,
    step: u32,
    #[serde(skip_serializing)]
    data: String,
}

#[derive(Serialize, Deserialize)]
struct Log {
    timestamp: Time,
    level: u8,
    message: String,
    name: String,
    file: String,
    line: u32,
}

fn write(out: &mut Vec<u8>, value: &impl Serialize) {
    serde_json::to_writer(out, value).expect("writing JSON to memory cannot fail");
}

/// Writes `value` (a struct whose last field, `data`, serde skips) with `"data"` set to the
/// base64 of `bytes`: the same JSON as serde would write with `data` a base64 string.
fn write_with_data(out: &mut Vec<u8>, value: &impl Serialize, bytes: &[u8]) {
    write(out, value);
    debug_assert_eq!(out.last(), Some(&b'}'));
    out.pop();
    out.extend_from_slice(b",\"data\":\"");
    let start = out.len();
    let len = base64::encoded_len(bytes.len(), true).expect("a message fits in memory");
    out.resize(start + len, 0);
    BASE64
        .encode_slice(bytes, &mut out[start..])
        .expect("sized by encoded_len");
    out.extend_from_slice(b"\"}");
}

fn read<'a, T: Deserialize<'a>>(data: &'a [u8], what: &str) -> Result<T, String> {
    serde_json::from_slice(data).map_err(|e| format!("expected a {what} JSON message: {e}"))
}

/// Encodes a scan as `foxglove.LaserScan`.
pub fn laser_scan(out: &mut Vec<u8>, scan: &LaserScan, stamp: Stamp, frame: &str) {
    let n = scan.ranges.len();
    write(
        out,
        &FoxLaserScan {
            timestamp: stamp.into(),
            frame_id: frame.into(),
            pose: Pose::of(&Pose2::default()),
            start_angle: scan.angle_min,
            end_angle: scan.angle_min + scan.angle_increment * n.saturating_sub(1) as f64,
            ranges: scan.ranges.to_vec(),
            intensities: Vec::new(),
            range_max: scan.range_max,
        },
    );
}

/// Decodes a `foxglove.LaserScan`.
pub fn read_laser_scan(data: &[u8]) -> Result<LaserScan, String> {
    let s: FoxLaserScan = read(data, "foxglove.LaserScan")?;
    let n = s.ranges.len();
    let increment = match n {
        0 | 1 => 0.0,
        n => (s.end_angle - s.start_angle) / (n - 1) as f64,
    };
    Ok(LaserScan {
        angle_min: s.start_angle,
        angle_increment: increment,
        range_max: s.range_max,
        ranges: s.ranges.into(),
    })
}

/// Encodes a pose as `foxglove.PoseInFrame`.
pub fn pose_in_frame(out: &mut Vec<u8>, p: &Pose2, stamp: Stamp, frame: &str) {
    write(
        out,
        &PoseInFrame {
            timestamp: stamp.into(),
            frame_id: frame.into(),
            pose: Pose::of(p),
        },
    );
}

/// Decodes a `foxglove.PoseInFrame`.
pub fn read_pose_in_frame(data: &[u8]) -> Result<Pose2, String> {
    Ok(read::<PoseInFrame>(data, "foxglove.PoseInFrame")?
        .pose
        .pose2())
}

/// Encodes a grid as `foxglove.Grid` with one `INT8` field, `occupancy`.
pub fn grid(out: &mut Vec<u8>, g: &OccupancyGrid, stamp: Stamp, frame: &str) {
    // Cells are `INT8`: their bytes, without a copy.
    let cells: &[u8] = bytemuck::cast_slice(&g.data);
    write_with_data(
        out,
        &Grid {
            timestamp: stamp.into(),
            frame_id: frame.into(),
            pose: Pose::of(&g.origin),
            column_count: g.width,
            cell_size: Vector2 {
                x: g.resolution,
                y: g.resolution,
            },
            row_stride: g.width,
            cell_stride: 1,
            fields: vec![PackedElementField {
                name: "occupancy".into(),
                offset: 0,
                kind: INT8,
            }],
            data: String::new(),
        },
        cells,
    );
}

/// The rows of a grid of `columns` columns holding `cells` cells. An empty grid (a map not
/// yet built: 0 x 0, what a mapper publishes first) has none.
fn rows(columns: u32, cells: usize) -> Result<u32, String> {
    match (columns, cells) {
        (0, 0) => Ok(0),
        (0, n) => Err(format!(
            "expected a column count for {n} cells, got 0 columns"
        )),
        (c, n) if n % c as usize == 0 => Ok((n / c as usize) as u32),
        (c, n) => Err(format!("expected whole rows of {c} cells, got {n} cells")),
    }
}

/// Decodes a `foxglove.Grid` of one `INT8` field per cell.
pub fn read_grid(data: &[u8]) -> Result<OccupancyGrid, String> {
    let g: Grid = read(data, "foxglove.Grid")?;
    if g.cell_stride != 1 || g.row_stride != g.column_count {
        return Err(format!(
            "expected a grid of one byte per cell (cell_stride 1, row_stride = column_count {}), got cell_stride {} and row_stride {}",
            g.column_count, g.cell_stride, g.row_stride
        ));
    }
    let cells = BASE64
        .decode(&g.data)
        .map_err(|e| format!("expected base64 cells in data: {e}"))?;
    let height = rows(g.column_count, cells.len())?;
    Ok(OccupancyGrid {
        width: g.column_count,
        height,
        resolution: g.cell_size.x,
        origin: g.pose.pose2(),
        data: cells.iter().map(|&c| c as i8).collect::<Vec<_>>().into(),
    })
}

/// Encodes an image as `foxglove.RawImage`.
pub fn raw_image(out: &mut Vec<u8>, img: &Image, stamp: Stamp, frame: &str) {
    write_with_data(
        out,
        &RawImage {
            timestamp: stamp.into(),
            frame_id: frame.into(),
            width: img.width,
            height: img.height,
            encoding: img.encoding.clone(),
            step: image_step(img),
            data: String::new(),
        },
        &img.data,
    );
}

/// Decodes a `foxglove.RawImage`.
pub fn read_raw_image(data: &[u8]) -> Result<Image, String> {
    let i: RawImage = read(data, "foxglove.RawImage")?;
    let bytes = BASE64
        .decode(&i.data)
        .map_err(|e| format!("expected base64 pixels in data: {e}"))?;
    Ok(Image {
        width: i.width,
        height: i.height,
        encoding: i.encoding,
        data: Arc::from(bytes),
    })
}

/// Encodes a log line as `foxglove.Log`.
pub fn log(out: &mut Vec<u8>, rec: &LogRecord) {
    let level = match rec.level {
        LogLevel::Trace | LogLevel::Debug => 1,
        LogLevel::Info => 2,
        LogLevel::Warn => 3,
        LogLevel::Error => 4,
    };
    write(
        out,
        &Log {
            timestamp: Stamp::from_ns(rec.stamp_ns).into(),
            level,
            message: rec.message.clone(),
            name: rec.target.clone(),
            file: rec.file.clone(),
            line: rec.line,
        },
    );
}

/// Decodes a `foxglove.Log`.
pub fn read_log(data: &[u8]) -> Result<LogRecord, String> {
    let l: Log = read(data, "foxglove.Log")?;
    let level = match l.level {
        0 | 1 => LogLevel::Debug,
        2 => LogLevel::Info,
        3 => LogLevel::Warn,
        _ => LogLevel::Error,
    };
    Ok(LogRecord {
        stamp_ns: u64::from(l.timestamp.sec) * 1_000_000_000 + u64::from(l.timestamp.nsec),
        level,
        target: l.name,
        message: l.message,
        file: l.file,
        line: l.line,
    })
}

/// A channel's schema as the Foxglove WebSocket protocol's `advertise` carries it, as text:
/// a binary one (protobuf's `FileDescriptorSet`) base64-encoded, as the protocol asks, a text
/// one (JSON schema, `ros2msg`) as it is; `None` for a text schema that is not UTF-8.
pub fn websocket_schema(schema: &super::SchemaDef) -> Option<String> {
    match schema.encoding {
        "protobuf" => Some(BASE64.encode(&schema.data)),
        _ => String::from_utf8(schema.data.clone()).ok(),
    }
}
