//! Whether a recording may be written where it is asked to go, before anything runs: `petrel
//! check` and `petrel run` refuse the same paths, with the same words. A device such as
//! `/dev/null` cannot be written as MCAP (the writer seeks back to finish a chunk), and a path
//! that is one of the run's own inputs would be overwritten by the recording.

use std::path::Path;

/// Why a recording cannot be written to `path`, if it cannot; `inputs` are the files the run
/// reads (its configs and overlays).
pub fn target_problem(path: &Path, inputs: &[&Path]) -> Option<String> {
    let shown = path.display();
    if path.as_os_str().as_encoded_bytes().contains(&0) {
        return Some(format!("{shown}: a file name cannot hold a NUL byte"));
    }
    if path.as_os_str().is_empty() {
        return Some("an empty file name; expected a path like out/run.mcap".into());
    }
    if let Ok(meta) = std::fs::metadata(path) {
        if meta.is_dir() {
            return Some(format!(
                "{shown} is a directory; expected a file path like out/run.mcap"
            ));
        }
        if !meta.is_file() {
            return Some(format!(
                "{shown} is not a regular file (a device, FIFO or socket): a recording is written as a file it can seek in"
            ));
        }
        let same = |input: &&&Path| {
            let canonical = |p: &Path| std::fs::canonicalize(p).ok();
            canonical(path).is_some_and(|c| Some(c) == canonical(input))
        };
        if let Some(input) = inputs.iter().find(same) {
            return Some(format!(
                "{shown} is {}, an input of this run: the recording would overwrite it",
                input.display()
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

#[cfg(test)]
mod tests {
    use super::target_problem;
    use std::path::Path;

    #[test]
    fn devices_folders_inputs_and_odd_names_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let config = dir.path().join("robot.ron");
        std::fs::write(&config, "Agent()").unwrap();
        let inputs = [config.as_path()];
        let refused = |p: &Path, want: &str| {
            let problem = target_problem(p, &inputs).unwrap_or_default();
            assert!(problem.contains(want), "{}: {problem:?}", p.display());
        };
        refused(Path::new("/dev/null"), "is not a regular file");
        refused(dir.path(), "is a directory");
        refused(&config, "an input of this run");
        refused(&dir.path().join("robot.ron/x.mcap"), "is not a directory");
        refused(Path::new("out/\0x.mcap"), "NUL byte");
        refused(Path::new(""), "an empty file name");
        for fine in ["run.mcap", "out/deeper/run.mcap"] {
            assert_eq!(
                target_problem(&dir.path().join(fine), &inputs),
                None,
                "{fine}"
            );
        }
    }
}
