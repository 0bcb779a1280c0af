//! `petrel check` agrees with `petrel run` (issue 19): every config of `tests/corpus/` goes
//! through both, as real processes. What `run` refuses, `check` refused first with the same
//! error; what `check` accepts, `run` starts and runs with no module failing. Each file's first
//! line says which it must be (see `tests/corpus/README.md`).

#[path = "common/bounded.rs"]
mod bounded;

use std::path::{Path, PathBuf};

use bounded::{petrel, text};

#[derive(Debug, Clone, Copy, PartialEq)]
enum Expect {
    Refused,
    Runs,
}

/// The corpus configs with what each must do, read from its first line.
fn corpus() -> Vec<(PathBuf, Expect)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus");
    let mut cases: Vec<(PathBuf, Expect)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .map(|path| {
            let text = std::fs::read_to_string(&path).unwrap();
            let first = text.trim_start_matches('\u{feff}').lines().next().unwrap_or("");
            let expect = match first.trim() {
                "// expect: refused" => Expect::Refused,
                "// expect: runs" => Expect::Runs,
                other => panic!("{}: first line `{other}` says neither `// expect: refused` nor `// expect: runs`", path.display()),
            };
            (path, expect)
        })
        .collect();
    cases.sort_by(|a, b| a.0.cmp(&b.0));
    cases
}

/// The first `error:` line a command printed.
fn first_error(stderr: &str) -> Option<&str> {
    stderr.lines().find(|l| l.contains(": error: "))
}

/// What is wrong with one case, if anything.
fn disagreement(path: &Path, expect: Expect) -> Option<String> {
    let file = path.to_str().unwrap();
    let check = petrel(&["check", file]);
    let run = petrel(&["run", file, "--for", "300ms", "--no-remote"]);
    let (check_err, run_err) = (text(&check.stderr), text(&run.stderr));
    let (check_code, run_code) = (check.status.code(), run.status.code());
    let name = path.file_name().unwrap().to_string_lossy();
    match expect {
        Expect::Refused => {
            let Some(error) = first_error(&check_err) else {
                return Some(format!(
                    "{name}: check accepted it (exit {check_code:?}): {check_err}"
                ));
            };
            if check_code != Some(2) || run_code != Some(2) {
                return Some(format!(
                    "{name}: check exit {check_code:?}, run exit {run_code:?} (both should be 2)\ncheck: {check_err}\nrun: {run_err}"
                ));
            }
            if !run_err.contains(error) {
                return Some(format!(
                    "{name}: run refused it differently\ncheck: {error}\nrun: {run_err}"
                ));
            }
            if !error.starts_with(file) && !error.contains("/tests/corpus/files/") {
                return Some(format!("{name}: the error names no file: {error}"));
            }
        }
        Expect::Runs => {
            let summary = text(&run.stdout);
            if check_code != Some(0) || run_code != Some(0) {
                return Some(format!(
                    "{name}: check exit {check_code:?}, run exit {run_code:?} (both should be 0)\ncheck: {check_err}\nrun: {run_err}"
                ));
            }
            if !summary.contains(" 0 failures") {
                return Some(format!("{name}: a module failed: {summary}"));
            }
        }
    }
    None
}

#[test]
fn check_refuses_what_run_would_refuse_and_run_starts_what_check_accepts() {
    let cases = corpus();
    assert!(cases.len() >= 20, "the corpus is there: {cases:?}");
    for expect in [Expect::Refused, Expect::Runs] {
        assert!(
            cases.iter().any(|(_, e)| *e == expect),
            "the corpus has {expect:?} cases"
        );
    }
    // Two at a time: each case starts two processes, and the machine may have two cores.
    let problems: Vec<String> = cases
        .chunks(2)
        .flat_map(|pair| {
            std::thread::scope(|s| {
                let running: Vec<_> = pair
                    .iter()
                    .map(|(path, expect)| s.spawn(move || disagreement(path, *expect)))
                    .collect();
                running
                    .into_iter()
                    .filter_map(|h| h.join().unwrap())
                    .collect::<Vec<_>>()
            })
        })
        .collect();
    assert!(problems.is_empty(), "{}", problems.join("\n\n"));
}
