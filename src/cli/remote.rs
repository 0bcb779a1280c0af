//! `petrel ls`, `petrel get` and `petrel set`: list, read and write the properties of running
//! agents. A tool finds an agent through the records every `petrel run` writes (see
//! `petrel_team::discovery`), or through the `team:` section of a config given with `--via`.

use std::path::PathBuf;
use std::process::ExitCode;

use petrel_actors::team::TeamConfig;
use petrel_actors::{ConfigFile, PropertyKind, PropertyUrl};
use petrel_team::discovery;
use petrel_team::{Client, TeamError};

use super::stdout::{say, sayln};
use super::{bad_input, EXIT_BAD_INPUT};

/// Exit code when the agent refused or did not answer.
const EXIT_REFUSED: u8 = 1;

/// Where to look for an agent.
#[derive(clap::Args)]
pub(crate) struct Reach {
    /// Reach the agent through the team of this config (any agent config of the team) instead
    /// of the runs recorded on this machine.
    #[arg(long)]
    pub(crate) via: Option<PathBuf>,
    /// Of the runs on this machine, the one with this process id (when several run the agent).
    #[arg(long, conflicts_with = "via")]
    pub(crate) pid: Option<u32>,
}

/// What to do once attached.
pub(crate) enum Request {
    Get,
    Set(String),
}

/// Carries out `request` on `url`.
pub(crate) fn property(reach: &Reach, url: &str, request: Request) -> ExitCode {
    // Text that is no value whatever the property's type is bad input, found before any agent
    // is asked; a value the agent refuses (its type, its range) is its answer.
    if let Request::Set(value) = &request {
        if let Err(why) = petrel_actors::parse_set_text(value) {
            eprintln!("error: cannot set `{url}`: {why}");
            return ExitCode::from(EXIT_BAD_INPUT);
        }
    }
    let (url, team) = match target(reach, url) {
        Ok(t) => t,
        Err(code) => return code,
    };
    attached(&team, |client| async move {
        match &request {
            Request::Get => client.get_json(&url).await.map(|(type_name, json)| {
                sayln!("{} ({type_name})", String::from_utf8_lossy(&json));
            }),
            Request::Set(value) => {
                client.set_ron(&url, value).await?;
                sayln!("{url} = {value}");
                if let Some(manager) = context_holding(&client, &url).await {
                    eprintln!(
                        "note: a context of `{manager}` holds `{}/{}`: while it is active it may write it again, and when it ends the value from before it comes back, not this one",
                        url.module(),
                        url.path()
                    );
                }
                Ok(())
            }
        }
    })
}

/// The context manager of `url`'s agent whose active contexts set `url` (one that will put
/// back its own original when they end), from the managers' `state/memory`.
async fn context_holding(client: &Client, url: &PropertyUrl) -> Option<String> {
    let agent = url.agent()?;
    let target = format!("{}/{}", url.module(), url.path());
    let memories = client.get_matching(agent, "*/state/memory").await.ok()?;
    memories.into_iter().find_map(|(key, _, json)| {
        let memory: serde_json::Value = serde_json::from_slice(&json).ok()?;
        let held = memory
            .get("original_values")?
            .as_array()?
            .iter()
            .any(|entry| entry.get(0).and_then(serde_json::Value::as_str) == Some(target.as_str()));
        held.then(|| key.trim_end_matches("/state/memory").to_string())
    })
}

/// The property `url` names and the team to reach it on.
pub(crate) fn target(reach: &Reach, url: &str) -> Result<(PropertyUrl, TeamConfig), ExitCode> {
    let url = tool_url(url).map_err(|e| {
        eprintln!("error: {e}");
        ExitCode::from(EXIT_BAD_INPUT)
    })?;
    let team = team_of(reach, url.agent().unwrap_or_default())?;
    Ok((url, team))
}

/// The property a tool names: `petrel://agent/module/path`, or the same without the scheme.
/// A tool always addresses a running agent, so there the first segment is the agent (`petrel
/// ls` lists it so: `agent robot1`, then its modules and their properties). An address whose
/// second segment is a property kind (`scale/params/factor`) is a module's property without
/// its agent, and is refused as such.
fn tool_url(text: &str) -> Result<PropertyUrl, String> {
    let kind_second = text.split('/').nth(1).is_some_and(|second| {
        use PropertyKind::*;
        [Input, Output, Param, State, Stats, Control]
            .iter()
            .any(|k| k.prefix().strip_suffix('/') == Some(second))
    });
    if !text.contains("://") && kind_second {
        return Err(format!(
            "`{text}` names no agent: write `AGENT/{text}` or `petrel://AGENT/{text}`"
        ));
    }
    let full = match text.contains("://") {
        true => text.to_string(),
        false => format!("petrel://{text}"),
    };
    PropertyUrl::parse(&full).map_err(|e| {
        format!(
            "`{text}` is not a property of an agent: {}; expected `agent/module/path` or `petrel://agent/module/path`",
            e.reason
        )
    })
}

/// `petrel ls`: the agents running on this machine, or with `agent`, its modules and
/// properties.
pub(crate) fn list(reach: &Reach, agent: Option<&str>) -> ExitCode {
    let Some(agent) = agent else {
        return list_agents(reach);
    };
    let team = match team_of(reach, agent) {
        Ok(t) => t,
        Err(code) => return code,
    };
    attached(&team, |client| async move {
        let info = client.info(agent).await?;
        say!("{}", super::listing::agent(&info));
        Ok(())
    })
}

fn list_agents(reach: &Reach) -> ExitCode {
    if reach.via.is_some() {
        eprintln!("error: `petrel ls --via CONFIG` needs an AGENT: a team has no list of agents to ask before it is joined");
        return ExitCode::from(EXIT_BAD_INPUT);
    }
    match runs(reach) {
        Ok(records) => {
            say!("{}", super::listing::agents(&records));
            ExitCode::SUCCESS
        }
        Err(code) => code,
    }
}

/// The runs on this machine, or with `--pid` that one; a pid that runs nothing here is an
/// error naming the pids that do (an empty listing looked like nothing running at all).
pub(crate) fn runs(reach: &Reach) -> Result<Vec<discovery::Record>, ExitCode> {
    let records = discovery::running(&discovery::directory());
    let Some(pid) = reach.pid else {
        return Ok(records);
    };
    let (mine, others): (Vec<_>, Vec<_>) = records.into_iter().partition(|r| r.pid == pid);
    if mine.is_empty() {
        let runs: Vec<u32> = others.iter().map(|r| r.pid).collect();
        eprintln!("error: {}", discovery::FindError::NoSuchRun { pid, runs });
        return Err(ExitCode::from(EXIT_REFUSED));
    }
    Ok(mine)
}

/// The team section to reach `agent` with: the `--via` config's, or the recorded run's.
pub(crate) fn team_of(reach: &Reach, agent: &str) -> Result<TeamConfig, ExitCode> {
    let Some(via) = &reach.via else {
        let records = discovery::running(&discovery::directory());
        return match discovery::find(&records, agent, reach.pid) {
            Ok(found) => Ok(found.tool_config()),
            Err(e) => {
                eprintln!("error: {e}");
                Err(ExitCode::from(EXIT_REFUSED))
            }
        };
    };
    let file = ConfigFile::load(via).map_err(|e| bad_input(&e))?;
    file.config.team.clone().ok_or_else(|| {
        eprintln!(
            "error: {} has no `team:` section: give the config of an agent of the team to reach",
            via.display()
        );
        ExitCode::from(EXIT_BAD_INPUT)
    })
}

/// Connects a client to `team`, runs `work` with it and closes it.
pub(crate) fn attached<F, Fut>(team: &TeamConfig, work: F) -> ExitCode
where
    F: FnOnce(std::sync::Arc<Client>) -> Fut,
    Fut: std::future::Future<Output = Result<(), TeamError>>,
{
    let runtime = match super::runtime::start(Some(1)) {
        Ok(rt) => rt,
        Err(code) => return code,
    };
    runtime.block_on(async {
        let client = match Client::connect(team).await {
            Ok(c) => std::sync::Arc::new(c),
            Err(e) => return failed(e),
        };
        let result = work(client.clone()).await;
        if let Ok(client) = std::sync::Arc::try_unwrap(client) {
            client.close().await;
        }
        match result {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => failed(e),
        }
    })
}

/// `e`, or, for an agent that no longer answers because its run ended, that: when it was found
/// in the records of the runs on this machine (`recorded`) and none has it any more. A run
/// that ended reads otherwise as an agent outside the team; one that is still recorded but
/// did not answer is said to be stopped or held, not asked whether it is in the team.
pub(crate) fn left_or(e: TeamError, agent: &str, recorded: bool) -> TeamError {
    if run_ended(&e, agent, recorded) {
        return TeamError::Refused(format!("agent `{agent}` left: its run ended"));
    }
    match e {
        // Its run is still here: the team is right, the process is not answering.
        TeamError::NoAnswer { timeout, .. } if recorded => TeamError::Refused(format!(
            "agent `{agent}` did not answer within {timeout:?}, though its run is still here: a stopped process (`kill -STOP`, a debugger), or a thread held by a step that does not return"
        )),
        e => e,
    }
}

/// Whether `e`, no answer from `agent`, is because its run ended (see [`left_or`]).
pub(crate) fn run_ended(e: &TeamError, agent: &str, recorded: bool) -> bool {
    recorded
        && matches!(e, TeamError::NoAnswer { .. })
        && !discovery::running(&discovery::directory())
            .iter()
            .flat_map(|r| &r.agents)
            .any(|a| a.agent == agent)
}

pub(crate) fn failed(e: TeamError) -> ExitCode {
    eprintln!("error: {e}");
    ExitCode::from(EXIT_REFUSED)
}

#[cfg(test)]
mod tests {
    use super::tool_url;

    #[test]
    fn a_tool_takes_an_address_with_or_without_the_scheme_and_the_agent_first() {
        for text in ["petrel://robot1/mapper/out/map", "robot1/mapper/out/map"] {
            let url = tool_url(text).unwrap();
            assert_eq!(
                (url.agent(), url.module(), url.path()),
                (Some("robot1"), "mapper", "out/map"),
                "{text}"
            );
        }
        let error = tool_url("scale/params/factor").unwrap_err();
        assert_eq!(
            error,
            "`scale/params/factor` names no agent: write `AGENT/scale/params/factor` or `petrel://AGENT/scale/params/factor`"
        );
        for (text, reason) in [
            ("mapper/enabled", "missing property path"),
            ("robot1", "missing module"),
            ("ros://robot1/mapper/out/map", "unknown scheme"),
        ] {
            let error = tool_url(text).unwrap_err();
            assert!(
                error.starts_with(&format!(
                    "`{text}` is not a property of an agent: {reason};"
                )),
                "{error}"
            );
        }
    }
}
