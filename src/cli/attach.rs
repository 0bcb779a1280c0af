//! `petrel console`: the web console attached to running agents over their teams, instead of
//! inside a `petrel run`. It finds agents as the CLI tools do (the records every `petrel run`
//! writes on this machine), shows each as it appears, and shows it gone when its process ends
//! (a SIGKILLed run included: its record is skipped once the process is gone). With `--via
//! CONFIG` it shows the members of that config's team instead, wherever they run, as they join
//! and leave (their liveliness tokens, as members see them).

use std::collections::{BTreeMap, HashMap};
use std::net::SocketAddr;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use petrel_actors::outln;
use petrel_console::{AgentSource, Console, RemoteAgent};
use petrel_team::discovery::{self, Reachable, Record};
use petrel_team::{Client, Members};

use super::team_agent::TeamAgent;
use super::EXIT_BAD_INPUT;

/// How often the records of running agents are read again (joins and departures show within it).
const ROSTER_PERIOD: Duration = Duration::from_millis(250);

/// Arguments of `petrel console`.
#[derive(clap::Args)]
pub(crate) struct ConsoleArgs {
    /// Where to serve the page (port 0: any free port, printed).
    #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:8080")]
    listen: SocketAddr,
    /// Only the agents of this team (repeat for several; default: every agent running here).
    #[arg(long, value_name = "NAME")]
    team: Vec<String>,
    /// Only the agents of the run with this process id.
    #[arg(long)]
    pid: Option<u32>,
    /// The members of the team of this config (any agent config of the team), wherever they
    /// run, instead of the runs recorded on this machine.
    #[arg(long, value_name = "CONFIG", conflicts_with_all = ["team", "pid"])]
    via: Option<std::path::PathBuf>,
    /// The token every request must carry (`?token=` or `Authorization: Bearer`); required
    /// beyond loopback, where one is generated and printed if not given.
    #[arg(long, value_name = "TOKEN")]
    token: Option<String>,
}

/// The agents to show: those of the records (of `teams` and `pid` when given), by name. An
/// agent that runs in several processes is shown once, from the oldest process.
pub(crate) fn roster(
    records: &[Record],
    teams: &[String],
    pid: Option<u32>,
) -> BTreeMap<String, Reachable> {
    let mut shown = BTreeMap::new();
    for record in records.iter().filter(|r| pid.is_none_or(|p| p == r.pid)) {
        for agent in &record.agents {
            if teams.is_empty() || teams.contains(&agent.team) {
                shown
                    .entry(agent.agent.clone())
                    .or_insert_with(|| agent.clone());
            }
        }
    }
    shown
}

/// Serves the console until Ctrl-C or SIGTERM.
pub(crate) fn run(args: ConsoleArgs) -> ExitCode {
    if let Err(e) = super::logging::init(super::LogFormat::Pretty, None) {
        eprintln!("error: cannot set up logging: {e}");
    }
    let given = args.token.as_deref();
    if let Err(e) = petrel_console::core::access::Access::for_bind(args.listen, given, String::new)
    {
        eprintln!("error: --listen {}: {e}", args.listen);
        return ExitCode::from(EXIT_BAD_INPUT);
    }
    if let Some(pid) = args.pid {
        // A pid that runs nothing now never will: the console would wait for it for ever.
        let reach = super::remote::Reach {
            via: None,
            pid: Some(pid),
        };
        if let Err(code) = super::remote::runs(&reach) {
            return code;
        }
    }
    if args.team.iter().any(|t| t.trim().is_empty()) {
        eprintln!("error: --team: an empty team name matches no agent; expected a team's name");
        return ExitCode::from(EXIT_BAD_INPUT);
    }
    let via = match &args.via {
        Some(path) => {
            let reach = super::remote::Reach {
                via: Some(path.clone()),
                pid: None,
            };
            match super::remote::team_of(&reach, "") {
                Ok(team) => Some(team),
                Err(code) => return code,
            }
        }
        None => None,
    };
    let runtime = match super::runtime::start(Some(2)) {
        Ok(rt) => rt,
        Err(code) => return code,
    };
    runtime.block_on(async {
        let console = match super::console::serve(args.listen, args.token.clone(), Vec::new()).await
        {
            Ok(c) => c,
            Err(e) => {
                eprintln!("error: {}", e.replacen("--console", "--listen", 1));
                return ExitCode::from(EXIT_BAD_INPUT);
            }
        };
        let mut attached = Attached::default();
        let mut finder = match via {
            Some(team) => match attached.follow(&team).await {
                Ok(members) => Finder::Team {
                    at: Reachable {
                        agent: String::new(),
                        team: team.name.clone(),
                        connect: discovery::endpoints_of(&team),
                    },
                    members,
                },
                Err(e) => {
                    eprintln!("error: --via: {e}");
                    super::console::stop(console).await;
                    return ExitCode::from(super::EXIT_FAILED);
                }
            },
            None => Finder::Records {
                teams: args.team.clone(),
                pid: args.pid,
            },
        };
        let mut tick = tokio::time::interval(ROSTER_PERIOD);
        let mut interrupt = super::interrupt::Interrupt::new();
        loop {
            tokio::select! {
                _ = tick.tick() => attached.update(&console, &finder).await,
                _ = finder.changed() => attached.update(&console, &finder).await,
                _ = interrupt.recv() => break,
            }
        }
        drop(finder);
        super::console::stop(console).await;
        attached.close().await;
        ExitCode::SUCCESS
    })
}

/// Where the agents to show are found.
enum Finder {
    /// In the records of the runs on this machine, of these teams (all: none named).
    Records {
        teams: Vec<String>,
        pid: Option<u32>,
    },
    /// Among the members of one team, reached at `at` (its agent left empty).
    Team { at: Reachable, members: Members },
}

impl Finder {
    /// The agents to show now, by name.
    fn wanted(&self) -> BTreeMap<String, Reachable> {
        match self {
            Finder::Records { teams, pid } => {
                roster(&discovery::running(&discovery::directory()), teams, *pid)
            }
            Finder::Team { at, members } => members
                .now()
                .into_iter()
                .map(|agent| {
                    let reach = Reachable {
                        agent: agent.clone(),
                        ..at.clone()
                    };
                    (agent, reach)
                })
                .collect(),
        }
    }

    /// Resolves when the team's membership changed (never for records: they are re-read).
    async fn changed(&mut self) {
        match self {
            Finder::Team { members, .. } => members.changed().await,
            Finder::Records { .. } => std::future::pending().await,
        }
    }
}

/// The agents shown and the team clients that reach them.
#[derive(Default)]
struct Attached {
    /// One client per team and endpoints (agents of one team share it).
    clients: HashMap<(String, Vec<String>), Arc<Client>>,
    /// The client following a `--via` team's members (kept while the console runs).
    following: Option<Arc<Client>>,
    /// Shown agents and where they were found.
    shown: BTreeMap<String, Reachable>,
}

impl Attached {
    /// Connects to `team` and follows its members; its agents are reached with that client.
    async fn follow(
        &mut self,
        team: &petrel_actors::team::TeamConfig,
    ) -> Result<Members, petrel_team::TeamError> {
        let client = Arc::new(Client::connect(team).await?);
        let members = client.members().await?;
        let key = (team.name.clone(), discovery::endpoints_of(team));
        self.clients.insert(key, client.clone());
        self.following = Some(client);
        Ok(members)
    }

    /// Shows the agents that appeared and marks gone those that left.
    async fn update(&mut self, console: &Console, finder: &Finder) {
        let wanted = finder.wanted();
        let gone: Vec<String> = self
            .shown
            .iter()
            .filter(|(name, at)| wanted.get(*name) != Some(at))
            .map(|(name, _)| name.clone())
            .collect();
        for name in gone {
            self.shown.remove(&name);
            console.leave(&name);
            outln!("console: agent `{name}` left");
        }
        for (name, at) in wanted {
            if self.shown.contains_key(&name) {
                continue;
            }
            // An agent not answering yet (a run still starting) is tried again next time.
            if let Some(source) = self.reach(&at).await {
                console.join(source).await;
                // Said once the console serves it: tests (and people) may ask at once.
                outln!("console: showing agent `{name}` (team `{}`)", at.team);
                self.shown.insert(name, at);
            }
        }
        let used: Vec<(String, Vec<String>)> = self
            .shown
            .values()
            .map(|a| (a.team.clone(), a.connect.clone()))
            .collect();
        let following = self.following.clone();
        self.clients.retain(|k, c| {
            used.contains(k) || following.as_ref().is_some_and(|f| Arc::ptr_eq(f, c))
        });
    }

    /// Connects to `at`'s team (or reuses its client) and asks the agent what it holds.
    async fn reach(&mut self, at: &Reachable) -> Option<AgentSource> {
        let key = (at.team.clone(), at.connect.clone());
        let client = match self.clients.get(&key) {
            Some(c) => c.clone(),
            None => match Client::connect(&at.tool_config()).await {
                Ok(c) => {
                    let c = Arc::new(c);
                    self.clients.insert(key, c.clone());
                    c
                }
                Err(e) => {
                    tracing::warn!(agent = %at.agent, team = %at.team, error = %e, "cannot reach the team");
                    return None;
                }
            },
        };
        let agent = TeamAgent {
            client,
            agent: at.agent.clone(),
        };
        let listing = match agent.listing().await {
            Ok(l) => l,
            Err(e) => {
                tracing::debug!(agent = %at.agent, error = %e, "not answering yet");
                return None;
            }
        };
        let plans = agent.plans(&listing).await;
        let mut source = AgentSource::remote(&at.agent, Arc::new(agent));
        source.plans = plans;
        Some(source)
    }

    async fn close(mut self) {
        self.following = None;
        for (_, client) in self.clients {
            if let Ok(client) = Arc::try_unwrap(client) {
                client.close().await;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(pid: u32, agents: &[(&str, &str)]) -> Record {
        Record {
            pid,
            started: None,
            agents: agents
                .iter()
                .map(|(agent, team)| Reachable {
                    agent: agent.to_string(),
                    team: team.to_string(),
                    connect: vec![format!("tcp/127.0.0.1:{pid}")],
                })
                .collect(),
        }
    }

    #[test]
    fn the_roster_keeps_the_teams_asked_for_and_one_agent_per_name() {
        let records = [
            record(10, &[("r1", "rescue"), ("sim", "rescue")]),
            record(11, &[("robot1", "local.11.robot1")]),
            record(12, &[("r1", "rescue")]),
        ];
        let all = roster(&records, &[], None);
        assert_eq!(all.keys().collect::<Vec<_>>(), ["r1", "robot1", "sim"]);
        assert_eq!(all["r1"].connect, ["tcp/127.0.0.1:10"], "the oldest run's");
        let rescue = roster(&records, &["rescue".into()], None);
        assert_eq!(rescue.keys().collect::<Vec<_>>(), ["r1", "sim"]);
        let one = roster(&records, &[], Some(12));
        assert_eq!(one["r1"].connect, ["tcp/127.0.0.1:12"]);
    }
}
