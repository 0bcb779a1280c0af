//! Who is in the team, from liveliness tokens: joins, departures, rejoins, and agents that
//! use a name already taken.
//!
//! Pure: fed the token events zenoh reports, it says what changed.

use std::collections::{BTreeMap, BTreeSet};

use petrel_actors::team::{TeamMember, TeamMembers};

/// A change of membership.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Change {
    /// An agent joined for the first time.
    Joined(String),
    /// An agent that had left is back (e.g. its process was restarted).
    Rejoined(String),
    /// An agent left (its session closed or stopped answering within the lease).
    Left(String),
    /// A session claims a name already taken by another live session: refused.
    Rejected {
        /// The name claimed.
        agent: String,
        /// The impostor's session.
        zid: String,
    },
}

impl Change {
    /// The agent concerned.
    pub fn agent(&self) -> &str {
        match self {
            Change::Joined(a) | Change::Rejoined(a) | Change::Left(a) => a,
            Change::Rejected { agent, .. } => agent,
        }
    }

    /// The event kind `_team/events` shows.
    pub fn kind(&self) -> &'static str {
        match self {
            Change::Joined(_) => "joined",
            Change::Rejoined(_) => "rejoined",
            Change::Left(_) => "left",
            Change::Rejected { .. } => "rejected",
        }
    }
}

#[derive(Debug)]
struct Member {
    zid: String,
    modules: Vec<String>,
}

/// The team as seen from one agent.
#[derive(Debug, Default)]
pub struct Membership {
    members: BTreeMap<String, Member>,
    /// Sessions claiming a taken name, in arrival order, by name.
    waiting: BTreeMap<String, Vec<String>>,
    ever_seen: BTreeSet<String>,
}

impl Membership {
    /// A token of `agent`'s session `zid` appeared.
    pub fn on_alive(&mut self, agent: &str, zid: &str) -> Option<Change> {
        match self.members.get(agent) {
            Some(m) if m.zid == zid => None,
            Some(_) => {
                let queue = self.waiting.entry(agent.to_string()).or_default();
                if !queue.iter().any(|z| z == zid) {
                    queue.push(zid.to_string());
                }
                Some(Change::Rejected {
                    agent: agent.to_string(),
                    zid: zid.to_string(),
                })
            }
            None => Some(self.admit(agent, zid)),
        }
    }

    fn admit(&mut self, agent: &str, zid: &str) -> Change {
        let member = Member {
            zid: zid.to_string(),
            modules: Vec::new(),
        };
        self.members.insert(agent.to_string(), member);
        match self.ever_seen.insert(agent.to_string()) {
            true => Change::Joined(agent.to_string()),
            false => Change::Rejoined(agent.to_string()),
        }
    }

    /// A token of `agent`'s session `zid` disappeared. The name passes to the next session
    /// that claimed it, if any (reported as a rejoin after the departure).
    pub fn on_gone(&mut self, agent: &str, zid: &str) -> Vec<Change> {
        if self.members.get(agent).is_some_and(|m| m.zid == zid) {
            self.members.remove(agent);
            let mut changes = vec![Change::Left(agent.to_string())];
            let next = self
                .waiting
                .get_mut(agent)
                .and_then(|q| (!q.is_empty()).then(|| q.remove(0)));
            if let Some(next) = next {
                changes.push(self.admit(agent, &next));
            }
            return changes;
        }
        if let Some(queue) = self.waiting.get_mut(agent) {
            queue.retain(|z| z != zid);
        }
        Vec::new()
    }

    /// The session that owns `agent`'s name, if the agent is a member.
    pub fn zid_of(&self, agent: &str) -> Option<&str> {
        self.members.get(agent).map(|m| m.zid.as_str())
    }

    /// Records `agent`'s modules (from its info query), if `zid` still owns the name.
    pub fn set_modules(&mut self, agent: &str, zid: &str, modules: Vec<String>) -> bool {
        match self.members.get_mut(agent) {
            Some(m) if m.zid == zid && m.modules != modules => {
                m.modules = modules;
                true
            }
            _ => false,
        }
    }

    /// The members, sorted by name, as `_team/members` shows them.
    pub fn members(&self) -> TeamMembers {
        TeamMembers(
            self.members
                .iter()
                .map(|(agent, m)| TeamMember {
                    agent: agent.clone(),
                    modules: m.modules.clone(),
                })
                .collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joins_departures_and_rejoins() {
        let mut m = Membership::default();
        assert_eq!(m.on_alive("a", "z1"), Some(Change::Joined("a".into())));
        assert_eq!(
            m.on_alive("a", "z1"),
            None,
            "a repeated token changes nothing"
        );
        assert_eq!(m.on_gone("a", "z1"), vec![Change::Left("a".into())]);
        assert_eq!(m.zid_of("a"), None);
        assert_eq!(m.on_alive("a", "z2"), Some(Change::Rejoined("a".into())));
        assert_eq!(m.zid_of("a"), Some("z2"));
        assert_eq!(
            m.on_gone("a", "z1"),
            vec![],
            "an old session's late goodbye is ignored"
        );
    }

    #[test]
    fn a_taken_name_is_refused_until_its_owner_leaves() {
        let mut m = Membership::default();
        m.on_alive("a", "z1");
        assert_eq!(
            m.on_alive("a", "z9"),
            Some(Change::Rejected {
                agent: "a".into(),
                zid: "z9".into()
            })
        );
        assert_eq!(m.zid_of("a"), Some("z1"));
        assert_eq!(
            m.on_gone("a", "z1"),
            vec![Change::Left("a".into()), Change::Rejoined("a".into())]
        );
        assert_eq!(m.zid_of("a"), Some("z9"));
    }

    #[test]
    fn members_list_modules_of_the_owning_session_only() {
        let mut m = Membership::default();
        m.on_alive("b", "z2");
        m.on_alive("a", "z1");
        assert!(m.set_modules("a", "z1", vec!["x".into()]));
        assert!(!m.set_modules("a", "z7", vec!["y".into()]));
        let list = m.members().0;
        assert_eq!(
            list.iter().map(|x| x.agent.as_str()).collect::<Vec<_>>(),
            ["a", "b"]
        );
        assert_eq!(list[0].modules, ["x"]);
    }
}
