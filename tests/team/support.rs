//! Agents on a team over loopback, and bounded waits on their properties.

use std::sync::Arc;
use std::time::Duration;

use petrel::actors::team::{LinkStatus, Message, QueueTap, TeamEvent, TeamMembers};
use petrel::actors::{
    Agent, ConfigFile, Context, Image, Input, Module, ModuleRegistry, Output, Ports,
    PropertyHandle, PropertyType, QueueReader, QueueWriter, Schedule,
};
use petrel::team::Team;

/// How long any wait in these tests may take before the test fails.
pub const DEADLINE: Duration = Duration::from_secs(20);

pub use crate::ports::free_port;

/// The victims of configs/rescue/rescue.txt (its `V` markers, metres), for the rescue-team
/// runs.
pub const VICTIMS: [(f64, f64); 6] = [
    (1.7, 4.3),
    (3.3, 8.1),
    (6.5, 1.3),
    (8.3, 10.5),
    (13.9, 1.3),
    (13.7, 8.1),
];

/// A unique team name, so parallel tests never see each other.
pub fn team_name(test: &str) -> String {
    format!("t{}-{test}", std::process::id())
}

/// An agent config on team `team` listening on `port`, connecting to `connect`, with
/// `extra` team fields and the modules `modules` (RON list items).
pub fn agent_config(
    name: &str,
    team: &str,
    port: u16,
    connect: &[u16],
    extra: &str,
    modules: &str,
) -> String {
    let connect: Vec<String> = connect
        .iter()
        .map(|p| format!("\"tcp/127.0.0.1:{p}\""))
        .collect();
    format!(
        r#"Agent(
    name: "{name}",
    team: (name: "{team}", listen: ["tcp/127.0.0.1:{port}"], connect: [{}], lease_ms: 1000, {extra}),
    modules: [{modules}],
)"#,
        connect.join(", ")
    )
}

/// Built-in module types plus `test.probe`.
pub fn registry() -> ModuleRegistry {
    let mut r = petrel::Petrel::new().registry().clone();
    r.register::<Probe>().register::<Mailer>();
    r
}

/// An 8x4 `mono8` image whose pixels count up from 0.
pub fn test_image() -> Image {
    Image {
        width: 8,
        height: 4,
        encoding: "mono8".into(),
        data: (0..32u8).collect::<Vec<u8>>().into(),
    }
}

/// `test.probe`: inputs to link to other agents' properties, so a test can watch them
/// (`in/status` for a link status, `in/value` for a number).
pub struct Probe {
    _status: Input<LinkStatus>,
    _value: Input<f64>,
    _image_in: Input<Image>,
    _image_out: Output<Image>,
}

impl Module for Probe {
    const TYPE: &'static str = "test.probe";
    const DESCRIPTION: &'static str = "Inputs for a test to watch.";
    fn declare(ports: &mut Ports) -> Self {
        Probe {
            _status: ports.input("in/status", LinkStatus::default(), "a link status"),
            _value: ports.input("in/value", 0.0, "a number"),
            _image_in: ports.input("in/image", Image::default(), "an image"),
            _image_out: ports.output("out/image", test_image(), "an 8x4 grey ramp"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new()
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        Ok(())
    }
}

/// `test.mailer`: when `in/send` changes to N, sends N messages (bodies 0, 1, ...) to
/// `params/to`; counts what its inbox receives and how much of it came out of order.
pub struct Mailer {
    to: Input<String>,
    send: Input<i64>,
    outbox: QueueWriter<Message>,
    inbox: QueueReader<Message>,
    sent: i64,
    /// The last `in/send` value acted on.
    handled: i64,
    received: Output<i64>,
    out_of_order: Output<i64>,
}

impl Module for Mailer {
    const TYPE: &'static str = "test.mailer";
    const DESCRIPTION: &'static str = "Sends numbered messages and checks the ones it receives.";
    fn declare(ports: &mut Ports) -> Self {
        Mailer {
            to: ports.param("params/to", String::new(), "recipient, agent/module"),
            send: ports.input("in/send", 0, "messages to send"),
            outbox: ports.queue_out("out/outbox", 1024, "messages out"),
            inbox: ports.queue_in("in/inbox", "messages in"),
            sent: 0,
            handled: 0,
            received: ports.output("out/received", 0, "messages received"),
            out_of_order: ports.output("out/out_of_order", 0, "messages not in order"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new().on_change(&self.send).on_items(&self.inbox)
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        // A new `in/send` value, whether it came before the first step or after.
        if self.send.value() != self.handled {
            self.handled = self.send.value();
            for _ in 0..self.send.value() {
                let body = self.sent.to_string();
                self.outbox.push(Message {
                    to: (*self.to.get()).clone(),
                    from: String::new(),
                    body,
                });
                self.sent += 1;
            }
        }
        for item in self.inbox.drain() {
            let n = self.received.value();
            if item.body != n.to_string() {
                self.out_of_order.set(self.out_of_order.value() + 1);
            }
            self.received.set(n + 1);
        }
        Ok(())
    }
}

/// A running agent and its team membership.
pub struct Member {
    pub agent: Agent,
    pub team: Team,
    /// The team's name.
    pub team_name: String,
    /// The port the agent listens on.
    pub port: u16,
}

/// Agents `a` and `b` on a fresh team named after `test`: `a` listens, `b` connects to it.
/// Each is given as (its extra team fields, its modules).
pub async fn pair(test: &str, a: (&str, &str), b: (&str, &str)) -> (Member, Member) {
    let team = team_name(test);
    let (pa, pb) = (free_port(), free_port());
    let a = start(&agent_config("a", &team, pa, &[], a.0, a.1)).await;
    let b = start(&agent_config("b", &team, pb, &[pa], b.0, b.1)).await;
    (a, b)
}

/// The agent names of a member list.
pub fn names(m: &TeamMembers) -> Vec<&str> {
    m.0.iter().map(|m| m.agent.as_str()).collect()
}

/// Takes `_team/events` items from `tap` until one satisfies `pred` (failing the test after
/// [`DEADLINE`]); returns every event taken.
pub async fn events_until(tap: &mut QueueTap, pred: impl Fn(&TeamEvent) -> bool) -> Vec<TeamEvent> {
    let deadline = tokio::time::Instant::now() + DEADLINE;
    let mut seen = Vec::new();
    loop {
        seen.extend(
            tap.take(64)
                .into_iter()
                .filter_map(|(_, _, v)| v.downcast_ref::<TeamEvent>().cloned()),
        );
        if seen.iter().any(&pred) {
            return seen;
        }
        if tokio::time::timeout_at(deadline, tap.changed())
            .await
            .is_err()
        {
            panic!("timed out waiting for a team event; seen: {seen:?}");
        }
    }
}

/// Starts the agent of `config` and joins its team.
pub async fn start(config: &str) -> Member {
    let file = ConfigFile::parse("team-test.ron", config)
        .unwrap_or_else(|e| panic!("config should parse:\n{e}\n{config}"));
    let registry = registry();
    let agent = Agent::start(&file, &registry)
        .await
        .unwrap_or_else(|e| panic!("agent should start:\n{e}"));
    let team_config = file.config.team.clone().expect("a team section");
    let team = Team::join(&agent, &team_config)
        .await
        .unwrap_or_else(|e| panic!("agent should join:\n{e}"));
    let port = team_config
        .listen
        .first()
        .and_then(|l| l.rsplit(':').next())
        .and_then(|p| p.parse().ok())
        .unwrap_or(0);
    Member {
        agent,
        team,
        team_name: team_config.name,
        port,
    }
}

/// Starts the agent of `config` and expects its team to refuse it: returns why, the agent
/// stopped again.
pub async fn start_refused(config: &str) -> petrel::team::TeamError {
    let file = ConfigFile::parse("team-test.ron", config)
        .unwrap_or_else(|e| panic!("config should parse:\n{e}\n{config}"));
    let agent = Agent::start(&file, &registry())
        .await
        .unwrap_or_else(|e| panic!("agent should start:\n{e}"));
    let team_config = file.config.team.clone().expect("a team section");
    let joined = Team::join(&agent, &team_config).await;
    agent.stop(Duration::from_secs(2)).await;
    match joined {
        Ok(team) => {
            team.leave().await;
            panic!("the team should have refused this agent:\n{config}");
        }
        Err(e) => e,
    }
}

impl Member {
    /// A handle to one of this agent's properties.
    pub async fn handle<T: PropertyType>(&self, address: &str) -> PropertyHandle<T> {
        self.agent
            .blackboard()
            .handle::<T>(address)
            .await
            .unwrap_or_else(|e| panic!("{address}: {e}"))
    }

    /// Stops the agent and leaves the team.
    pub async fn stop(self) {
        self.agent.stop(Duration::from_secs(2)).await;
        self.team.leave().await;
    }
}

/// Waits until `pred` holds for `handle`'s value, failing the test after [`DEADLINE`]; returns
/// the value that satisfied it.
pub async fn wait_for<T: PropertyType>(
    handle: &PropertyHandle<T>,
    what: &str,
    pred: impl Fn(&T) -> bool,
) -> Arc<T> {
    let deadline = tokio::time::Instant::now() + DEADLINE;
    loop {
        let value = handle.get();
        if pred(&value) {
            return value;
        }
        if tokio::time::timeout_at(deadline, handle.changed())
            .await
            .is_err()
        {
            panic!(
                "timed out waiting for {what}; last value of {}: {value:?}",
                handle.key()
            );
        }
    }
}

/// Starts `bin run CONFIGS --for RUN_FOR` in `dir`, standard output piped and standard error
/// as asked, with `RUST_LOG` set to `log` if given: a whole team as one process, the way the
/// rescue-team tests and measurements run it.
pub fn spawn_run<S: AsRef<std::ffi::OsStr>>(
    bin: &str,
    dir: &std::path::Path,
    configs: &[S],
    run_for: &str,
    stderr: std::process::Stdio,
    log: Option<&str>,
) -> std::process::Child {
    let mut command = std::process::Command::new(bin);
    if let Some(log) = log {
        command.env("RUST_LOG", log);
    }
    command
        .current_dir(dir)
        .arg("run")
        .args(configs)
        .args(["--for", run_for])
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(stderr)
        .spawn()
        .expect("petrel starts")
}
