//! The Foxglove protobuf messages checked against `prost-reflect`, a protobuf implementation
//! of its own: the schemas petrel writes are valid `FileDescriptorSet`s with Foxglove's field
//! numbers and types, petrel's messages decode through them to the values sent, and messages
//! another encoder writes from those schemas decode through petrel's reader.

use std::sync::Arc;

use petrel_actors::{AnyValue, Image, LaserScan, OccupancyGrid, Pose2, TypeInfo};
use petrel_record::{Codec, Format, Kind, Stamp};
use prost_reflect::prost::Message;
use prost_reflect::{DescriptorPool, DynamicMessage, Kind as FieldKind, MessageDescriptor, Value};

const STAMP: Stamp = Stamp {
    sec: 1_700_000_000,
    nsec: 123_456_789,
};

fn grid() -> OccupancyGrid {
    OccupancyGrid {
        width: 3,
        height: 2,
        resolution: 0.05,
        origin: Pose2::new(-1.5, 2.25, 0.5),
        data: vec![-1, 0, 100, 50, -1, 7].into(),
    }
}

fn scan() -> LaserScan {
    LaserScan {
        angle_min: -1.5,
        angle_increment: 0.25,
        range_max: 8.0,
        ranges: vec![1.0, 2.5, 0.125, 7.75, 3.0].into(),
    }
}

/// The codec petrel records `value` with, its schema's message descriptor, and the message.
fn encoded<T: petrel_actors::PropertyType>(value: T) -> (Codec, MessageDescriptor, Vec<u8>) {
    let ti = TypeInfo::of::<T>();
    let value: AnyValue = Arc::new(value);
    let codec = Codec::for_value(Format::Foxglove, &ti, &value);
    let schema = codec.schema(ti.name());
    assert_eq!(
        (schema.encoding, schema.message_encoding),
        ("protobuf", "protobuf")
    );
    let pool = DescriptorPool::decode(&schema.data[..]).expect("a valid FileDescriptorSet");
    let desc = pool
        .get_message_by_name(&schema.name)
        .unwrap_or_else(|| panic!("{} in its own schema", schema.name));
    let mut out = Vec::new();
    codec.encode(&ti, &value, STAMP, &mut out).unwrap();
    (codec, desc, out)
}

fn field(m: &DynamicMessage, name: &str) -> Value {
    m.get_field_by_name(name)
        .unwrap_or_else(|| panic!("no field {name}"))
        .into_owned()
}

fn sub(m: &DynamicMessage, name: &str) -> DynamicMessage {
    field(m, name).as_message().unwrap().clone()
}

/// Foxglove's numbers and types for the fields petrel fills.
fn check_fields(desc: &MessageDescriptor, fields: &[(&str, u32, FieldKind)]) {
    for (name, number, kind) in fields {
        let f = desc.get_field_by_name(name).unwrap();
        assert_eq!(f.number(), *number, "{name}");
        assert_eq!(
            format!("{:?}", f.kind()),
            format!("{kind:?}"),
            "{}.{name}",
            desc.full_name()
        );
    }
}

#[test]
fn a_grid_is_a_foxglove_grid_with_raw_cells() {
    let (codec, desc, bytes) = encoded(grid());
    assert_eq!(codec.kind, Kind::Grid);
    check_fields(
        &desc,
        &[
            ("frame_id", 2, FieldKind::String),
            ("column_count", 4, FieldKind::Fixed32),
            ("row_stride", 6, FieldKind::Fixed32),
            ("cell_stride", 7, FieldKind::Fixed32),
            ("data", 9, FieldKind::Bytes),
        ],
    );
    let m = DynamicMessage::decode(desc, &bytes[..]).unwrap();
    let time = sub(&m, "timestamp");
    assert_eq!(field(&time, "seconds").as_i64(), Some(1_700_000_000));
    assert_eq!(field(&time, "nanos").as_i32(), Some(123_456_789));
    assert_eq!(field(&m, "frame_id").as_str(), Some("map"));
    assert_eq!(field(&m, "column_count").as_u32(), Some(3));
    assert_eq!(field(&m, "row_stride").as_u32(), Some(3));
    assert_eq!(field(&m, "cell_stride").as_u32(), Some(1));
    assert_eq!(field(&sub(&m, "cell_size"), "y").as_f64(), Some(0.05));
    let pose = sub(&m, "pose");
    assert_eq!(field(&sub(&pose, "position"), "x").as_f64(), Some(-1.5));
    assert_eq!(field(&sub(&pose, "position"), "y").as_f64(), Some(2.25));
    let w = field(&sub(&pose, "orientation"), "w").as_f64().unwrap();
    assert!((w - (0.25_f64).cos()).abs() < 1e-12, "{w}");
    let fields = field(&m, "fields");
    let fields = fields.as_list().unwrap();
    assert_eq!(fields.len(), 1);
    let occupancy = fields[0].as_message().unwrap();
    assert_eq!(field(occupancy, "name").as_str(), Some("occupancy"));
    assert_eq!(field(occupancy, "type").as_enum_number(), Some(2), "INT8");
    let cells: Vec<u8> = grid().data.iter().map(|&c| c as u8).collect();
    assert_eq!(
        field(&m, "data").as_bytes().map(|b| b.to_vec()),
        Some(cells)
    );
}

#[test]
fn a_scan_is_a_foxglove_laser_scan_with_packed_ranges() {
    let (_, desc, bytes) = encoded(scan());
    check_fields(
        &desc,
        &[
            ("start_angle", 4, FieldKind::Double),
            ("end_angle", 5, FieldKind::Double),
            ("ranges", 6, FieldKind::Double),
            ("intensities", 7, FieldKind::Double),
        ],
    );
    assert!(desc.get_field_by_name("ranges").unwrap().is_packed());
    let m = DynamicMessage::decode(desc, &bytes[..]).unwrap();
    assert_eq!(field(&m, "frame_id").as_str(), Some("laser"));
    assert_eq!(field(&m, "start_angle").as_f64(), Some(-1.5));
    assert_eq!(field(&m, "end_angle").as_f64(), Some(-0.5));
    assert_eq!(field(&m, "range_max").as_f64(), Some(8.0));
    let ranges: Vec<f64> = field(&m, "ranges")
        .as_list()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(ranges, scan().ranges.to_vec());
}

#[test]
fn a_pose_is_a_foxglove_pose_in_frame_with_its_exact_heading() {
    let (codec, desc, bytes) = encoded(Pose2::new(1.25, -3.5, 2.5));
    check_fields(&desc, &[("frame_id", 2, FieldKind::String)]);
    let pose_field = desc.get_field_by_name("pose").unwrap();
    assert_eq!(pose_field.number(), 3);
    assert!(matches!(pose_field.kind(), FieldKind::Message(m) if m.full_name() == "foxglove.Pose"));
    let m = DynamicMessage::decode(desc, &bytes[..]).unwrap();
    assert_eq!(field(&m, "frame_id").as_str(), Some("map"));
    let pose = sub(&m, "pose");
    assert_eq!(field(&sub(&pose, "position"), "x").as_f64(), Some(1.25));
    assert_eq!(field(&sub(&pose, "position"), "y").as_f64(), Some(-3.5));
    let q = sub(&pose, "orientation");
    let (z, w) = (
        field(&q, "z").as_f64().unwrap(),
        field(&q, "w").as_f64().unwrap(),
    );
    assert!((z - 1.25_f64.sin()).abs() < 1e-12 && (w - 1.25_f64.cos()).abs() < 1e-12);
    assert_eq!(field(&pose, "theta").as_f64(), Some(2.5));
    let back = codec.decode(&TypeInfo::of::<Pose2>(), &bytes).unwrap();
    assert_eq!(
        back.downcast_ref::<Pose2>(),
        Some(&Pose2::new(1.25, -3.5, 2.5))
    );
}

#[test]
fn an_image_is_a_foxglove_raw_image_with_raw_pixels() {
    let image = Image {
        width: 2,
        height: 1,
        encoding: "rgb8".into(),
        data: Arc::from(&[1_u8, 2, 3, 250, 251, 252][..]),
    };
    let (_, desc, bytes) = encoded(image);
    check_fields(
        &desc,
        &[
            ("width", 2, FieldKind::Fixed32),
            ("data", 6, FieldKind::Bytes),
        ],
    );
    let m = DynamicMessage::decode(desc, &bytes[..]).unwrap();
    assert_eq!(field(&m, "width").as_u32(), Some(2));
    assert_eq!(field(&m, "step").as_u32(), Some(6));
    assert_eq!(field(&m, "encoding").as_str(), Some("rgb8"));
    assert_eq!(
        field(&m, "data").as_bytes().map(|b| b.to_vec()),
        Some(vec![1, 2, 3, 250, 251, 252])
    );
}

/// A message another encoder writes (fields in another order, Foxglove's own fields only)
/// decodes through petrel's reader.
#[test]
fn petrels_reader_decodes_another_encoders_messages() {
    let (codec, desc, _) = encoded(grid());
    let mut m = DynamicMessage::new(desc.clone());
    m.set_field_by_name("data", Value::Bytes(vec![1_u8, 2, 3, 4].into()));
    m.set_field_by_name("column_count", Value::U32(2));
    m.set_field_by_name("row_stride", Value::U32(2));
    m.set_field_by_name("cell_stride", Value::U32(1));
    let pool = desc.parent_pool();
    let v2 = pool.get_message_by_name("foxglove.Vector2").unwrap();
    let mut size = DynamicMessage::new(v2);
    size.set_field_by_name("x", Value::F64(0.5));
    size.set_field_by_name("y", Value::F64(0.5));
    m.set_field_by_name("cell_size", Value::Message(size));
    let back = codec
        .decode(&TypeInfo::of::<OccupancyGrid>(), &m.encode_to_vec())
        .unwrap();
    let back = back.downcast_ref::<OccupancyGrid>().unwrap();
    assert_eq!((back.width, back.height, back.resolution), (2, 2, 0.5));
    assert_eq!(&back.data[..], &[1, 2, 3, 4]);

    let (codec, desc, _) = encoded(scan());
    let mut m = DynamicMessage::new(desc);
    m.set_field_by_name("start_angle", Value::F64(-1.0));
    m.set_field_by_name("end_angle", Value::F64(1.0));
    let ranges = [2.0, 3.0, 4.0].map(Value::F64).to_vec();
    m.set_field_by_name("ranges", Value::List(ranges));
    let back = codec
        .decode(&TypeInfo::of::<LaserScan>(), &m.encode_to_vec())
        .unwrap();
    let back = back.downcast_ref::<LaserScan>().unwrap();
    assert_eq!((back.angle_min, back.angle_increment), (-1.0, 1.0));
    assert_eq!(&back.ranges[..], &[2.0, 3.0, 4.0]);
}

/// Cut or damaged messages give an error naming the offset, never a panic.
#[test]
fn a_damaged_message_is_an_error() {
    let (codec, _, bytes) = encoded(grid());
    let ti = TypeInfo::of::<OccupancyGrid>();
    for cut in 0..bytes.len() {
        let _ = codec.decode(&ti, &bytes[..cut]);
    }
    let err = codec.decode(&ti, &bytes[..bytes.len() - 3]).unwrap_err();
    assert!(
        err.contains("foxglove.Grid") && err.contains("at byte"),
        "{err}"
    );
    let mut flipped = bytes.clone();
    flipped[0] = 0x07;
    assert!(codec.decode(&ti, &flipped).is_err());
}

#[test]
fn an_empty_grid_round_trips_in_every_format() {
    // What a mapper publishes before its first scan: replaying a recording of it failed with
    // "expected whole rows of 0 cells, got 0 cells" in both Foxglove encodings.
    let ti = TypeInfo::of::<OccupancyGrid>();
    let empty: AnyValue = Arc::new(OccupancyGrid::default());
    for format in [Format::Foxglove, Format::FoxgloveJson, Format::Ros2] {
        let codec = Codec::for_value(format, &ti, &empty);
        let mut out = Vec::new();
        codec
            .encode(&ti, &empty, Stamp::from_ns(1), &mut out)
            .unwrap();
        let back = codec.decode(&ti, &out).unwrap();
        let back = back.downcast_ref::<OccupancyGrid>().unwrap();
        assert_eq!(
            (back.width, back.height, back.data.len()),
            (0, 0, 0),
            "{format:?}"
        );
    }
}
