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
        .map_err(|e| TeamError::Open(open_problem(&e.to_string())))
}

/// zenoh's words for a session that did not open, without the source locations it appends
/// (` at /path/to/file.rs:61.`), and what to do about a port another process holds.
fn open_problem(zenoh: &str) -> String {
    let mut text = String::with_capacity(zenoh.len());
    let mut rest = zenoh;
    while let Some(at) = rest.find(" at /") {
        text.push_str(&rest[..at]);
        let location = &rest[at + 1..];
        // The location ends at `.rs:LINE`, then an optional `.`.
        let Some(rs) = location.find(".rs:") else {
            text.push_str(&rest[at..]);
            rest = "";
            break;
        };
        let after = &location[rs + 4..];
        let digits = after.bytes().take_while(u8::is_ascii_digit).count();
        rest = after[digits..]
            .strip_prefix('.')
            .unwrap_or(&after[digits..]);
    }
    text.push_str(rest);
    if zenoh.contains("Address already in use") {
        text.push_str(
            " (another process listens there: another run of this config? `petrel ls` lists the runs here)",
        );
    }
    text
}

#[cfg(test)]
mod open_tests {
    use super::open_problem;

    #[test]
    fn a_port_in_use_is_said_without_zenohs_source_locations_and_with_what_to_do() {
        let zenoh = "Can not create a new TCP listener bound to tcp/127.0.0.1:7450: [127.0.0.1:7450: Address already in use (os error 98) at /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/zenoh-link-commons-1.10.2/src/tcp.rs:61.] at /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/zenoh-link-tcp-1.10.2/src/unicast.rs:338.";
        assert_eq!(
            open_problem(zenoh),
            "Can not create a new TCP listener bound to tcp/127.0.0.1:7450: [127.0.0.1:7450: Address already in use (os error 98)] (another process listens there: another run of this config? `petrel ls` lists the runs here)"
        );
        assert_eq!(open_problem("no route"), "no route");
    }
}
