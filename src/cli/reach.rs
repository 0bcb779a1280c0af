//! How a `petrel run` can be reached: each agent joins the team its config names, or, without
//! a `team:` section, answers tools on a private loopback team; a record of the process's
//! agents lets `petrel ls|get|set` find them (see `petrel_team::discovery`).

use std::process::ExitCode;

use petrel_actors::team::TeamConfig;
use petrel_actors::{Agent, ConfigFile};
use petrel_team::discovery::{self, Reachable, Record, Registration};
use petrel_team::{Team, TeamError};

/// Joins every agent to its team (a failure to join one is fatal: its links would never
/// work) or makes it reachable on a private team (a failure there only costs the tools, so
/// it is a warning), then writes the record.
pub(crate) async fn join_all(
    agents: &[Agent],
    files: &[ConfigFile],
    teams: &mut Vec<Team>,
) -> Result<Option<Registration>, ExitCode> {
    let mut reachable = Vec::new();
    for (agent, file) in agents.iter().zip(files) {
        let joined = match &file.config.team {
            Some(team) => Team::join(agent, team).await.map(|t| (t, team.clone())),
            None => reach_privately(agent).await,
        };
        match (joined, &file.config.team) {
            (Ok((t, team)), _) => {
                teams.push(t);
                reachable.push(Reachable {
                    agent: agent.name().to_string(),
                    team: team.name.clone(),
                    connect: discovery::endpoints_of(&team),
                });
            }
            (Err(e), Some(_)) => {
                eprintln!(
                    "error: agent `{}` ({}): {e}",
                    agent.name(),
                    file.path().display()
                );
                return Err(ExitCode::FAILURE);
            }
            (Err(e), None) => tracing::warn!(
                agent = agent.name(),
                "tools cannot reach this agent: {e} (run with --no-remote to not try)"
            ),
        }
    }
    let record = Record {
        pid: std::process::id(),
        started: discovery::process_start(std::process::id()),
        agents: reachable,
    };
    let dir = discovery::directory();
    match Registration::write(&dir, &record) {
        Ok(r) => {
            let agents: Vec<&str> = record.agents.iter().map(|a| a.agent.as_str()).collect();
            tracing::info!(?agents, "reachable by tools on this machine (`petrel ls`)");
            Ok(Some(r))
        }
        Err(e) => {
            tracing::warn!(
                "tools cannot find this run: cannot write its record in {}: {e}",
                dir.display()
            );
            Ok(None)
        }
    }
}

/// Opens a private team on a free loopback port. The port is free when asked for but could be
/// taken before zenoh binds it: try a few.
async fn reach_privately(agent: &Agent) -> Result<(Team, TeamConfig), TeamError> {
    let mut last = None;
    for _ in 0..3 {
        let port = std::net::TcpListener::bind(("127.0.0.1", 0))
            .and_then(|l| l.local_addr())
            .map_err(|e| TeamError::Open(format!("no free loopback port: {e}")))?
            .port();
        let team = discovery::private_team(agent.name(), std::process::id(), port);
        match Team::reachable(agent, &team).await {
            Ok(t) => return Ok((t, team)),
            Err(e) => last = Some(e),
        }
    }
    Err(last.expect("tried at least once"))
}
