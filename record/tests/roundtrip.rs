//! Every recorded kind through the sink and back through the `mcap` crate's own readers (and
//! through petrel's tolerant reader), in both formats; damaged files never panic a reader.

use std::collections::BTreeMap;
use std::sync::Arc;

use petrel_actors::{AnyValue, Image, LaserScan, OccupancyGrid, Pose2, PropertyType, TypeInfo};
use petrel_record::{
    ChannelSpec, Codec, Entry, Format, Kind, LogLevel, LogRecord, Recording, Sink, SplitPolicy,
};

fn samples() -> Vec<(ChannelSpec, AnyValue)> {
    fn spec<T: PropertyType>(key: &str, queue: bool) -> ChannelSpec {
        ChannelSpec {
            topic: format!("/r/{key}"),
            url: format!("petrel://r/{key}"),
            type_info: TypeInfo::of::<T>(),
            queue,
        }
    }
    let scan = LaserScan {
        angle_min: -std::f64::consts::FRAC_PI_2,
        angle_increment: std::f64::consts::PI / 180.0,
        range_max: 8.0,
        ranges: (0..181)
            .map(|i| 0.5 + f64::from(i) * 0.03125)
            .collect::<Vec<_>>()
            .into(),
    };
    let grid = OccupancyGrid {
        width: 3,
        height: 2,
        resolution: 0.1,
        origin: Pose2::new(-1.0, -2.0, 0.0),
        data: vec![-1, 0, 100, 50, -1, 0].into(),
    };
    let image = Image {
        width: 2,
        height: 2,
        encoding: "rgb8".into(),
        data: Arc::from((0..12u8).collect::<Vec<_>>()),
    };
    let log = LogRecord {
        stamp_ns: 1_700_000_000_123_456_789,
        level: LogLevel::Info,
        target: "petrel::test".into(),
        message: "hello".into(),
        file: "x.rs".into(),
        line: 3,
    };
    let mut log_spec = spec::<LogRecord>("log", true);
    log_spec.url = String::new();
    vec![
        (
            spec::<LaserScan>("robot/out/laserScan", true),
            Arc::new(scan),
        ),
        (
            spec::<Pose2>("robot/out/pose", false),
            Arc::new(Pose2::new(1.25, -3.5, 0.75)),
        ),
        (
            spec::<OccupancyGrid>("mapper/out/map", false),
            Arc::new(grid),
        ),
        (spec::<Image>("camera/out/image", true), Arc::new(image)),
        (log_spec, Arc::new(log)),
        (spec::<f64>("robot/out/simTime", false), Arc::new(12.5_f64)),
        (
            spec::<String>("m/params/name", false),
            Arc::new("x\"y".to_string()),
        ),
        (
            spec::<petrel_actors::Twist2>("robot/out/actualSpeed", false),
            Arc::new(petrel_actors::Twist2::new(0.5, -0.25)),
        ),
    ]
}

fn write(path: &std::path::Path, format: Format, copies: u64) {
    let mut sink = Sink::create(path, format, SplitPolicy::default()).unwrap();
    for (spec, value) in samples() {
        let ch = sink.channel(spec);
        for i in 0..copies {
            sink.write(&Entry {
                channel: ch,
                value: value.clone(),
                sequence: i,
                publish_ns: 1_000_000_000 + i * 1000,
                log_ns: 1_000_000_500 + i * 1000,
            })
            .unwrap();
        }
    }
    let report = sink.finish().unwrap();
    assert_eq!(report.written, 8 * copies);
}

/// Values compared through their RON text (exact: RON writes floats to round-trip).
fn same(ti: &TypeInfo, a: &AnyValue, b: &AnyValue) {
    assert_eq!(
        ti.to_ron(a).unwrap(),
        ti.to_ron(b).unwrap(),
        "{}",
        ti.name()
    );
}

#[test]
fn every_kind_round_trips_through_the_mcap_reader() {
    for format in [Format::Foxglove, Format::FoxgloveJson, Format::Ros2] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run.mcap");
        write(&path, format, 3);
        let bytes = std::fs::read(&path).unwrap();
        let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
        assert_eq!(summary.channels.len(), 8);
        assert!(!summary.chunk_indexes.is_empty(), "chunked and indexed");
        assert!(summary
            .chunk_indexes
            .iter()
            .all(|c| c.compression == "zstd"));
        assert_eq!(summary.stats.as_ref().unwrap().message_count, 24);
        let wanted: BTreeMap<String, (ChannelSpec, AnyValue)> = samples()
            .into_iter()
            .map(|(s, v)| (s.topic.clone(), (s, v)))
            .collect();
        let mut seen = 0;
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            let (spec, value) = &wanted[&m.channel.topic];
            let schema = m.channel.schema.as_ref().unwrap();
            let wrapped = m.channel.metadata.contains_key("petrel.wrapped");
            let codec = Codec::from_channel(&schema.name, &m.channel.message_encoding, wrapped)
                .unwrap_or_else(|| panic!("{} {}", schema.name, m.channel.message_encoding));
            let expected_schema = Codec::for_value(format, &spec.type_info, value);
            // Binary where Foxglove reads protobuf: grids, scans, poses, images (JSON in
            // foxglove-json).
            let binary = format == Format::Foxglove
                && matches!(
                    codec.kind,
                    Kind::Grid | Kind::LaserScan | Kind::Pose | Kind::Image
                );
            assert_eq!(schema.encoding == "protobuf", binary, "{}", m.channel.topic);
            if spec.url.is_empty() {
                assert_eq!(codec.kind, Kind::Log);
                assert_eq!(codec.format == Format::Ros2, format == Format::Ros2);
            } else {
                assert_eq!(codec.kind, expected_schema.kind, "{}", m.channel.topic);
                assert_eq!(m.channel.metadata["petrel.type"], spec.type_info.name());
            }
            let back = codec.decode(&spec.type_info, &m.data).unwrap();
            // ROS 2 messages are float32 where ROS 2 is (angles, ranges, grid resolution):
            // there, exact only for images, grid cells, the log and JSON.
            let ros2 = format == Format::Ros2;
            if let (true, Some(grid)) = (ros2, back.downcast_ref::<OccupancyGrid>()) {
                let sent = value.downcast_ref::<OccupancyGrid>().unwrap();
                assert_eq!((grid.width, &grid.data), (sent.width, &sent.data));
                assert!((grid.resolution - sent.resolution).abs() < 1e-7);
            } else if !(ros2 && (spec.type_info.is::<LaserScan>() || spec.type_info.is::<Pose2>()))
            {
                same(&spec.type_info, value, &back);
            }
            seen += 1;
        }
        assert_eq!(seen, 24);
        // petrel's own reader sees the same.
        let rec = Recording::parse(&bytes);
        assert!(rec.finished && rec.problem.is_none(), "{:?}", rec.problem);
        assert_eq!(rec.messages.len(), 24);
        assert_eq!(rec.channels.len(), 8);
    }
}

#[test]
fn ros2_files_carry_ros2_schemas_and_profile() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    write(&path, Format::Ros2, 1);
    let bytes = std::fs::read(&path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let names: Vec<(String, String)> = summary
        .schemas
        .values()
        .map(|s| (s.name.clone(), s.encoding.clone()))
        .collect();
    for n in [
        "sensor_msgs/msg/LaserScan",
        "geometry_msgs/msg/PoseStamped",
        "nav_msgs/msg/OccupancyGrid",
        "sensor_msgs/msg/Image",
        "rcl_interfaces/msg/Log",
    ] {
        assert!(
            names.contains(&(n.to_string(), "ros2msg".to_string())),
            "{n}: {names:?}"
        );
    }
    let laser = summary
        .schemas
        .values()
        .find(|s| s.name == "sensor_msgs/msg/LaserScan")
        .unwrap();
    let text = String::from_utf8(laser.data.to_vec()).unwrap();
    assert!(
        text.starts_with("std_msgs/Header header\nfloat32 angle_min\n"),
        "{text}"
    );
    assert!(
        text.contains("\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"),
        "{text}"
    );
    let header = mcap::read::LinearReader::new(&bytes)
        .unwrap()
        .next()
        .unwrap()
        .unwrap();
    match header {
        mcap::records::Record::Header(h) => assert_eq!(h.profile, "ros2"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn files_split_at_their_duration_limit_and_each_part_opens() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    let split = SplitPolicy::new(None, Some(1.0)).unwrap();
    let mut sink = Sink::create(&path, Format::Foxglove, split).unwrap();
    let (spec, value) = samples().remove(0);
    let ch = sink.channel(spec);
    for i in 0..400 {
        // 10 ms apart: 4 s in all.
        let ns = i * 10_000_000;
        sink.write(&Entry {
            channel: ch,
            value: value.clone(),
            sequence: i,
            publish_ns: ns,
            log_ns: ns,
        })
        .unwrap();
    }
    let report = sink.finish().unwrap();
    assert_eq!(report.files.len(), 4, "{:?}", report.files);
    assert_eq!(report.files[1], dir.path().join("run.1.mcap"));
    let mut total = 0;
    for f in &report.files {
        let bytes = std::fs::read(f).unwrap();
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        total += summary.stats.unwrap().message_count;
    }
    assert_eq!(total, 400);
}

#[test]
fn files_cut_or_damaged_anywhere_never_panic_a_reader() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    write(&path, Format::Foxglove, 40);
    let bytes = std::fs::read(&path).unwrap();
    // A fixed xorshift: the same offsets every run, spread over the whole file.
    let mut state = 0x9E3779B97F4A7C15_u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut complete_before = 0;
    for _ in 0..300 {
        let cut = (next() % bytes.len() as u64) as usize;
        let rec = Recording::parse(&bytes[..cut]);
        if cut < bytes.len() {
            assert!(!rec.finished);
            // Cut between two records: an unfinished file (a killed run), readable so far.
            if let Some(p) = &rec.problem {
                assert!(p.offset <= cut as u64, "{p}");
                assert!(!p.expected.is_empty());
            }
        }
        if rec.messages.len() == 320 {
            complete_before += 1;
        }
        let mut damaged = bytes.clone();
        let at = (next() % bytes.len() as u64) as usize;
        damaged[at] ^= 1 << (next() % 8);
        let _ = Recording::parse(&damaged);
        // The mcap crate's streaming reader, told the end may be missing.
        if let Ok(stream) = mcap::MessageStream::new_with_options(
            &bytes[..cut],
            mcap::read::Options::IgnoreEndMagic.into(),
        ) {
            for m in stream {
                if m.is_err() {
                    break;
                }
            }
        }
    }
    assert!(complete_before < 300, "some cuts lose messages");
    let err = Recording::open(
        &{
            let p = dir.path().join("cut.mcap");
            std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
            p
        },
        false,
    )
    .unwrap_err();
    assert!(
        err.contains("cut.mcap: at byte ") && err.contains("expected"),
        "{err}"
    );
    let not_mcap = Recording::parse(b"hello world, not a recording");
    assert!(not_mcap.problem.unwrap().expected.contains("magic"));
}

#[test]
fn foxglove_json_grids_and_images_carry_their_bytes_as_base64_in_valid_json() {
    let fields = |kind: &str| -> (serde_json::Value, Vec<u8>) {
        let (spec, value) = samples()
            .into_iter()
            .find(|(s, _)| s.type_info.name() == kind)
            .unwrap();
        let codec = Codec::for_value(Format::FoxgloveJson, &spec.type_info, &value);
        let mut out = Vec::new();
        codec
            .encode(&spec.type_info, &value, Default::default(), &mut out)
            .unwrap();
        let json: serde_json::Value = serde_json::from_slice(&out).unwrap();
        let raw = match kind {
            "OccupancyGrid" => value
                .downcast_ref::<OccupancyGrid>()
                .unwrap()
                .data
                .iter()
                .map(|&c| c as u8)
                .collect(),
            _ => value.downcast_ref::<Image>().unwrap().data.to_vec(),
        };
        (json, raw)
    };
    let (grid, cells) = fields("OccupancyGrid");
    assert_eq!(grid["data"], "/wBkMv8A");
    assert_eq!(cells, [0xff, 0, 100, 50, 0xff, 0]);
    assert_eq!(grid["column_count"], 3);
    assert_eq!(grid["fields"][0]["name"], "occupancy");
    let (image, pixels) = fields("Image");
    assert_eq!(image["data"], "AAECAwQFBgcICQoL");
    assert_eq!(pixels, (0..12).collect::<Vec<u8>>());
    assert_eq!(image["step"], 6);
    assert_eq!(image["encoding"], "rgb8");
}
