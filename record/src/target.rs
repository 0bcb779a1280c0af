//! Whether a recording may be written where it is asked to go, before anything runs: `petrel
//! check` and `petrel run` refuse the same paths, with the same words. A device such as
//! `/dev/null` cannot be written as MCAP (the writer seeks back to finish a chunk), and a path
//! that is one of the run's own inputs would be overwritten by the recording.

use std::path::Path;

/// Why a recording cannot be written to `path`, if it cannot; `inputs` are the files the run
/// uses (its configs and overlays, the files they name). The judgement of every output
/// ([`petrel_actors::files::output_problem`], tested there), with a recording's example.
pub fn target_problem(path: &Path, inputs: &[&Path]) -> Option<String> {
    petrel_actors::files::output_problem(path, inputs, "out/run.mcap")
}
