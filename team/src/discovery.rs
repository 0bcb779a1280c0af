//! Finding the agents that run on this machine. Every `petrel run` writes a record of its
//! agents and where to reach them (`<pid>.ron`) to a directory of the user's, and removes it
//! when it ends; tools (`petrel ls|get|set`) read the records, skipping those whose process
//! is gone (a process killed with SIGKILL leaves its record behind).
//!
//! The directory is `$PETREL_RUNTIME_DIR`, else `$XDG_RUNTIME_DIR/petrel`, else
//! `<temp dir>/petrel-<uid>`; it is created readable by its owner only.

use std::path::{Path, PathBuf};

use petrel_actors::team::TeamConfig;
use serde::{Deserialize, Serialize};

/// The environment variable naming the directory of records (tests set their own).
pub const DIR_ENV: &str = "PETREL_RUNTIME_DIR";

/// One agent of a running process and how a tool reaches it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Reachable {
    /// The agent's name.
    pub agent: String,
    /// The team it answers on (a private one when its config has no `team:` section).
    pub team: String,
    /// zenoh endpoints to connect to.
    pub connect: Vec<String>,
}

impl Reachable {
    /// The team section a tool connects with.
    pub fn tool_config(&self) -> TeamConfig {
        TeamConfig {
            name: self.team.clone(),
            connect: self.connect.clone(),
            ..TeamConfig::default()
        }
    }
}

/// What one `petrel run` process wrote.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Record {
    /// The process.
    pub pid: u32,
    /// When the process started, in clock ticks since boot (see [`process_start`]): the
    /// record of a process that was killed, whose pid another process took since, is told
    /// apart by it. `None` where it is not known.
    #[serde(default)]
    pub started: Option<u64>,
    /// Its agents.
    pub agents: Vec<Reachable>,
}

/// Where a tool reaches an agent whose team section is `team`: where it listens (with an
/// unspecified address made loopback), or, for an agent that only connects (to peers or a
/// router), where it connects.
pub fn endpoints_of(team: &TeamConfig) -> Vec<String> {
    let listen: Vec<String> = team
        .listen
        .iter()
        .map(|e| {
            e.replacen("tcp/0.0.0.0:", "tcp/127.0.0.1:", 1)
                .replacen("tcp/[::]:", "tcp/[::1]:", 1)
        })
        .collect();
    match listen.is_empty() {
        true => team.connect.clone(),
        false => listen,
    }
}

/// The team section of an agent run without one: a team of its own (no other agent can
/// claim to be in it), listening on loopback only, where tools may set `params/` and
/// `control/` properties (the only kinds ever writable remotely).
pub fn private_team(agent: &str, pid: u32, port: u16) -> TeamConfig {
    TeamConfig {
        name: format!("local.{pid}.{agent}"),
        listen: vec![format!("tcp/127.0.0.1:{port}")],
        remote_write: vec!["**".into()],
        ..TeamConfig::default()
    }
}

/// Why a tool cannot tell where an agent runs.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FindError {
    /// No running process has the agent.
    #[error("no running agent `{agent}`{}", running_list(.running))]
    NotRunning {
        /// The agent asked for.
        agent: String,
        /// The agents that do run, nearest name first.
        running: Vec<String>,
    },
    /// `--pid` names no process that runs agents here.
    #[error("no `petrel run` has pid {pid}{}", runs_list(.runs))]
    NoSuchRun {
        /// The pid asked for.
        pid: u32,
        /// The pids that do run agents here.
        runs: Vec<u32>,
    },
    /// Several processes run an agent of that name.
    #[error("agent `{agent}` runs in {} processes (pids {}): pick one with --pid", .pids.len(), join(.pids))]
    Ambiguous {
        /// The agent asked for.
        agent: String,
        /// The processes.
        pids: Vec<u32>,
    },
}

fn running_list(running: &[String]) -> String {
    match running.first() {
        None => " (no `petrel run` is running on this machine for this user)".to_string(),
        Some(nearest) => format!(
            "; running: {} (nearest: `{nearest}`)",
            running
                .iter()
                .map(|a| format!("`{a}`"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

fn runs_list(runs: &[u32]) -> String {
    match runs {
        [] => " (no `petrel run` is running on this machine for this user)".to_string(),
        pids => format!("; runs here: pid {}", join(pids)),
    }
}

fn join(pids: &[u32]) -> String {
    pids.iter()
        .map(u32::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Finds `agent` among `records` (of process `pid` when given).
pub fn find(records: &[Record], agent: &str, pid: Option<u32>) -> Result<Reachable, FindError> {
    if let Some(pid) = pid.filter(|p| records.iter().all(|r| r.pid != *p)) {
        return Err(FindError::NoSuchRun {
            pid,
            runs: records.iter().map(|r| r.pid).collect(),
        });
    }
    let hits: Vec<(u32, &Reachable)> = records
        .iter()
        .filter(|r| pid.is_none_or(|p| p == r.pid))
        .flat_map(|r| r.agents.iter().map(move |a| (r.pid, a)))
        .filter(|(_, a)| a.agent == agent)
        .collect();
    match hits.as_slice() {
        [(_, one)] => Ok((*one).clone()),
        [] => {
            let mut running: Vec<String> = records
                .iter()
                .flat_map(|r| r.agents.iter().map(|a| a.agent.clone()))
                .collect();
            running.sort_by_key(|a| (edit_distance(a, agent), a.clone()));
            running.dedup();
            Err(FindError::NotRunning {
                agent: agent.to_string(),
                running,
            })
        }
        many => Err(FindError::Ambiguous {
            agent: agent.to_string(),
            pids: many.iter().map(|(p, _)| *p).collect(),
        }),
    }
}

/// Levenshtein distance, for "nearest name" hints.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let above = row[j + 1];
            row[j + 1] = (above + 1)
                .min(row[j] + 1)
                .min(diagonal + usize::from(ca != *cb));
            diagonal = above;
        }
    }
    row[b.len()]
}

/// The directory of records (see the module docs).
pub fn directory() -> PathBuf {
    if let Some(dir) = std::env::var_os(DIR_ENV).filter(|d| !d.is_empty()) {
        return dir.into();
    }
    if let Some(dir) = std::env::var_os("XDG_RUNTIME_DIR").filter(|d| !d.is_empty()) {
        return Path::new(&dir).join("petrel");
    }
    // SAFETY: getuid has no preconditions and cannot fail.
    let uid = unsafe { libc::getuid() };
    std::env::temp_dir().join(format!("petrel-{uid}"))
}

/// This process's record, removed when dropped.
pub struct Registration {
    path: PathBuf,
}

impl Registration {
    /// Writes `record` to `dir` (created owner-only if missing), atomically: a tool never
    /// reads half a record.
    pub fn write(dir: &Path, record: &Record) -> std::io::Result<Registration> {
        use std::os::unix::fs::DirBuilderExt;
        std::fs::DirBuilder::new()
            .recursive(true)
            .mode(0o700)
            .create(dir)?;
        let path = dir.join(format!("{}.ron", record.pid));
        let partial = dir.join(format!(".{}.ron.partial", record.pid));
        let text = ron::ser::to_string_pretty(record, ron::ser::PrettyConfig::default())
            .map_err(std::io::Error::other)?;
        std::fs::write(&partial, text)?;
        std::fs::rename(&partial, &path)?;
        Ok(Registration { path })
    }
}

impl Drop for Registration {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// The records in `dir` of processes still running. Records of processes that are gone are
/// removed; files that are not records are skipped.
pub fn running(dir: &Path) -> Vec<Record> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut records = Vec::new();
    for entry in entries.flatten() {
        let path = entry.path();
        let Some(pid) = path
            .file_name()
            .and_then(|n| n.to_str())
            .and_then(|n| n.strip_suffix(".ron"))
            .and_then(|n| n.parse::<u32>().ok())
        else {
            continue;
        };
        if !alive(pid) {
            let _ = std::fs::remove_file(&path);
            continue;
        }
        let record = std::fs::read_to_string(&path)
            .ok()
            .and_then(|t| ron::from_str::<Record>(&t).ok());
        let Some(record) = record.filter(|r| r.pid == pid) else {
            continue;
        };
        // The pid is another process's now: the run was killed and left its record.
        if record.started.is_some() && record.started != process_start(pid) {
            let _ = std::fs::remove_file(&path);
            continue;
        }
        records.push(record);
    }
    records.sort_by_key(|r| r.pid);
    records
}

/// When process `pid` started, in clock ticks since boot (`starttime` of `/proc/PID/stat`);
/// `None` where there is no such file.
pub fn process_start(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command's name (the 2nd field) may hold spaces and parentheses: count from the last
    // `)`, after which the 3rd field comes; `starttime` is the 22nd.
    let after_name = &stat[stat.rfind(')')? + 1..];
    after_name.split_whitespace().nth(19)?.parse().ok()
}

/// Whether process `pid` exists (signal 0 checks without sending anything).
fn alive(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return false;
    };
    // SAFETY: kill with signal 0 only checks that the process exists and may be signalled.
    let r = unsafe { libc::kill(pid, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(pid: u32, agents: &[&str]) -> Record {
        Record {
            pid,
            started: None,
            agents: agents
                .iter()
                .map(|a| Reachable {
                    agent: a.to_string(),
                    team: "t".into(),
                    connect: vec![format!("tcp/127.0.0.1:{pid}")],
                })
                .collect(),
        }
    }

    #[test]
    fn a_record_whose_pid_another_process_took_is_removed() {
        let dir = tempfile::tempdir().unwrap();
        let me = std::process::id();
        let started = process_start(me);
        assert!(started.is_some(), "this process has a start time");
        let write = |started| {
            let record = Record {
                started,
                ..record(me, &["robot"])
            };
            let text = ron::to_string(&record).unwrap();
            std::fs::write(dir.path().join(format!("{me}.ron")), text).unwrap();
        };
        write(started);
        assert_eq!(running(dir.path()).len(), 1, "this very process");
        write(started.map(|s| s + 1));
        assert!(
            running(dir.path()).is_empty(),
            "another process of that pid"
        );
        assert!(!dir.path().join(format!("{me}.ron")).exists(), "removed");
        write(None);
        assert_eq!(running(dir.path()).len(), 1, "a record from before: kept");
    }

    #[test]
    fn finds_an_agent_and_names_the_nearest_when_it_is_missing() {
        let records = [record(10, &["robot", "sim"]), record(11, &["display"])];
        assert_eq!(
            find(&records, "sim", None).unwrap().connect,
            ["tcp/127.0.0.1:10"]
        );
        let err = find(&records, "robt", None).unwrap_err();
        assert_eq!(
            err.to_string(),
            "no running agent `robt`; running: `robot`, `sim`, `display` (nearest: `robot`)"
        );
        let none = find(&[], "robot", None).unwrap_err().to_string();
        assert!(none.contains("no `petrel run` is running"), "{none}");
    }

    #[test]
    fn an_agent_in_two_processes_needs_a_pid() {
        let records = [record(10, &["robot"]), record(12, &["robot"])];
        assert_eq!(
            find(&records, "robot", None).unwrap_err().to_string(),
            "agent `robot` runs in 2 processes (pids 10, 12): pick one with --pid"
        );
        assert_eq!(
            find(&records, "robot", Some(12)).unwrap().connect,
            ["tcp/127.0.0.1:12"]
        );
        // A pid that runs nothing here is said to be one, not the agent to be missing.
        assert_eq!(
            find(&records, "robot", Some(9)).unwrap_err().to_string(),
            "no `petrel run` has pid 9; runs here: pid 10, 12"
        );
    }

    #[test]
    fn tools_reach_listeners_on_loopback_or_else_what_the_agent_connects_to() {
        let mut team = TeamConfig {
            listen: vec!["tcp/0.0.0.0:7450".into(), "tcp/10.0.0.2:7451".into()],
            connect: vec!["tcp/127.0.0.1:7447".into()],
            ..TeamConfig::default()
        };
        assert_eq!(
            endpoints_of(&team),
            ["tcp/127.0.0.1:7450", "tcp/10.0.0.2:7451"]
        );
        team.listen.clear();
        assert_eq!(endpoints_of(&team), ["tcp/127.0.0.1:7447"]);
    }

    #[test]
    fn records_are_written_read_and_removed_and_dead_processes_are_skipped() {
        let dir = tempfile::tempdir().unwrap();
        let mine = record(std::process::id(), &["robot"]);
        let registration = Registration::write(dir.path(), &mine).unwrap();
        // pid_t::MAX is above any real pid limit: that process does not exist.
        let dead = record(libc::pid_t::MAX as u32, &["ghost"]);
        let dead_path = dir.path().join(format!("{}.ron", dead.pid));
        std::fs::write(&dead_path, ron::to_string(&dead).unwrap()).unwrap();
        std::fs::write(dir.path().join("notes.txt"), "not a record").unwrap();
        assert_eq!(running(dir.path()), [mine]);
        assert!(!dead_path.exists(), "a dead process's record is removed");
        drop(registration);
        assert_eq!(running(dir.path()), []);
    }
}
