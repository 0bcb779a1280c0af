//! Opening the zenoh session an agent's team membership runs on.

use petrel_actors::team::{SessionMode, TeamConfig};

use crate::TeamError;

/// The zenoh config a team section stands for: explicit endpoints, multicast scouting off
/// unless asked for, the team's lease.
pub fn zenoh_config(team: &TeamConfig) -> Result<zenoh::Config, TeamError> {
    let mut config = zenoh::Config::default();
    let json = |v: &[String]| serde_json::to_string(v).expect("strings serialize");
    let mode = match team.mode {
        SessionMode::Peer => "\"peer\"",
        SessionMode::Client => "\"client\"",
    };
    let lease = team.lease_ms.to_string();
    let settings = [
        ("mode", mode.to_string()),
        ("listen/endpoints", json(&team.listen)),
        ("connect/endpoints", json(&team.connect)),
        ("scouting/multicast/enabled", team.scouting.to_string()),
        ("transport/link/tx/lease", lease),
        // Four keep-alives per lease: a silent peer is one that missed all four.
        ("transport/link/tx/keep_alive", "4".into()),
        ("adminspace/enabled", "false".into()),
    ];
    for (key, value) in settings {
        config
            .insert_json5(key, &value)
            .map_err(|e| TeamError::Config(format!("{key} = {value}: {e}")))?;
    }
    Ok(config)
}

/// Opens the session.
pub async fn open(team: &TeamConfig) -> Result<zenoh::Session, TeamError> {
    zenoh::open(zenoh_config(team)?)
        .await
        .map_err(|e| TeamError::Open(e.to_string()))
}
