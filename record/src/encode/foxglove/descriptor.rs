//! The protobuf schemas of the Foxglove messages petrel writes in binary, as the binary
//! `FileDescriptorSet` Foxglove reads from an MCAP schema of encoding `protobuf` (what `protoc
//! --include_imports --descriptor_set_out` writes for Foxglove's `.proto` files), built from
//! the descriptor messages' field numbers in `google/protobuf/descriptor.proto`.
//!
//! Same field numbers and types as Foxglove's schemas, plus petrel's additions at numbers
//! from 100 (Foxglove shows them as extra fields): a pose's exact heading (`theta`) and a
//! scan's maximum range (`range_max`), so a replay gives back the recorded values.

use crate::encode::protobuf::{bytes, message, uint};

/// A field's type (`FieldDescriptorProto.Type`).
#[derive(Clone, Copy)]
enum Ty {
    Double,
    Int64,
    Int32,
    Fixed32,
    String,
    Bytes,
    Message(&'static str),
    Enum(&'static str),
}

/// A field: name, number, type, repeated or not.
struct Field(&'static str, u32, Ty, bool);

/// A `.proto` file of one message (with its nested enums: name and values).
struct File {
    path: &'static str,
    package: &'static str,
    dependencies: &'static [&'static str],
    message: &'static str,
    fields: &'static [Field],
    enums: &'static [(&'static str, &'static [(&'static str, u64)])],
}

const fn file(
    path: &'static str,
    dependencies: &'static [&'static str],
    message: &'static str,
    fields: &'static [Field],
) -> File {
    File {
        path,
        package: "foxglove",
        dependencies,
        message,
        fields,
        enums: &[],
    }
}

const TIMESTAMP: File = File {
    path: "google/protobuf/timestamp.proto",
    package: "google.protobuf",
    dependencies: &[],
    message: "Timestamp",
    fields: &[
        Field("seconds", 1, Ty::Int64, false),
        Field("nanos", 2, Ty::Int32, false),
    ],
    enums: &[],
};
const XY: &[Field] = &[
    Field("x", 1, Ty::Double, false),
    Field("y", 2, Ty::Double, false),
];
const VECTOR2: File = file("foxglove/Vector2.proto", &[], "Vector2", XY);
const VECTOR3: File = file(
    "foxglove/Vector3.proto",
    &[],
    "Vector3",
    &[
        Field("x", 1, Ty::Double, false),
        Field("y", 2, Ty::Double, false),
        Field("z", 3, Ty::Double, false),
    ],
);
const QUATERNION: File = file(
    "foxglove/Quaternion.proto",
    &[],
    "Quaternion",
    &[
        Field("x", 1, Ty::Double, false),
        Field("y", 2, Ty::Double, false),
        Field("z", 3, Ty::Double, false),
        Field("w", 4, Ty::Double, false),
    ],
);
const POSE: File = file(
    "foxglove/Pose.proto",
    &["foxglove/Quaternion.proto", "foxglove/Vector3.proto"],
    "Pose",
    &[
        Field("position", 1, Ty::Message(".foxglove.Vector3"), false),
        Field("orientation", 2, Ty::Message(".foxglove.Quaternion"), false),
        Field("theta", 100, Ty::Double, false),
    ],
);
const PACKED_ELEMENT_FIELD: File = File {
    enums: &[(
        "NumericType",
        &[
            ("UNKNOWN", 0),
            ("UINT8", 1),
            ("INT8", 2),
            ("UINT16", 3),
            ("INT16", 4),
            ("UINT32", 5),
            ("INT32", 6),
            ("FLOAT32", 7),
            ("FLOAT64", 8),
        ],
    )],
    ..file(
        "foxglove/PackedElementField.proto",
        &[],
        "PackedElementField",
        &[
            Field("name", 1, Ty::String, false),
            Field("offset", 2, Ty::Fixed32, false),
            Field(
                "type",
                3,
                Ty::Enum(".foxglove.PackedElementField.NumericType"),
                false,
            ),
        ],
    )
};
const TIME: Ty = Ty::Message(".google.protobuf.Timestamp");
const GRID: File = file(
    "foxglove/Grid.proto",
    &[
        "foxglove/PackedElementField.proto",
        "foxglove/Pose.proto",
        "foxglove/Vector2.proto",
        "google/protobuf/timestamp.proto",
    ],
    "Grid",
    &[
        Field("timestamp", 1, TIME, false),
        Field("frame_id", 2, Ty::String, false),
        Field("pose", 3, Ty::Message(".foxglove.Pose"), false),
        Field("column_count", 4, Ty::Fixed32, false),
        Field("cell_size", 5, Ty::Message(".foxglove.Vector2"), false),
        Field("row_stride", 6, Ty::Fixed32, false),
        Field("cell_stride", 7, Ty::Fixed32, false),
        Field(
            "fields",
            8,
            Ty::Message(".foxglove.PackedElementField"),
            true,
        ),
        Field("data", 9, Ty::Bytes, false),
    ],
);
const LASER_SCAN: File = file(
    "foxglove/LaserScan.proto",
    &["foxglove/Pose.proto", "google/protobuf/timestamp.proto"],
    "LaserScan",
    &[
        Field("timestamp", 1, TIME, false),
        Field("frame_id", 2, Ty::String, false),
        Field("pose", 3, Ty::Message(".foxglove.Pose"), false),
        Field("start_angle", 4, Ty::Double, false),
        Field("end_angle", 5, Ty::Double, false),
        Field("ranges", 6, Ty::Double, true),
        Field("intensities", 7, Ty::Double, true),
        Field("range_max", 100, Ty::Double, false),
    ],
);
const POSE_IN_FRAME: File = file(
    "foxglove/PoseInFrame.proto",
    &["foxglove/Pose.proto", "google/protobuf/timestamp.proto"],
    "PoseInFrame",
    &[
        Field("timestamp", 1, TIME, false),
        Field("frame_id", 2, Ty::String, false),
        Field("pose", 3, Ty::Message(".foxglove.Pose"), false),
    ],
);
const RAW_IMAGE: File = file(
    "foxglove/RawImage.proto",
    &["google/protobuf/timestamp.proto"],
    "RawImage",
    &[
        Field("timestamp", 1, TIME, false),
        Field("frame_id", 7, Ty::String, false),
        Field("width", 2, Ty::Fixed32, false),
        Field("height", 3, Ty::Fixed32, false),
        Field("encoding", 4, Ty::String, false),
        Field("step", 5, Ty::Fixed32, false),
        Field("data", 6, Ty::Bytes, false),
    ],
);

/// `FieldDescriptorProto`.
fn field(out: &mut Vec<u8>, f: &Field) {
    let Field(name, number, ty, repeated) = *f;
    bytes(out, 1, name.as_bytes());
    uint(out, 3, u64::from(number));
    uint(out, 4, if repeated { 3 } else { 1 });
    let (code, type_name) = match ty {
        Ty::Double => (1, None),
        Ty::Int64 => (3, None),
        Ty::Int32 => (5, None),
        Ty::Fixed32 => (7, None),
        Ty::String => (9, None),
        Ty::Message(m) => (11, Some(m)),
        Ty::Bytes => (12, None),
        Ty::Enum(e) => (14, Some(e)),
    };
    uint(out, 5, code);
    if let Some(t) = type_name {
        bytes(out, 6, t.as_bytes());
    }
}

/// `FileDescriptorProto`.
fn file_proto(out: &mut Vec<u8>, f: &File) {
    bytes(out, 1, f.path.as_bytes());
    bytes(out, 2, f.package.as_bytes());
    for d in f.dependencies {
        bytes(out, 3, d.as_bytes());
    }
    message(out, 4, |m| {
        bytes(m, 1, f.message.as_bytes());
        for x in f.fields {
            message(m, 2, |o| field(o, x));
        }
        for (name, values) in f.enums {
            message(m, 4, |e| {
                bytes(e, 1, name.as_bytes());
                for (value, number) in *values {
                    message(e, 2, |v| {
                        bytes(v, 1, value.as_bytes());
                        uint(v, 2, *number);
                    });
                }
            });
        }
    });
    bytes(out, 12, b"proto3");
}

/// A `FileDescriptorSet` of `files`, each after the files it imports.
fn set(files: &[&File]) -> Vec<u8> {
    let mut out = Vec::new();
    for f in files {
        message(&mut out, 1, |o| file_proto(o, f));
    }
    out
}

/// `foxglove.Grid`'s `FileDescriptorSet`.
pub fn grid() -> Vec<u8> {
    set(&[
        &TIMESTAMP,
        &VECTOR2,
        &VECTOR3,
        &QUATERNION,
        &POSE,
        &PACKED_ELEMENT_FIELD,
        &GRID,
    ])
}

/// `foxglove.LaserScan`'s `FileDescriptorSet`.
pub fn laser_scan() -> Vec<u8> {
    set(&[&TIMESTAMP, &VECTOR3, &QUATERNION, &POSE, &LASER_SCAN])
}

/// `foxglove.PoseInFrame`'s `FileDescriptorSet`.
pub fn pose_in_frame() -> Vec<u8> {
    set(&[&TIMESTAMP, &VECTOR3, &QUATERNION, &POSE, &POSE_IN_FRAME])
}

/// `foxglove.RawImage`'s `FileDescriptorSet`.
pub fn raw_image() -> Vec<u8> {
    set(&[&TIMESTAMP, &RAW_IMAGE])
}
