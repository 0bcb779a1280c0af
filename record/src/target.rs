//! Whether a recording may be written where it is asked to go, before anything runs: `petrel
//! check` and `petrel run` refuse the same paths, with the same words. A device such as
//! `/dev/null` cannot be written as MCAP (the writer seeks back to finish a chunk), and a path
//! that is one of the run's own inputs would be overwritten by the recording.

use std::path::Path;

/// Why a recording cannot be written to `path`, if it cannot; `inputs` are the files the run
/// reads (its configs and overlays).
pub fn target_problem(path: &Path, inputs: &[&Path]) -> Option<String> {
    petrel_actors::files::output_problem(path, inputs, "out/run.mcap")
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
        refused(&config, "a file this run reads or writes");
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
