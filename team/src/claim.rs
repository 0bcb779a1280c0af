//! Claiming the agent's name when it joins: a second run of one agent in a team is refused at
//! start, while an agent whose earlier process died and whose token has not expired yet may
//! still take its name back.
//!
//! The judgement is pure ([`judge`]); [`check`] asks the team who holds the name and whether
//! the holder answers.

use std::time::Duration;

use zenoh::query::ConsolidationMode;

use crate::client::AgentInfo;
use crate::keys::Keys;
use crate::TeamError;

/// How long the holders of the name are given to answer.
const ANSWER_TIMEOUT: Duration = Duration::from_secs(2);

/// Who holds an agent's name when it joins.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Claim {
    /// Nobody else: the name is this agent's.
    Free,
    /// A session that answers holds it: another run of this agent is in the team.
    Held {
        /// The holder's session.
        zid: String,
        /// The holder's process, if it said (agents from before it was said do not).
        pid: Option<u32>,
        /// The holder's machine, if it said.
        host: Option<String>,
    },
    /// Sessions hold it but none answered (a process stopped, or gone and its lease not yet
    /// over): this agent waits and takes the name over when their tokens end.
    Silent(Vec<String>),
}

/// Judges a claim of the name by session `own`, from the sessions holding a token of the name
/// and the `@info` answers given under it.
pub(crate) fn judge(own: &str, holders: &[String], answers: &[AgentInfo]) -> Claim {
    let others: Vec<&String> = holders.iter().filter(|z| *z != own).collect();
    if others.is_empty() {
        return Claim::Free;
    }
    let answered = answers
        .iter()
        .find(|info| info.zid != own && others.iter().any(|z| **z == info.zid));
    match answered {
        Some(info) => Claim::Held {
            zid: info.zid.clone(),
            pid: info.pid,
            host: info.host.clone(),
        },
        None => Claim::Silent(others.into_iter().cloned().collect()),
    }
}

impl Claim {
    /// The error that refuses a held name; `None` when the agent may go on.
    pub(crate) fn refusal(&self, agent: &str, team: &str) -> Option<TeamError> {
        match self {
            Claim::Held { zid, pid, host } => Some(TeamError::NameTaken {
                agent: agent.to_string(),
                team: team.to_string(),
                holder: describe(zid, *pid, host.as_deref()),
            }),
            _ => None,
        }
    }
}

fn describe(zid: &str, pid: Option<u32>, host: Option<&str>) -> String {
    match (pid, host) {
        (Some(pid), Some(host)) => format!("process {pid} on `{host}` (session {zid})"),
        (Some(pid), None) => format!("process {pid} (session {zid})"),
        _ => format!("session {zid}"),
    }
}

/// Asks the team who holds `agent`'s name, and the holders whether they answer. Called before
/// this session declares its own queryables and token, so only others reply.
pub(crate) async fn check(
    session: &zenoh::Session,
    keys: &Keys,
    agent: &str,
    own: &str,
) -> Result<Claim, TeamError> {
    let tokens = session
        .liveliness()
        .get(keys.alive(agent, "*"))
        .timeout(ANSWER_TIMEOUT)
        .await?;
    let mut holders = Vec::new();
    while let Ok(reply) = tokens.recv_async().await {
        if let Ok(sample) = reply.result() {
            if let Some((_, zid)) = keys.parse_alive(sample.key_expr().as_str()) {
                holders.push(zid.to_string());
            }
        }
    }
    // Nobody else holds the name: no one to ask.
    if holders.iter().all(|z| z == own) {
        return Ok(Claim::Free);
    }
    // Every holder's answer: they reply under one key, which zenoh would otherwise keep one of.
    let replies = session
        .get(keys.info(agent))
        .consolidation(ConsolidationMode::None)
        .timeout(ANSWER_TIMEOUT)
        .await?;
    let mut answers = Vec::new();
    while let Ok(reply) = replies.recv_async().await {
        if let Ok(sample) = reply.result() {
            if let Ok(info) = serde_json::from_slice::<AgentInfo>(&sample.payload().to_bytes()) {
                answers.push(info);
            }
        }
    }
    Ok(judge(own, &holders, &answers))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info(zid: &str, pid: Option<u32>) -> AgentInfo {
        AgentInfo {
            agent: "robot_1".into(),
            zid: zid.into(),
            team: "rescue".into(),
            pid,
            host: pid.map(|_| "hub".to_string()),
            modules: Vec::new(),
            types: Default::default(),
            properties: Vec::new(),
        }
    }

    fn zids(z: &[&str]) -> Vec<String> {
        z.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn a_name_nobody_else_holds_is_free() {
        assert_eq!(judge("me", &[], &[]), Claim::Free);
        assert_eq!(
            judge("me", &zids(&["me"]), &[info("me", Some(1))]),
            Claim::Free
        );
    }

    #[test]
    fn a_holder_that_answers_refuses_the_name_and_is_named() {
        let claim = judge("me", &zids(&["old"]), &[info("old", Some(4242))]);
        assert_eq!(
            claim,
            Claim::Held {
                zid: "old".into(),
                pid: Some(4242),
                host: Some("hub".into())
            }
        );
        let error = claim.refusal("robot_1", "rescue").unwrap().to_string();
        assert!(
            error.contains("`robot_1`")
                && error.contains("`rescue`")
                && error.contains("process 4242 on `hub`"),
            "{error}"
        );
        // An agent from before `pid` was said is named by its session.
        let claim = judge("me", &zids(&["old"]), &[info("old", None)]);
        let error = claim.refusal("robot_1", "rescue").unwrap().to_string();
        assert!(error.contains("session old"), "{error}");
    }

    #[test]
    fn a_holder_that_does_not_answer_leaves_the_name_to_be_taken_over() {
        let claim = judge("me", &zids(&["old"]), &[]);
        assert_eq!(claim, Claim::Silent(zids(&["old"])));
        assert!(claim.refusal("robot_1", "rescue").is_none());
    }

    #[test]
    fn only_answers_from_a_holder_count() {
        // An answer from a session without a token (a token gone meanwhile) or from this
        // session does not hold the name.
        let claim = judge(
            "me",
            &zids(&["old"]),
            &[info("other", Some(1)), info("me", Some(2))],
        );
        assert_eq!(claim, Claim::Silent(zids(&["old"])));
    }
}
