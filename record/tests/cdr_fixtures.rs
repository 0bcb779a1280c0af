//! ROS 2 CDR encodings checked byte for byte against messages laid out by hand from the
//! `.msg` definitions: a 4-byte CDR_LE header; primitives aligned to their size counted from
//! after it; strings as u32 length (with the NUL) + bytes + NUL; sequences as u32 count +
//! elements.

use std::sync::Arc;

use petrel_actors::{Image, LaserScan, OccupancyGrid, Pose2};
use petrel_record::encode::ros2;
use petrel_record::{LogLevel, LogRecord, Stamp};

const STAMP: Stamp = Stamp { sec: 1, nsec: 2 };

/// A little-endian message being laid out by hand.
#[derive(Default)]
struct Hand(Vec<u8>);

impl Hand {
    fn new() -> Self {
        Hand(vec![0x00, 0x01, 0x00, 0x00])
    }
    fn raw(mut self, bytes: &[u8]) -> Self {
        self.0.extend_from_slice(bytes);
        self
    }
    fn pad(self, n: usize) -> Self {
        self.raw(&vec![0; n])
    }
    fn u32(self, v: u32) -> Self {
        self.raw(&v.to_le_bytes())
    }
    fn f32(self, v: f32) -> Self {
        self.raw(&v.to_le_bytes())
    }
    fn f64(self, v: f64) -> Self {
        self.raw(&v.to_le_bytes())
    }
}

#[test]
fn laser_scan_pads_after_the_frame_id_and_writes_float32_sequences() {
    let scan = LaserScan {
        angle_min: -1.0,
        angle_increment: 0.5,
        range_max: 8.0,
        ranges: vec![1.0, 2.0, 8.0].into(),
    };
    let mut out = Vec::new();
    ros2::laser_scan(&mut out, &scan, STAMP, "laser");
    let expected = Hand::new()
        .u32(1) // header.stamp.sec (int32)
        .u32(2) // header.stamp.nanosec
        .u32(6) // "laser" + NUL
        .raw(b"laser\0") // ends at payload byte 18
        .pad(2) // float32 aligns to 4: 18 -> 20
        .f32(-1.0) // angle_min
        .f32(0.0) // angle_max = -1 + 0.5 * 2
        .f32(0.5) // angle_increment
        .f32(0.0) // time_increment
        .f32(0.0) // scan_time
        .f32(0.0) // range_min
        .f32(8.0) // range_max
        .u32(3) // ranges: count
        .f32(1.0)
        .f32(2.0)
        .f32(8.0)
        .u32(0); // intensities: empty
    assert_eq!(out, expected.0);
    assert_eq!(out.len(), 4 + 68);
    let back = ros2::read_laser_scan(&out).unwrap();
    assert_eq!(back, scan);
}

#[test]
fn pose_stamped_aligns_float64_to_8() {
    let mut out = Vec::new();
    ros2::pose_stamped(&mut out, &Pose2::new(1.5, -2.0, 0.0), STAMP, "base");
    let expected = Hand::new()
        .u32(1)
        .u32(2)
        .u32(5)
        .raw(b"base\0") // ends at payload byte 17
        .pad(7) // float64 aligns to 8: 17 -> 24
        .f64(1.5)
        .f64(-2.0)
        .f64(0.0)
        .f64(0.0) // orientation x
        .f64(0.0) // y
        .f64(0.0) // z = sin(0 / 2)
        .f64(1.0); // w = cos(0 / 2)
    assert_eq!(out, expected.0);
    let turned = {
        let mut o = Vec::new();
        ros2::pose_stamped(&mut o, &Pose2::new(0.0, 0.0, 1.0), STAMP, "base");
        ros2::read_pose_stamped(&o).unwrap()
    };
    assert!((turned.theta() - 1.0).abs() < 1e-12);
}

#[test]
fn occupancy_grid_writes_its_metadata_and_int8_cells() {
    let grid = OccupancyGrid {
        width: 2,
        height: 1,
        resolution: 0.5,
        origin: Pose2::new(-1.0, 0.0, 0.0),
        data: vec![-1, 100].into(),
    };
    let mut out = Vec::new();
    ros2::occupancy_grid(&mut out, &grid, STAMP, "map");
    let expected = Hand::new()
        .u32(1)
        .u32(2)
        .u32(4)
        .raw(b"map\0") // ends at 16
        .u32(1) // info.map_load_time.sec
        .u32(2) // info.map_load_time.nanosec
        .f32(0.5) // info.resolution
        .u32(2) // info.width
        .u32(1) // info.height -> 36
        .pad(4) // float64 aligns to 8: 36 -> 40
        .f64(-1.0)
        .f64(0.0)
        .f64(0.0)
        .f64(0.0)
        .f64(0.0)
        .f64(0.0)
        .f64(1.0) // -> 96
        .u32(2) // data: count
        .raw(&[0xff, 100]);
    assert_eq!(out, expected.0);
    assert_eq!(ros2::read_occupancy_grid(&out).unwrap(), grid);
}

#[test]
fn image_writes_a_byte_between_strings_and_sequences() {
    let img = Image {
        width: 2,
        height: 1,
        encoding: "mono8".into(),
        data: Arc::from(&[7u8, 9][..]),
    };
    let mut out = Vec::new();
    ros2::image(&mut out, &img, STAMP, "camera");
    let expected = Hand::new()
        .u32(1)
        .u32(2)
        .u32(7)
        .raw(b"camera\0") // ends at 19
        .pad(1) // 19 -> 20
        .u32(1) // height
        .u32(2) // width
        .u32(6)
        .raw(b"mono8\0") // ends at 34
        .raw(&[0]) // is_bigendian (uint8, no alignment) -> 35
        .pad(1) // uint32 aligns to 4: 35 -> 36
        .u32(2) // step
        .u32(2) // data: count
        .raw(&[7, 9]);
    assert_eq!(out, expected.0);
    assert_eq!(ros2::read_image(&out).unwrap(), img);
}

#[test]
fn log_writes_level_byte_then_aligned_strings() {
    let rec = LogRecord {
        stamp_ns: 3_000_000_004,
        level: LogLevel::Warn,
        target: "nav".into(),
        message: "hi".into(),
        file: "a.rs".into(),
        line: 7,
    };
    let mut out = Vec::new();
    ros2::log(&mut out, &rec);
    let expected = Hand::new()
        .u32(3) // stamp.sec
        .u32(4) // stamp.nanosec
        .raw(&[30]) // level WARN -> 9
        .pad(3) // 9 -> 12
        .u32(4)
        .raw(b"nav\0") // name -> 20
        .u32(3)
        .raw(b"hi\0") // msg -> 27
        .pad(1) // -> 28
        .u32(5)
        .raw(b"a.rs\0") // file -> 37
        .pad(3) // -> 40
        .u32(1)
        .raw(b"\0") // function: empty -> 45
        .pad(3) // -> 48
        .u32(7); // line
    assert_eq!(out, expected.0);
    assert_eq!(ros2::read_log(&out).unwrap(), rec);
}

#[test]
fn short_or_foreign_messages_are_errors_naming_the_field() {
    let mut out = Vec::new();
    ros2::pose_stamped(&mut out, &Pose2::new(1.0, 2.0, 0.0), STAMP, "map");
    for cut in 0..out.len() {
        let err = ros2::read_pose_stamped(&out[..cut]).unwrap_err();
        assert!(err.starts_with("expected"), "{err}");
    }
    let err = ros2::read_pose_stamped(&[0x00, 0x00, 0, 0, 1]).unwrap_err();
    assert!(err.contains("CDR_LE"), "{err}");
}
