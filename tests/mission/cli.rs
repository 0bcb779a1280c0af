//! The shipped mission demo, run by the real binary from the repository root.

use std::process::Command;

#[test]
fn the_mission_demo_ends_by_itself_at_the_goal_with_exit_0() {
    let out = crate::bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(["run", "configs/mission-demo.ron"])
            .env("RUST_LOG", "warn"),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{:?}\n{stdout}\n{stderr}",
        out.status
    );
    assert!(stdout.contains("mission `demo` ended: goal"), "{stdout}");
    assert!(
        stdout.contains("agent robot1: 7 modules, 0 failures"),
        "{stdout}"
    );
    let row = stdout
        .lines()
        .find(|l| l.contains("mission.pnp"))
        .unwrap_or("");
    assert!(row.contains("stopped"), "{stdout}");
    assert!(
        !stderr.contains("WARN") && !stderr.contains("ERROR"),
        "{stderr}"
    );
}

#[test]
fn check_accepts_the_mission_demo() {
    let out = crate::bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel")).args(["check", "configs/mission-demo.ron"]),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn plan_simulate_exit_codes_say_goal_fail_or_still_running_and_read_scripts_from_stdin() {
    use std::io::Write;
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("p.plan");
    std::fs::write(&plan, "a; b").unwrap();
    let plan = plan.display().to_string();
    let simulate = |script: &str, steps: &str| {
        let mut child = Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(["plan", "simulate", &plan, "--script", "-", "--steps", steps])
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .spawn()
            .expect("petrel runs");
        child
            .stdin
            .take()
            .unwrap()
            .write_all(script.as_bytes())
            .unwrap();
        let out = crate::bounded::wait_within_deadline(child, "petrel plan simulate");
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
        )
    };
    assert_eq!(simulate("", "100").0, Some(0));
    let (code, out) = simulate("fail b 1", "100");
    assert_eq!(code, Some(1), "an unhandled failure fails the plan: {out}");
    let (code, out) = simulate("", "2");
    assert_eq!(code, Some(4), "steps ran out: {out}");
    assert!(
        out.ends_with("{\"result\":\"running\",\"step\":2}\n"),
        "{out}"
    );
    let help = crate::bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel")).args(["plan", "simulate", "--help"]),
    );
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(
        help.contains("--script <FILE|->") && help.contains("4 when --steps runs out"),
        "{help}"
    );
}

#[test]
fn a_run_stopped_by_for_while_the_mission_runs_says_so_and_exits_4() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("slow.plan"), "wait_60").unwrap();
    let config = dir.path().join("slow.ron");
    std::fs::write(
        &config,
        r#"Agent(name: "r1", modules: [
            (name: "m", type: "mission.pnp", values: {"params/plan": "slow.plan", "params/is_mission": true}),
        ])"#,
    )
    .unwrap();
    let (out, stdout) = run_for(&config, "300ms");
    assert_eq!(out.status.code(), Some(4), "{stdout}");
    assert!(stdout.contains("mission still running: r1/m"), "{stdout}");
}

#[test]
fn a_give_up_exits_3_naming_the_agent_wide_limit_even_though_a_module_failed() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("giveup.ron");
    std::fs::write(
        &config,
        r#"Agent(name: "r1", supervision: (max_restarts: 2, within_s: 10.0, backoff: (min_ms: 5, max_ms: 5, jitter: 0.0)),
            modules: [
                (name: "producer", type: "demo.producer", values: {"params/period_ms": 5}),
                (name: "chaos", type: "demo.chaos", values: {"params/targets": "producer", "params/faults": "panic",
                                                            "params/mean_interval_ms": 50, "params/seed": 7}),
            ])"#,
    )
    .unwrap();
    let (out, stdout) = run_for(&config, "20s");
    assert_eq!(out.status.code(), Some(3), "{stdout}");
    assert!(
        stdout.contains("the agent-wide restart limit (supervision max_restarts: 2 within_s: 10) was reached; restarts so far: `producer` 2"),
        "{stdout}"
    );
}

#[test]
fn check_warns_about_a_binding_no_action_uses_with_the_nearest_name() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("m.plan"), "report_dock").unwrap();
    let config = dir.path().join("m.ron");
    std::fs::write(
        &config,
        r#"Agent(name: "r1", modules: [
            (name: "m", type: "mission.pnp", values: {"params/plan": "m.plan", "params/allow_unbound": true,
             "params/actions": {"reprot_dock": (finished: "true")}}),
        ])"#,
    )
    .unwrap();
    let out = crate::bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel")).args(["check", &config.display().to_string()]),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "a warning, not an error: {stderr}");
    assert!(
        stderr.contains("warning: ")
            && stderr.contains("m/params/actions[\"reprot_dock\"]: the plan has no action `reprot_dock` (nor `reprot_dock_...`); did you mean `report_dock`?"),
        "{stderr}"
    );
    // A condition the plan waits on that nothing binds: legal (a tool may set it), but said.
    std::fs::write(dir.path().join("m.plan"), "< door ? report_dock >").unwrap();
    let out = crate::bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel")).args(["check", &config.display().to_string()]),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "a warning, not an error: {stderr}");
    assert!(
        stderr.contains("warning: m/params/conditions: the plan's condition `door` is not bound; it is read from `m/in/conditions`"),
        "{stderr}"
    );
}

#[test]
fn check_shows_what_plan_check_finds_and_refuses_its_errors() {
    let dir = tempfile::tempdir().unwrap();
    // `work.end` also waits for a place nothing ever marks: the plan gets stuck.
    let net = |arcs: &str| {
        format!(
            r#"<pnml><net id="n" type="PTNet">
  <place id="p1"><name><value>init</value></name><initialMarking><value>1</value></initialMarking></place>
  <place id="p2"><name><value>work.exec</value></name></place>
  <place id="p3"><name><value>goal</value></name></place>
  <place id="p4"><name><value>never</value></name></place>
  <transition id="t1"><name><value>work.start</value></name></transition>
  <transition id="t2"><name><value>work.end</value></name></transition>
  <arc id="a1" source="p1" target="t1"/><arc id="a2" source="t1" target="p2"/>
  <arc id="a4" source="t2" target="p3"/>{arcs}
</net></pnml>"#
        )
    };
    let stuck =
        net(r#"<arc id="a3" source="p2" target="t2"/><arc id="a5" source="p4" target="t2"/>"#);
    std::fs::write(dir.path().join("stuck.pnml"), stuck).unwrap();
    // Without its input arcs `work.end` fires at every step: an error.
    std::fs::write(dir.path().join("source.pnml"), net("")).unwrap();
    let check = |plan: &str| {
        let config = dir.path().join(format!("{plan}.ron"));
        let text = format!(
            r#"Agent(name: "r1", modules: [
            (name: "m", type: "mission.pnp", values: {{"params/plan": "{plan}.pnml", "params/allow_unbound": true}}),
        ])"#
        );
        std::fs::write(&config, text).unwrap();
        crate::bounded::output_within_deadline(
            Command::new(env!("CARGO_BIN_EXE_petrel"))
                .args(["check", &config.display().to_string()]),
        )
    };
    let out = check("stuck");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "warnings, not errors: {stderr}");
    assert!(
        stderr.contains("warning: m/params/plan: ")
            && stderr.contains("stuck.pnml: warning[deadlock]: the plan can get stuck in a marking that is neither goal nor fail: {'work.exec': 1}"),
        "{stderr}"
    );
    let out = check("source");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("error: m/params/plan: ")
            && stderr.contains("source.pnml: error[source-transition]: transition 't2' ('work.end') has no input place"),
        "{stderr}"
    );
}

#[test]
fn a_simulator_drives_mission_time_without_a_link() {
    // wait_5 is 5 simulated seconds: half a second of wall time at time_scale 10.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("w.plan"), "wait_5").unwrap();
    let world = std::path::Path::new("configs/worlds/cluttered.txt")
        .canonicalize()
        .unwrap();
    let config = dir.path().join("w.ron");
    std::fs::write(
        &config,
        format!(
            r#"Agent(name: "r1", modules: [
            (name: "robot", type: "sim.world", values: {{"params/world": {:?}, "params/time_scale": 10.0}}),
            (name: "m", type: "mission.pnp", values: {{"params/plan": "w.plan", "params/is_mission": true}}),
        ])"#,
            world.display().to_string()
        ),
    )
    .unwrap();
    let out = crate::bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args([
                "run",
                &config.display().to_string(),
                "--for",
                "3s",
                "--no-remote",
            ])
            .env("RUST_LOG", "warn"),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "ended before --for: {stdout}");
    assert!(stdout.contains("mission `w` ended: goal"), "{stdout}");
}

/// `petrel run CONFIG --for DURATION --no-remote` (logs off), under the process deadline;
/// returns the output and its standard output as text.
fn run_for(config: &std::path::Path, duration: &str) -> (std::process::Output, String) {
    let out = crate::bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args([
                "run",
                &config.display().to_string(),
                "--for",
                duration,
                "--no-remote",
            ])
            .env("RUST_LOG", "off"),
    );
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    (out, stdout)
}

/// `petrel run CONFIG --no-remote ARGS` with warnings logged, in the config's directory (which
/// holds its runtime records too); its exit code and standard error.
fn run_warning(config: &std::path::Path, args: &[&str]) -> (Option<i32>, String) {
    let dir = config.parent().unwrap();
    let out = crate::bounded::output_within_deadline(
        Command::new(env!("CARGO_BIN_EXE_petrel"))
            .args(["run", config.to_str().unwrap(), "--no-remote"])
            .args(args)
            .env("PETREL_RUNTIME_DIR", dir)
            .env("RUST_LOG", "warn"),
    );
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    (out.status.code(), stderr)
}

/// A mission whose `state/memory` is of another plan (a snapshot whose plan file was renamed
/// or replaced) starts the plan over, and says so rather than drop the memory in silence.
#[test]
fn a_memory_of_another_plan_is_not_used_and_the_run_says_so() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("b.plan"), "say_hello").unwrap();
    let config = dir.path().join("r.ron");
    std::fs::write(
        &config,
        r#"Agent(name: "r1", modules: [(name: "m", type: "mission.pnp", values: {
            "params/plan": "b.plan", "params/is_mission": true,
            "state/memory": (plan: "a", marking: [1, 0]),
        })])"#,
    )
    .unwrap();
    let (code, stderr) = run_warning(&config, &[]);
    assert_eq!(code, Some(0), "the plan ran anew: {stderr}");
    assert!(
        stderr.contains("state/memory is of another plan: not used; the plan starts over")
            && stderr.contains("kept=a")
            && stderr.contains("plan=b"),
        "{stderr}"
    );
}

/// The same for a context manager: a memory of another rules file is not used, and the run
/// says so (the values its contexts set stay as they are).
#[test]
fn a_context_memory_of_other_rules_is_not_used_and_the_run_says_so() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("r.rules.ron"),
        r#"Contexts(contexts: [(name: "high", when: "c/out/value > 1000000", set: {"c/params/period_ms": "50"})])"#,
    )
    .unwrap();
    let config = dir.path().join("r.ron");
    std::fs::write(
        &config,
        r#"Agent(name: "r1", modules: [
            (name: "c", type: "demo.counter"),
            (name: "ctx", type: "context.manager", values: {"params/rules": "r.rules.ron",
             "state/memory": (rules: "/elsewhere/old.rules.ron", engine: (active: [("high", 1.0)]))}),
        ])"#,
    )
    .unwrap();
    let (code, stderr) = run_warning(&config, &["--for", "300ms"]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stderr.contains("state/memory is of another rules file: not used")
            && stderr.contains("kept=/elsewhere/old.rules.ron"),
        "{stderr}"
    );
}
