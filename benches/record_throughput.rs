//! `record_throughput`: petrel's recording core writing N laser scans (encoding each, then
//! writing it chunked and zstd-compressed) against the raw `mcap::Writer` writing the same
//! encoded bytes with the same options, in the same run.

mod common;

use std::collections::BTreeMap;
use std::hint::black_box;
use std::sync::Arc;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use mcap::records::MessageHeader;
use petrel::actors::{AnyValue, LaserScan, TypeInfo};
use petrel::record::sink::{CHUNK_BYTES, ZSTD_LEVEL};
use petrel::record::{ChannelSpec, Codec, Entry, Format, Sink, SplitPolicy, Stamp};

const SCANS: u64 = 1000;

/// The `n`th scan: each differs from the others, as a moving robot's do (the same scan
/// repeated compresses to almost nothing, which would leave only the encoding to measure).
fn scan(n: u64) -> AnyValue {
    Arc::new(LaserScan {
        angle_min: -std::f64::consts::FRAC_PI_2,
        angle_increment: std::f64::consts::PI / 180.0,
        range_max: 8.0,
        ranges: (0..181)
            .map(|i| 1.0 + (i as f64 * 0.37 + n as f64 * 0.011).sin().abs() * 6.0)
            .collect::<Vec<_>>()
            .into(),
    })
}

fn scans() -> Vec<AnyValue> {
    (0..SCANS).map(scan).collect()
}

fn petrel_sink(dir: &std::path::Path, format: Format, scans: &[AnyValue]) -> u64 {
    let mut sink = Sink::create(dir.join("petrel.mcap"), format, SplitPolicy::default()).unwrap();
    let ch = sink.channel(ChannelSpec {
        topic: "/robot1/robot/out/laserScan".into(),
        url: "petrel://robot1/robot/out/laserScan".into(),
        type_info: TypeInfo::of::<LaserScan>(),
        queue: true,
    });
    for i in 0..SCANS {
        let ns = 1_000_000_000 + i * 50_000_000;
        sink.write(&Entry {
            channel: ch,
            value: scans[i as usize].clone(),
            sequence: i,
            publish_ns: ns,
            log_ns: ns,
        })
        .unwrap();
    }
    sink.finish().unwrap().written
}

/// The messages petrel writes, encoded ahead (the floor: writing bytes only).
fn encoded(format: Format, scans: &[AnyValue]) -> Vec<Vec<u8>> {
    let codec = Codec::for_value(format, &TypeInfo::of::<LaserScan>(), &scans[0]);
    (0..SCANS)
        .map(|i| {
            let mut bytes = Vec::new();
            let ns = 1_000_000_000 + i * 50_000_000;
            codec
                .encode(
                    &TypeInfo::of::<LaserScan>(),
                    &scans[i as usize],
                    Stamp::from_ns(ns),
                    &mut bytes,
                )
                .unwrap();
            bytes
        })
        .collect()
}

/// The raw writer; with `ahead`, the bytes come encoded, else it encodes each as petrel does.
fn raw_mcap(
    dir: &std::path::Path,
    format: Format,
    scans: &[AnyValue],
    ahead: Option<&[Vec<u8>]>,
) -> u64 {
    let codec = Codec::for_value(format, &TypeInfo::of::<LaserScan>(), &scans[0]);
    let schema = codec.schema("LaserScan");
    let file = std::io::BufWriter::new(std::fs::File::create(dir.join("raw.mcap")).unwrap());
    let mut w = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .compression_level(ZSTD_LEVEL)
        .compression_threads(0)
        .chunk_size(Some(CHUNK_BYTES))
        .create(file)
        .unwrap();
    let sid = w
        .add_schema(&schema.name, schema.encoding, &schema.data)
        .unwrap();
    let cid = w
        .add_channel(
            sid,
            "/robot1/robot/out/laserScan",
            schema.message_encoding,
            &BTreeMap::new(),
        )
        .unwrap();
    let mut bytes = Vec::new();
    for i in 0..SCANS {
        let ns = 1_000_000_000 + i * 50_000_000;
        let header = MessageHeader {
            channel_id: cid,
            sequence: i as u32,
            log_time: ns,
            publish_time: ns,
        };
        match ahead {
            Some(messages) => w
                .write_to_known_channel(&header, &messages[i as usize])
                .unwrap(),
            None => {
                bytes.clear();
                codec
                    .encode(
                        &TypeInfo::of::<LaserScan>(),
                        &scans[i as usize],
                        Stamp::from_ns(ns),
                        &mut bytes,
                    )
                    .unwrap();
                w.write_to_known_channel(&header, &bytes).unwrap();
            }
        }
    }
    w.finish().unwrap();
    SCANS
}

fn record_throughput(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let scans = scans();
    let mut g = c.benchmark_group("record_throughput");
    for format in [Format::Ros2, Format::Foxglove] {
        let name = format!("{format:?}").to_lowercase();
        g.bench_function(BenchmarkId::new("petrel", &name), |b| {
            b.iter(|| black_box(petrel_sink(dir.path(), format, &scans)))
        });
        let messages = encoded(format, &scans);
        g.bench_function(BenchmarkId::new("raw_mcap_same_bytes", &name), |b| {
            b.iter(|| black_box(raw_mcap(dir.path(), format, &scans, Some(&messages))))
        });
        g.bench_function(BenchmarkId::new("raw_mcap_encoding", &name), |b| {
            b.iter(|| black_box(raw_mcap(dir.path(), format, &scans, None)))
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = common::criterion().sample_size(20);
    targets = record_throughput
}
criterion_main!(benches);
