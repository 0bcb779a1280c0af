//! Occupancy grids recorded as patches: every write of a grid is in the file (whole, or as the
//! rectangle of cells it changed, on `TOPIC/_patches`), the `mcap` crate's reader reads both
//! channels, and petrel's reader gives back every grid, byte for byte as if written whole.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::sync::Arc;

use petrel_actors::{AnyValue, OccupancyGrid, Pose2, TypeInfo};
use petrel_record::grid_patch::PATCH_SUFFIX;
use petrel_record::{ChannelSpec, Codec, Entry, Format, Recording, Sink, SplitPolicy, Stamp};

const TOPIC: &str = "/r/mapper/out/map";

/// A mapper's writes: a 100x100 grid changing in a few cells at a time (a "scan" marks a
/// short run of cells), one write unchanged, then a grid of another size.
fn grids() -> Vec<OccupancyGrid> {
    let mut grid = OccupancyGrid {
        width: 100,
        height: 100,
        resolution: 0.05,
        origin: Pose2::new(-2.5, 1.25, 0.3),
        data: vec![-1; 10_000].into(),
    };
    let mut out = vec![grid.clone()];
    for i in 0..60u32 {
        let mut data = grid.data.to_vec();
        for k in 0..5 {
            let cell = ((i * 37 + k * 3) % 90 + 5) * 100 + (i * 13 + k) % 100;
            data[cell as usize] = ((i + k) % 101) as i8;
        }
        grid.data = data.into();
        out.push(grid.clone());
        if i == 30 {
            out.push(grid.clone());
        }
    }
    out.push(OccupancyGrid {
        width: 50,
        height: 20,
        data: vec![7; 1000].into(),
        ..grid
    });
    out
}

/// Writes `grids` 10 ms apart (publish times), returns the file's bytes.
fn record(format: Format, grids: &[OccupancyGrid]) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("map.mcap");
    let mut sink = Sink::create(&path, format, SplitPolicy::default()).unwrap();
    let ch = sink.channel(ChannelSpec {
        topic: TOPIC.into(),
        url: "petrel://r/mapper/out/map".into(),
        type_info: TypeInfo::of::<OccupancyGrid>(),
        queue: false,
    });
    for (i, g) in grids.iter().enumerate() {
        let ns = 1_000_000_000 + i as u64 * 10_000_000;
        sink.write(&Entry {
            channel: ch,
            value: Arc::new(g.clone()),
            sequence: i as u64 + 1,
            publish_ns: ns,
            log_ns: ns + 500,
        })
        .unwrap();
    }
    assert_eq!(sink.finish().unwrap().written, grids.len() as u64);
    std::fs::read(path).unwrap()
}

#[test]
fn every_grid_write_is_in_the_file_and_reads_back_whole() {
    let grids = grids();
    let ti = TypeInfo::of::<OccupancyGrid>();
    for format in [Format::Foxglove, Format::FoxgloveJson, Format::Ros2] {
        let bytes = record(format, &grids);

        // The mcap crate reads every write: whole grids on the grid's channel, patches on its
        // patch channel, the same schema, the sequence and times of each write.
        let mut per_topic: BTreeMap<String, Vec<(u32, usize)>> = BTreeMap::new();
        let mut schemas = Vec::new();
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            let schema = m.channel.schema.as_ref().unwrap();
            schemas.push((schema.name.clone(), schema.encoding.clone()));
            per_topic
                .entry(m.channel.topic.clone())
                .or_default()
                .push((m.sequence, m.data.len()));
        }
        schemas.dedup();
        assert_eq!(schemas.len(), 1, "{format:?}: one grid schema: {schemas:?}");
        let whole = &per_topic[TOPIC];
        let patches = &per_topic[&format!("{TOPIC}{PATCH_SUFFIX}")];
        assert_eq!(whole.len() + patches.len(), grids.len(), "{format:?}");
        let mut sequences: Vec<u32> = whole.iter().chain(patches).map(|w| w.0).collect();
        sequences.sort();
        assert_eq!(sequences, (1..=grids.len() as u32).collect::<Vec<_>>());
        // The first write and the one of another size are whole, most others patches.
        let whole_seqs: Vec<u32> = whole.iter().map(|w| w.0).collect();
        assert_eq!(whole_seqs.first(), Some(&1), "{format:?}");
        assert_eq!(whole_seqs.last(), Some(&(grids.len() as u32)), "{format:?}");
        assert!(whole.len() * 10 < grids.len(), "{format:?}: {whole_seqs:?}");
        let largest_patch = patches.iter().map(|p| p.1).max().unwrap();
        assert!(
            largest_patch * 4 < whole[0].1,
            "{format:?}: patches are small: {largest_patch} against {}",
            whole[0].1
        );

        // petrel's reader gives back every write whole, encoded as a whole write would be.
        let rec = Recording::parse(&bytes);
        assert_eq!((&rec.problem, &rec.unrebuilt), (&None, &None), "{format:?}");
        assert_eq!(rec.channels.len(), 1, "{format:?}: the patch channel is folded in");
        let (&id, ch) = rec.channels.iter().next().unwrap();
        assert_eq!(ch.topic, TOPIC);
        let codec = Codec::from_channel(&ch.schema, &ch.message_encoding, false).unwrap();
        let messages: Vec<_> = rec.messages_of(id).collect();
        assert_eq!(messages.len(), grids.len(), "{format:?}");
        for (i, (m, g)) in messages.iter().zip(&grids).enumerate() {
            assert_eq!(m.sequence as usize, i + 1);
            let back = codec.decode(&ti, &m.data).unwrap();
            let back = back.downcast_ref::<OccupancyGrid>().unwrap();
            assert_eq!(back.data, g.data, "{format:?}: grid {i}");
            assert_eq!((back.width, back.height), (g.width, g.height));
            let mut wanted = Vec::new();
            let value: AnyValue = Arc::new(g.clone());
            codec
                .encode(&ti, &value, Stamp::from_ns(m.publish_ns), &mut wanted)
                .unwrap();
            if format != Format::Ros2 {
                // ROS 2 carries the heading as a quaternion: the rebuilt origin may differ
                // from the written one in the last bit, so only its cells are compared.
                assert_eq!(m.data, wanted, "{format:?}: grid {i} as written whole");
            }
        }
    }
}

#[test]
fn a_grid_patch_without_its_whole_grid_is_an_error_naming_it_unless_salvaged() {
    let grids = grids();
    let codec = Codec {
        format: Format::Foxglove,
        kind: petrel_record::Kind::Grid,
    };
    let schema = codec.schema("OccupancyGrid");
    let mut w = mcap::WriteOptions::new()
        .create(Cursor::new(Vec::new()))
        .unwrap();
    let sid = w
        .add_schema(&schema.name, schema.encoding, &schema.data)
        .unwrap();
    w.add_channel(sid, TOPIC, "protobuf", &BTreeMap::new())
        .unwrap();
    let meta = BTreeMap::from([("petrel.patch_of".to_string(), TOPIC.to_string())]);
    let patch_channel = w
        .add_channel(sid, &format!("{TOPIC}{PATCH_SUFFIX}"), "protobuf", &meta)
        .unwrap();
    let mut data = Vec::new();
    let value: AnyValue = Arc::new(grids[1].clone());
    codec
        .encode(&TypeInfo::of::<OccupancyGrid>(), &value, Stamp::default(), &mut data)
        .unwrap();
    let header = mcap::records::MessageHeader {
        channel_id: patch_channel,
        sequence: 9,
        log_time: 1,
        publish_time: 1,
    };
    w.write_to_known_channel(&header, &data).unwrap();
    w.finish().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("orphan.mcap");
    std::fs::write(&path, w.into_inner().into_inner()).unwrap();
    let err = Recording::open(&path, false).unwrap_err();
    assert!(
        err.contains("orphan.mcap") && err.contains("grid patch 9") && err.contains("no whole grid"),
        "{err}"
    );
    let rec = Recording::open(&path, true).unwrap();
    assert_eq!(rec.messages.len(), 1, "the patch stays as it was");
    assert_eq!(rec.channels.len(), 2);
}
