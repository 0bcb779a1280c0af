//! Helpers: plan files in a temporary directory, agents started from config text.

use std::time::Duration;

use petrel::actors::{Agent, AgentExit, ConfigFile, RunSummary, DEFAULT_STOP_TIMEOUT};

/// A directory holding plan files; paths inside it for configs.
pub struct Plans(pub tempfile::TempDir);

impl Plans {
    /// Writes `files` (name, text) into a fresh directory.
    pub fn new(files: &[(&str, &str)]) -> Plans {
        let dir = tempfile::tempdir().unwrap();
        for (name, text) in files {
            std::fs::write(dir.path().join(name), text).unwrap();
        }
        Plans(dir)
    }

    /// The path of `name` in the directory, as a config string.
    pub fn path(&self, name: &str) -> String {
        self.0.path().join(name).display().to_string()
    }
}

/// Starts an agent from config text with the built-in types (`mission.pnp` included).
pub async fn start(text: &str) -> Agent {
    let file = ConfigFile::parse("test.ron", text).unwrap_or_else(|e| panic!("{e}"));
    Agent::start(&file, petrel::Petrel::new().registry())
        .await
        .unwrap_or_else(|e| panic!("agent should start:\n{e}"))
}

/// Waits (on the paused clock) until the agent is asked to stop; fails after a minute.
pub async fn finished(agent: &Agent) -> AgentExit {
    tokio::time::timeout(Duration::from_secs(60), agent.finished())
        .await
        .expect("the mission should end the run")
}

/// Stops the agent and returns its summary.
pub async fn stop(agent: Agent) -> RunSummary {
    agent.stop(DEFAULT_STOP_TIMEOUT).await
}

/// Advances the paused clock by `ms`.
pub async fn advance(ms: u64) {
    tokio::time::sleep(Duration::from_millis(ms)).await;
}

/// Counter modules `c1`, `c2`, `c3` (10 ms period, disabled) and a mission `m` with `values`.
pub fn agent_with_mission(values: &str) -> String {
    format!(
        r#"Agent(name: "r1", modules: [
            (name: "c1", type: "demo.counter", values: {{"enabled": false, "params/period_ms": 10}}),
            (name: "c2", type: "demo.counter", values: {{"enabled": false, "params/period_ms": 10}}),
            (name: "c3", type: "demo.counter", values: {{"enabled": false, "params/period_ms": 10}}),
            (name: "m", type: "mission.pnp", restart: temporary, values: {{ {values} }}),
        ])"#
    )
}
