//! Team scaling, for BENCHMARKS.md: the shipped rescue team (configs/rescue/team) with 1, 2, 4
//! and 8 robots on the same floor, each run in one `petrel run`. Per size: the simulated time
//! by which every victim was found and the search's end, wall time, CPU seconds per simulated
//! second, and the bytes per second the agents sent each other over the team's TCP
//! connections (read with `ss` from the kernel's per-socket counters while the run goes).
//! Ignored: it takes minutes, and its figures are measurements, not assertions. Run it on a
//! release build and copy the table it prints into BENCHMARKS.md:
//!
//! ```sh
//! cargo build --release --bin petrel
//! PETREL_BIN=$PWD/target/release/petrel cargo test --test team team_scaling -- --ignored --nocapture
//! ```
//!
//! (`PETREL_BIN` picks the binary measured; without it, the one built with the test.)
//!
//! It also writes docs/team-scaling.png (drawn with the `image` crate, no plotting library).

use std::collections::HashMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::support::{free_port, spawn_run, team_name, VICTIMS};

/// Robots per run.
const SIZES: [usize; 4] = [1, 2, 4, 8];

/// Where robot `k` (1-based) starts: a grid in the start room, clear of its furniture.
fn start(k: usize) -> (f64, f64) {
    let i = k - 1;
    (1.0 + (i / 4) as f64, 1.0 + (i % 4) as f64 * 0.8)
}

/// One run's figures.
#[derive(Debug, Default, Clone)]
struct Figures {
    robots: usize,
    all_victims_s: Option<f64>,
    done_s: Option<f64>,
    wall_s: f64,
    cpu_s: f64,
    bytes: u64,
}

/// Text between `from` and the first `to` after it, in the block of `text` that begins with
/// `from` (the shipped configs' per-robot blocks: a body, a team member).
fn block<'a>(text: &'a str, from: &str, to: &str) -> &'a str {
    let start = text.find(from).expect("the block's start");
    let end = text[start..].find(to).expect("the block's end") + start + to.len();
    &text[start..end]
}

/// Writes the team of `n` robots into `dir` (the shipped files rewritten: robot_1's blocks
/// repeated per robot, free ports, a team name of its own); returns the config paths.
fn write_team(dir: &Path, n: usize) -> Vec<String> {
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/rescue");
    let read = |f: &str| std::fs::read_to_string(shipped.join(f)).unwrap();
    std::fs::create_dir_all(dir.join("team/rules")).unwrap();
    std::fs::copy(shipped.join("rescue.txt"), dir.join("rescue.txt")).unwrap();
    let rules = "team/rules/robot.rules.ron";
    std::fs::copy(shipped.join(rules), dir.join(rules)).unwrap();
    let names: Vec<String> = (1..=n).map(|k| format!("robot_{k}")).collect();
    let quoted: Vec<String> = names.iter().map(|r| format!("{r:?}")).collect();
    let plan: Vec<String> = names
        .iter()
        .map(|r| format!("{{ {r}#search ! *if* action_failed *do* skip_action ! }}"))
        .collect();
    std::fs::write(dir.join("team/team.plan"), plan.join("\n|| ") + "\n").unwrap();
    let team = team_name(&format!("scaling{n}"));
    let world_port = free_port();
    let retarget = |text: String, own: u16| {
        text.replace("name: \"rescue\"", &format!("name: \"{team}\""))
            .replace("127.0.0.1:7460", &format!("127.0.0.1:{world_port}"))
            .replace("127.0.0.1:7461", &format!("127.0.0.1:{own}"))
            .replace("127.0.0.1:7464", &format!("127.0.0.1:{own}"))
    };
    let mut paths = Vec::new();
    let mut write = |name: &str, text: String| {
        let path = dir.join(format!("team/{name}.ron"));
        std::fs::write(&path, text).unwrap();
        paths.push(path.display().to_string());
    };
    // The world: robot_1's body block once per robot, each at its own start.
    let world = read("team/world.ron");
    let body = block(&world, "(name: \"robot_1\", type: \"sim.body\"", "}),\n");
    let bodies: String = (1..=n)
        .map(|k| {
            let (x, y) = start(k);
            body.replace("robot_1", &format!("robot_{k}"))
                .replace("[1.0, 1.0, 0.0]", &format!("[{x:.1}, {y:.1}, 0.0]"))
                + "        "
        })
        .collect();
    let first = world.find(body).unwrap();
    let last = world.rfind("(name: \"robot_").unwrap();
    let end = world[last..].find("}),\n").unwrap() + last + 4;
    let mut text = format!(
        "{}{}\n{}",
        &world[..first],
        bodies.trim_end(),
        &world[end..]
    );
    text = text.replace(
        "[\"robot_1\", \"robot_2\", \"robot_3\"]",
        &format!("[{}]", quoted.join(", ")),
    );
    write("world", retarget(text, world_port));
    // The robots: robot_1.ron renamed.
    let robot = read("team/robot_1.ron");
    for name in &names {
        write(name, retarget(robot.replace("robot_1", name), free_port()));
    }
    // The coordinator: robot_1's team member block once per robot.
    let coordinator = read("team/coordinator.ron");
    let member = block(
        &coordinator,
        "(name: \"robot_1\", type: \"nav.team_member\"",
        "}),\n",
    );
    let members: String = names
        .iter()
        .map(|r| member.replace("robot_1", r) + "        ")
        .collect();
    let first = coordinator.find(member).unwrap();
    let last = coordinator.rfind("type: \"nav.team_member\"").unwrap();
    let end = coordinator[last..].find("}),\n").unwrap() + last + 4;
    let mut text = format!(
        "{}{}\n{}",
        &coordinator[..first],
        members.trim_end(),
        &coordinator[end..]
    );
    text = text.replace(
        "[\"robot_1\", \"robot_2\", \"robot_3\"]",
        &format!("[{}]", quoted.join(", ")),
    );
    write("coordinator", retarget(text, free_port()));
    paths
}

/// Bytes sent so far on each TCP socket of process `pid` (`ss`'s `bytes_sent`).
fn socket_bytes(pid: u32) -> HashMap<String, u64> {
    let out = Command::new("ss").args(["-tinpH"]).output();
    let Ok(out) = out else { return HashMap::new() };
    let text = String::from_utf8_lossy(&out.stdout);
    let mut sockets = HashMap::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        if !line.starts_with(char::is_whitespace) {
            let ours = line.contains(&format!("pid={pid},"));
            // Local and peer address: the queue sizes before them change as the run goes.
            current = ours.then(|| {
                line.split_whitespace()
                    .skip(3)
                    .take(2)
                    .collect::<Vec<_>>()
                    .join(" ")
            });
        } else if let Some(key) = &current {
            if let Some(n) = line
                .split_whitespace()
                .find_map(|f| f.strip_prefix("bytes_sent:"))
                .and_then(|n| n.parse().ok())
            {
                sockets.insert(key.clone(), n);
            }
        }
    }
    sockets
}

/// CPU seconds (user + system) of this process's waited-for children so far.
fn children_cpu() -> f64 {
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut usage) };
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    secs(usage.ru_utime) + secs(usage.ru_stime)
}

/// Runs the team of `n` robots to its goal (at most 20 minutes) and measures it.
fn run(n: usize) -> Figures {
    let dir = tempfile::tempdir().unwrap();
    let configs = write_team(dir.path(), n);
    let cpu_before = children_cpu();
    let started = Instant::now();
    let bin = std::env::var("PETREL_BIN").unwrap_or(env!("CARGO_BIN_EXE_petrel").into());
    let child = spawn_run(&bin, dir.path(), &configs, "1200s", Stdio::null(), None);
    let pid = child.id();
    // The kernel forgets a socket's counters when it closes: keep the last seen of each.
    let seen = Arc::new(Mutex::new(HashMap::<String, u64>::new()));
    let over = Arc::new(AtomicBool::new(false));
    let sampler = {
        let (seen, over) = (seen.clone(), over.clone());
        std::thread::spawn(move || {
            while !over.load(Ordering::Relaxed) {
                for (k, v) in socket_bytes(pid) {
                    let mut seen = seen.lock().unwrap();
                    let e = seen.entry(k).or_default();
                    *e = (*e).max(v);
                }
                std::thread::sleep(Duration::from_millis(500));
            }
        })
    };
    let out = child.wait_with_output().expect("petrel runs");
    over.store(true, Ordering::Relaxed);
    sampler.join().unwrap();
    let wall_s = started.elapsed().as_secs_f64();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{n} robots: {}\n{stdout}", out.status);
    let done_s = stdout
        .lines()
        .find_map(|l| l.strip_prefix("team search: done at t = "))
        .and_then(|t| t.trim_end_matches(" s").parse().ok());
    // `[victims] victim 3 at (x, y), found by robot_2 at t = 41.0 s`, and `... at (x, y) from 2
    // reports, the last by robot_1 at t = 50.2 s` as more reports refine it: a victim counts as
    // found when the team's list first puts it within 1.5 m.
    let found: Vec<((f64, f64), f64)> = stdout
        .lines()
        .filter(|l| l.starts_with("[victims] victim ") && l.contains(" at t = "))
        .filter_map(|l| {
            let inside = l.split_once('(')?.1.split_once(')')?.0;
            let (x, y) = inside.split_once(", ")?;
            let t = l.rsplit_once(" at t = ")?.1.trim_end_matches(" s");
            Some(((x.parse().ok()?, y.parse().ok()?), t.parse().ok()?))
        })
        .collect();
    let times: Option<Vec<f64>> = VICTIMS
        .iter()
        .map(|(x, y)| {
            found
                .iter()
                .filter(|((fx, fy), _)| (fx - x).hypot(fy - y) < 1.5)
                .map(|(_, t)| *t)
                .reduce(f64::min)
        })
        .collect();
    let bytes = seen.lock().unwrap().values().sum();
    Figures {
        robots: n,
        all_victims_s: times.map(|t| t.into_iter().fold(0.0, f64::max)),
        done_s,
        wall_s,
        cpu_s: children_cpu() - cpu_before,
        bytes,
    }
}

#[test]
#[ignore = "a measurement taking minutes: run by hand for BENCHMARKS.md (see the module docs)"]
fn team_scaling() {
    let figures: Vec<Figures> = SIZES.iter().map(|&n| run(n)).collect();
    println!("| robots | all 6 victims found (sim s) | search done (sim s) | wall (s) | CPU s per sim s | team transport (kB/s, wall) |");
    println!("|---|---|---|---|---|---|");
    for f in &figures {
        let sim = f.done_s.unwrap_or(f64::NAN);
        let victims = f
            .all_victims_s
            .map_or("not all".into(), |t| format!("{t:.1}"));
        println!(
            "| {} | {victims} | {sim:.1} | {:.1} | {:.2} | {:.1} |",
            f.robots,
            f.wall_s,
            f.cpu_s / sim,
            f.bytes as f64 / f.wall_s / 1000.0
        );
    }
    let png = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/team-scaling.png");
    super::scaling_plot::save(&png, &figures_for_plot(&figures)).expect("the plot is written");
    println!("plot: {}", png.display());
}

/// The four series of the plot, one value per size.
fn figures_for_plot(figures: &[Figures]) -> [Vec<f64>; 4] {
    let pick = |f: fn(&Figures) -> f64| figures.iter().map(f).collect();
    [
        pick(|f| f.all_victims_s.unwrap_or(f64::NAN)),
        pick(|f| f.wall_s),
        pick(|f| f.cpu_s / f.done_s.unwrap_or(f64::NAN)),
        pick(|f| f.bytes as f64 / f.wall_s / 1000.0),
    ]
}
