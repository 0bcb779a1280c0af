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
