//! The other tools: `modules`, `plan simulate`/`check`, `graph`, bad arguments, a closed pipe.

use std::process::{Command, Output};

use crate::bounded::{self, petrel, text};

#[test]
fn modules_lists_and_describes_types() {
    let list = text(&petrel(&["modules"]).stdout);
    assert!(
        list.contains("demo.scale") && list.contains("demo.consumer"),
        "{list}"
    );
    let out = petrel(&["modules", "describe", "demo.scale"]);
    let described = text(&out.stdout);
    assert!(
        described.lines().any(|l| l.split_whitespace().take(5).eq([
            "params/factor",
            "param",
            "f64",
            "-1e9..=1e9",
            "1.0"
        ])),
        "{described}"
    );
    let unknown = petrel(&["modules", "describe", "demo.scal"]);
    assert_eq!(unknown.status.code(), Some(2));
    assert!(text(&unknown.stderr).contains("did you mean demo.scale?"));
    let control = petrel(&["modules", "describe", "demo.scale\u{1}"]);
    assert_eq!(control.status.code(), Some(2));
    assert!(
        text(&control.stderr).contains("unknown module type `demo.scaleU+0001`"),
        "{}",
        text(&control.stderr)
    );
}

#[test]
fn bad_arguments_are_explained() {
    let out = petrel(&["run", "configs/pipeline.ron", "--for", "soon"]);
    assert_eq!(out.status.code(), Some(2));
    // The wording is clap's: only that it names the option and the value is ours to hold.
    let said = text(&out.stderr);
    assert!(said.contains("'soon'") && said.contains("--for"), "{said}");
    let missing = petrel(&["run", "configs/nope.ron"]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(text(&missing.stderr).starts_with("configs/nope.ron: error: cannot read config:"));
}

#[test]
fn plan_simulate_prints_one_json_line_per_step() {
    let out = petrel(&["plan", "simulate", "plans/tests/fixtures/editor_three.pnml"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(
        text(&out.stdout),
        concat!(
            "{\"step\":0,\"marking\":{\"P\":1}}\n",
            "{\"step\":1,\"calls\":[\"azione1.start\"],\"marking\":{\"azione1.ex\":1}}\n",
            "{\"step\":2,\"calls\":[],\"marking\":{\"azione1.ex\":1}}\n",
            "{\"step\":3,\"calls\":[\"azione1.end\"],\"marking\":{\"goal\":1}}\n",
            "{\"result\":\"goal\",\"step\":3}\n",
        )
    );
    let broken = petrel(&["plan", "check", "plans/tests/fixtures/malformed.pnml"]);
    assert_eq!(broken.status.code(), Some(2));
    assert!(
        text(&broken.stderr).starts_with("error: "),
        "{}",
        text(&broken.stderr)
    );
}

#[test]
fn plan_check_stops_at_max_states_and_says_how_to_go_further() {
    let out = petrel(&[
        "plan",
        "check",
        "plans/tests/fixtures/delivery.plan",
        "--max-states",
        "3",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("(3 markings explored, incomplete)")
            && stdout.contains("warning[incomplete]: stopped after exploring 3 markings (the limit); raise --max-states"),
        "{stdout}"
    );
    let full = petrel(&["plan", "check", "plans/tests/fixtures/delivery.plan"]);
    assert!(
        !text(&full.stdout).contains("incomplete"),
        "{}",
        text(&full.stdout)
    );
}

#[test]
fn graph_draws_modules_and_links_as_dot() {
    let out = petrel(&["graph", "configs/team/filter.ron"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let dot = text(&out.stdout);
    assert!(dot.starts_with("digraph \"filter\" {"), "{dot}");
    // One box per module, one dashed box per module of another agent that a link reads.
    assert!(dot.contains("[ label = \"scale\\ndemo.scale\"]"), "{dot}");
    assert!(
        dot.contains("[ label = \"sensor/producer\", style = dashed]"),
        "{dot}"
    );
    // A remote queue link is bold (a queue) and dashed (remote).
    assert!(
        dot.contains("label = \"out/items → in/items\", style = \"bold,dashed\""),
        "{dot}"
    );
    assert_eq!(dot.matches(" -> ").count(), 2, "{dot}");

    let local = text(&petrel(&["graph", "configs/pipeline.ron"]).stdout);
    assert_eq!(local.matches(" -> ").count(), 3, "3 links: {local}");
    assert!(!local.contains("dashed"), "no remote link: {local}");

    let out = petrel(&["graph", "configs/does-not-exist.ron"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("does-not-exist.ron"));
}

/// Runs petrel with its standard output a pipe whose reading end is already closed, so every
/// write to it fails (as `petrel … | head -1` after `head` has exited).
fn petrel_into_a_closed_pipe(args: &[&str]) -> Output {
    use std::os::fd::{FromRawFd, OwnedFd};
    let mut fds = [0; 2];
    // SAFETY: `pipe` fills two fresh descriptors; the reading one is closed at once and the
    // writing one is owned by the `Stdio` handed to the child.
    let stdout = unsafe {
        assert_eq!(libc::pipe(fds.as_mut_ptr()), 0, "pipe");
        libc::close(fds[0]);
        std::process::Stdio::from(OwnedFd::from_raw_fd(fds[1]))
    };
    let child = Command::new(env!("CARGO_BIN_EXE_petrel"))
        .args(args)
        .env("RUST_LOG", "info")
        .stdin(std::process::Stdio::null())
        .stdout(stdout)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    bounded::wait_within_deadline(child, &format!("petrel {args:?}"))
}

/// Every command that prints and ends, with its standard output on `/dev/full`: each write
/// fails with "no space left", as on a full disk.
#[test]
fn a_standard_output_that_cannot_be_written_is_an_error_not_a_panic_or_a_success() {
    for args in [
        &["check", "configs/pipeline.ron"][..],
        &["plan", "dot", "plans/tests/fixtures/delivery.plan"],
        &["plan", "check", "plans/tests/fixtures/delivery.plan"],
        &["plan", "simulate", "plans/tests/fixtures/delivery.plan"],
        &["graph", "configs/navigate.ron"],
        &["modules"],
        &["modules", "describe", "sim.world"],
    ] {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let child = Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(args)
            .stdin(std::process::Stdio::null())
            .stdout(full)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let out = bounded::wait_within_deadline(child, &format!("petrel {args:?}"));
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(74), "{args:?}: {err}");
        assert!(
            err.contains("error: cannot write to standard output: No space left on device"),
            "{args:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

#[test]
fn a_closed_standard_output_ends_tools_quietly_and_a_run_goes_on() {
    use std::os::unix::process::ExitStatusExt;
    for args in [
        &["check", "configs/pipeline.ron"][..],
        &["plan", "dot", "plans/tests/fixtures/delivery.plan"],
        &["plan", "check", "plans/tests/fixtures/delivery.plan"],
        &["graph", "configs/navigate.ron"],
        &["modules"],
    ] {
        let out = petrel_into_a_closed_pipe(args);
        let err = text(&out.stderr);
        assert_eq!(
            out.status.signal(),
            Some(libc::SIGPIPE),
            "{args:?} ends by SIGPIPE like other Unix tools: {:?} {err}",
            out.status
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    // A run keeps going to its end (cleanup, summary attempt) with its printer quiet.
    let out =
        petrel_into_a_closed_pipe(&["run", "configs/pipeline.ron", "--for", "1s", "--no-remote"]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert_eq!(
        err.matches("standard output was closed: nothing more is printed")
            .count(),
        1,
        "said once: {err}"
    );
    assert!(
        !err.contains("panicked") && !err.contains("module failed"),
        "{err}"
    );
}
