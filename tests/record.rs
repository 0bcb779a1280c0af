//! Recording from the command line: `petrel run --record`, a SIGKILLed recording, `petrel
//! record info`, `petrel replay` and its errors.

#[path = "common/bounded.rs"]
mod bounded;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use bounded::text;
use petrel::record::Recording;

fn petrel(dir: &Path, args: &[&str]) -> Output {
    bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(args)
            .current_dir(dir)
            .env("RUST_LOG", "warn"),
    )
}

fn shipped(name: &str) -> String {
    let path: PathBuf = [env!("CARGO_MANIFEST_DIR"), "configs", name]
        .iter()
        .collect();
    path.display().to_string()
}

const DEMO: &str = r#"Agent(name: "d", modules: [
    (name: "counter", type: "demo.counter", values: {"params/period_ms": 20}),
    (name: "scale", type: "demo.scale", links: {"in/value": "counter/out/value"}),
])"#;

#[cfg(unix)]
#[test]
fn a_sigkilled_recording_opens_up_to_its_last_chunk() {
    use std::io::BufRead;
    use std::sync::mpsc;
    let dir = tempfile::tempdir().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_petrel"))
        .args([
            "run",
            &shipped("navigate.ron"),
            "--record",
            "run.mcap",
            "--no-remote",
            "--for",
            "120s",
        ])
        .current_dir(dir.path())
        .env("RUST_LOG", "info")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("petrel runs");
    let pid = child.id() as libc::pid_t;
    // A run that never reports its first chunk is killed at the deadline, failing the test.
    let (found, watch) = mpsc::channel::<()>();
    let watchdog = std::thread::spawn(move || {
        if watch.recv_timeout(bounded::PROCESS_DEADLINE).is_err() {
            unsafe { libc::kill(pid, libc::SIGKILL) };
        }
    });
    let log = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut seen = false;
    for line in log.lines() {
        if line
            .expect("the log is text")
            .contains("first chunks on disk")
        {
            seen = true;
            break;
        }
    }
    unsafe { libc::kill(pid, libc::SIGKILL) };
    let _ = found.send(());
    watchdog.join().unwrap();
    child.wait().unwrap();
    assert!(seen, "the run never reported its first chunk");
    let path = dir.path().join("run.mcap");
    let bytes = std::fs::read(&path).unwrap();
    let rec = Recording::parse(&bytes);
    assert!(!rec.finished, "killed before its summary");
    assert!(
        rec.chunks >= 1 && !rec.messages.is_empty(),
        "{} chunks",
        rec.chunks
    );
    // The mcap crate's own streaming reader reads it too, up to where it was cut.
    let stream =
        mcap::MessageStream::new_with_options(&bytes, mcap::read::Options::IgnoreEndMagic.into())
            .expect("the file starts like an MCAP file");
    let read = stream.take_while(Result::is_ok).count();
    assert!(read >= rec.messages.len().min(1), "{read}");
    let out = petrel(dir.path(), &["record", "info", "run.mcap", "--salvage"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    assert!(stdout.contains("unfinished"), "{stdout}");
    // Killed files open without `--salvage`: only the chunk being written is lost.
    assert!(petrel(dir.path(), &["record", "info", "run.mcap"])
        .status
        .success());
    assert!(
        stdout.contains("/robot1/robot/out/laserScan") && stdout.contains("foxglove.LaserScan"),
        "{stdout}"
    );
}

#[test]
fn a_recorded_run_is_listed_and_replayed_in_place_of_a_module() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("demo.ron"), DEMO).unwrap();
    let out = petrel(
        dir.path(),
        &[
            "run",
            "demo.ron",
            "--for",
            "1s",
            "--no-remote",
            "--record",
            "demo.mcap",
            "--record-format",
            "ros2",
        ],
    );
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    assert!(
        stdout.contains("recorded ") && stdout.contains("demo.mcap (dropped 0)"),
        "{stdout}"
    );
    let info = petrel(dir.path(), &["record", "info", "demo.mcap"]);
    let listing = text(&info.stdout);
    assert!(info.status.success(), "{listing}");
    assert!(
        listing.contains("finished (summary and index written)"),
        "{listing}"
    );
    assert!(listing.contains("format:    ros2"), "{listing}");
    assert!(listing.contains("/d/counter/out/value"), "{listing}");
    // The run's summary counts the channels a reader finds (not those that got no message).
    let said = stdout
        .split_once(" messages on ")
        .and_then(|(_, rest)| rest.split_once(" channels"))
        .map(|(n, _)| n.to_string());
    let listed = listing
        .lines()
        .find_map(|l| l.strip_prefix("channels:"))
        .map(|n| n.trim().to_string());
    assert!(said.is_some() && said == listed, "{stdout}\n{listing}");
    let out = petrel(
        dir.path(),
        &[
            "replay",
            "demo.mcap",
            "demo.ron",
            "--replace",
            "counter",
            "--rate",
            "max",
            "--no-remote",
        ],
    );
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    assert!(stdout.contains("the recording is replayed"), "{stdout}");
    assert!(
        stdout.contains("replay") && !stdout.contains("counter  "),
        "counter not started: {stdout}"
    );
}

#[test]
fn a_recorded_run_holds_the_first_items_its_modules_push() {
    let dir = tempfile::tempdir().unwrap();
    // The first batch goes out 1 ms after the start: only a recorder attached before the
    // modules start sees it. The queue holds the whole run (200 batches of 50), so a tap that
    // lags on a loaded machine loses nothing: with the default 64 a second batch before the
    // tap's first read overwrote the oldest items (a tap that lags drops, by design).
    let config = r#"Agent(name: "p", modules: [
        (name: "producer", type: "demo.producer", values: {"params/period_ms": 1, "params/batch": 50},
         capacities: {"out/items": 20000}),
    ])"#;
    std::fs::write(dir.path().join("producer.ron"), config).unwrap();
    let out = petrel(
        dir.path(),
        &[
            "run",
            "producer.ron",
            "--for",
            "200ms",
            "--no-remote",
            "--record",
            "producer.mcap",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let rec = Recording::open(&dir.path().join("producer.mcap"), false).unwrap();
    let (&id, _) = rec
        .channels
        .iter()
        .find(|(_, c)| c.topic == "/p/producer/out/items")
        .expect("the items are recorded");
    let sequences: Vec<u32> = rec.messages_of(id).map(|m| m.sequence).collect();
    assert!(sequences.len() >= 50, "{} items", sequences.len());
    assert_eq!(
        sequences[..50],
        (0..50).collect::<Vec<u32>>(),
        "the first batch, from item 0"
    );
}

#[test]
fn bad_recordings_and_mismatched_configs_are_errors_naming_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let without_counter = DEMO.replace(
        r#"Agent(name: "d","#,
        r#"Agent(name: "d", record: (file: "part.mcap", exclude: ["counter/out/*"]),"#,
    );
    std::fs::write(dir.path().join("demo.ron"), DEMO).unwrap();
    std::fs::write(dir.path().join("part.ron"), without_counter).unwrap();
    let out = petrel(
        dir.path(),
        &["run", "part.ron", "--for", "500ms", "--no-remote"],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = petrel(
        dir.path(),
        &[
            "replay",
            "part.mcap",
            "demo.ron",
            "--replace",
            "counter",
            "--no-remote",
        ],
    );
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(2), "{stdout}{}", text(&out.stderr));
    assert!(
        stdout.contains("input `scale/in/value` (f64) reads `counter/out/value`, and the recording has no channel for it"),
        "{stdout}"
    );
    // Cut in the middle: an error naming the offset, unless salvaged.
    let bytes = std::fs::read(dir.path().join("part.mcap")).unwrap();
    std::fs::write(dir.path().join("cut.mcap"), &bytes[..bytes.len() * 2 / 3]).unwrap();
    let out = petrel(dir.path(), &["record", "info", "cut.mcap"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("cut.mcap: at byte ") && stderr.contains("expected"),
        "{stderr}"
    );
    std::fs::write(dir.path().join("junk.mcap"), b"not a recording at all").unwrap();
    let out = petrel(
        dir.path(),
        &[
            "replay",
            "junk.mcap",
            "demo.ron",
            "--replace",
            "counter",
            "--no-remote",
        ],
    );
    // Refused by the check before anything runs, as `petrel check` would.
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("junk.mcap: at byte 0: expected the MCAP magic bytes")
            && stderr.contains("nothing was started"),
        "{stderr}"
    );
    let out = petrel(
        dir.path(),
        &[
            "replay",
            "part.mcap",
            "demo.ron",
            "--replace",
            "counter",
            "--rate",
            "fast",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("expected a factor (e.g. 2) or `max`, got `fast`"),
        "{}",
        text(&out.stderr)
    );
    let bad = DEMO.replace(
        r#"Agent(name: "d","#,
        "Agent(name: \"d\",\n  record: (max_duration_s: 0.1),",
    );
    std::fs::write(dir.path().join("bad.ron"), bad).unwrap();
    let out = petrel(dir.path(), &["check", "bad.ron"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("bad.ron:2:")
            && stderr.contains("max_duration_s: expected seconds in [1, 1e9], got 0.1"),
        "{stderr}"
    );
}

/// The compression of every chunk of a recording, read by the `mcap` crate's own reader, and
/// how many messages that reader decompresses from them.
fn chunks(path: &Path) -> (Vec<String>, usize) {
    let bytes = std::fs::read(path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    let compressions = summary
        .chunk_indexes
        .iter()
        .map(|c| c.compression.clone())
        .collect();
    let mut messages = 0;
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        message.expect("a readable message");
        messages += 1;
    }
    (compressions, messages)
}

#[test]
fn the_chunk_compression_is_chosen_on_the_command_line_or_in_the_section_and_checked() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("demo.ron"), DEMO).unwrap();
    let record = |file: &str, extra: &[&str]| {
        let mut args = vec!["run", "demo.ron", "--for", "300ms", "--no-remote"];
        args.extend(["--record", file]);
        args.extend(extra);
        let out = petrel(dir.path(), &args);
        assert!(out.status.success(), "{}", text(&out.stderr));
        chunks(&dir.path().join(file))
    };
    let (compressions, messages) = record("default.mcap", &[]);
    assert!(messages > 0 && !compressions.is_empty());
    assert!(compressions.iter().all(|c| c == "zstd"), "{compressions:?}");
    let (compressions, messages) = record("lz4.mcap", &["--record-compression", "lz4"]);
    assert!(messages > 0 && !compressions.is_empty());
    assert!(compressions.iter().all(|c| c == "lz4"), "{compressions:?}");

    let in_section = DEMO.replace(
        r#"Agent(name: "d","#,
        r#"Agent(name: "d", record: (file: "section.mcap", compression: "lz4"),"#,
    );
    std::fs::write(dir.path().join("section.ron"), in_section).unwrap();
    let out = petrel(
        dir.path(),
        &["run", "section.ron", "--for", "300ms", "--no-remote"],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let (compressions, _) = chunks(&dir.path().join("section.mcap"));
    assert!(compressions.iter().all(|c| c == "lz4"), "{compressions:?}");

    let bad = DEMO.replace(
        r#"Agent(name: "d","#,
        "Agent(name: \"d\",\n  record: (compression: \"gzip\"),",
    );
    std::fs::write(dir.path().join("bad.ron"), bad).unwrap();
    for args in [
        &["check", "bad.ron"][..],
        &["run", "bad.ron", "--for", "100ms", "--no-remote"],
    ] {
        let out = petrel(dir.path(), args);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains("compression: expected `zstd` or `lz4`, got `gzip`"),
            "{args:?}: {stderr}"
        );
    }
    let out = petrel(dir.path(), &["check", "bad.ron"]);
    assert!(
        text(&out.stderr).contains("bad.ron:2:"),
        "{}",
        text(&out.stderr)
    );
    let out = petrel(
        dir.path(),
        &[
            "run",
            "demo.ron",
            "--record",
            "x.mcap",
            "--record-compression",
            "gzip",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("gzip"), "{}", text(&out.stderr));
    assert!(!dir.path().join("x.mcap").exists());
}
