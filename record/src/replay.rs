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
    /// Whether it feeds a value (else a queue).
    pub value: bool,
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

impl ReplayPlan {
    /// The end of the instant that begins at `start` in the schedule: the index past the last
    /// message published at the same time. A module writes its outputs of one step with one
    /// time, so an instant is what a replayed module wrote together.
    pub fn instant_end(&self, start: usize) -> usize {
        let Some(&(ns, _, _)) = self.schedule.get(start) else {
            return start;
        };
        let rest = &self.schedule[start..];
        start + rest.iter().take_while(|&&(t, _, _)| t == ns).count()
    }
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
                "expected a factor in [0.001, 1000] or 0 (as fast as possible), got {r}"
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
        // `outputs` lists the value output kind first, then the queue output.
        let value = kind == outputs[0];
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
            value,
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
    // A value's version 0 is its declared default, recorded as it stood when the recorder
    // attached: not something the module wrote, so not replayed (a pose at the origin before
    // the first real one).
    let mut schedule: Vec<(u64, usize, usize)> = rec
        .messages
        .iter()
        .enumerate()
        .filter_map(|(i, m)| {
            let track = *track_of.get(&m.channel)?;
            let default = tracks[track].value && m.sequence == 0;
            (!default).then_some((m.publish_ns, track, i))
        })
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
        assert!(Rate::from_param(-1.0).unwrap_err().contains("got -1"));
        assert!(Rate::from_param(0.0005).is_err(), "below 0.001");
        assert!(Rate::from_param(f64::INFINITY).is_err());
    }

    #[test]
    fn an_instant_is_what_was_published_at_one_time() {
        let plan = ReplayPlan {
            tracks: Vec::new(),
            schedule: vec![
                (5, 0, 0),
                (5, 1, 1),
                (7, 0, 2),
                (9, 0, 3),
                (9, 1, 4),
                (9, 2, 5),
            ],
        };
        assert_eq!(plan.instant_end(0), 2);
        assert_eq!(plan.instant_end(1), 2);
        assert_eq!(plan.instant_end(2), 3);
        assert_eq!(plan.instant_end(3), 6);
        assert_eq!(plan.instant_end(6), 6);
        assert_eq!(ReplayPlan::default().instant_end(0), 0);
    }

    /// A recording of `robot`'s value output `out/speed` and queue output `out/ticks`.
    fn recording(messages: &[(u16, u32, u64)]) -> (Recording, AgentListing) {
        use crate::read::{ChannelInfo, RecordedMessage};
        let channel = |path: &str| ChannelInfo {
            topic: format!("/r1/robot/{path}"),
            schema: "f64".into(),
            schema_encoding: "jsonschema".into(),
            message_encoding: "json".into(),
            metadata: [
                (meta::URL.to_string(), format!("petrel://r1/robot/{path}")),
                (meta::TYPE.to_string(), "f64".to_string()),
            ]
            .into(),
        };
        let rec = Recording {
            channels: [(1, channel("out/speed")), (2, channel("out/ticks"))].into(),
            messages: messages
                .iter()
                .map(|&(channel, sequence, publish_ns)| RecordedMessage {
                    channel,
                    sequence,
                    log_ns: publish_ns,
                    publish_ns,
                    data: b"1.0".to_vec(),
                })
                .collect(),
            ..Recording::default()
        };
        let property = |path: &str, kind: PropertyKind| petrel_actors::PropertyListing {
            key: format!("robot/{path}"),
            kind: kind.to_string(),
            type_name: "f64".into(),
            link: None,
        };
        let listing = AgentListing {
            modules: vec![petrel_actors::ModuleListing {
                name: "robot".into(),
                type_name: "sim.world".into(),
            }],
            properties: vec![
                property("out/speed", PropertyKind::Output),
                property("out/ticks", PropertyKind::QueueOut),
            ],
        };
        (rec, listing)
    }

    #[test]
    fn declared_defaults_are_not_replayed() {
        // The value's version 0 (recorded as it stood when the recorder attached) is left
        // out; its later versions and every queue item, the first (sequence 0) too, are kept.
        let (rec, listing) = recording(&[(1, 0, 10), (2, 0, 20), (1, 1, 20), (2, 1, 30)]);
        let plan = plan(&rec, &["robot".into()], &listing).unwrap();
        let kept: Vec<usize> = plan.schedule.iter().map(|&(_, _, i)| i).collect();
        assert_eq!(kept, [1, 2, 3]);
        assert_eq!(
            plan.instant_end(0),
            2,
            "the item and the value written at 20"
        );
    }

    #[test]
    fn keys_come_from_urls_and_links() {
        assert_eq!(key_of("petrel://r1/robot/out/scan"), "robot/out/scan");
        assert_eq!(key_of("robot/out/scan"), "robot/out/scan");
        assert_eq!(module_of("robot/out/scan"), "robot");
    }
}
