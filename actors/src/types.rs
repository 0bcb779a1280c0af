//! Property value types: the [`PropertyType`] trait and the built-in robot types.
//!
//! Every value stored in a blackboard is shared behind an `Arc`, so reading a large value (a
//! camera [`Image`], an [`OccupancyGrid`]) copies nothing. Types that are themselves big
//! (image bytes, grid cells, laser ranges) keep their payload behind an `Arc` too, so cloning
//! the value to modify one field does not copy the payload either.

use std::fmt::Debug;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use nalgebra::{Isometry2, Point2 as NaPoint2, Vector2};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// A type that can live in a blackboard property or queue.
///
/// `TYPE_NAME` is the stable name used in configs, snapshots, `petrel modules describe` and
/// type-mismatch errors; two types must never share a name. Implement it for your own types:
///
/// ```
/// # use serde::{Deserialize, Serialize};
/// #[derive(Clone, Debug, Serialize, Deserialize)]
/// struct Battery { volts: f64, charging: bool }
/// impl petrel_actors::PropertyType for Battery { const TYPE_NAME: &'static str = "my.Battery"; }
/// ```
pub trait PropertyType:
    Clone + Debug + Send + Sync + Serialize + DeserializeOwned + 'static
{
    /// Stable, unique name of the type.
    const TYPE_NAME: &'static str;
}

macro_rules! property_types {
    ($($t:ty => $name:literal),* $(,)?) => {
        $(impl PropertyType for $t { const TYPE_NAME: &'static str = $name; })*
    };
}

property_types! {
    bool => "bool",
    i64 => "i64",
    f64 => "f64",
    String => "string",
    Vec<f64> => "f64[]",
    Pose2 => "Pose2",
    Point2 => "Point2",
    Twist2 => "Twist2",
    LaserScan => "LaserScan",
    Image => "Image",
    OccupancyGrid => "OccupancyGrid",
    Path2 => "Path2",
    FilePath => "path",
}

/// A default value of the built-in structured types, so that an expression can learn a queue's
/// item fields before the first item is pushed (`None` for other types).
pub(crate) fn sample_of(info: crate::TypeInfo) -> Option<crate::AnyValue> {
    fn any<T: PropertyType + Default>() -> crate::AnyValue {
        std::sync::Arc::new(T::default())
    }
    Some(match () {
        _ if info.is::<Pose2>() => any::<Pose2>(),
        _ if info.is::<Point2>() => any::<Point2>(),
        _ if info.is::<Twist2>() => any::<Twist2>(),
        _ if info.is::<LaserScan>() => any::<LaserScan>(),
        _ if info.is::<Image>() => any::<Image>(),
        _ if info.is::<OccupancyGrid>() => any::<OccupancyGrid>(),
        _ if info.is::<Path2>() => any::<Path2>(),
        _ if info.is::<f64>() => any::<f64>(),
        _ if info.is::<i64>() => any::<i64>(),
        _ if info.is::<bool>() => any::<bool>(),
        _ if info.is::<String>() => any::<String>(),
        _ if info.is::<Vec<f64>>() => any::<Vec<f64>>(),
        _ => return None,
    })
}

/// A file a module reads or writes, written in configs as a plain string. A relative path in a
/// config file is taken relative to the directory of that file (made absolute when the config
/// is built), so `petrel run` behaves the same from any working directory.
#[derive(Clone, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(transparent)]
pub struct FilePath(pub PathBuf);

impl FilePath {
    /// The path.
    pub fn as_path(&self) -> &Path {
        &self.0
    }

    /// Whether no path is given.
    pub fn is_empty(&self) -> bool {
        self.0.as_os_str().is_empty()
    }

    /// The path, made absolute against `dir` if it is relative; an empty path stays empty.
    pub fn resolved_against(&self, dir: &Path) -> FilePath {
        if self.is_empty() || self.0.is_absolute() {
            return self.clone();
        }
        let joined = dir.join(&self.0);
        FilePath(std::path::absolute(&joined).unwrap_or(joined))
    }
}

impl std::fmt::Display for FilePath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0.display())
    }
}

impl From<&str> for FilePath {
    fn from(s: &str) -> Self {
        FilePath(s.into())
    }
}

/// A coordinate shown to the millimetre (`1.250`), or in exponent form when that would take
/// more than a dozen digits (`1.000e308`, where a value a check refuses would print 309).
struct Milli(f64);

impl std::fmt::Display for Milli {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0.abs() < 1e9 || !self.0.is_finite() {
            true => write!(f, "{:.3}", self.0),
            false => write!(f, "{:.3e}", self.0),
        }
    }
}

/// A planar pose (position and heading), an [`Isometry2`] written as `(x: 1.0, y: 2.0, theta: 0.5)`.
#[derive(Clone, Copy, PartialEq, Default)]
pub struct Pose2(pub Isometry2<f64>);

impl Debug for Pose2 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Pose2(x: {}, y: {}, theta: {})",
            Milli(self.x()),
            Milli(self.y()),
            Milli(self.theta())
        )
    }
}

impl Pose2 {
    /// A pose at `(x, y)` with heading `theta` (radians, counter-clockwise from +x).
    pub fn new(x: f64, y: f64, theta: f64) -> Self {
        Pose2(Isometry2::new(Vector2::new(x, y), theta))
    }
    /// Position along x (metres).
    pub fn x(&self) -> f64 {
        self.0.translation.x
    }
    /// Position along y (metres).
    pub fn y(&self) -> f64 {
        self.0.translation.y
    }
    /// Heading in radians, in `(-pi, pi]`.
    pub fn theta(&self) -> f64 {
        self.0.rotation.angle()
    }
    /// The position as a point.
    pub fn position(&self) -> Point2 {
        Point2::new(self.x(), self.y())
    }
}

#[derive(Serialize, Deserialize)]
#[serde(rename = "Pose2", deny_unknown_fields)]
struct PoseRepr {
    x: f64,
    y: f64,
    theta: f64,
}

impl Serialize for Pose2 {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        PoseRepr {
            x: self.x(),
            y: self.y(),
            theta: self.theta(),
        }
        .serialize(s)
    }
}

impl<'de> Deserialize<'de> for Pose2 {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let r = PoseRepr::deserialize(d)?;
        Ok(Pose2::new(r.x, r.y, r.theta))
    }
}

/// A planar point, written as `(x: 1.0, y: 2.0)`.
#[derive(Clone, Copy, PartialEq, Default)]
pub struct Point2(pub NaPoint2<f64>);

impl Debug for Point2 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Point2(x: {}, y: {})", Milli(self.0.x), Milli(self.0.y))
    }
}

impl Point2 {
    /// The point `(x, y)`.
    pub fn new(x: f64, y: f64) -> Self {
        Point2(NaPoint2::new(x, y))
    }
}

#[derive(Serialize, Deserialize)]
#[serde(rename = "Point2", deny_unknown_fields)]
struct PointRepr {
    x: f64,
    y: f64,
}

impl Serialize for Point2 {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        PointRepr {
            x: self.0.x,
            y: self.0.y,
        }
        .serialize(s)
    }
}

impl<'de> Deserialize<'de> for Point2 {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let r = PointRepr::deserialize(d)?;
        Ok(Point2::new(r.x, r.y))
    }
}

/// A list of planar points: a planned path, a trajectory or a list of goals, written as
/// `[(x: 1.0, y: 2.0), (x: 3.0, y: 2.0)]`. The points are shared, not copied, when cloned.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Path2(pub Arc<[Point2]>);

impl Path2 {
    /// The points, in order.
    pub fn points(&self) -> &[Point2] {
        &self.0
    }
}

impl From<Vec<Point2>> for Path2 {
    fn from(points: Vec<Point2>) -> Self {
        Path2(points.into())
    }
}

/// A planar velocity command or measurement in the robot frame.
///
/// `v` is forward speed (m/s), `omega` turn rate (rad/s); `vy` is sideways speed for
/// holonomic bases and stays 0 for differential drives.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Twist2 {
    /// Forward speed, m/s.
    pub v: f64,
    /// Sideways speed, m/s (holonomic bases only).
    #[serde(default)]
    pub vy: f64,
    /// Turn rate, rad/s, counter-clockwise positive.
    pub omega: f64,
}

impl Twist2 {
    /// A differential-drive command: forward speed and turn rate.
    pub fn new(v: f64, omega: f64) -> Self {
        Twist2 { v, vy: 0.0, omega }
    }
}

/// One planar laser scan: ray `i` points at `angle_min + i * angle_increment` in the sensor frame.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LaserScan {
    /// Angle of the first ray, radians.
    pub angle_min: f64,
    /// Angle between consecutive rays, radians.
    pub angle_increment: f64,
    /// Maximum range; a ray that hits nothing reports this value.
    pub range_max: f64,
    /// Measured ranges, metres; shared, not copied, when the scan is cloned.
    pub ranges: Arc<[f64]>,
}

impl LaserScan {
    /// The angle of ray `i` in the sensor frame.
    pub fn angle(&self, i: usize) -> f64 {
        self.angle_min + self.angle_increment * i as f64
    }
}

/// A camera image. The pixel bytes are shared, never copied, when the image is cloned or read.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixel layout, e.g. `"mono8"`, `"rgb8"`.
    pub encoding: String,
    /// Row-major pixel bytes.
    pub data: Arc<[u8]>,
}

/// A 2D occupancy grid in the ROS `nav_msgs/OccupancyGrid` convention.
///
/// Cell `(col, row)` is `data[row * width + col]`; values are occupancy probability in
/// percent (0 free .. 100 occupied) or `-1` for unknown. Row 0 is at `origin`'s y.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OccupancyGrid {
    /// Cells along x.
    pub width: u32,
    /// Cells along y.
    pub height: u32,
    /// Cell edge length, metres.
    pub resolution: f64,
    /// World pose of the lower-left corner of cell (0, 0).
    pub origin: Pose2,
    /// Cell values, shared, not copied, when the grid is cloned.
    pub data: Arc<[i8]>,
}

/// The cell of a grid (origin pose of cell (0, 0)'s lower-left corner, cell size) holding world
/// point `(x, y)`, maybe outside the grid: the one world-to-cell conversion of petrel's grids,
/// with the origin's yaw honoured.
pub fn world_to_cell(origin: &Pose2, resolution: f64, x: f64, y: f64) -> (i64, i64) {
    let local = origin
        .0
        .inverse_transform_point(&nalgebra::Point2::new(x, y));
    (
        (local.x / resolution).floor() as i64,
        (local.y / resolution).floor() as i64,
    )
}

/// The world position of the centre of cell `(col, row)`: the inverse of [`world_to_cell`].
pub fn cell_to_world(origin: &Pose2, resolution: f64, col: i64, row: i64) -> Point2 {
    let local = nalgebra::Point2::new(
        (col as f64 + 0.5) * resolution,
        (row as f64 + 0.5) * resolution,
    );
    Point2(origin.0.transform_point(&local))
}

impl OccupancyGrid {
    /// The cell holding world point `(x, y)` (maybe outside the grid); see [`world_to_cell`].
    pub fn cell_of(&self, x: f64, y: f64) -> (i64, i64) {
        world_to_cell(&self.origin, self.resolution, x, y)
    }

    /// The world position of cell `(col, row)`'s centre; see [`cell_to_world`].
    pub fn cell_center(&self, col: i64, row: i64) -> Point2 {
        cell_to_world(&self.origin, self.resolution, col, row)
    }

    /// The value of cell `(col, row)`, or `None` outside the grid.
    pub fn get(&self, col: i64, row: i64) -> Option<i8> {
        if col < 0 || row < 0 || col >= self.width as i64 || row >= self.height as i64 {
            return None;
        }
        Some(self.data[row as usize * self.width as usize + col as usize])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn world_and_cell_conversions_honour_a_rotated_origin_and_invert_each_other() {
        let res = 0.5;
        let plain = Pose2::new(1.0, 2.0, 0.0);
        assert_eq!(world_to_cell(&plain, res, 1.0, 2.0), (0, 0));
        assert_eq!(world_to_cell(&plain, res, 0.99, 2.0), (-1, 0));
        assert_eq!(world_to_cell(&plain, res, 2.6, 3.1), (3, 2));
        // Turned a quarter left: the grid's x axis points along world +y.
        let turned = Pose2::new(1.0, 2.0, std::f64::consts::FRAC_PI_2);
        assert_eq!(world_to_cell(&turned, res, 0.9, 3.1), (2, 0));
        for origin in [plain, turned] {
            for (col, row) in [(0, 0), (3, -2), (-5, 7)] {
                let c = cell_to_world(&origin, res, col, row);
                assert_eq!(world_to_cell(&origin, res, c.0.x, c.0.y), (col, row));
            }
        }
    }

    #[test]
    fn pose_round_trips_through_ron_as_x_y_theta() {
        let p = Pose2::new(1.5, -2.0, 0.25);
        let text = ron::to_string(&p).unwrap();
        assert_eq!(text, "(x:1.5,y:-2.0,theta:0.25)");
        let back: Pose2 = ron::from_str(&text).unwrap();
        assert!((back.theta() - 0.25).abs() < 1e-12);
        assert_eq!(back.x(), 1.5);
    }

    #[test]
    fn path_is_written_as_a_list_of_points() {
        let p = Path2::from(vec![Point2::new(1.0, 2.0), Point2::new(3.0, -1.5)]);
        let text = ron::to_string(&p).unwrap();
        assert_eq!(text, "[(x:1.0,y:2.0),(x:3.0,y:-1.5)]");
        let back: Path2 = ron::from_str("[(x: 1.0, y: 2.0), (x: 3.0, y: -1.5)]").unwrap();
        assert_eq!(back, p);
        assert_eq!(ron::from_str::<Path2>("[]").unwrap().points().len(), 0);
    }

    #[test]
    fn twist_without_vy_reads_as_zero_sideways_speed() {
        let t: Twist2 = ron::from_str("(v: 0.5, omega: 0.1)").unwrap();
        assert_eq!(t, Twist2::new(0.5, 0.1));
    }
}
