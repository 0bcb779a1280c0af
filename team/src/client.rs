//! Requests to other agents of a team: remote writes and current values. Members make them
//! through [`Team`](crate::Team) (and modules through their blackboard); tools that attach
//! without joining use a [`Client`].

use std::time::Duration;

use petrel_actors::team::TeamConfig;
use petrel_actors::url::PropertyUrl;
use tokio::time::Instant;
use zenoh::bytes::Encoding;

use crate::keys::{Keys, CANONICAL};
use crate::wire::Attachment;
use crate::TeamError;

/// How long a request waits for the owner's answer.
pub const REQUEST_TIMEOUT: Duration = Duration::from_secs(3);

/// The encoding of a remote write given as RON text (config syntax) rather than JSON.
pub fn ron_encoding() -> Encoding {
    Encoding::TEXT_PLAIN.with_schema("ron")
}

/// Sends a remote write; the owner's refusal comes back as [`TeamError::Refused`].
pub(crate) async fn set(
    session: &zenoh::Session,
    keys: &Keys,
    team: &str,
    url: &PropertyUrl,
    payload: Vec<u8>,
    encoding: Encoding,
) -> Result<(), TeamError> {
    let agent = url.agent().unwrap_or_default();
    let replies = session
        .get(keys.set(agent, &url.key()))
        .payload(payload)
        .encoding(encoding)
        .timeout(REQUEST_TIMEOUT)
        .await?;
    match replies.recv_async().await {
        Ok(reply) => match reply.result() {
            Ok(_) => Ok(()),
            Err(e) => Err(refused(agent, e)),
        },
        Err(_) => Err(no_answer(agent, team)),
    }
}

/// Asks for a property's current value: its type name and JSON.
pub(crate) async fn get(
    session: &zenoh::Session,
    keys: &Keys,
    team: &str,
    url: &PropertyUrl,
) -> Result<(String, Vec<u8>), TeamError> {
    let agent = url.agent().unwrap_or_default();
    let replies = session
        .get(keys.data(CANONICAL, agent, &url.key()))
        .timeout(REQUEST_TIMEOUT)
        .await?;
    let reply = replies
        .recv_async()
        .await
        .map_err(|_| no_answer(agent, team))?;
    match reply.result() {
        Ok(sample) => {
            let type_name = sample
                .attachment()
                .and_then(|a| Attachment::decode(&a.to_bytes()).ok())
                .map(|a| a.type_name)
                .unwrap_or_default();
            Ok((type_name, sample.payload().to_bytes().into_owned()))
        }
        Err(e) => Err(refused(agent, e)),
    }
}

/// What an agent's error reply says; zenoh's own `Timeout` (the agent's session answered for
/// it: the agent did not reply in time) is said as such.
fn refused(agent: &str, e: &zenoh::query::ReplyError) -> TeamError {
    let said = String::from_utf8_lossy(&e.payload().to_bytes()).into_owned();
    match said.as_str() {
        "Timeout" => TeamError::Busy {
            agent: agent.to_string(),
            timeout: REQUEST_TIMEOUT,
        },
        _ => TeamError::Refused(said),
    }
}

fn no_answer(agent: &str, team: &str) -> TeamError {
    TeamError::NoAnswer {
        agent: agent.to_string(),
        team: team.to_string(),
        timeout: REQUEST_TIMEOUT,
    }
}

/// What an agent says of itself (its `@info` answer).
#[derive(Debug, Clone, serde::Deserialize)]
pub struct AgentInfo {
    /// Its name.
    pub agent: String,
    /// Its zenoh session id.
    pub zid: String,
    /// Its team.
    pub team: String,
    /// Its process id (agents from before it was said leave it out).
    #[serde(default)]
    pub pid: Option<u32>,
    /// Its machine's host name (agents from before it was said leave it out).
    #[serde(default)]
    pub host: Option<String>,
    /// Its modules, in declaration order.
    pub modules: Vec<String>,
    /// The type of each module.
    pub types: std::collections::BTreeMap<String, String>,
    /// Its properties, in key order.
    pub properties: Vec<petrel_actors::PropertyListing>,
}

/// Asks `agent` what it holds.
pub(crate) async fn info(
    session: &zenoh::Session,
    keys: &Keys,
    team: &str,
    agent: &str,
) -> Result<AgentInfo, TeamError> {
    let replies = session
        .get(keys.info(agent))
        .timeout(REQUEST_TIMEOUT)
        .await?;
    let reply = replies
        .recv_async()
        .await
        .map_err(|_| no_answer(agent, team))?;
    match reply.result() {
        Ok(sample) => serde_json::from_slice(&sample.payload().to_bytes())
            .map_err(|e| TeamError::Refused(format!("agent `{agent}` answered nonsense: {e}"))),
        Err(e) => Err(refused(agent, e)),
    }
}

/// A tool's view of a team: it reaches the agents a team config names, without being a member.
pub struct Client {
    pub(crate) session: zenoh::Session,
    pub(crate) keys: Keys,
    team: String,
}

impl Client {
    /// Connects to the endpoints of `team` (its `listen` and `connect` entries): any agent
    /// config of the team will do.
    pub async fn connect(team: &TeamConfig) -> Result<Client, TeamError> {
        let mut tool = team.clone();
        tool.connect.append(&mut tool.listen);
        let session = crate::session::open(&tool).await?;
        Ok(Client {
            session,
            keys: Keys::new(&team.name),
            team: team.name.clone(),
        })
    }

    /// Sets another agent's property from RON text (config syntax), checked by its owner.
    pub async fn set_ron(&self, url: &PropertyUrl, ron_text: &str) -> Result<(), TeamError> {
        self.retry(|| {
            set(
                &self.session,
                &self.keys,
                &self.team,
                url,
                ron_text.as_bytes().to_vec(),
                ron_encoding(),
            )
        })
        .await
    }

    /// The current value of another agent's property: its type name and JSON.
    pub async fn get_json(&self, url: &PropertyUrl) -> Result<(String, Vec<u8>), TeamError> {
        self.retry(|| get(&self.session, &self.keys, &self.team, url))
            .await
    }

    /// The current values of `agent`'s value properties whose `module/path` matches
    /// `pattern` (`*` one segment, `**` any): (key, type name, JSON) in key order.
    pub async fn get_matching(
        &self,
        agent: &str,
        pattern: &str,
    ) -> Result<Vec<(String, String, Vec<u8>)>, TeamError> {
        let replies = self
            .session
            .get(self.keys.data(CANONICAL, agent, pattern))
            .timeout(REQUEST_TIMEOUT)
            .await?;
        let mut values = Vec::new();
        while let Ok(reply) = replies.recv_async().await {
            let Ok(sample) = reply.result() else {
                continue;
            };
            let Some(key) = self.keys.parse_value(agent, sample.key_expr().as_str()) else {
                continue;
            };
            let type_name = sample
                .attachment()
                .and_then(|a| Attachment::decode(&a.to_bytes()).ok())
                .map(|a| a.type_name)
                .unwrap_or_default();
            values.push((
                key.to_string(),
                type_name,
                sample.payload().to_bytes().into_owned(),
            ));
        }
        values.sort();
        Ok(values)
    }

    /// What `agent` holds: its modules and properties.
    pub async fn info(&self, agent: &str) -> Result<AgentInfo, TeamError> {
        self.retry(|| info(&self.session, &self.keys, &self.team, agent))
            .await
    }

    /// A fresh session learns the agents' queryables shortly after connecting: a request
    /// nobody answered is sent again until [`REQUEST_TIMEOUT`] has passed.
    async fn retry<T, F: std::future::Future<Output = Result<T, TeamError>>>(
        &self,
        request: impl Fn() -> F,
    ) -> Result<T, TeamError> {
        let deadline = Instant::now() + REQUEST_TIMEOUT;
        loop {
            match request().await {
                Err(TeamError::NoAnswer { .. }) if Instant::now() < deadline => {
                    tokio::time::sleep(Duration::from_millis(50)).await
                }
                other => return other,
            }
        }
    }

    /// Closes the session.
    pub async fn close(self) {
        let _ = self.session.close().await;
    }
}
