//! Teams, as the core sees them: the `team:` config section, links to other agents' properties,
//! and the hooks a transport uses to feed and publish them.
//!
//! The core knows no network. The `petrel-team` crate joins an agent to its team over zenoh
//! through [`RemoteLinks`] (inputs fed from other agents), [`Tap`]s (this agent's properties
//! to publish) and the `_team/members` / `_team/events` properties. A recorder drains many
//! taps from one task through a [`TapReady`].

mod config;
mod ready;
mod remote;
mod types;

pub use config::{
    check, pattern_error, pattern_matches, LinkTarget, Mode, Qos, Reliability, SessionMode,
    TeamConfig, DEFAULT_LEASE_MS, MAX_LEASE_MS, MIN_LEASE_MS,
};
pub use ready::TapReady;
pub use remote::{
    Outbox, OutboxWriter, QueueTap, RemoteFeed, RemoteLink, RemoteLinks, RemoteQueue, RemoteValue,
    RemoteWriter, StatWriter, StatusWriter, Tap, ValueTap, TEAM_MODULE,
};
pub use types::{
    link_state, LinkStatus, Message, OutboxStatus, TeamEvent, TeamMember, TeamMembers, INBOX,
    OUTBOX,
};
