//! The shipped rescue team (configs/rescue/team) in one `petrel run`: a world agent with three
//! robot bodies, three robot agents linked to them over the team, a coordinator running the
//! team plan and the shared search (merged maps, frontiers allocated to the robots). The run
//! ends at the plan's goal with every victim of the floor found.

use std::path::Path;
use std::process::{Child, Output, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use crate::support::*;

/// The team runs at the shipped speed (4x real time). These tests ran at 2x for a while: at
/// 4x, beside the binary's other team tests, a run missed a victim (no sighting within 2 m of
/// it though a robot searched frontiers there). Two faults that explain such a miss were
/// fixed since: frames were placed from the pose of when they were processed rather than
/// taken (session 23), and the searched map counted cells where a victim on their near or
/// outer part is cut by the image (session 24: the missed victim's one nearby sighting, from
/// 1 m, was). The rescue teams of these tests run one at a time ([`ONE_TEAM_AT_A_TIME`]):
/// three simulated teams at once starve each other's worlds of CPU. The search takes 200 to
/// 340 simulated seconds with three robots, about 420 with two (50 to 105 s of wall time,
/// more on a loaded machine), up to its 700 s limit when one robot is left alone (one killed,
/// one wedged): each run is given 440 s (`--for`), the test 520 s before it kills it and
/// fails.
const DEADLINE: Duration = Duration::from_secs(520);

/// Held by each test while its team runs: three simulated teams at once starve each other's
/// worlds of CPU, and their simulated time falls behind.
static ONE_TEAM_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// The lock of [`ONE_TEAM_AT_A_TIME`] (a test that failed holding it does not poison the rest).
fn alone() -> std::sync::MutexGuard<'static, ()> {
    ONE_TEAM_AT_A_TIME
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Waits for `child` on its own thread, an explicit deadline (no polling); kills it after.
fn wait(child: Child) -> Output {
    let pid = child.id();
    let (done, finished) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = done.send(child.wait_with_output());
    });
    match finished.recv_timeout(DEADLINE) {
        Ok(out) => out.expect("waiting for petrel"),
        Err(_) => {
            // Not reaped yet, so the pid is still this child's.
            unsafe { libc::kill(pid as libc::pid_t, libc::SIGKILL) };
            panic!("the rescue team still ran after {DEADLINE:?}; killed");
        }
    }
}

const AGENTS: [&str; 5] = ["world", "robot_1", "robot_2", "robot_3", "coordinator"];

/// The fault scenario: `fault/robot_1` (robot_1 dies at a set time) in place of robot_1.
const FAULT_AGENTS: [&str; 5] = [
    "world",
    "fault/robot_1",
    "robot_2",
    "robot_3",
    "coordinator",
];

/// The shipped configs with a fresh team name and free ports, in `dir/team` beside the plan,
/// and the world file in `dir` (the configs name it `../rescue.txt`).
fn team_configs(dir: &Path, team: &str, agents: &[&str]) -> Vec<String> {
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/rescue");
    std::fs::create_dir(dir.join("team")).unwrap();
    std::fs::copy(shipped.join("rescue.txt"), dir.join("rescue.txt")).unwrap();
    std::fs::copy(shipped.join("team/team.plan"), dir.join("team/team.plan")).unwrap();
    std::fs::create_dir(dir.join("team/rules")).unwrap();
    std::fs::create_dir(dir.join("team/fault")).unwrap();
    let rules = "team/rules/robot.rules.ron";
    std::fs::copy(shipped.join(rules), dir.join(rules)).unwrap();
    let ports: Vec<(u16, u16)> = (7460..=7464).map(|p| (p, free_port())).collect();
    agents
        .iter()
        .map(|agent| {
            let mut text =
                std::fs::read_to_string(shipped.join(format!("team/{agent}.ron"))).unwrap();
            text = text.replace("name: \"rescue\"", &format!("name: \"{team}\""));
            for (port, free) in &ports {
                text = text.replace(&format!("127.0.0.1:{port}"), &format!("127.0.0.1:{free}"));
            }
            let path = dir.join(format!("team/{agent}.ron"));
            std::fs::write(&path, text).unwrap();
            path.display().to_string()
        })
        .collect()
}

#[test]
fn the_rescue_team_splits_the_floor_and_reaches_the_plan_goal() {
    let _alone = alone();
    let dir = tempfile::tempdir().unwrap();
    let configs = team_configs(dir.path(), &team_name("rescue-team"), &AGENTS);
    let bin = env!("CARGO_BIN_EXE_petrel");
    let child = spawn_run(bin, dir.path(), &configs, "440s", Stdio::piped(), Some(LOG));
    let out = wait(child);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && stdout.contains("plan `team`: goal"),
        "{}\nstdout:\n{stdout}\nwhy it stopped, and problems:\n{}",
        out.status,
        stderr
            .lines()
            .filter(|l| l.contains("stopping") || l.contains("ERROR") || l.contains(" WARN petrel"))
            .collect::<Vec<_>>()
            .join("\n")
    );
    // The picture of the run: every robot's trajectory.
    assert!(dir.path().join("out/rescue-team.png").is_file(), "{stdout}");
    assert!(
        stdout.contains("robots' trajectories") && stdout.contains("  robot_3: #"),
        "{stdout}"
    );
    // Each robot carried out its search, to the end, once, exploring frontiers of the merged
    // map the coordinator gave it. (The summary after `team search: done` is the run's: the
    // search's log is kept in `state/log`, so a move off its agent's thread does not start
    // the counts over.)
    let Some((_, done)) = stdout.split_once("team search: done at t = ") else {
        panic!("the search was not done:\n{stdout}");
    };
    for robot in ["robot_1", "robot_2", "robot_3"] {
        assert!(
            stdout.contains(&format!("{robot}#search: 1 start, 1 end, 0 failures")),
            "{robot}:\n{stdout}"
        );
        assert!(
            !done.contains(&format!("  {robot}: 0 frontier(s)")),
            "{robot} explored nothing:\n{stdout}"
        );
    }
    assert_every_victim_found(&stdout, &stderr);
    // Victims found by any robot are merged into the coordinator's list, with who found them.
    assert!(
        stdout.contains("[victims] victim 1 at ("),
        "victims:\n{stdout}"
    );
    assert!(
        stdout.contains("team victims: ") && stdout.contains(" found by robot_"),
        "{stdout}"
    );
}

#[test]
fn a_robot_whose_agent_dies_at_a_set_time_hands_its_frontier_on_and_every_victim_is_found() {
    let _alone = alone();
    let dir = tempfile::tempdir().unwrap();
    let configs = team_configs(dir.path(), &team_name("rescue-dies"), &FAULT_AGENTS);
    let bin = env!("CARGO_BIN_EXE_petrel");
    let child = spawn_run(bin, dir.path(), &configs, "440s", Stdio::piped(), Some(LOG));
    let out = wait(child);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && stdout.contains("plan `team`: goal"),
        "{}\n{stdout}",
        out.status
    );
    // robot_1's agent died at 40 s, in this process as a killed process would: the team saw
    // it leave at once, its search failed, the world crossed its body out.
    for line in [
        "[fault] t =   40.0 s  agent robot_1 dies",
        "agent `robot_1` died: killed by sim.fault at t = 40.0 s",
        "robot_1 left the team",
        "robot_1#search: 1 start, 0 ends, 1 failure,",
        "robot_2#search: 1 start, 1 end, 0 failures",
        "robot_3#search: 1 start, 1 end, 0 failures",
        "robot_1: #1f77b4, left the team at t = ",
    ] {
        assert!(stdout.contains(line), "{line}:\n{stdout}");
    }
    // The summary says who left when; the others found every victim.
    assert!(stdout.contains(", left the team at t = 40."), "{stdout}");
    assert_every_victim_found(&stdout, &stderr);
}

#[test]
fn a_robot_killed_mid_search_hands_its_area_on_and_the_team_still_reaches_the_goal() {
    let _alone = alone();
    use std::io::{BufRead, BufReader};
    let dir = tempfile::tempdir().unwrap();
    let configs = team_configs(dir.path(), &team_name("rescue-fault"), &AGENTS);
    // robot_1 in its own process, the rest of the team in another.
    let (robot_1, others): (Vec<_>, Vec<_>) =
        configs.iter().partition(|c| c.ends_with("robot_1.ron"));
    let run = |configs: &[&String], stderr: Stdio| {
        spawn_run(
            env!("CARGO_BIN_EXE_petrel"),
            dir.path(),
            configs,
            "440s",
            stderr,
            Some(LOG),
        )
    };
    let mut team = run(&others, Stdio::piped());
    // The team's log is read from the start: it logs every sighting, and a pipe nobody reads
    // would fill while robot_1 starts, blocking the team's logging and with it the coordinator
    // robot_1 waits for.
    let mut team_log = team.stderr.take().unwrap();
    let team_log = std::thread::spawn(move || {
        let mut bytes = Vec::new();
        let _ = std::io::Read::read_to_end(&mut team_log, &mut bytes);
        bytes
    });
    let mut victim = run(&robot_1, Stdio::piped());
    // Killed (SIGKILL: no goodbye) as soon as its search has started; the log line is the
    // signal, read as it comes (a dead or silent process ends the read: the test then fails).
    let log = BufReader::new(victim.stderr.take().unwrap());
    let mut seen = Vec::new();
    let started = log.lines().map_while(Result::ok).any(|l| {
        let hit = l.contains("robot_1#search call=start");
        seen.push(l);
        hit
    });
    victim.kill().unwrap();
    victim.wait().unwrap();
    if !started {
        let _ = team.kill();
        let _ = team.wait();
        let tail = seen[seen.len().saturating_sub(15)..].join("\n");
        panic!("robot_1 never started its search; its log ends:\n{tail}");
    }
    // robot_1 started again, as an operator would: it rejoins the team, but its search action
    // failed while it was away, so its explorer stays off and it must be given no frontier.
    let mut back = run(&robot_1, Stdio::piped());
    let back_log = BufReader::new(back.stderr.take().unwrap());
    let mut back_lines = back_log.lines().map_while(Result::ok);
    let rejoined = back_lines.any(|l| l.contains("reachable by tools"));
    let back_log = std::thread::spawn(move || back_lines.count());
    let out = wait(team);
    let _ = back.kill();
    let _ = back.wait();
    let _ = back_log.join();
    assert!(rejoined, "robot_1 started again");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let team_log = team_log.join().unwrap();
    let stderr = String::from_utf8_lossy(&team_log);
    assert!(
        out.status.success() && stdout.contains("plan `team`: goal"),
        "{}\n{stdout}",
        out.status
    );
    // The world saw robot_1's agent leave: its body is crossed out where it stopped.
    assert!(
        stdout.contains("robot_1: #1f77b4, left the team at t = "),
        "{stdout}"
    );
    // robot_1's search failed when it left the team (so early, its first second, that the
    // coordinator's search may not have seen it at all), and the others searched on to the end.
    assert!(
        stdout.contains("robot_1#search: 1 start, 0 ends, 1 failure,")
            && stdout.contains("robot_2#search: 1 start, 1 end, 0 failures")
            && stdout.contains("robot_3#search: 1 start, 1 end, 0 failures"),
        "{stdout}"
    );
    // Back, robot_1 was given no frontier: given one, it sat still and was found stalled.
    assert!(!stdout.contains("robot_1 stalled"), "{stdout}");
    assert_every_victim_found(&stdout, &stderr);
}

/// The log of a team run: the victim mappers' sightings and the frontiers assigned, so that a
/// victim not found can be explained (see [`sightings_near`]).
const LOG: &str =
    "info,petrel_modules::robot::victim_mapper=debug,petrel_modules::robot::team_search=debug";

/// Every victim of the floor is on the coordinator's list (`  N (x, y) found by ...`), within
/// 1.5 m (sightings on the shaking rubble floor land up to about 1.2 m off; victims are more
/// than 4 m apart). A victim missing is shown with the sightings placed near it and the
/// frontiers assigned near it (from `stderr`, logged at [`LOG`]).
fn assert_every_victim_found(stdout: &str, stderr: &str) {
    let found: Vec<(f64, f64)> = stdout
        .lines()
        .filter(|l| l.contains(") found by robot_"))
        .filter_map(|l| {
            let inside = l.split_once('(')?.1.split_once(')')?.0;
            let (x, y) = inside.split_once(", ")?;
            Some((x.parse().ok()?, y.parse().ok()?))
        })
        .collect();
    for (x, y) in VICTIMS {
        assert!(
            found.iter().any(|(fx, fy)| (fx - x).hypot(fy - y) < 1.5),
            "the victim at ({x}, {y}) was not found; the team's list: {found:?}\n{stdout}\n{}",
            sightings_near(stderr, x, y)
        );
    }
}

/// The log lines about the floor around `(x, y)`: sightings placed within 2 m of it (with the
/// pose they were placed from and their confidence) and frontiers assigned within 3 m.
fn sightings_near(stderr: &str, x: f64, y: f64) -> String {
    let field = |line: &str, name: &str| -> Option<f64> {
        let at = line.find(&format!(" {name}="))? + name.len() + 2;
        line[at..].split([' ', ',']).next()?.parse().ok()
    };
    let (mut near, mut frontiers, mut sightings) = (Vec::new(), Vec::new(), 0);
    for line in stderr.lines() {
        if line.contains("sighting") {
            sightings += 1;
            let (Some(rx), Some(ry), Some(th), Some(b), Some(r)) = (
                field(line, "x"),
                field(line, "y"),
                field(line, "theta"),
                field(line, "bearing"),
                field(line, "range"),
            ) else {
                continue;
            };
            let (px, py) = (rx + r * (th + b).cos(), ry + r * (th + b).sin());
            if (px - x).hypot(py - y) < 2.0 {
                near.push(line.to_string());
            }
        } else if line.contains("frontier assigned") {
            if let (Some(fx), Some(fy)) = (field(line, "x"), field(line, "y")) {
                if (fx - x).hypot(fy - y) < 3.0 {
                    frontiers.push(line.to_string());
                }
            }
        }
    }
    let shown = |lines: &[String]| {
        lines
            .iter()
            .take(30)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n")
    };
    format!(
        "sightings placed within 2 m of ({x}, {y}): {} of {sightings}\n{}\nfrontiers assigned within 3 m: {}\n{}",
        near.len(),
        shown(&near),
        frontiers.len(),
        shown(&frontiers)
    )
}

/// The explanation of a missed victim finds what the log says about its floor.
#[test]
fn a_missed_victim_is_shown_with_the_sightings_and_frontiers_near_it() {
    let log = [
        // Placed at (3.0, 8.0): near.
        "T DEBUG module: petrel_modules::robot::victim_mapper: sighting x=1.0 y=8.0 theta=0.0 bearing=0.0 range=2.0 confidence=1.0 agent=robot_2",
        // Placed at (1.0, 4.0): far.
        "T DEBUG module: petrel_modules::robot::victim_mapper: sighting x=1.0 y=2.0 theta=1.5707963 bearing=0.0 range=2.0 confidence=1.0 agent=robot_2",
        "T DEBUG module: petrel_modules::robot::team_search: frontier assigned robot=\"robot_3\" x=4.0 y=9.0 t=12.5 agent=coordinator",
        "T DEBUG module: petrel_modules::robot::team_search: frontier assigned robot=\"robot_3\" x=12.0 y=9.0 t=14.5 agent=coordinator",
    ]
    .join("\n");
    let shown = sightings_near(&log, 3.3, 8.1);
    assert!(
        shown.starts_with("sightings placed within 2 m of (3.3, 8.1): 1 of 2\n")
            && shown.contains("x=1.0 y=8.0")
            && shown.contains("frontiers assigned within 3 m: 1\n")
            && shown.contains("x=4.0 y=9.0")
            && !shown.contains("x=12.0"),
        "{shown}"
    );
}

/// The shipped team plan against scripted worlds (`petrel plan simulate`'s simulator): how it
/// ends.
fn simulate_team_plan(script: &str) -> (String, petrel::plans::PlanStatus) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/rescue/team/team.plan");
    let plan = petrel::plans::load_plan(&path, None)
        .unwrap_or_else(|e| panic!("team.plan should load: {e}"))
        .plan;
    let script = petrel::plans::Script::parse(script, "script").unwrap();
    script.check(&plan, "script").unwrap();
    let mut out = Vec::new();
    let status = petrel::plans::simulate(&plan, &script, 100, &mut out).unwrap();
    (String::from_utf8(out).unwrap(), status)
}

#[test]
fn the_team_plan_fails_when_every_robot_left_before_the_search_was_done() {
    // Every robot's process died: each search failed and was let go, the floor not searched.
    let all_dead = "fail robot_1#search 3\nfail robot_2#search 4\nfail robot_3#search 5";
    let (trace, status) = simulate_team_plan(all_dead);
    assert_eq!(status, petrel::plans::PlanStatus::Fail, "{trace}");
    assert!(
        trace.contains("say_every_robot_left_before_the_search_was_done"),
        "{trace}"
    );
    // Two died, the third finished the search: the goal.
    let one_left =
        "fail robot_1#search 3\nfail robot_2#search 4\nfinish robot_3#search 9\ncond search_done 8 100";
    let (trace, status) = simulate_team_plan(one_left);
    assert_eq!(status, petrel::plans::PlanStatus::Goal, "{trace}");
    assert!(trace.contains("say_the_floor_is_searched"), "{trace}");
}
