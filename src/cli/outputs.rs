//! The files `petrel run` writes (`--record` or `record.file`, `--trace-out`, `--snapshot-out`),
//! judged together before anything is written or started.
//!
//! Each must be a place a new file can go (not a device, FIFO or folder), none may be a file
//! the run uses (its configs, overlays, and the worlds, rules and plans they name), and no two
//! may be the same file. Before this, `--trace-out` truncated a world file the run was about to
//! read, and `--record a --trace-out a` left a corrupt recording.

use std::path::{Path, PathBuf};

use petrel_actors::files;

use super::RunArgs;

/// Why the outputs of `args` cannot be written as asked, given the files the run uses and the
/// recording's path (already checked on its own by `record::options`).
pub(crate) fn problem(args: &RunArgs, used: &[&Path], recording: Option<&Path>) -> Option<String> {
    let mut outputs: Vec<(&str, &Path)> = Vec::new();
    if let Some(trace) = &args.trace_out {
        if let Some(p) = files::output_problem(trace, used, "out/trace.json") {
            return Some(format!("--trace-out: {p}"));
        }
        outputs.push(("--trace-out", trace));
    }
    if let Some(snapshot) = &args.snapshot_out {
        if let Some(p) = files::output_problem(snapshot, used, "out/snapshot.ron") {
            return Some(format!("--snapshot-out: {p}"));
        }
        // Found now, not after the whole run: a folder that is missing or cannot be written.
        if let Err(e) = files::check_writable(snapshot) {
            return Some(format!("--snapshot-out {}: {e}", snapshot.display()));
        }
        outputs.push(("--snapshot-out", snapshot));
    }
    let record_flag = match args.record {
        Some(_) => "--record",
        None => "the config's record.file",
    };
    outputs.extend(recording.map(|r| (record_flag, r)));
    for (i, (flag, path)) in outputs.iter().enumerate() {
        if let Some((other, _)) = outputs[i + 1..]
            .iter()
            .find(|(_, p)| files::same_file(path, p))
        {
            return Some(format!(
                "{flag} and {other} both name {}: each output needs a file of its own",
                path.display()
            ));
        }
    }
    None
}

/// `used` as borrowed paths.
pub(crate) fn borrowed(used: &[PathBuf]) -> Vec<&Path> {
    used.iter().map(PathBuf::as_path).collect()
}
