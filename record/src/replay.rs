//! Replay, decided without actors or clocks: which recorded channels stand in for which
//! modules' outputs (checked against the agent's properties and the inputs that read them),
//! and when each message is due at a given rate.

use std::collections::BTreeMap;
use std::time::Duration;

use petrel_actors::{AgentListing, PropertyKind};

use crate::encode::Codec;
use crate::read::Recording;
use crate::sink::meta;

/// One recorded channel played into one output.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    /// The recorded topic.
    pub topic: String,
    /// The output it feeds, `module/path`.
    pub key: String,
    /// How its messages decode.
    pub codec: Codec,
    /// The recorded channel id.
    pub channel: u16,
}

/// What a replay publishes, in order.
#[derive(Clone, Debug, Default)]
pub struct ReplayPlan {
    /// The tracks.
    pub tracks: Vec<Track>,
    /// (publish time ns, track, index of the message in the recording), by publish time
    /// (file order among equal times).
    pub schedule: Vec<(u64, usize, usize)>,
}

/// How fast a replay goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rate {
    /// Recorded time scaled by this factor (2 = twice as fast).
    Scaled(f64),
    /// As fast as the agent takes it.
    Max,
}

impl Rate {
    /// `params/rate`: a positive factor, or 0 for as fast as possible.
    pub fn from_param(rate: f64) -> Result<Self, String> {
        match rate {
            0.0 => Ok(Rate::Max),
            r if r.is_finite() && (1e-3..=1e3).contains(&r) => Ok(Rate::Scaled(r)),
            r => Err(format!(
                "invalid parameter `params/rate`: expected a factor in [0.001, 1000] or 0 (as fast as possible), got {r}"
            )),
        }
    }

    /// When a message recorded `since_first_ns` after the first one is due, from the start.
    pub fn due(&self, since_first_ns: u64) -> Duration {
        match self {
            Rate::Max => Duration::ZERO,
            Rate::Scaled(r) => Duration::from_nanos((since_first_ns as f64 / r) as u64),
        }
    }
}

/// The module of a `module/path` key.
fn module_of(key: &str) -> &str {
    key.split('/').next().unwrap_or(key)
}

/// `module/path` of a link target or recorded URL (`petrel://agent/module/path` or short).
fn key_of(address: &str) -> &str {
    match address.strip_prefix("petrel://") {
        Some(rest) => rest.split_once('/').map_or(rest, |(_, key)| key),
        None => address,
    }
}

/// Plans the replay of `modules`' recorded outputs into an agent holding `listing`. Every
/// input linked to one of those outputs must find a channel of the output's type; every
/// recorded output of those modules must exist in the agent with the recorded type.
pub fn plan(
    rec: &Recording,
    modules: &[String],
    listing: &AgentListing,
) -> Result<ReplayPlan, String> {
    let properties: BTreeMap<&str, (&str, &str)> = listing
        .properties
        .iter()
        .map(|p| (p.key.as_str(), (p.kind.as_str(), p.type_name.as_str())))
        .collect();
    let outputs = [
        PropertyKind::Output.to_string(),
        PropertyKind::QueueOut.to_string(),
    ];
    let mut problems = Vec::new();
    for m in modules {
        if !listing.modules.iter().any(|l| &l.name == m) {
            problems.push(format!(
                "module `{m}` is not in the config: nothing to replay it into"
            ));
        }
    }
    // Channels of the replayed modules' outputs, by key.
    let mut tracks: Vec<Track> = Vec::new();
    let mut by_key: BTreeMap<String, usize> = BTreeMap::new();
    for (&id, ch) in &rec.channels {
        let Some(url) = ch.url() else { continue };
        let key = key_of(url);
        if !modules.iter().any(|m| m == module_of(key)) {
            continue;
        }
        let Some(&(kind, type_name)) = properties.get(key) else {
            problems.push(format!(
                "channel `{}` (schema `{}`) records `{key}`, which the config's module `{}` does not have",
                ch.topic, ch.schema, module_of(key)
            ));
            continue;
        };
        if !outputs.iter().any(|o| o == kind) {
            continue;
        }
        let recorded = ch.petrel_type().unwrap_or("?");
        if recorded != type_name {
            problems.push(format!(
                "channel `{}` (schema `{}`) carries `{recorded}`, but `{key}` is a {type_name}",
                ch.topic, ch.schema
            ));
            continue;
        }
        let wrapped = ch.metadata.contains_key(meta::WRAPPED);
        let Some(codec) = Codec::from_channel(&ch.schema, &ch.message_encoding, wrapped) else {
            problems.push(format!(
                "channel `{}` has schema `{}` in `{}` messages, which petrel cannot decode",
                ch.topic, ch.schema, ch.message_encoding
            ));
            continue;
        };
        by_key.insert(key.to_string(), tracks.len());
        tracks.push(Track {
            topic: ch.topic.clone(),
            key: key.to_string(),
            codec,
            channel: id,
        });
    }
    // Every input reading a replayed output needs its channel.
    for p in &listing.properties {
        let Some(target) = p.link.as_deref().map(key_of) else {
            continue;
        };
        if !modules.iter().any(|m| m == module_of(target)) || by_key.contains_key(target) {
            continue;
        }
        let problem = match properties.get(target) {
            Some((kind, _)) if !outputs.iter().any(|o| o == kind) => continue,
            _ => format!(
                "input `{}` ({}) reads `{target}`, and the recording has no channel for it",
                p.key, p.type_name
            ),
        };
        if !problems.contains(&problem) {
            problems.push(problem);
        }
    }
    if !problems.is_empty() {
        return Err(problems.join("\n"));
    }
    let track_of: BTreeMap<u16, usize> = tracks
        .iter()
        .enumerate()
        .map(|(i, t)| (t.channel, i))
        .collect();
    let mut schedule: Vec<(u64, usize, usize)> = rec
        .messages
        .iter()
        .enumerate()
        .filter_map(|(i, m)| Some((m.publish_ns, *track_of.get(&m.channel)?, i)))
        .collect();
    schedule.sort_by_key(|&(ns, _, i)| (ns, i));
    Ok(ReplayPlan { tracks, schedule })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_scale_recorded_time() {
        assert_eq!(
            Rate::from_param(2.0).unwrap().due(1_000_000_000),
            Duration::from_millis(500)
        );
        assert_eq!(Rate::from_param(0.0).unwrap().due(5), Duration::ZERO);
        assert!(Rate::from_param(-1.0).unwrap_err().contains("params/rate"));
        assert!(Rate::from_param(f64::INFINITY).is_err());
    }

    #[test]
    fn keys_come_from_urls_and_links() {
        assert_eq!(key_of("petrel://r1/robot/out/scan"), "robot/out/scan");
        assert_eq!(key_of("robot/out/scan"), "robot/out/scan");
        assert_eq!(module_of("robot/out/scan"), "robot");
    }
}
