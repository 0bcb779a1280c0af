//! The standard robot types as ROS 2 messages: `ros2msg` schemas (the `.msg` definitions with
//! their dependencies, as rosbag2 writes them) and CDR encoding.

use std::sync::Arc;

use petrel_actors::{Image, LaserScan, OccupancyGrid, Pose2};

use super::cdr::{CdrReader, CdrWriter};
use super::{LogLevel, LogRecord, Stamp};

/// The separator rosbag2 puts between a message definition and each dependency.
const SEPARATOR: &str =
    "================================================================================\n";

const TIME: &str = "int32 sec\nuint32 nanosec\n";
const HEADER: &str = "builtin_interfaces/Time stamp\nstring frame_id\n";
const POSE: &str = "Point position\nQuaternion orientation\n";
const POINT: &str = "float64 x\nfloat64 y\nfloat64 z\n";
const QUATERNION: &str = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n";

fn definition(main: &str, deps: &[(&str, &str)]) -> String {
    let mut text = main.to_string();
    for (name, body) in deps {
        text.push_str(SEPARATOR);
        text.push_str(&format!("MSG: {name}\n{body}"));
    }
    text
}

/// `sensor_msgs/msg/LaserScan`'s schema text.
pub fn laser_scan_schema() -> String {
    definition(
        "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\n\
         float32 time_increment\nfloat32 scan_time\nfloat32 range_min\nfloat32 range_max\n\
         float32[] ranges\nfloat32[] intensities\n",
        &[
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
        ],
    )
}

/// `geometry_msgs/msg/PoseStamped`'s schema text.
pub fn pose_stamped_schema() -> String {
    definition(
        "std_msgs/Header header\nPose pose\n",
        &[
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
            ("geometry_msgs/Pose", POSE),
            ("geometry_msgs/Point", POINT),
            ("geometry_msgs/Quaternion", QUATERNION),
        ],
    )
}

/// `nav_msgs/msg/OccupancyGrid`'s schema text.
pub fn occupancy_grid_schema() -> String {
    definition(
        "std_msgs/Header header\nMapMetaData info\nint8[] data\n",
        &[
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
            (
                "nav_msgs/MapMetaData",
                "builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\n\
                 uint32 height\ngeometry_msgs/Pose origin\n",
            ),
            ("geometry_msgs/Pose", POSE),
            ("geometry_msgs/Point", POINT),
            ("geometry_msgs/Quaternion", QUATERNION),
        ],
    )
}

/// `sensor_msgs/msg/Image`'s schema text.
pub fn image_schema() -> String {
    definition(
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n\
         uint8 is_bigendian\nuint32 step\nuint8[] data\n",
        &[
            ("std_msgs/Header", HEADER),
            ("builtin_interfaces/Time", TIME),
        ],
    )
}

/// `rcl_interfaces/msg/Log`'s schema text.
pub fn log_schema() -> String {
    definition(
        "byte DEBUG=10\nbyte INFO=20\nbyte WARN=30\nbyte ERROR=40\nbyte FATAL=50\n\
         builtin_interfaces/Time stamp\nuint8 level\nstring name\nstring msg\nstring file\n\
         string function\nuint32 line\n",
        &[("builtin_interfaces/Time", TIME)],
    )
}

fn header(w: &mut CdrWriter, stamp: Stamp, frame: &str) {
    w.i32(stamp.sec as i32);
    w.u32(stamp.nsec);
    w.string(frame);
}

fn read_header(r: &mut CdrReader) -> Result<(), String> {
    r.i32("header.stamp.sec")?;
    r.u32("header.stamp.nanosec")?;
    r.string("header.frame_id")?;
    Ok(())
}

/// The quaternion of a planar heading: a rotation about z.
pub fn quaternion(theta: f64) -> [f64; 4] {
    let half = theta / 2.0;
    [0.0, 0.0, half.sin(), half.cos()]
}

/// The heading of a quaternion's rotation about z.
pub fn heading(q: [f64; 4]) -> f64 {
    let [x, y, z, w] = q;
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

fn pose(w: &mut CdrWriter, p: &Pose2) {
    w.f64(p.x());
    w.f64(p.y());
    w.f64(0.0);
    for v in quaternion(p.theta()) {
        w.f64(v);
    }
}

fn read_pose(r: &mut CdrReader) -> Result<Pose2, String> {
    let x = r.f64("pose.position.x")?;
    let y = r.f64("pose.position.y")?;
    r.f64("pose.position.z")?;
    let mut q = [0.0; 4];
    for (v, name) in q.iter_mut().zip(["x", "y", "z", "w"]) {
        *v = r.f64(&format!("pose.orientation.{name}"))?;
    }
    Ok(Pose2::new(x, y, heading(q)))
}

/// Encodes a scan as `sensor_msgs/msg/LaserScan` (ranges become `float32`).
pub fn laser_scan(out: &mut Vec<u8>, scan: &LaserScan, stamp: Stamp, frame: &str) {
    let mut w = CdrWriter::new(out);
    header(&mut w, stamp, frame);
    let n = scan.ranges.len();
    let last = scan.angle_min + scan.angle_increment * n.saturating_sub(1) as f64;
    w.f32(scan.angle_min as f32);
    w.f32(last as f32);
    w.f32(scan.angle_increment as f32);
    w.f32(0.0);
    w.f32(0.0);
    w.f32(0.0);
    w.f32(scan.range_max as f32);
    w.f32_seq(scan.ranges.iter().map(|&r| r as f32));
    w.f32_seq(std::iter::empty());
}

/// Decodes a `sensor_msgs/msg/LaserScan`.
pub fn read_laser_scan(data: &[u8]) -> Result<LaserScan, String> {
    let mut r = CdrReader::new(data)?;
    read_header(&mut r)?;
    let angle_min = r.f32("angle_min")?;
    r.f32("angle_max")?;
    let angle_increment = r.f32("angle_increment")?;
    r.f32("time_increment")?;
    r.f32("scan_time")?;
    r.f32("range_min")?;
    let range_max = r.f32("range_max")?;
    let ranges = r.f32_seq("ranges")?;
    r.f32_seq("intensities")?;
    Ok(LaserScan {
        angle_min: angle_min.into(),
        angle_increment: angle_increment.into(),
        range_max: range_max.into(),
        ranges: ranges.into_iter().map(f64::from).collect::<Vec<_>>().into(),
    })
}

/// Encodes a pose as `geometry_msgs/msg/PoseStamped`.
pub fn pose_stamped(out: &mut Vec<u8>, p: &Pose2, stamp: Stamp, frame: &str) {
    let mut w = CdrWriter::new(out);
    header(&mut w, stamp, frame);
    pose(&mut w, p);
}

/// Decodes a `geometry_msgs/msg/PoseStamped`.
pub fn read_pose_stamped(data: &[u8]) -> Result<Pose2, String> {
    let mut r = CdrReader::new(data)?;
    read_header(&mut r)?;
    read_pose(&mut r)
}

/// Encodes a grid as `nav_msgs/msg/OccupancyGrid` (same cell convention as petrel's).
pub fn occupancy_grid(out: &mut Vec<u8>, g: &OccupancyGrid, stamp: Stamp, frame: &str) {
    let mut w = CdrWriter::new(out);
    header(&mut w, stamp, frame);
    w.i32(stamp.sec as i32);
    w.u32(stamp.nsec);
    w.f32(g.resolution as f32);
    w.u32(g.width);
    w.u32(g.height);
    pose(&mut w, &g.origin);
    // Cells are `int8`, written as their bytes without a copy.
    w.bytes(bytemuck::cast_slice(&g.data));
}

/// Decodes a `nav_msgs/msg/OccupancyGrid`.
pub fn read_occupancy_grid(data: &[u8]) -> Result<OccupancyGrid, String> {
    let mut r = CdrReader::new(data)?;
    read_header(&mut r)?;
    r.i32("info.map_load_time.sec")?;
    r.u32("info.map_load_time.nanosec")?;
    let resolution = r.f32("info.resolution")?;
    let width = r.u32("info.width")?;
    let height = r.u32("info.height")?;
    let origin = read_pose(&mut r)?;
    let cells = r.bytes("data")?;
    if cells.len() as u64 != u64::from(width) * u64::from(height) {
        return Err(format!(
            "expected {width} x {height} cells in data, got {}",
            cells.len()
        ));
    }
    Ok(OccupancyGrid {
        width,
        height,
        resolution: resolution.into(),
        origin,
        data: cells.iter().map(|&c| c as i8).collect::<Vec<_>>().into(),
    })
}

/// Bytes per row of an image (its `step`).
pub fn image_step(img: &Image) -> u32 {
    match img.height {
        0 => 0,
        h => (img.data.len() as u64 / u64::from(h)) as u32,
    }
}

/// Encodes an image as `sensor_msgs/msg/Image`.
pub fn image(out: &mut Vec<u8>, img: &Image, stamp: Stamp, frame: &str) {
    let mut w = CdrWriter::new(out);
    header(&mut w, stamp, frame);
    w.u32(img.height);
    w.u32(img.width);
    w.string(&img.encoding);
    w.u8(0);
    w.u32(image_step(img));
    w.bytes(&img.data);
}

/// Decodes a `sensor_msgs/msg/Image`.
pub fn read_image(data: &[u8]) -> Result<Image, String> {
    let mut r = CdrReader::new(data)?;
    read_header(&mut r)?;
    let height = r.u32("height")?;
    let width = r.u32("width")?;
    let encoding = r.string("encoding")?;
    r.u8("is_bigendian")?;
    r.u32("step")?;
    let bytes = r.bytes("data")?;
    Ok(Image {
        width,
        height,
        encoding,
        data: Arc::from(bytes),
    })
}

/// The `rcl_interfaces/msg/Log` level of a log level.
pub fn log_level(level: LogLevel) -> u8 {
    match level {
        LogLevel::Trace | LogLevel::Debug => 10,
        LogLevel::Info => 20,
        LogLevel::Warn => 30,
        LogLevel::Error => 40,
    }
}

/// Encodes a log line as `rcl_interfaces/msg/Log`.
pub fn log(out: &mut Vec<u8>, rec: &LogRecord) {
    let mut w = CdrWriter::new(out);
    let stamp = Stamp::from_ns(rec.stamp_ns);
    w.i32(stamp.sec as i32);
    w.u32(stamp.nsec);
    w.u8(log_level(rec.level));
    w.string(&rec.target);
    w.string(&rec.message);
    w.string(&rec.file);
    w.string("");
    w.u32(rec.line);
}

/// Decodes a `rcl_interfaces/msg/Log`.
pub fn read_log(data: &[u8]) -> Result<LogRecord, String> {
    let mut r = CdrReader::new(data)?;
    let sec = r.i32("stamp.sec")?;
    let nsec = r.u32("stamp.nanosec")?;
    let level = match r.u8("level")? {
        0..=10 => LogLevel::Debug,
        11..=20 => LogLevel::Info,
        21..=30 => LogLevel::Warn,
        _ => LogLevel::Error,
    };
    let target = r.string("name")?;
    let message = r.string("msg")?;
    let file = r.string("file")?;
    r.string("function")?;
    let line = r.u32("line")?;
    Ok(LogRecord {
        stamp_ns: (sec.max(0) as u64) * 1_000_000_000 + u64::from(nsec),
        level,
        target,
        message,
        file,
        line,
    })
}
