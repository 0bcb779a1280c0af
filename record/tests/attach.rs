//! The recorder misses no write: attached before the agent's modules start, it records what
//! they write in their first step, every value of a property written several times in one
//! step; a module added while the agent runs is recorded from its first step too. Read back
//! with the `mcap` crate's own reader.

use std::collections::BTreeMap;
use std::time::Duration;

use petrel_actors::{
    Agent, ConfigFile, Context, Module, ModuleConfig, ModuleRegistry, Output, Ports, QueueWriter,
    Schedule, DEFAULT_STOP_TIMEOUT,
};
use petrel_record::{Format, RecordOptions, Recorder};

/// Pushes three items and sets its count after each in its first step, then never steps again.
struct Burst {
    items: QueueWriter<i64>,
    count: Output<i64>,
}

impl Module for Burst {
    const TYPE: &'static str = "test.burst";
    const DESCRIPTION: &'static str = "Pushes 0, 1, 2 in its first step.";
    fn declare(ports: &mut Ports) -> Self {
        Burst {
            items: ports.queue_out("out/items", 16, "0, 1, 2"),
            count: ports.output("out/count", 0, "items pushed"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::new()
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        for i in 0..3 {
            self.items.push(i);
            self.count.set(i + 1);
        }
        Ok(())
    }
}

/// Counts its steps in a value and pushes each count on a queue, 20 steps, every `period`.
struct Counter {
    steps: Output<i64>,
    pushed: QueueWriter<i64>,
    period: petrel_actors::Input<f64>,
}

impl Module for Counter {
    const TYPE: &'static str = "test.counter";
    const DESCRIPTION: &'static str = "Writes 1, 2, ... 20, one a step.";
    fn declare(ports: &mut Ports) -> Self {
        Counter {
            steps: ports.output("out/steps", 0, "steps so far"),
            pushed: ports.queue_out("out/pushed", 64, "each step's count"),
            period: ports.param("params/period_ms", 10.0, "step period, ms"),
        }
    }
    fn schedule(&self) -> Schedule {
        Schedule::every(Duration::from_secs_f64(self.period.value() / 1000.0))
    }
    async fn step(&mut self, _ctx: &mut Context) -> anyhow::Result<()> {
        let n = self.steps.value() + 1;
        if n <= 20 {
            self.steps.set(n);
            self.pushed.push(n);
        }
        Ok(())
    }
}

fn registry() -> ModuleRegistry {
    let mut r = ModuleRegistry::new();
    r.register::<Burst>().register::<Counter>();
    r
}

/// Waits (on the paused clock, so at most a virtual minute) until `key` reads 3.
async fn wait_for_three(agent: &Agent, key: &str) {
    let count = agent.blackboard().handle::<i64>(key).await.unwrap();
    tokio::time::timeout(Duration::from_secs(60), async {
        while *count.get() < 3 {
            count.changed().await;
        }
    })
    .await
    .unwrap_or_else(|_| panic!("{key} never reached 3"));
}

/// Each topic's messages as (sequence, JSON text), read with the `mcap` crate.
fn recorded(path: &std::path::Path) -> BTreeMap<String, Vec<(u32, String)>> {
    let bytes = std::fs::read(path).unwrap();
    let mut topics: BTreeMap<String, Vec<(u32, String)>> = BTreeMap::new();
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        let message = message.unwrap();
        topics
            .entry(message.channel.topic.clone())
            .or_default()
            .push((
                message.sequence,
                String::from_utf8_lossy(&message.data).into_owned(),
            ));
    }
    topics
}

fn items(topics: &BTreeMap<String, Vec<(u32, String)>>, topic: &str) -> Vec<(u32, String)> {
    topics
        .get(topic)
        .unwrap_or_else(|| panic!("no {topic} in {:?}", topics.keys().collect::<Vec<_>>()))
        .clone()
}

fn pushed() -> Vec<(u32, String)> {
    (0..3).map(|i| (i, format!("{{\"value\":{i}}}"))).collect()
}

#[tokio::test(start_paused = true)]
async fn what_modules_write_in_their_first_step_is_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("first.mcap");
    let file = ConfigFile::parse(
        "first.ron",
        r#"Agent(name: "a", modules: [(name: "burst", type: "test.burst")])"#,
    )
    .unwrap();
    let prepared = Agent::prepare(&file, &registry(), &[]).await.unwrap();
    let mut recorder = Recorder::start(RecordOptions::everything(&path, Format::Foxglove)).unwrap();
    recorder.attach("a", prepared.blackboard()).await.unwrap();
    let agent = prepared.start().await.unwrap();
    wait_for_three(&agent, "burst/out/count").await;
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
    let report = recorder.finish().await.unwrap();
    assert_eq!(report.dropped, 0);

    let topics = recorded(&path);
    assert_eq!(items(&topics, "/a/burst/out/items"), pushed());
    // The value before the step, then each of the step's three writes, by version.
    let counts: Vec<(u32, String)> = (0..=3).map(|n| (n, format!("{{\"value\":{n}}}"))).collect();
    assert_eq!(items(&topics, "/a/burst/out/count"), counts);
}

#[tokio::test(start_paused = true)]
async fn a_module_added_while_running_is_recorded_from_its_first_step() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("added.mcap");
    let file = ConfigFile::parse(
        "added.ron",
        r#"Agent(name: "a", modules: [(name: "burst", type: "test.burst")])"#,
    )
    .unwrap();
    let prepared = Agent::prepare(&file, &registry(), &[]).await.unwrap();
    let mut options = RecordOptions::everything(&path, Format::Foxglove);
    options.selection = petrel_record::Selection::new(&["late/**".into()], &[]).unwrap();
    let mut recorder = Recorder::start(options).unwrap();
    assert_eq!(
        recorder.attach("a", prepared.blackboard()).await.unwrap(),
        0
    );
    let agent = prepared.start().await.unwrap();
    wait_for_three(&agent, "burst/out/count").await;
    agent
        .modules()
        .add(ModuleConfig {
            name: "late".into(),
            type_name: "test.burst".into(),
            ..Default::default()
        })
        .await
        .unwrap();
    wait_for_three(&agent, "late/out/count").await;
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
    recorder.finish().await.unwrap();

    let topics = recorded(&path);
    assert_eq!(items(&topics, "/a/late/out/items"), pushed());
    assert!(
        topics.keys().all(|t| t.starts_with("/a/late/")),
        "only the selection is recorded: {:?}",
        topics.keys().collect::<Vec<_>>()
    );
}

/// One drain task reads many taps: every version of each value and every item of each queue,
/// written by modules stepping at different rates, is in the file, in order.
#[tokio::test(start_paused = true)]
async fn every_change_of_every_tapped_property_is_recorded() {
    every_change_is_recorded().await;
}

/// The same on the wall clock, with the agent on its own thread as `petrel run` starts it
/// (`scheduler: agent_thread`): the drain runs there too, between the modules' steps. The
/// agent is shut down before the recording finishes (`Agent::stop`, then `Recorder::finish`),
/// which ends the drain's task with the agent's thread.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_change_is_recorded_from_an_agent_on_its_own_thread() {
    every_change_is_recorded().await;
}

/// Two counters (20 steps every 10 and 25 ms), recorded from before their first step; every
/// version of their values and every item of their queues must be in the file, in order.
async fn every_change_is_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("every.mcap");
    let file = ConfigFile::parse(
        "every.ron",
        r#"Agent(name: "a", modules: [
            (name: "fast", type: "test.counter", values: {"params/period_ms": 10.0}),
            (name: "slow", type: "test.counter", values: {"params/period_ms": 25.0}),
        ])"#,
    )
    .unwrap();
    let prepared = Agent::prepare(&file, &registry(), &[]).await.unwrap();
    let mut recorder = Recorder::start(RecordOptions::everything(&path, Format::Foxglove)).unwrap();
    recorder.attach("a", prepared.blackboard()).await.unwrap();
    let agent = prepared.start().await.unwrap();
    for module in ["fast", "slow"] {
        let steps = agent
            .blackboard()
            .handle::<i64>(&format!("{module}/out/steps"))
            .await
            .unwrap();
        tokio::time::timeout(Duration::from_secs(60), async {
            while *steps.get() < 20 {
                steps.changed().await;
            }
        })
        .await
        .unwrap_or_else(|_| panic!("{module} never reached 20"));
    }
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
    let report = recorder.finish().await.unwrap();
    assert_eq!(report.dropped, 0);

    let topics = recorded(&path);
    let counted = |n: i64| format!("{{\"value\":{n}}}");
    for module in ["fast", "slow"] {
        let mut values = items(&topics, &format!("/a/{module}/out/steps"));
        // The declared default (version 0) is there if the drain read before the first step.
        if values.first() == Some(&(0, counted(0))) {
            values.remove(0);
        }
        let expected: Vec<(u32, String)> = (1..=20).map(|n| (n as u32, counted(n))).collect();
        assert_eq!(values, expected, "{module}/out/steps");
        let pushed = items(&topics, &format!("/a/{module}/out/pushed"));
        let expected: Vec<(u32, String)> = (1..=20).map(|n| (n as u32 - 1, counted(n))).collect();
        assert_eq!(pushed, expected, "{module}/out/pushed");
    }
}
