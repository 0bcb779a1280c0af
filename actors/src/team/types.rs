//! The property types of a team's traffic and membership: link and outbox status, members,
//! membership events, and the messages between missions.

use serde::{Deserialize, Serialize};

use crate::types::PropertyType;

/// The state of one remote link, as `stats/links/<input>` shows it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkStatus {
    /// `waiting` (nothing received yet), `live`, `stale` (the owner left; the last value is
    /// kept) or `broken` (the remote property has another type: the input keeps its default).
    pub state: String,
    /// The remote property, `petrel://agent/module/path`.
    pub source: String,
    /// Samples accepted.
    pub received: i64,
    /// Samples refused (undecodable, wrong type, from an impostor).
    pub rejected: i64,
    /// Samples lost on the way (gaps in the owner's sequence numbers).
    pub dropped: i64,
    /// Why the link is broken or what was last rejected; empty when all is well.
    pub detail: String,
}

/// The states a [`LinkStatus`] can be in.
pub mod link_state {
    /// Nothing received yet.
    pub const WAITING: &str = "waiting";
    /// Samples arrive.
    pub const LIVE: &str = "live";
    /// The owner left the team; the input keeps the last value.
    pub const STALE: &str = "stale";
    /// The remote property's type differs from the input's.
    pub const BROKEN: &str = "broken";
}

/// An agent of the team, as `_team/members` lists it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TeamMember {
    /// The agent name.
    pub agent: String,
    /// Its modules.
    pub modules: Vec<String>,
}

/// The alive agents of the team (this one included), sorted by name: `_team/members`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct TeamMembers(pub Vec<TeamMember>);

/// A change of team membership, as the `_team/events` queue carries it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TeamEvent {
    /// The agent concerned.
    pub agent: String,
    /// `joined`, `left`, `rejoined`, or `rejected` (an agent using a name already taken).
    pub kind: String,
    /// Wall-clock time of the event, ms since the Unix epoch.
    pub unix_ms: u64,
}

/// A message between modules (OpenRDK's mailbox): a module pushes it to its `out/outbox`
/// queue, addressed `agent/module`; it arrives in that module's `in/inbox` queue, in order, at
/// least once (repeats after a lost acknowledgement are dropped by the receiver).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Message {
    /// The recipient, `agent/module` (or `module` for one of the sender's own agent).
    pub to: String,
    /// The sender, `agent/module`; filled in by the runtime on the way.
    #[serde(default)]
    pub from: String,
    /// What the message says: free text, often JSON or RON.
    pub body: String,
}

/// How a module's outbox fares: `stats/outbox`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutboxStatus {
    /// Messages the recipient acknowledged.
    pub delivered: i64,
    /// Messages the recipient refused (no such module, no inbox).
    pub refused: i64,
    /// Messages dropped because the recipient is not (or no longer) in the team.
    pub dropped: i64,
    /// Why the last message was refused or dropped.
    pub detail: String,
}

/// The path of a module's outbox queue.
pub const OUTBOX: &str = "out/outbox";
/// The path of a module's inbox queue.
pub const INBOX: &str = "in/inbox";

impl PropertyType for Message {
    const TYPE_NAME: &'static str = "Message";
}
impl PropertyType for OutboxStatus {
    const TYPE_NAME: &'static str = "OutboxStatus";
}

impl PropertyType for LinkStatus {
    const TYPE_NAME: &'static str = "LinkStatus";
}
impl PropertyType for TeamMembers {
    const TYPE_NAME: &'static str = "TeamMembers";
}
impl PropertyType for TeamEvent {
    const TYPE_NAME: &'static str = "TeamEvent";
}
