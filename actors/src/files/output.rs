//! Where petrel may write a file a user names (a recording, a trace, a snapshot, a compiled
//! plan), judged before anything is written: `petrel check` and `petrel run` refuse the same
//! paths, in the same words.
//!
//! Why: every output is written through a temporary file renamed over the destination (or, for
//! a recording, a file it seeks in), so a device, a FIFO or a symlink at the destination would
//! be replaced by a plain file (`plan compile -o /dev/null` did that), and an output that is
//! one of the run's inputs, or another of its outputs, would destroy it.

use std::path::{Path, PathBuf};

/// Why a file cannot be written to `path`, if it cannot. `inputs` are the files the run or
/// command reads (configs, overlays, the files they name); `example` is a path of the kind
/// expected, for the message (`out/run.mcap`).
pub fn output_problem(path: &Path, inputs: &[&Path], example: &str) -> Option<String> {
    let shown = path.display();
    if path.as_os_str().as_encoded_bytes().contains(&0) {
        return Some(format!("{shown}: a file name cannot hold a NUL byte"));
    }
    if path.as_os_str().is_empty() {
        return Some(format!(
            "an empty file name; expected a path like {example}"
        ));
    }
    if std::fs::symlink_metadata(path).is_ok() {
        let Ok(meta) = std::fs::metadata(path) else {
            return Some(format!(
                "{shown} is a symlink to nothing, or in a loop; expected a file path like {example}"
            ));
        };
        if meta.is_dir() {
            return Some(format!(
                "{shown} is a directory; expected a file path like {example}"
            ));
        }
        if !meta.is_file() {
            return Some(format!(
                "{shown} is not a regular file (a device, FIFO or socket): petrel writes a new file there, which would replace it"
            ));
        }
        if let Some(input) = super::overwrites_an_input(path, inputs) {
            let named = match input == path {
                true => String::new(),
                false => format!(" ({})", input.display()),
            };
            return Some(format!(
                "{shown}{named} is a file this run reads or writes: writing there would overwrite it"
            ));
        }
    }
    // The first ancestor that exists must be a folder the missing ones can be made in.
    let existing = path.ancestors().skip(1).find(|a| {
        let a = if a.as_os_str().is_empty() {
            Path::new(".")
        } else {
            a
        };
        a.exists()
    });
    if let Some(dir) = existing.filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            return Some(format!(
                "{shown}: {} is not a directory, so the file cannot be made in it",
                dir.display()
            ));
        }
    }
    None
}

/// Whether `a` and `b` name the same file, whether or not it exists yet (`out/../x` and `x`,
/// or a symlink and its target).
pub fn same_file(a: &Path, b: &Path) -> bool {
    fn resolved(p: &Path) -> Option<PathBuf> {
        if let Ok(c) = std::fs::canonicalize(p) {
            return Some(c);
        }
        // Not there yet: its folder resolved, and its name.
        let name = p.file_name()?;
        let parent = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        Some(std::fs::canonicalize(parent).ok()?.join(name))
    }
    match (resolved(a), resolved(b)) {
        (Some(x), Some(y)) => x == y,
        _ => std::path::absolute(a).ok() == std::path::absolute(b).ok(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_folders_symlinks_inputs_and_odd_names_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let config = dir.path().join("robot.ron");
        std::fs::write(&config, "Agent()").unwrap();
        let inputs = [config.as_path()];
        let refused = |p: &Path, want: &str| {
            let problem = output_problem(p, &inputs, "out/x").unwrap_or_default();
            assert!(problem.contains(want), "{}: {problem:?}", p.display());
        };
        refused(Path::new("/dev/null"), "is not a regular file");
        refused(dir.path(), "is a directory");
        refused(&config, "a file this run reads or writes");
        let link = dir.path().join("link.ron");
        std::os::unix::fs::symlink(&config, &link).unwrap();
        refused(&link, "a file this run reads or writes");
        let dangling = dir.path().join("dangling");
        std::os::unix::fs::symlink(dir.path().join("nothing"), &dangling).unwrap();
        refused(&dangling, "a symlink to nothing");
        refused(&dir.path().join("robot.ron/x.mcap"), "is not a directory");
        refused(Path::new("out/\0x.mcap"), "NUL byte");
        refused(Path::new(""), "an empty file name");
        for fine in ["run.mcap", "out/deeper/run.mcap"] {
            assert_eq!(
                output_problem(&dir.path().join(fine), &inputs, "out/x"),
                None,
                "{fine}"
            );
        }
    }

    #[test]
    fn the_same_file_is_recognised_before_it_exists() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.mcap");
        let b = dir.path().join("sub/../a.mcap");
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        assert!(same_file(&a, &b));
        assert!(!same_file(&a, &dir.path().join("b.mcap")));
        std::fs::write(&a, b"x").unwrap();
        assert!(same_file(&a, &b));
    }
}
