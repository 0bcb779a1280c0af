//! The recorder misses no write: attached before the agent's modules start, it records what
//! they write in their first step; a module added while the agent runs is recorded from its
//! first step too. Read back with the `mcap` crate's own reader.

use std::collections::BTreeMap;
use std::time::Duration;

use petrel_actors::{
    Agent, ConfigFile, Context, Module, ModuleConfig, ModuleRegistry, Output, Ports, QueueWriter,
    Schedule, DEFAULT_STOP_TIMEOUT,
};
use petrel_record::{Format, RecordOptions, Recorder};

/// Pushes three items and sets its count in its first step, then never steps again.
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
        }
        self.count.set(3);
        Ok(())
    }
}

fn registry() -> ModuleRegistry {
    let mut r = ModuleRegistry::new();
    r.register::<Burst>();
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
    let counts = items(&topics, "/a/burst/out/count");
    assert_eq!(counts.last().unwrap().1, "{\"value\":3}", "{counts:?}");
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
