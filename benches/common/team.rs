//! Agents on a team over TCP loopback, for the team benchmarks.

use petrel::actors::{Agent, ConfigFile};
use petrel::team::Team;

/// A free TCP port on 127.0.0.1.
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .unwrap()
}

/// A team agent config listening on `port` and connecting to `connect`.
pub fn config(name: &str, team: &str, port: u16, connect: Option<u16>, modules: &str) -> String {
    let connect = connect.map_or(String::new(), |p| format!("\"tcp/127.0.0.1:{p}\""));
    format!(
        r#"Agent(name: "{name}",
            team: (name: "{team}", listen: ["tcp/127.0.0.1:{port}"], connect: [{connect}]),
            modules: [{modules}])"#
    )
}

/// Starts an agent and joins its team.
pub async fn start(text: &str) -> (Agent, Team) {
    let file = ConfigFile::parse("bench.ron", text).unwrap_or_else(|e| panic!("{e}"));
    let agent = Agent::start(&file, &super::registry())
        .await
        .unwrap_or_else(|e| panic!("{e}"));
    let team = Team::join(&agent, file.config.team.as_ref().unwrap())
        .await
        .unwrap_or_else(|e| panic!("{e}"));
    (agent, team)
}

/// A raw zenoh session on loopback: the floor petrel's team transport is measured against.
pub async fn raw_session(listen: Option<u16>, connect: Option<u16>) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    let list = |p: Option<u16>| match p {
        Some(p) => format!("[\"tcp/127.0.0.1:{p}\"]"),
        None => "[]".into(),
    };
    c.insert_json5("listen/endpoints", &list(listen)).unwrap();
    c.insert_json5("connect/endpoints", &list(connect)).unwrap();
    c.insert_json5("scouting/multicast/enabled", "false").unwrap();
    zenoh::open(c).await.unwrap()
}
