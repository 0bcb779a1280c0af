//! Pure encoders: petrel values ↔ MCAP messages users can open. This is the small public API
//! shared by the recorder, replay and live views: pick a [`Codec`] for a property's type and
//! [`Format`], ask it for its [`SchemaDef`], then [`Codec::encode`] / [`Codec::decode`].
//!
//! | petrel type | Foxglove | Foxglove JSON (`jsonschema`, `json`) | ROS 2 (`ros2msg`, `cdr`) |
//! |---|---|---|---|
//! | `LaserScan` | `foxglove.LaserScan` (`protobuf`) | `foxglove.LaserScan` | `sensor_msgs/msg/LaserScan` |
//! | `Pose2` | `foxglove.PoseInFrame` (`protobuf`) | `foxglove.PoseInFrame` | `geometry_msgs/msg/PoseStamped` |
//! | `OccupancyGrid` | `foxglove.Grid` (`protobuf`) | `foxglove.Grid` | `nav_msgs/msg/OccupancyGrid` |
//! | `Image` | `foxglove.RawImage` (`protobuf`) | `foxglove.RawImage` | `sensor_msgs/msg/Image` |
//! | the log | `foxglove.Log` (JSON) | `foxglove.Log` | `rcl_interfaces/msg/Log` |
//! | anything else | JSON with a JSON schema titled by the type | the same | the same |

pub mod cdr;
pub mod foxglove;
pub mod protobuf;
pub mod ros2;

use std::sync::Arc;

use petrel_actors::{AnyValue, Image, LaserScan, OccupancyGrid, Pose2, TypeInfo};
use serde::{Deserialize, Serialize};

/// Which message family a recording uses for the standard robot types.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// Foxglove schemas (Foxglove opens them without configuration): grids, scans, poses and
    /// images as protobuf (raw cells and pixels, binary floats), the log and other types as JSON.
    #[default]
    Foxglove,
    /// Foxglove schemas, every one as JSON (grid cells and pixels as base64 text): for tools
    /// that read JSON only; more CPU and larger files than [`Format::Foxglove`].
    #[serde(rename = "foxglove-json")]
    FoxgloveJson,
    /// ROS 2 messages in CDR (rosbag2 and its tools read them).
    Ros2,
}

impl std::str::FromStr for Format {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "foxglove" => Ok(Format::Foxglove),
            "foxglove-json" => Ok(Format::FoxgloveJson),
            "ros2" => Ok(Format::Ros2),
            other => Err(format!(
                "expected `foxglove`, `foxglove-json` or `ros2`, got `{other}`"
            )),
        }
    }
}

/// A time as messages carry it: seconds and nanoseconds since the Unix epoch.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Stamp {
    /// Whole seconds.
    pub sec: u32,
    /// Nanoseconds within the second.
    pub nsec: u32,
}

impl Stamp {
    /// The stamp of `ns` nanoseconds since the epoch.
    pub fn from_ns(ns: u64) -> Self {
        Stamp {
            sec: (ns / 1_000_000_000).min(u64::from(u32::MAX)) as u32,
            nsec: (ns % 1_000_000_000) as u32,
        }
    }
}

/// How serious a log line is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum LogLevel {
    /// Tracing's `TRACE`.
    Trace,
    /// `DEBUG`.
    Debug,
    /// `INFO`.
    Info,
    /// `WARN`.
    Warn,
    /// `ERROR`.
    Error,
}

/// One line of the tracing log, as the log channel records it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct LogRecord {
    /// When it was logged, ns since the Unix epoch.
    pub stamp_ns: u64,
    /// Its level.
    pub level: LogLevel,
    /// Where from (the tracing target, e.g. `petrel_actors::supervisor`).
    pub target: String,
    /// The message and its fields, as the log prints them.
    pub message: String,
    /// Source file, if known.
    pub file: String,
    /// Source line, if known (0 otherwise).
    pub line: u32,
}

impl petrel_actors::PropertyType for LogRecord {
    const TYPE_NAME: &'static str = "LogRecord";
}

/// A channel's schema and message encoding.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SchemaDef {
    /// Schema name, e.g. `foxglove.LaserScan` or `sensor_msgs/msg/LaserScan`.
    pub name: String,
    /// Schema encoding: `jsonschema` or `ros2msg`.
    pub encoding: &'static str,
    /// The schema text.
    pub data: Vec<u8>,
    /// Message encoding: `json` or `cdr`.
    pub message_encoding: &'static str,
}

/// What a channel carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `LaserScan`.
    LaserScan,
    /// `Pose2`.
    Pose,
    /// `OccupancyGrid`.
    Grid,
    /// `Image`.
    Image,
    /// The tracing log.
    Log,
    /// Any other type, as its JSON; `wrapped`: as `{"value": ...}`, for values that are not
    /// JSON objects (Foxglove shows objects only).
    Json {
        /// Whether the value sits in a `value` field.
        wrapped: bool,
    },
}

/// Encodes and decodes one channel's messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Codec {
    /// The message family.
    pub format: Format,
    /// What the channel carries.
    pub kind: Kind,
}

/// Frame ids of the standard types (petrel has no transform tree: one fixed frame each).
fn frame(kind: Kind) -> &'static str {
    match kind {
        Kind::LaserScan => "laser",
        Kind::Image => "camera",
        _ => "map",
    }
}

impl Codec {
    /// The codec for a property of type `ti` whose first recorded value is `first`.
    pub fn for_value(format: Format, ti: &TypeInfo, first: &AnyValue) -> Self {
        let kind = if ti.is::<LaserScan>() {
            Kind::LaserScan
        } else if ti.is::<Pose2>() {
            Kind::Pose
        } else if ti.is::<OccupancyGrid>() {
            Kind::Grid
        } else if ti.is::<Image>() {
            Kind::Image
        } else {
            let object = ti.to_json(first).is_ok_and(|j| j.first() == Some(&b'{'));
            Kind::Json { wrapped: !object }
        };
        Codec { format, kind }
    }

    /// The codec of the log channel.
    pub fn log(format: Format) -> Self {
        Codec {
            format,
            kind: Kind::Log,
        }
    }

    /// The schema of the channel; `type_name` titles the JSON schema of other types.
    pub fn schema(&self, type_name: &str) -> SchemaDef {
        let (name, data) = match (self.format, self.kind) {
            (_, Kind::Json { wrapped }) => return json_schema(type_name, wrapped),
            (Format::Foxglove, k @ (Kind::Grid | Kind::LaserScan | Kind::Pose | Kind::Image)) => {
                let (name, data) = match k {
                    Kind::Grid => ("foxglove.Grid", foxglove::descriptor::grid()),
                    Kind::LaserScan => ("foxglove.LaserScan", foxglove::descriptor::laser_scan()),
                    Kind::Pose => (
                        "foxglove.PoseInFrame",
                        foxglove::descriptor::pose_in_frame(),
                    ),
                    _ => ("foxglove.RawImage", foxglove::descriptor::raw_image()),
                };
                return SchemaDef {
                    name: name.into(),
                    encoding: "protobuf",
                    data,
                    message_encoding: "protobuf",
                };
            }
            (Format::Foxglove | Format::FoxgloveJson, k) => {
                let (name, data) = match k {
                    Kind::LaserScan => ("foxglove.LaserScan", foxglove::laser_scan_schema()),
                    Kind::Pose => ("foxglove.PoseInFrame", foxglove::pose_in_frame_schema()),
                    Kind::Grid => ("foxglove.Grid", foxglove::grid_schema()),
                    Kind::Image => ("foxglove.RawImage", foxglove::raw_image_schema()),
                    _ => ("foxglove.Log", foxglove::log_schema()),
                };
                return SchemaDef {
                    name: name.into(),
                    encoding: "jsonschema",
                    data,
                    message_encoding: "json",
                };
            }
            (Format::Ros2, Kind::LaserScan) => {
                ("sensor_msgs/msg/LaserScan", ros2::laser_scan_schema())
            }
            (Format::Ros2, Kind::Pose) => {
                ("geometry_msgs/msg/PoseStamped", ros2::pose_stamped_schema())
            }
            (Format::Ros2, Kind::Grid) => {
                ("nav_msgs/msg/OccupancyGrid", ros2::occupancy_grid_schema())
            }
            (Format::Ros2, Kind::Image) => ("sensor_msgs/msg/Image", ros2::image_schema()),
            (Format::Ros2, Kind::Log) => ("rcl_interfaces/msg/Log", ros2::log_schema()),
        };
        SchemaDef {
            name: name.into(),
            encoding: "ros2msg",
            data: data.into_bytes(),
            message_encoding: "cdr",
        }
    }

    /// The codec of a recorded channel, from its schema name and message encoding.
    pub fn from_channel(schema: &str, message_encoding: &str, wrapped: bool) -> Option<Self> {
        let (format, kind) = match (schema, message_encoding) {
            ("foxglove.LaserScan", "protobuf") => (Format::Foxglove, Kind::LaserScan),
            ("foxglove.PoseInFrame", "protobuf") => (Format::Foxglove, Kind::Pose),
            ("foxglove.Grid", "protobuf") => (Format::Foxglove, Kind::Grid),
            ("foxglove.RawImage", "protobuf") => (Format::Foxglove, Kind::Image),
            ("foxglove.LaserScan", "json") => (Format::FoxgloveJson, Kind::LaserScan),
            ("foxglove.PoseInFrame", "json") => (Format::FoxgloveJson, Kind::Pose),
            ("foxglove.Grid", "json") => (Format::FoxgloveJson, Kind::Grid),
            ("foxglove.RawImage", "json") => (Format::FoxgloveJson, Kind::Image),
            ("foxglove.Log", "json") => (Format::Foxglove, Kind::Log),
            ("sensor_msgs/msg/LaserScan", "cdr") => (Format::Ros2, Kind::LaserScan),
            ("geometry_msgs/msg/PoseStamped", "cdr") => (Format::Ros2, Kind::Pose),
            ("nav_msgs/msg/OccupancyGrid", "cdr") => (Format::Ros2, Kind::Grid),
            ("sensor_msgs/msg/Image", "cdr") => (Format::Ros2, Kind::Image),
            ("rcl_interfaces/msg/Log", "cdr") => (Format::Ros2, Kind::Log),
            (_, "json") => (Format::Foxglove, Kind::Json { wrapped }),
            _ => return None,
        };
        Some(Codec { format, kind })
    }

    /// Encodes `value` (of type `ti`) stamped `stamp` at the end of `out` (on an error, `out`
    /// may hold part of it: callers clear it before the next message).
    pub fn encode(
        &self,
        ti: &TypeInfo,
        value: &AnyValue,
        stamp: Stamp,
        out: &mut Vec<u8>,
    ) -> Result<(), String> {
        use foxglove::proto;
        let fr = frame(self.kind);
        let f = self.format;
        match self.kind {
            Kind::LaserScan => {
                let s = downcast::<LaserScan>(value)?;
                match f {
                    Format::Foxglove => proto::laser_scan(out, s, stamp, fr),
                    Format::FoxgloveJson => foxglove::laser_scan(out, s, stamp, fr),
                    Format::Ros2 => ros2::laser_scan(out, s, stamp, fr),
                }
            }
            Kind::Pose => {
                let p = downcast::<Pose2>(value)?;
                match f {
                    Format::Foxglove => proto::pose_in_frame(out, p, stamp, fr),
                    Format::FoxgloveJson => foxglove::pose_in_frame(out, p, stamp, fr),
                    Format::Ros2 => ros2::pose_stamped(out, p, stamp, fr),
                }
            }
            Kind::Grid => {
                let g = downcast::<OccupancyGrid>(value)?;
                match f {
                    Format::Foxglove => proto::grid(out, g, stamp, fr),
                    Format::FoxgloveJson => foxglove::grid(out, g, stamp, fr),
                    Format::Ros2 => ros2::occupancy_grid(out, g, stamp, fr),
                }
            }
            Kind::Image => {
                let i = downcast::<Image>(value)?;
                match f {
                    Format::Foxglove => proto::raw_image(out, i, stamp, fr),
                    Format::FoxgloveJson => foxglove::raw_image(out, i, stamp, fr),
                    Format::Ros2 => ros2::image(out, i, stamp, fr),
                }
            }
            Kind::Log => {
                let l = downcast::<LogRecord>(value)?;
                match f {
                    Format::Ros2 => ros2::log(out, l),
                    _ => foxglove::log(out, l),
                }
            }
            // Straight into the message buffer: no JSON of its own per value.
            Kind::Json { wrapped: true } => {
                out.extend_from_slice(b"{\"value\":");
                ti.write_json(value, out)?;
                out.push(b'}');
            }
            Kind::Json { wrapped: false } => ti.write_json(value, out)?,
        }
        Ok(())
    }

    /// Decodes a message into a value of type `ti` (the property it is replayed into).
    pub fn decode(&self, ti: &TypeInfo, data: &[u8]) -> Result<AnyValue, String> {
        use foxglove::proto;
        let f = self.format;
        let value: AnyValue = match self.kind {
            Kind::LaserScan if ti.is::<LaserScan>() => Arc::new(match f {
                Format::Foxglove => proto::read_laser_scan(data)?,
                Format::FoxgloveJson => foxglove::read_laser_scan(data)?,
                Format::Ros2 => ros2::read_laser_scan(data)?,
            }),
            Kind::Pose if ti.is::<Pose2>() => Arc::new(match f {
                Format::Foxglove => proto::read_pose_in_frame(data)?,
                Format::FoxgloveJson => foxglove::read_pose_in_frame(data)?,
                Format::Ros2 => ros2::read_pose_stamped(data)?,
            }),
            Kind::Grid if ti.is::<OccupancyGrid>() => Arc::new(match f {
                Format::Foxglove => proto::read_grid(data)?,
                Format::FoxgloveJson => foxglove::read_grid(data)?,
                Format::Ros2 => ros2::read_occupancy_grid(data)?,
            }),
            Kind::Image if ti.is::<Image>() => Arc::new(match f {
                Format::Foxglove => proto::read_raw_image(data)?,
                Format::FoxgloveJson => foxglove::read_raw_image(data)?,
                Format::Ros2 => ros2::read_image(data)?,
            }),
            Kind::Log if ti.is::<LogRecord>() => Arc::new(match f {
                Format::Ros2 => ros2::read_log(data)?,
                _ => foxglove::read_log(data)?,
            }),
            Kind::Json { wrapped: false } => ti.from_json(data)?,
            Kind::Json { wrapped: true } => {
                let mut w: serde_json::Value = serde_json::from_slice(data)
                    .map_err(|e| format!("expected {{\"value\": ...}}: {e}"))?;
                let inner = w
                    .get_mut("value")
                    .map(serde_json::Value::take)
                    .ok_or("expected {\"value\": ...}: no `value` field")?;
                let bytes = serde_json::to_vec(&inner).map_err(|e| e.to_string())?;
                ti.from_json(&bytes)?
            }
            other => return Err(format!("a {other:?} message cannot become a {}", ti.name())),
        };
        Ok(value)
    }
}

fn downcast<T: 'static>(value: &AnyValue) -> Result<&T, String> {
    value
        .downcast_ref::<T>()
        .ok_or_else(|| format!("expected a {}", std::any::type_name::<T>()))
}

/// The JSON schema of a type without a standard message: titled by petrel's type name.
pub fn json_schema(type_name: &str, wrapped: bool) -> SchemaDef {
    let schema = match wrapped {
        true => serde_json::json!({"title": type_name, "type": "object",
            "properties": {"value": {"description": format!("a petrel {type_name}")}}}),
        false => serde_json::json!({"title": type_name, "type": "object",
            "description": format!("a petrel {type_name}, as serde writes it")}),
    };
    SchemaDef {
        name: type_name.to_string(),
        encoding: "jsonschema",
        data: serde_json::to_vec_pretty(&schema).expect("a JSON value serializes"),
        message_encoding: "json",
    }
}
