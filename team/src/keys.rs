//! zenoh key expressions of a team (the wire layout is documented in `docs/wire-format.md`).
//!
//! ```text
//! petrel/<team>/<agent>/<module>/<path>                 a property's value stream (on change, lossless)
//! petrel/<team>/@v/<variant>/<agent>/<module>/<path>    the same at another pace or quality
//! petrel/<team>/@want/<owner>/<reader>/<variant>/<module>/<path>   liveliness: a reader wants it
//! petrel/<team>/@alive/<agent>/<zid>                    liveliness: the agent is a member
//! petrel/<team>/@info/<agent>                           queryable: the agent's modules
//! petrel/<team>/@set/<agent>/<module>/<path>            queryable: remote writes
//! petrel/<team>/@inbox/<agent>/<module>                 messages for a module's in/inbox
//! ```
//! Every stream is published only while some reader wants it (a liveliness token under
//! `@want`), so an agent pays for what others read, never for what it merely has.

use petrel_actors::team::{Mode, Qos, Reliability};

/// The root of every petrel key.
pub const ROOT: &str = "petrel";

/// The keys of one team.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Keys {
    team: String,
}

impl Keys {
    /// Keys of team `team`.
    pub fn new(team: &str) -> Self {
        Keys {
            team: team.to_string(),
        }
    }

    /// Where the stream of `agent`'s `key` (`module/path`) at pace `variant` is published.
    pub fn data(&self, variant: &str, agent: &str, key: &str) -> String {
        match variant {
            CANONICAL => format!("{ROOT}/{}/{agent}/{key}", self.team),
            _ => format!("{ROOT}/{}/@v/{variant}/{agent}/{key}", self.team),
        }
    }

    /// The liveliness token of `reader` wanting `owner`'s `key` at `variant`.
    pub fn want(&self, owner: &str, reader: &str, variant: &str, key: &str) -> String {
        format!(
            "{ROOT}/{}/@want/{owner}/{reader}/{variant}/{key}",
            self.team
        )
    }

    /// Every token of readers wanting something of `owner`.
    pub fn wants_of(&self, owner: &str) -> String {
        format!("{ROOT}/{}/@want/{owner}/**", self.team)
    }

    /// Parses a want token of `owner`'s: (reader, variant, key).
    pub fn parse_want<'a>(
        &self,
        owner: &str,
        token: &'a str,
    ) -> Option<(&'a str, &'a str, &'a str)> {
        let prefix = format!("{ROOT}/{}/@want/{owner}/", self.team);
        let rest = token.strip_prefix(&prefix)?;
        let (reader, rest) = rest.split_once('/')?;
        let (variant, key) = rest.split_once('/')?;
        key.contains('/').then_some((reader, variant, key))
    }

    /// The membership token of `agent` (session `zid`).
    pub fn alive(&self, agent: &str, zid: &str) -> String {
        format!("{ROOT}/{}/@alive/{agent}/{zid}", self.team)
    }

    /// Every membership token of the team.
    pub fn all_alive(&self) -> String {
        format!("{ROOT}/{}/@alive/**", self.team)
    }

    /// Parses a membership token: (agent, zid).
    pub fn parse_alive<'a>(&self, token: &'a str) -> Option<(&'a str, &'a str)> {
        let prefix = format!("{ROOT}/{}/@alive/", self.team);
        let (agent, zid) = token.strip_prefix(&prefix)?.split_once('/')?;
        (!zid.contains('/')).then_some((agent, zid))
    }

    /// The info queryable of `agent`.
    pub fn info(&self, agent: &str) -> String {
        format!("{ROOT}/{}/@info/{agent}", self.team)
    }

    /// The remote-write queryable of `agent`'s `key`.
    pub fn set(&self, agent: &str, key: &str) -> String {
        format!("{ROOT}/{}/@set/{agent}/{key}", self.team)
    }

    /// Every remote-write key of `agent`.
    pub fn sets_of(&self, agent: &str) -> String {
        format!("{ROOT}/{}/@set/{agent}/**", self.team)
    }

    /// The `module/path` a remote write of `agent`'s is about.
    pub fn parse_set<'a>(&self, agent: &str, key: &'a str) -> Option<&'a str> {
        let prefix = format!("{ROOT}/{}/@set/{agent}/", self.team);
        key.strip_prefix(&prefix).filter(|k| k.contains('/'))
    }

    /// Every value key of `agent` (the canonical streams, and current values by query).
    pub fn values_of(&self, agent: &str) -> String {
        format!("{ROOT}/{}/{agent}/**", self.team)
    }

    /// The `module/path` of one of `agent`'s canonical keys.
    pub fn parse_value<'a>(&self, agent: &str, key: &'a str) -> Option<&'a str> {
        let prefix = format!("{ROOT}/{}/{agent}/", self.team);
        key.strip_prefix(&prefix).filter(|k| k.contains('/'))
    }

    /// The inbox of `agent`'s `module`.
    pub fn inbox(&self, agent: &str, module: &str) -> String {
        format!("{ROOT}/{}/@inbox/{agent}/{module}", self.team)
    }

    /// Every inbox of `agent`.
    pub fn inboxes_of(&self, agent: &str) -> String {
        format!("{ROOT}/{}/@inbox/{agent}/*", self.team)
    }

    /// The module an inbox key of `agent`'s is for.
    pub fn parse_inbox<'a>(&self, agent: &str, key: &'a str) -> Option<&'a str> {
        let prefix = format!("{ROOT}/{}/@inbox/{agent}/", self.team);
        key.strip_prefix(&prefix)
            .filter(|m| !m.is_empty() && !m.contains('/'))
    }
}

/// The variant of the canonical stream: every change, reliable, lossless.
pub const CANONICAL: &str = "c0";

/// The stream variant a link's settings ask for: `c<ms>` (on change, at most every ms) or
/// `p<ms>` (periodic), then `.be` for best effort and `.lossy` for degraded big payloads.
pub fn variant(qos: &Qos) -> String {
    let mut v = match qos.mode {
        Mode::OnChange { min_interval_ms } => format!("c{min_interval_ms}"),
        Mode::Periodic { ms } => format!("p{ms}"),
    };
    if qos.reliability == Reliability::BestEffort {
        v.push_str(".be");
    }
    if qos.lossy {
        v.push_str(".lossy");
    }
    v
}

/// The settings a variant stands for (the inverse of [`variant`]); `None` if malformed.
pub fn parse_variant(variant: &str) -> Option<Qos> {
    let mut parts = variant.split('.');
    let head = parts.next()?;
    let (kind, ms) = head.split_at_checked(1)?;
    let ms: u64 = ms.parse().ok()?;
    let mode = match kind {
        "c" => Mode::OnChange {
            min_interval_ms: ms,
        },
        "p" if ms > 0 => Mode::Periodic { ms },
        _ => return None,
    };
    let mut qos = Qos {
        mode,
        ..Qos::default()
    };
    for flag in parts {
        match flag {
            "be" if qos.reliability == Reliability::Reliable && !qos.lossy => {
                qos.reliability = Reliability::BestEffort
            }
            "lossy" if !qos.lossy => qos.lossy = true,
            _ => return None,
        }
    }
    Some(qos)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variants_round_trip_and_refuse_garbage() {
        for qos in [
            Qos::default(),
            Qos {
                mode: Mode::Periodic { ms: 200 },
                reliability: Reliability::BestEffort,
                lossy: true,
            },
            Qos {
                mode: Mode::OnChange {
                    min_interval_ms: 50,
                },
                reliability: Reliability::Reliable,
                lossy: true,
            },
        ] {
            assert_eq!(parse_variant(&variant(&qos)), Some(qos));
        }
        assert_eq!(variant(&Qos::default()), CANONICAL);
        for bad in [
            "",
            "x5",
            "c",
            "p0",
            "c5.lossy.be",
            "c5.be.be",
            "c-1",
            "c5.fast",
        ] {
            assert_eq!(parse_variant(bad), None, "{bad}");
        }
    }

    #[test]
    fn keys_parse_back() {
        let k = Keys::new("rescue");
        assert_eq!(
            k.data(CANONICAL, "r1", "loc/out/pose"),
            "petrel/rescue/r1/loc/out/pose"
        );
        assert_eq!(
            k.data("p200", "r1", "loc/out/pose"),
            "petrel/rescue/@v/p200/r1/loc/out/pose"
        );
        let want = k.want("r1", "r2", "c0", "loc/out/pose");
        assert_eq!(
            k.parse_want("r1", &want),
            Some(("r2", "c0", "loc/out/pose"))
        );
        assert_eq!(k.parse_want("r3", &want), None);
        assert_eq!(k.parse_alive(&k.alive("r1", "abc")), Some(("r1", "abc")));
        assert_eq!(
            k.parse_set("r1", &k.set("r1", "p/params/x")),
            Some("p/params/x")
        );
        assert_eq!(
            k.parse_value("r1", "petrel/rescue/r1/p/out/x"),
            Some("p/out/x")
        );
        assert_eq!(k.parse_value("r1", "petrel/rescue/r1/p"), None);
    }
}
