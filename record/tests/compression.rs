//! petrel's reader against chunks compressed every way the `mcap` crate writes them: zstd
//! (what petrel writes), LZ4 (what it wrote before) and none.

use std::collections::BTreeMap;
use std::io::Cursor;

use mcap::records::MessageHeader;
use mcap::{Compression, WriteOptions};
use petrel_record::Recording;

const MESSAGES: u32 = 300;

/// A message that compresses (a run of one value) but differs from the next.
fn payload(i: u32) -> Vec<u8> {
    let mut bytes = vec![(i % 7) as u8; 3000];
    bytes.extend_from_slice(&i.to_le_bytes());
    bytes
}

/// A file of [`MESSAGES`] messages on one channel in chunks of 64 KiB.
fn file(compression: Option<Compression>) -> Vec<u8> {
    let mut w = WriteOptions::new()
        .compression(compression)
        .chunk_size(Some(64 * 1024))
        .create(Cursor::new(Vec::new()))
        .unwrap();
    let schema = w.add_schema("Blob", "jsonschema", b"{}").unwrap();
    let channel = w
        .add_channel(schema, "/blob", "json", &BTreeMap::new())
        .unwrap();
    for i in 0..MESSAGES {
        let header = MessageHeader {
            channel_id: channel,
            sequence: i,
            log_time: u64::from(i) * 1000,
            publish_time: u64::from(i) * 1000,
        };
        w.write_to_known_channel(&header, &payload(i)).unwrap();
    }
    w.finish().unwrap();
    w.into_inner().into_inner()
}

#[test]
fn zstd_lz4_and_plain_chunks_read_back_every_message() {
    for (compression, name) in [
        (Some(Compression::Zstd), "zstd"),
        (Some(Compression::Lz4), "lz4"),
        (None, ""),
    ] {
        let bytes = file(compression);
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        assert!(summary.chunk_indexes.len() > 1, "{name}: several chunks");
        assert!(summary.chunk_indexes.iter().all(|c| c.compression == name));
        let rec = Recording::parse(&bytes);
        assert!(rec.finished, "{name}");
        assert_eq!(rec.problem, None, "{name}");
        assert_eq!(rec.chunks, summary.chunk_indexes.len(), "{name}");
        let data: Vec<Vec<u8>> = rec.messages.iter().map(|m| m.data.clone()).collect();
        let wanted: Vec<Vec<u8>> = (0..MESSAGES).map(payload).collect();
        assert!(data == wanted, "{name}: the messages differ");
    }
}

#[test]
fn a_damaged_zstd_chunk_is_a_problem_at_its_offset_not_a_panic() {
    let bytes = file(Some(Compression::Zstd));
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let chunk = &summary.chunk_indexes[1];
    // Overwrite the middle of the second chunk's compressed data.
    let mut damaged = bytes.clone();
    let end = (chunk.chunk_start_offset + chunk.chunk_length) as usize;
    let middle = end - chunk.compressed_size as usize / 2;
    damaged[middle..middle + 16].fill(0xAB);
    let rec = Recording::parse(&damaged);
    let problem = rec.problem.expect("the damage is found");
    assert_eq!(problem.offset, chunk.chunk_start_offset, "{problem:?}");
    assert!(problem.expected.contains("zstd"), "{problem:?}");
    // The first chunk still reads.
    assert!(rec.chunks >= 1);
    assert!(!rec.messages.is_empty());
}

#[test]
fn a_chunk_whose_bytes_changed_but_still_read_is_refused_by_its_crc() {
    // A plain chunk: a flipped byte inside a message leaves every record well formed, so only
    // the CRC the writer stored tells the message from the one recorded.
    let bytes = file(None);
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let chunk = &summary.chunk_indexes[1];
    let mut damaged = bytes.clone();
    let end = (chunk.chunk_start_offset + chunk.chunk_length) as usize;
    damaged[end - 100] ^= 0x55;
    let rec = Recording::parse(&damaged);
    let problem = rec.problem.expect("the damage is found");
    assert_eq!(problem.offset, chunk.chunk_start_offset, "{problem:?}");
    assert!(problem.expected.contains("CRC-32"), "{problem:?}");
    // What came before the damaged chunk is kept (for `--salvage`), nothing of it after.
    let first = &summary.chunk_indexes[0];
    let before = rec.messages.len();
    assert!(
        before > 0 && rec.chunks == 1,
        "{before} messages, {} chunks",
        rec.chunks
    );
    assert!(rec
        .messages
        .iter()
        .all(|m| m.log_ns <= first.message_end_time));
}
