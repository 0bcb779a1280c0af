//! Teams: agents share properties, queues and remote writes over zenoh, across processes and
//! machines, and notice each other's departures.
//!
//! [`Team::join`] puts a running [`Agent`] on the team its config names. The agent's remote
//! links (inputs linked to `petrel://other_agent/...`) are then fed from the other agents, its
//! own properties are published to the agents that link to them, and `_team/members` and
//! `_team/events` show who is in the team. Modules see none of this: a remote input reads like
//! any input.
//!
//! The pure parts (key layout, attachments, link states, membership) are in [`keys`],
//! [`wire`], [`tracker`] and [`membership`], tested without a network; the rest is a thin
//! shell around a zenoh session. The wire format is documented in `docs/wire-format.md`.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use parking_lot::Mutex;
use petrel_actors::team::{RemoteWriter, TeamConfig, TeamEvent, TeamMembers, TEAM_MODULE};
use petrel_actors::url::PropertyUrl;
use petrel_actors::{Agent, Blackboard, PropertyType};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;
use zenoh::sample::SampleKind;

mod claim;
mod client;
pub mod discovery;
mod export;
mod import;
pub mod keys;
pub mod lossy;
mod mail;
mod members;
pub mod membership;
mod roster;
mod service;
mod session;
pub mod tracker;
mod watch;
pub mod wire;

pub use client::{ron_encoding, AgentInfo, Client, REQUEST_TIMEOUT};
pub use roster::Members;
pub use session::zenoh_config;
pub use watch::{Update, Watch, WatchEvent};

use keys::Keys;
use membership::Membership;

/// Why an agent could not join its team, or a remote request failed.
#[derive(Debug, Clone, thiserror::Error)]
pub enum TeamError {
    /// The team section cannot be turned into a zenoh config.
    #[error("team config: {0}")]
    Config(String),
    /// zenoh could not open a session (e.g. a `listen` port is taken).
    #[error("cannot join the team: {0}")]
    Open(String),
    /// A zenoh declaration failed.
    #[error("team transport: {0}")]
    Transport(String),
    /// Another run of this agent, which answers, holds the agent's name in the team.
    #[error("team `{team}` already has an agent `{agent}`: {holder} runs it and answers. Two agents of one team cannot share a name: stop that run (`petrel ls` lists the runs on this machine), or give this agent another name")]
    NameTaken {
        /// The agent's name.
        agent: String,
        /// The team.
        team: String,
        /// Who holds the name: process, host and session, as far as it said.
        holder: String,
    },
    /// The agent lacks the `_team` properties (its config has no `team:` section).
    #[error("agent `{0}` was built without a `team:` section")]
    NotATeamAgent(String),
    /// The other agent refused a remote write, saying why.
    #[error("{0}")]
    Refused(String),
    /// The agent is there but did not answer in time.
    #[error("agent `{agent}` did not answer within {timeout:?}: it runs, but its thread is busy (a step that does not return? `petrel top` shows each module's last step)")]
    Busy {
        /// The agent asked.
        agent: String,
        /// How long we waited.
        timeout: std::time::Duration,
    },
    /// Nobody answered.
    #[error(
        "agent `{agent}` did not answer within {timeout:?} (is it a member of team `{team}`?)"
    )]
    NoAnswer {
        /// The agent asked.
        agent: String,
        /// The team.
        team: String,
        /// How long we waited.
        timeout: std::time::Duration,
    },
}

impl From<zenoh::Error> for TeamError {
    fn from(e: zenoh::Error) -> Self {
        TeamError::Transport(e.to_string())
    }
}

/// What the shell's tasks and callbacks share.
pub(crate) struct Ctx {
    session: zenoh::Session,
    keys: Keys,
    agent: String,
    zid: String,
    config: TeamConfig,
    blackboard: Blackboard,
    /// Incoming streams by id, for membership changes to reach their trackers.
    streams: Mutex<HashMap<String, Arc<import::Stream>>>,
    membership: Mutex<Membership>,
    /// The last message number received from each sender, for dropping repeats.
    seen: Mutex<mail::Seen>,
}

/// Token events buffered between zenoh's callbacks and the tasks that apply them; beyond it
/// events are dropped and counted (a peer flooding the team cannot grow memory).
const EVENT_BUFFER: usize = 4096;

/// An agent's membership of its team. Dropping it leaves the team.
pub struct Team {
    ctx: Arc<Ctx>,
    tasks: Vec<JoinHandle<()>>,
    declared: Vec<Box<dyn Send + Sync>>,
    overflow: Arc<AtomicU64>,
}

impl Team {
    /// Joins `agent` to the team `config` describes (the agent's config's `team:` section).
    pub async fn join(agent: &Agent, config: &TeamConfig) -> Result<Team, TeamError> {
        let blackboard = agent.blackboard();
        let members = blackboard
            .handle::<TeamMembers>(&format!("{TEAM_MODULE}/members"))
            .await
            .map_err(|_| TeamError::NotATeamAgent(agent.name().into()))?;
        let events = blackboard
            .queue_writer::<TeamEvent>(&format!("{TEAM_MODULE}/events"))
            .await
            .map_err(|_| TeamError::NotATeamAgent(agent.name().into()))?;
        let team = Team::open(agent, config, Some(members::Board { members, events })).await?;
        tracing::info!(agent = %agent.name(), team = %config.name, zid = %team.zid(), "joined the team");
        Ok(team)
    }

    /// Makes an agent that is in no team reachable by tools (`petrel get`, `ls`, ...) on the
    /// team `config` describes, usually [`discovery::private_team`]: it answers requests and
    /// publishes what is asked for, but follows no members and has no remote links.
    pub async fn reachable(agent: &Agent, config: &TeamConfig) -> Result<Team, TeamError> {
        let team = Team::open(agent, config, None).await?;
        tracing::debug!(agent = %agent.name(), reach = ?config.listen, "reachable by tools");
        Ok(team)
    }

    async fn open(
        agent: &Agent,
        config: &TeamConfig,
        board: Option<members::Board>,
    ) -> Result<Team, TeamError> {
        let blackboard = agent.blackboard().clone();
        let session = session::open(config).await?;
        let zid = session.zid().to_string();
        let ctx = Arc::new(Ctx {
            keys: Keys::new(&config.name),
            agent: agent.name().to_string(),
            zid,
            config: config.clone(),
            blackboard: blackboard.clone(),
            streams: Mutex::default(),
            membership: Mutex::default(),
            seen: Mutex::default(),
            session,
        });
        if board.is_some() {
            claim_name(&ctx).await?;
        }
        let mut team = Team {
            ctx: ctx.clone(),
            tasks: Vec::new(),
            declared: Vec::new(),
            overflow: Arc::default(),
        };
        team.serve().await?;
        let (want_tx, want_rx) = mpsc::channel(EVENT_BUFFER);
        team.watch_tokens(ctx.keys.wants_of(&ctx.agent), want_tx)
            .await?;
        team.tasks
            .push(tokio::spawn(export::run(ctx.clone(), want_rx)));
        let Some(board) = board else {
            return Ok(team);
        };
        let board = Arc::new(board);
        let (alive_tx, alive_rx) = mpsc::channel(EVENT_BUFFER);
        team.watch_tokens(ctx.keys.all_alive(), alive_tx).await?;
        team.tasks.push(tokio::spawn(members::run(
            ctx.clone(),
            board.clone(),
            alive_rx,
        )));
        let (info_tx, info_rx) = mpsc::channel(EVENT_BUFFER);
        team.watch_samples(ctx.keys.info("*"), info_tx).await?;
        team.tasks.push(tokio::spawn(members::follow_announcements(
            ctx.clone(),
            board,
            info_rx,
        )));
        team.tasks.push(tokio::spawn(import::follow_links(
            ctx.clone(),
            blackboard.remote_links(),
        )));
        team.tasks
            .push(tokio::spawn(members::follow_modules(ctx.clone())));
        // Announced last: when others see the agent, it already answers.
        let alive = ctx.keys.alive(&ctx.agent, &ctx.zid);
        let token = ctx.session.liveliness().declare_token(alive).await?;
        team.declared.push(Box::new(token));
        blackboard.set_remote_writer(Some(Arc::new(Writer(ctx.clone()))));
        Ok(team)
    }

    /// This agent's zenoh session id.
    pub fn zid(&self) -> &str {
        &self.ctx.zid
    }

    /// Token events dropped because they came faster than they could be applied.
    pub fn overflowed(&self) -> u64 {
        self.overflow.load(Ordering::Relaxed)
    }

    /// Sets another agent's `params/` or `control/` property to `value`, if its owner's
    /// `remote_write` patterns allow it; the owner's refusal comes back as the error.
    pub async fn set<T: PropertyType>(
        &self,
        url: &PropertyUrl,
        value: &T,
    ) -> Result<(), TeamError> {
        let json = serde_json::to_vec(value).map_err(|e| TeamError::Refused(e.to_string()))?;
        self.set_json(url, json).await
    }

    /// [`set`](Self::set) with the value already in JSON (as tools have it).
    pub async fn set_json(&self, url: &PropertyUrl, json: Vec<u8>) -> Result<(), TeamError> {
        let ctx = &self.ctx;
        let encoding = zenoh::bytes::Encoding::APPLICATION_JSON;
        client::set(
            &ctx.session,
            &ctx.keys,
            &ctx.config.name,
            url,
            json,
            encoding,
        )
        .await
    }

    /// The current value of another agent's property: its type name and JSON text.
    pub async fn get_json(&self, url: &PropertyUrl) -> Result<(String, Vec<u8>), TeamError> {
        let ctx = &self.ctx;
        client::get(&ctx.session, &ctx.keys, &ctx.config.name, url).await
    }

    /// [`get_json`](Self::get_json), decoded as a `T`.
    pub async fn get<T: PropertyType>(&self, url: &PropertyUrl) -> Result<T, TeamError> {
        let (type_name, json) = self.get_json(url).await?;
        if type_name != T::TYPE_NAME {
            return Err(TeamError::Refused(format!(
                "`{url}` is a {type_name}, not a {}",
                T::TYPE_NAME
            )));
        }
        serde_json::from_slice(&json).map_err(|e| TeamError::Refused(e.to_string()))
    }

    /// The agent this membership is of.
    pub fn agent(&self) -> &str {
        &self.ctx.agent
    }

    /// Leaves the team: others see this agent leave at once (not after the lease).
    pub async fn leave(mut self) {
        self.stop();
        if let Err(e) = self.ctx.session.close().await {
            tracing::warn!(error = %e, "closing the team session");
        }
        tracing::info!(agent = %self.ctx.agent, "left the team");
    }

    fn stop(&mut self) {
        self.ctx.blackboard.set_remote_writer(None);
        for task in self.tasks.drain(..) {
            task.abort();
        }
        // Undeclaring drops the callbacks, which hold the shared context.
        self.declared.clear();
    }

    /// Declares the queryables this agent answers.
    async fn serve(&mut self) -> Result<(), TeamError> {
        let ctx = &self.ctx;
        for (key, kind) in [
            (ctx.keys.info(&ctx.agent), Service::Info),
            (ctx.keys.values_of(&ctx.agent), Service::Get),
            (ctx.keys.sets_of(&ctx.agent), Service::Set),
            (ctx.keys.inboxes_of(&ctx.agent), Service::Inbox),
        ] {
            let (ctx, runtime) = (ctx.clone(), tokio::runtime::Handle::current());
            let q = self
                .ctx
                .session
                .declare_queryable(key)
                .callback(move |query| {
                    let ctx = ctx.clone();
                    drop(match kind {
                        Service::Info => runtime.spawn(service::info(ctx, query)),
                        Service::Get => runtime.spawn(service::get(ctx, query)),
                        Service::Set => runtime.spawn(service::set(ctx, query)),
                        Service::Inbox => runtime.spawn(mail::receive(ctx, query)),
                    })
                })
                .await?;
            self.declared.push(Box::new(q));
        }
        Ok(())
    }

    /// Sends samples put under `key` (key, payload) to `tx`; beyond its capacity they are
    /// dropped and counted.
    async fn watch_samples(
        &mut self,
        key: String,
        tx: mpsc::Sender<(String, Vec<u8>)>,
    ) -> Result<(), TeamError> {
        let overflow = self.overflow.clone();
        let sub = self
            .ctx
            .session
            .declare_subscriber(key)
            .callback(move |sample| {
                let item = (
                    sample.key_expr().to_string(),
                    sample.payload().to_bytes().into_owned(),
                );
                if tx.try_send(item).is_err() {
                    overflow.fetch_add(1, Ordering::Relaxed);
                }
            })
            .await?;
        self.declared.push(Box::new(sub));
        Ok(())
    }

    /// Sends liveliness tokens under `key` (those alive now, then changes) to `tx`.
    async fn watch_tokens(
        &mut self,
        key: String,
        tx: mpsc::Sender<(String, bool)>,
    ) -> Result<(), TeamError> {
        let overflow = self.overflow.clone();
        let sub = self
            .ctx
            .session
            .liveliness()
            .declare_subscriber(key)
            .history(true)
            .callback(move |sample| {
                let event = (
                    sample.key_expr().to_string(),
                    sample.kind() == SampleKind::Put,
                );
                if tx.try_send(event).is_err() {
                    let n = overflow.fetch_add(1, Ordering::Relaxed) + 1;
                    if n.is_power_of_two() {
                        tracing::warn!(
                            dropped = n,
                            "team token events come faster than they are applied: dropped"
                        );
                    }
                }
            })
            .await?;
        self.declared.push(Box::new(sub));
        Ok(())
    }
}

/// Refuses the agent's name when another run that answers holds it; one that does not answer
/// (stopped, or killed and its lease not over) is left to be taken over when its token ends,
/// as a restarted robot must be able to do.
async fn claim_name(ctx: &Ctx) -> Result<(), TeamError> {
    let claim = claim::check(&ctx.session, &ctx.keys, &ctx.agent, &ctx.zid).await?;
    if let Some(refused) = claim.refusal(&ctx.agent, &ctx.config.name) {
        return Err(refused);
    }
    if let claim::Claim::Silent(holders) = claim {
        tracing::warn!(
            agent = %ctx.agent,
            team = %ctx.config.name,
            ?holders,
            "the name `{}` is held in the team by a session that does not answer (a stopped or killed run?): this agent takes it over when that session's lease ({} ms) ends; until then the team refuses its samples",
            ctx.agent,
            ctx.config.lease_ms
        );
    }
    Ok(())
}

impl Drop for Team {
    fn drop(&mut self) {
        self.stop();
    }
}

/// The queries an agent answers.
#[derive(Clone, Copy)]
enum Service {
    Info,
    Get,
    Set,
    Inbox,
}

/// Carries the agent's writes to other agents' properties (`Blackboard::set` on their URLs).
struct Writer(Arc<Ctx>);

impl RemoteWriter for Writer {
    fn set_json(
        &self,
        url: PropertyUrl,
        json: Vec<u8>,
    ) -> std::pin::Pin<Box<dyn std::future::Future<Output = Result<(), String>> + Send>> {
        let ctx = self.0.clone();
        Box::pin(async move {
            let encoding = zenoh::bytes::Encoding::APPLICATION_JSON;
            client::set(
                &ctx.session,
                &ctx.keys,
                &ctx.config.name,
                &url,
                json,
                encoding,
            )
            .await
            .map_err(|e| e.to_string())
        })
    }
}
