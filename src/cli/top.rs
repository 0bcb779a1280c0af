//! `petrel top`: every module of every running agent with its status and step figures,
//! refreshed each second like `top`, or printed once with `--once`.

use std::process::ExitCode;
use std::time::Duration;

use petrel_team::discovery::{self, Reachable};
use petrel_team::{Client, TeamError};

use super::remote::{failed, team_of, Reach};
use super::stdout::say;
use super::EXIT_BAD_INPUT;

/// One row: a module's figures, from its `stats/` properties.
#[derive(Debug, Default, Clone, PartialEq)]
pub(crate) struct ModuleRow {
    pub agent: String,
    pub module: String,
    pub type_name: String,
    pub status: String,
    pub steps: i64,
    pub mean_interval_ms: f64,
    pub mean_step_us: f64,
    pub last_step_us: f64,
    pub restarts: i64,
    pub failures: i64,
    /// Items its queue inputs lost by lagging (`stats/dropped/...`, summed).
    pub dropped: i64,
    /// Steps per second seen between two refreshes (or, with `--once`, two samples a second
    /// apart): a module whose steps stopped (one that hangs) shows 0, where its last steps'
    /// mean interval said on.
    pub seen_rate: Option<f64>,
}

/// The status shown for an agent that is still running but did not answer (a stopped
/// process, a busy thread): its one row, beside the agents that did.
const NO_ANSWER: &str = "no answer";

impl ModuleRow {
    /// The one row of an agent that did not answer.
    fn silent(agent: &str) -> ModuleRow {
        ModuleRow {
            agent: agent.to_string(),
            module: "-".into(),
            type_name: "-".into(),
            status: NO_ANSWER.into(),
            ..ModuleRow::default()
        }
    }
}

/// Each row's [`ModuleRow::seen_rate`]: its steps since `previous` (the rows of the refresh
/// before, `elapsed` ago).
pub(crate) fn seen_rates(rows: &mut [ModuleRow], previous: &[ModuleRow], elapsed: f64) {
    for row in rows.iter_mut() {
        let before = previous
            .iter()
            .find(|p| p.agent == row.agent && p.module == row.module);
        row.seen_rate = match before {
            Some(p) if elapsed > 0.0 && row.steps >= p.steps => {
                Some((row.steps - p.steps) as f64 / elapsed)
            }
            _ => None,
        };
    }
}

/// The rows of one agent (shown as `agent`) from its module types and its `*/stats/**`
/// values (key, JSON).
pub(crate) fn rows(
    agent: &str,
    modules: &[(String, String)],
    stats: &[(String, Vec<u8>)],
) -> Vec<ModuleRow> {
    modules
        .iter()
        .filter(|(name, _)| !name.starts_with('_'))
        .map(|(name, type_name)| {
            let mut row = ModuleRow {
                agent: agent.to_string(),
                module: name.clone(),
                type_name: type_name.clone(),
                ..ModuleRow::default()
            };
            let prefix = format!("{name}/stats/");
            for (key, json) in stats {
                let Some(stat) = key.strip_prefix(&prefix) else {
                    continue;
                };
                let value: serde_json::Value = serde_json::from_slice(json).unwrap_or_default();
                let int = value.as_i64().unwrap_or(0);
                let float = value.as_f64().unwrap_or(0.0);
                match stat {
                    "status" => row.status = value.as_str().unwrap_or_default().to_string(),
                    "steps" => row.steps = int,
                    "mean_interval_ms" => row.mean_interval_ms = float,
                    "mean_step_us" => row.mean_step_us = float,
                    "last_step_us" => row.last_step_us = float,
                    "restarts" => row.restarts = int,
                    "failures" => row.failures = int,
                    s if s.starts_with("dropped/") => row.dropped += int,
                    _ => {}
                }
            }
            row
        })
        .collect()
}

/// The table of `rows`.
pub(crate) fn table(rows: &[ModuleRow]) -> String {
    let cells: Vec<[String; 11]> = rows
        .iter()
        .map(|r| {
            if r.status == NO_ANSWER {
                let mut cells = std::array::from_fn(|_| "-".to_string());
                cells[0] = r.agent.clone();
                cells[3] = r.status.clone();
                return cells;
            }
            // The mean interval is what the module's last steps had: of a module that no
            // longer runs (failed, stopped, disabled) it is no rate.
            let running = r.status == petrel_actors::status::RUNNING;
            let rate = match (r.seen_rate, r.mean_interval_ms > 0.0 && running) {
                (Some(seen), _) => format!("{seen:.1}"),
                (None, true) => format!("{:.1}", 1000.0 / r.mean_interval_ms),
                (None, false) => "-".into(),
            };
            [
                r.agent.clone(),
                r.module.clone(),
                r.type_name.clone(),
                r.status.clone(),
                r.steps.to_string(),
                rate,
                format!("{:.1}", r.mean_step_us),
                format!("{:.1}", r.last_step_us),
                r.restarts.to_string(),
                r.failures.to_string(),
                r.dropped.to_string(),
            ]
        })
        .collect();
    super::listing::table(
        [
            "AGENT", "MODULE", "TYPE", "STATUS", "STEPS", "STEPS/S", "MEAN_US", "LAST_US",
            "RESTARTS", "FAILURES", "DROPPED",
        ],
        &cells,
    )
}

/// An agent a follower shows: its name, how it is shown, and where to reach it.
pub(crate) struct Target {
    /// The agent's name, as its run answers to it.
    pub agent: String,
    /// The name shown: with its run's pid when another run here has an agent of that name
    /// (two runs of one config), so their rows and events are told apart.
    pub label: String,
    reach: Reachable,
}

/// An agent followed: a [`Target`] and the client connected to its team.
pub(crate) struct Followed {
    /// The agent's name.
    pub agent: String,
    /// The name shown (see [`Target::label`]).
    pub label: String,
    /// The client reaching it.
    pub client: Client,
}

/// The agents a tool looks at: `agent`, or every agent running here.
pub(crate) fn targets(reach: &Reach, agent: Option<&str>) -> Result<Vec<Target>, ExitCode> {
    match agent {
        Some(agent) => team_of(reach, agent).map(|team| {
            let reach = Reachable {
                agent: agent.to_string(),
                team: team.name.clone(),
                connect: discovery::endpoints_of(&team),
            };
            vec![Target {
                agent: agent.to_string(),
                label: agent.to_string(),
                reach,
            }]
        }),
        None if reach.via.is_some() => {
            eprintln!("error: with --via CONFIG, name the AGENT");
            Err(ExitCode::from(EXIT_BAD_INPUT))
        }
        None => Ok(labelled(super::remote::runs(reach)?)),
    }
}

/// Every agent of `runs`, an agent whose name another run also has labelled with its pid.
fn labelled(runs: Vec<discovery::Record>) -> Vec<Target> {
    let named = |name: &str| {
        runs.iter()
            .filter(|r| r.agents.iter().any(|a| a.agent == name))
            .count()
    };
    let mut targets = Vec::new();
    for run in &runs {
        for reach in &run.agents {
            let label = match named(&reach.agent) {
                1 => reach.agent.clone(),
                _ => format!("{} (pid {})", reach.agent, run.pid),
            };
            targets.push(Target {
                agent: reach.agent.clone(),
                label,
                reach: reach.clone(),
            });
        }
    }
    targets
}

/// Connects a client to each target's team and runs `work` with the agents followed.
pub(crate) fn with_clients<F, Fut>(targets: &[Target], work: F) -> ExitCode
where
    F: FnOnce(std::sync::Arc<Vec<Followed>>) -> Fut,
    Fut: std::future::Future<Output = Result<(), TeamError>>,
{
    let runtime = match super::runtime::start(Some(1)) {
        Ok(rt) => rt,
        Err(code) => return code,
    };
    runtime.block_on(async {
        let mut clients = Vec::new();
        for target in targets {
            match Client::connect(&target.reach.tool_config()).await {
                Ok(client) => clients.push(Followed {
                    agent: target.agent.clone(),
                    label: target.label.clone(),
                    client,
                }),
                Err(e) => return failed(e),
            }
        }
        let clients = std::sync::Arc::new(clients);
        let result = work(clients.clone()).await;
        if let Ok(clients) = std::sync::Arc::try_unwrap(clients) {
            for followed in clients {
                followed.client.close().await;
            }
        }
        match result {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => failed(e),
        }
    })
}

/// Shows `agent` (or every agent running here), once or every second until Ctrl-C.
pub(crate) fn run(reach: &Reach, agent: Option<&str>, once: bool) -> ExitCode {
    let targets = match targets(reach, agent) {
        Ok(t) => t,
        Err(code) => return code,
    };
    let recorded = reach.via.is_none();
    with_clients(&targets, |clients| async move {
        let mut interrupt = super::interrupt::Interrupt::new();
        let mut tick = tokio::time::interval(Duration::from_secs(1));
        let mut left = Vec::new();
        let mut previous: (Vec<ModuleRow>, tokio::time::Instant) =
            (Vec::new(), tokio::time::Instant::now());
        if once {
            // A rate from the steps seen, not from the last steps' mean interval: a module
            // that hangs has a mean interval as good as ever.
            let first = collect(&clients, &mut left, recorded).await?;
            let at = tokio::time::Instant::now();
            tick.tick().await;
            tick.tick().await;
            let mut rows = collect(&clients, &mut left, recorded).await?;
            seen_rates(&mut rows, &first, at.elapsed().as_secs_f64());
            say!("{}", table(&rows));
            return Ok(());
        }
        loop {
            let mut rows = collect(&clients, &mut left, recorded).await?;
            let now = tokio::time::Instant::now();
            seen_rates(&mut rows, &previous.0, (now - previous.1).as_secs_f64());
            // Clear the screen and go home, as `top` does.
            say!("\x1b[2J\x1b[H{}", table(&rows));
            if super::stdout::failed() {
                return Ok(());
            }
            previous = (rows, now);
            tokio::select! {
                _ = tick.tick() => {}
                _ = interrupt.recv() => return Ok(()),
            }
        }
    })
}

/// The rows of every agent of `clients` but those in `left` (by label); an agent whose run
/// ended (see `remote::run_ended`) joins `left`, one that runs but did not answer shows as
/// such, and the others are still shown. An error once all left, or when none answered.
async fn collect(
    clients: &[Followed],
    left: &mut Vec<String>,
    recorded: bool,
) -> Result<Vec<ModuleRow>, TeamError> {
    let mut all = Vec::new();
    let mut silent = None;
    for followed in clients {
        if left.contains(&followed.label) {
            continue;
        }
        match agent_rows(followed).await {
            Ok(rows) => all.extend(rows),
            Err(e) if super::remote::run_ended(&e, &followed.agent, recorded) => {
                left.push(followed.label.clone())
            }
            Err(e @ (TeamError::NoAnswer { .. } | TeamError::Busy { .. })) => {
                all.push(ModuleRow::silent(&followed.label));
                silent.get_or_insert(super::remote::left_or(e, &followed.agent, recorded));
            }
            Err(e) => return Err(e),
        }
    }
    if let Some(e) = silent.filter(|_| all.iter().all(|r| r.status == NO_ANSWER)) {
        return Err(e);
    }
    if !clients.is_empty() && left.len() == clients.len() {
        return Err(TeamError::Refused(match left.as_slice() {
            [one] => format!("agent `{one}` left: its run ended"),
            _ => "every agent shown left: their runs ended".to_string(),
        }));
    }
    Ok(all)
}

/// The rows of one agent, shown under its label.
async fn agent_rows(followed: &Followed) -> Result<Vec<ModuleRow>, TeamError> {
    let (agent, client) = (followed.agent.as_str(), &followed.client);
    let info = client.info(agent).await?;
    let modules: Vec<(String, String)> = info
        .modules
        .iter()
        .map(|m| (m.clone(), info.types.get(m).cloned().unwrap_or_default()))
        .collect();
    let stats: Vec<(String, Vec<u8>)> = client
        .get_matching(agent, "*/stats/**")
        .await?
        .into_iter()
        .map(|(key, _, json)| (key, json))
        .collect();
    Ok(rows(&followed.label, &modules, &stats))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_gathers_a_modules_stats_and_sums_its_queue_drops() {
        let json = |v: &str| v.as_bytes().to_vec();
        let stats = [
            ("scale/stats/status".to_string(), json("\"running\"")),
            ("scale/stats/steps".to_string(), json("42")),
            ("scale/stats/mean_interval_ms".to_string(), json("20.0")),
            ("scale/stats/mean_step_us".to_string(), json("3.5")),
            ("scale/stats/last_step_us".to_string(), json("4.0")),
            ("scale/stats/restarts".to_string(), json("1")),
            ("scale/stats/failures".to_string(), json("2")),
            ("scale/stats/dropped/in/a".to_string(), json("3")),
            ("scale/stats/dropped/in/b".to_string(), json("4")),
            ("scaler/stats/steps".to_string(), json("7")),
        ];
        let modules = [
            ("scale".to_string(), "demo.scale".to_string()),
            ("_team".to_string(), "runtime.team".to_string()),
        ];
        let rows = rows("a", &modules, &stats);
        assert_eq!(rows.len(), 1, "runtime modules are left out");
        let r = &rows[0];
        assert_eq!(
            (
                r.status.as_str(),
                r.steps,
                r.restarts,
                r.failures,
                r.dropped
            ),
            ("running", 42, 1, 2, 7)
        );
        assert_eq!(
            table(&rows),
            "AGENT  MODULE  TYPE        STATUS   STEPS  STEPS/S  MEAN_US  LAST_US  RESTARTS  FAILURES  DROPPED\n\
             a      scale   demo.scale  running  42     50.0     3.5      4.0      1         2         7\n"
        );
        let failed = ModuleRow {
            status: "failed".into(),
            ..rows[0].clone()
        };
        let shown = table(&[failed]);
        let cells: Vec<&str> = shown.lines().nth(1).unwrap().split_whitespace().collect();
        assert_eq!(
            cells[3..6],
            ["failed", "42", "-"],
            "no rate once it no longer runs"
        );
    }

    #[test]
    fn an_agent_that_did_not_answer_shows_one_row_saying_so() {
        let shown = table(&[ModuleRow::silent("frozen")]);
        let cells: Vec<&str> = shown
            .lines()
            .nth(1)
            .unwrap()
            .split("  ")
            .filter(|c| !c.is_empty())
            .map(str::trim)
            .collect();
        assert_eq!(
            cells,
            [
                "frozen",
                "-",
                "-",
                "no answer",
                "-",
                "-",
                "-",
                "-",
                "-",
                "-",
                "-"
            ]
        );
    }

    #[test]
    fn an_agent_name_two_runs_share_is_shown_with_each_runs_pid() {
        let run = |pid, agents: &[&str]| discovery::Record {
            pid,
            started: None,
            agents: agents
                .iter()
                .map(|a| Reachable {
                    agent: a.to_string(),
                    team: format!("t{pid}"),
                    connect: Vec::new(),
                })
                .collect(),
        };
        let targets = labelled(vec![run(10, &["robot1", "base"]), run(11, &["robot1"])]);
        let shown: Vec<(&str, &str)> = targets
            .iter()
            .map(|t| (t.agent.as_str(), t.label.as_str()))
            .collect();
        assert_eq!(
            shown,
            [
                ("robot1", "robot1 (pid 10)"),
                ("base", "base"),
                ("robot1", "robot1 (pid 11)")
            ]
        );
        assert_eq!(
            targets[2].reach.team, "t11",
            "each reached on its own run's team"
        );
    }

    #[test]
    fn between_refreshes_the_rate_is_the_steps_seen_so_a_hung_module_shows_none() {
        let row = |steps, mean_interval_ms| ModuleRow {
            agent: "a".into(),
            module: "m".into(),
            type_name: "t".into(),
            status: petrel_actors::status::RUNNING.into(),
            steps,
            mean_interval_ms,
            ..ModuleRow::default()
        };
        // Its last steps came every 100 ms, then it hung at step 16.
        let before = [row(16, 100.0)];
        let mut now = [row(16, 100.0)];
        seen_rates(&mut now, &before, 1.0);
        let rate = |rows: &[ModuleRow]| {
            let shown = table(rows);
            let line = shown.lines().nth(1).unwrap().to_string();
            line.split_whitespace().nth(5).unwrap().to_string()
        };
        assert_eq!(rate(&now), "0.0", "no step seen in a second");
        assert_eq!(
            rate(&before),
            "10.0",
            "before any refresh: the mean interval"
        );
        let mut going = [row(36, 100.0)];
        seen_rates(&mut going, &before, 2.0);
        assert_eq!(rate(&going), "10.0");
        // Another instance (fewer steps than before, after a restart): the mean interval.
        let mut restarted = [row(3, 50.0)];
        seen_rates(&mut restarted, &before, 1.0);
        assert_eq!(rate(&restarted), "20.0");
    }
}
