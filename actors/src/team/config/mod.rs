//! The `team:` section of an agent config and the long form of links to other agents.
//!
//! Pure data: the zenoh transport that acts on it lives in the `petrel-team` crate, so the
//! core (and every module) stays unaware of the network.

use std::fmt;

use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};

/// Shortest lease accepted, ms: below it a busy machine reports live peers as gone.
pub const MIN_LEASE_MS: u64 = 100;
/// Longest lease accepted, ms.
pub const MAX_LEASE_MS: u64 = 600_000;
/// Default lease, ms: a peer silent this long has left the team.
pub const DEFAULT_LEASE_MS: u64 = 1000;

/// How an agent joins its team (`team: (name: "rescue", listen: [...], connect: [...])`).
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TeamConfig {
    /// The team name: agents of different teams on one network never see each other.
    pub name: String,
    /// `peer` (default: agents connect to each other) or `client` (through a `zenohd` router).
    #[serde(default)]
    pub mode: SessionMode,
    /// zenoh endpoints this agent listens on, e.g. `tcp/127.0.0.1:7447`.
    #[serde(default)]
    pub listen: Vec<String>,
    /// zenoh endpoints this agent connects to (other agents, or a router in client mode).
    #[serde(default)]
    pub connect: Vec<String>,
    /// How long a silent peer stays a member, ms.
    #[serde(default = "default_lease")]
    pub lease_ms: u64,
    /// Which of this agent's properties other agents may set, as `module/path` patterns where
    /// `*` matches one segment and `**` any number (`"planner/params/**"`, `"*/control/*"`).
    /// Only `params/` and `control/` properties can ever be set remotely.
    #[serde(default)]
    pub remote_write: Vec<String>,
    /// Multicast scouting (finding peers without `connect`); off unless asked for.
    #[serde(default)]
    pub scouting: bool,
}

impl Default for TeamConfig {
    /// What a section that gives only its name means (the serde defaults).
    fn default() -> Self {
        TeamConfig {
            name: String::new(),
            mode: SessionMode::default(),
            listen: Vec::new(),
            connect: Vec::new(),
            lease_ms: DEFAULT_LEASE_MS,
            remote_write: Vec::new(),
            scouting: false,
        }
    }
}

impl TeamConfig {
    /// The section as config text (what a snapshot writes).
    pub fn to_ron(&self) -> String {
        let list = |v: &[String]| {
            let items: Vec<String> = v.iter().map(|s| format!("{s:?}")).collect();
            format!("[{}]", items.join(", "))
        };
        let mode = match self.mode {
            SessionMode::Peer => "peer",
            SessionMode::Client => "client",
        };
        format!(
            "(name: {:?}, mode: {mode}, listen: {}, connect: {}, lease_ms: {}, remote_write: {}, scouting: {})",
            self.name,
            list(&self.listen),
            list(&self.connect),
            self.lease_ms,
            list(&self.remote_write),
            self.scouting
        )
    }
}

fn default_lease() -> u64 {
    DEFAULT_LEASE_MS
}

/// The zenoh session mode of an agent.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SessionMode {
    /// Agents talk to each other directly (the default; no router needed).
    #[default]
    Peer,
    /// Agents talk through a `zenohd` router they `connect` to (large deployments).
    Client,
}

/// How values of a remote link travel: the long form `(from: URL, mode: ..., reliability: ...,
/// lossy: ...)` of a link.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Qos {
    /// When the owner sends.
    pub mode: Mode,
    /// Whether lost samples are resent.
    pub reliability: Reliability,
    /// Whether big payloads (images, maps) may be sent degraded, for display.
    pub lossy: bool,
}

/// When the owner of a remote property sends it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// On every change, at most once per `min_interval_ms` (0: every change; the latest
    /// value is always sent in the end).
    OnChange {
        /// Shortest time between two sends, ms.
        min_interval_ms: u64,
    },
    /// The latest value every `ms`, changed or not.
    Periodic {
        /// The period, ms.
        ms: u64,
    },
}

impl Default for Mode {
    fn default() -> Self {
        Mode::OnChange { min_interval_ms: 0 }
    }
}

/// Whether samples lost on the way are resent.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Reliability {
    /// Resent until delivered while the peer is reachable (the default).
    #[default]
    Reliable,
    /// Sent once; the newest sample matters more than every sample.
    BestEffort,
}

/// A link target in a config: a property address (short form), or an address of another
/// agent's property with how its values travel (long form).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LinkTarget {
    /// The address, `module/path` or `petrel://agent/module/path`.
    pub url: String,
    /// Transport settings, for the long form.
    pub qos: Option<Qos>,
}

impl LinkTarget {
    /// A short-form target.
    pub fn new(url: impl Into<String>) -> Self {
        LinkTarget {
            url: url.into(),
            qos: None,
        }
    }

    /// The target as config text (what a snapshot writes).
    pub fn to_ron(&self) -> String {
        let Some(q) = self.qos else {
            return format!("{:?}", self.url);
        };
        let mode = match q.mode {
            Mode::OnChange { min_interval_ms: 0 } => "on_change".to_string(),
            Mode::OnChange { min_interval_ms } => {
                format!("on_change(min_interval_ms: {min_interval_ms})")
            }
            Mode::Periodic { ms } => format!("periodic(ms: {ms})"),
        };
        let reliability = match q.reliability {
            Reliability::Reliable => "reliable",
            Reliability::BestEffort => "best_effort",
        };
        format!(
            "(from: {:?}, mode: {mode}, reliability: {reliability}, lossy: {})",
            self.url, q.lossy
        )
    }
}

impl From<&str> for LinkTarget {
    fn from(url: &str) -> Self {
        LinkTarget::new(url)
    }
}

impl From<String> for LinkTarget {
    fn from(url: String) -> Self {
        LinkTarget::new(url)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LongForm {
    from: String,
    #[serde(default)]
    mode: Mode,
    #[serde(default)]
    reliability: Reliability,
    #[serde(default)]
    lossy: bool,
}

impl<'de> Deserialize<'de> for LinkTarget {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct TargetVisitor;
        impl<'de> Visitor<'de> for TargetVisitor {
            type Value = LinkTarget;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a property address `\"module/path\"` or `(from: \"petrel://agent/module/path\", mode: ..., reliability: ..., lossy: ...)`")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<LinkTarget, E> {
                Ok(LinkTarget::new(v))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<LinkTarget, A::Error> {
                let long = LongForm::deserialize(de::value::MapAccessDeserializer::new(map))?;
                Ok(LinkTarget {
                    url: long.from,
                    qos: Some(Qos {
                        mode: long.mode,
                        reliability: long.reliability,
                        lossy: long.lossy,
                    }),
                })
            }
        }
        d.deserialize_any(TargetVisitor)
    }
}

/// The longest period or minimum interval of a link, ms: a day.
const MAX_LINK_MS: u64 = 86_400_000;

#[derive(Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
enum ModeArgs {
    OnChange {
        #[serde(default)]
        min_interval_ms: u64,
    },
    Periodic {
        ms: u64,
    },
}

impl<'de> Deserialize<'de> for Mode {
    // `on_change` and `on_change(min_interval_ms: 50)` are one variant written with and
    // without arguments, which serde's derive cannot express: read the raw text first.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let raw = Box::<ron::value::RawValue>::deserialize(d)?;
        let text = raw.get_ron().trim();
        if text == "on_change" {
            return Ok(Mode::default());
        }
        // A period of 0 is no pace the owner can send at (it refused the stream, and the input
        // never changed); past a day, a typo.
        let within = |what: &str, ms: u64, min: u64| match (min..=MAX_LINK_MS).contains(&ms) {
            true => Ok(ms),
            false => Err(de::Error::custom(format!(
                "link mode `{text}`: {what} is {ms}; expected {min}..={MAX_LINK_MS} ms (a day)"
            ))),
        };
        match raw.into_rust::<ModeArgs>() {
            Ok(ModeArgs::OnChange { min_interval_ms }) => Ok(Mode::OnChange {
                min_interval_ms: within("min_interval_ms", min_interval_ms, 0)?,
            }),
            Ok(ModeArgs::Periodic { ms }) => Ok(Mode::Periodic {
                ms: within("ms", ms, 1)?,
            }),
            Err(e) => {
                // An unknown variant would name the private helper enum: say nothing more.
                let detail = match e.code {
                    ron::Error::NoSuchEnumVariant { .. } => String::new(),
                    other => format!(" ({other})"),
                };
                Err(de::Error::custom(format!(
                    "link mode `{text}`: expected `on_change`, `on_change(min_interval_ms: N)` or `periodic(ms: N)`{detail}"
                )))
            }
        }
    }
}

/// Whether `key` (`module/path`) matches a `remote_write` pattern: segments compared one by
/// one, `*` matching any one segment and `**` any number of segments (zero included).
pub fn pattern_matches(pattern: &str, key: &str) -> bool {
    fn go(p: &[&str], k: &[&str]) -> bool {
        match (p.first(), k.first()) {
            (None, None) => true,
            (Some(&"**"), _) => go(&p[1..], k) || (!k.is_empty() && go(p, &k[1..])),
            (Some(&ps), Some(&ks)) => (ps == "*" || ps == ks) && go(&p[1..], &k[1..]),
            _ => false,
        }
    }
    let p: Vec<&str> = pattern.split('/').collect();
    let k: Vec<&str> = key.split('/').collect();
    go(&p, &k)
}

/// What is wrong with a `remote_write` pattern, if anything.
pub fn pattern_error(pattern: &str) -> Option<String> {
    let bad = pattern
        .split('/')
        .find(|s| !(*s == "*" || *s == "**" || crate::url::valid_segment(s)));
    bad.map(|s| {
        format!("remote_write pattern `{pattern}`: segment `{s}` is neither a name, `*` nor `**`")
    })
}

/// The problems of a team section, in config terms (empty when it is sound).
pub fn check(team: &TeamConfig) -> Vec<String> {
    let mut errors = Vec::new();
    if !crate::url::valid_segment(&team.name) {
        errors.push(format!(
            "team name `{}`: expected letters, digits, `_`, `-` or `.`",
            team.name
        ));
    }
    if !(MIN_LEASE_MS..=MAX_LEASE_MS).contains(&team.lease_ms) {
        errors.push(format!(
            "team lease_ms is {}; expected {MIN_LEASE_MS}..={MAX_LEASE_MS}",
            team.lease_ms
        ));
    }
    for endpoint in team.listen.iter().chain(&team.connect) {
        if let Some(e) = endpoint_error(endpoint) {
            errors.push(e);
        }
    }
    // A second listen on one endpoint fails at start ("address already in use"): say it here.
    for (i, endpoint) in team.listen.iter().enumerate() {
        if team.listen[..i].contains(endpoint) {
            errors.push(format!(
                "team listen has `{endpoint}` twice; expected each endpoint once"
            ));
        }
    }
    if team.mode == SessionMode::Client && team.connect.is_empty() {
        errors.push(
            "team mode `client` needs a router in `connect` (e.g. \"tcp/127.0.0.1:7447\")".into(),
        );
    }
    errors.extend(team.remote_write.iter().filter_map(|p| pattern_error(p)));
    errors
}

/// What is wrong with a zenoh endpoint (`tcp/host:port`), if anything.
fn endpoint_error(endpoint: &str) -> Option<String> {
    let expected = "expected `tcp/HOST:PORT`, e.g. `tcp/127.0.0.1:7447`";
    let Some(address) = endpoint.strip_prefix("tcp/") else {
        return Some(format!(
            "team endpoint `{endpoint}`: {expected} (petrel is built with zenoh's TCP transport only)"
        ));
    };
    let address = address.split('#').next().unwrap_or_default();
    let port = address
        .rsplit_once(':')
        .map(|(host, port)| (host, port.parse::<u16>()));
    match port {
        Some((host, Ok(_))) if !host.is_empty() => None,
        _ => Some(format!("team endpoint `{endpoint}`: {expected}")),
    }
}

#[cfg(test)]
mod tests;
