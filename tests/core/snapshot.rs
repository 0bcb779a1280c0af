//! Freeze and resume: a snapshot restarts an agent with the same values and links.

use petrel::actors::{Agent, ConfigFile, DEFAULT_STOP_TIMEOUT};

use crate::support::{advance, config, registry, start};

const BASE: &str = r#"Agent(name: "r1", modules: [
    (name: "count", type: "demo.counter", values: {"params/period_ms": 10, "params/increment": 0.5}),
    (name: "scale", type: "demo.scale", values: {"params/factor": 3.0}, links: {"in/value": "count/out/value"}),
    (name: "producer", type: "demo.producer", capacities: {"out/items": 7}),
])"#;

#[tokio::test(start_paused = true)]
async fn a_snapshot_resumes_the_agent_with_the_same_values() {
    let agent = start(BASE).await;
    let bb = agent.blackboard().clone();
    advance(45).await;
    bb.set("scale/params/offset", 1.0).await.unwrap();
    advance(10).await;
    agent.stop_modules(DEFAULT_STOP_TIMEOUT).await;
    let snapshot = agent.snapshot().await.unwrap();
    agent.shutdown().await;

    let resumed =
        ConfigFile::parse("snapshot.ron", &snapshot).unwrap_or_else(|e| panic!("{e}\n{snapshot}"));
    for (overlaid, file) in [
        (false, resumed.clone()),
        (true, {
            let mut base = config(BASE);
            base.overlay(resumed);
            base
        }),
    ] {
        let agent = Agent::start(&file, &registry()).await.unwrap();
        let bb = agent.blackboard();
        assert_eq!(
            *bb.get::<i64>("count/state/count").await.unwrap(),
            5,
            "overlay={overlaid}"
        );
        assert_eq!(*bb.get::<f64>("count/out/value").await.unwrap(), 2.5);
        assert_eq!(
            *bb.get::<f64>("scale/params/offset").await.unwrap(),
            1.0,
            "a value changed while running"
        );
        assert_eq!(
            *bb.get::<f64>("scale/out/value").await.unwrap(),
            8.5,
            "3 * 2.5 + 1"
        );
        assert_eq!(
            *bb.get::<f64>("scale/in/value").await.unwrap(),
            2.5,
            "the link survived"
        );
        advance(10).await;
        assert_eq!(
            *bb.get::<f64>("count/out/value").await.unwrap(),
            3.0,
            "counting resumes from the saved state"
        );
        let again = agent.snapshot().await.unwrap();
        assert!(
            again.contains("\"out/items\": 7"),
            "queue capacity kept:\n{again}"
        );
        agent.stop(DEFAULT_STOP_TIMEOUT).await;
    }
}

const SETTINGS: &str = r#"Agent(name: "r1",
    supervision: (max_restarts: 7, within_s: 3.5, on_give_up: disable_module, shutdown_timeout_ms: 1200,
                  backoff: (min_ms: 20, max_ms: 400, jitter: 0.0)),
    groups: [(name: "perception", strategy: one_for_all, max_restarts: 2, within_s: 9.0)],
    record: (file: "out/r1.mcap", include: ["count/**"], exclude: ["count/stats/**"], log: false, max_bytes: 1000000),
    modules: [
        (name: "count", type: "demo.counter", group: "perception", restart: transient, watchdog_ms: 250, shutdown_timeout_ms: 900),
        (name: "scale", type: "demo.scale", restart: temporary),
    ])"#;

#[tokio::test(start_paused = true)]
async fn a_snapshot_carries_supervision_groups_recording_and_module_settings() {
    let agent = start(SETTINGS).await;
    agent
        .modules()
        .add(
            ConfigFile::parse(
                "added.ron",
                r#"Agent(name: "x", modules: [(name: "late", type: "demo.counter", restart: temporary, watchdog_ms: 75)])"#,
            )
            .unwrap()
            .config
            .modules
            .remove(0),
        )
        .await
        .unwrap();
    advance(20).await;
    agent.stop_modules(DEFAULT_STOP_TIMEOUT).await;
    let snapshot = agent.snapshot().await.unwrap();
    agent.shutdown().await;

    let original = config(SETTINGS).config;
    let resumed = ConfigFile::parse("snapshot.ron", &snapshot)
        .unwrap_or_else(|e| panic!("{e}\n{snapshot}"))
        .config;
    assert_eq!(resumed.supervision, original.supervision, "{snapshot}");
    assert_eq!(resumed.groups, original.groups, "{snapshot}");
    assert_eq!(resumed.record, original.record, "{snapshot}");
    let settings = |m: &petrel::actors::ModuleConfig| {
        (
            m.name.clone(),
            m.group.clone(),
            m.restart,
            m.watchdog_ms,
            m.shutdown_timeout_ms,
        )
    };
    let mut expected: Vec<_> = original.modules.iter().map(settings).collect();
    expected.push((
        "late".into(),
        None,
        petrel::actors::supervision::RestartPolicy::Temporary,
        Some(75),
        None,
    ));
    let got: Vec<_> = resumed.modules.iter().map(settings).collect();
    assert_eq!(got, expected, "{snapshot}");
    // And it runs: the settings check as they did in the original.
    let agent = Agent::start(&config(&snapshot), &registry()).await.unwrap();
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}
