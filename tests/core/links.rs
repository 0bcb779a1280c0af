//! Links: chains, cycles, type checks, relinking while running.

use crate::support::{advance, start};

const CHAIN: &str = r#"Agent(name: "r1", modules: [
    (name: "src", type: "demo.counter", values: {"params/period_ms": 10, "params/increment": 1.0}),
    (name: "a", type: "test.echo", links: {"in/value": "src/out/value"}),
    (name: "b", type: "test.echo", links: {"in/value": "a/in/value"}),
    (name: "c", type: "test.echo", links: {"in/value": "petrel://r1/b/in/value"}),
])"#;

#[tokio::test(start_paused = true)]
async fn a_chain_of_links_reads_the_final_target() {
    let agent = start(CHAIN).await;
    advance(55).await;
    let bb = agent.blackboard();
    assert_eq!(*bb.get::<f64>("src/out/value").await.unwrap(), 5.0);
    for m in ["a", "b", "c"] {
        assert_eq!(
            *bb.get::<f64>(&format!("{m}/in/value")).await.unwrap(),
            5.0,
            "{m} reads src through the chain"
        );
        assert_eq!(
            *bb.get::<f64>(&format!("{m}/out/value")).await.unwrap(),
            5.0,
            "{m} was woken and copied it"
        );
    }
    agent.stop(petrel::actors::DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn relinking_while_running_switches_source_and_wakes_the_reader() {
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "slow", type: "demo.counter", values: {"params/period_ms": 1000, "params/start": 100.0}),
            (name: "fast", type: "demo.counter", values: {"params/period_ms": 10}),
            (name: "echo", type: "test.echo", links: {"in/value": "slow/out/value"}),
        ])"#,
    )
    .await;
    let bb = agent.blackboard().clone();
    advance(25).await;
    assert_eq!(
        *bb.get::<f64>("echo/out/value").await.unwrap(),
        0.0,
        "slow has not counted yet"
    );
    bb.link("echo/in/value", "fast/out/value").await.unwrap();
    advance(1).await;
    assert_eq!(
        *bb.get::<f64>("echo/out/value").await.unwrap(),
        2.0,
        "woken by the relink itself"
    );
    advance(30).await;
    assert_eq!(
        *bb.get::<f64>("echo/out/value").await.unwrap(),
        5.0,
        "follows the new source"
    );
    bb.unlink("echo/in/value").await.unwrap();
    bb.set("echo/in/value", 42.0).await.unwrap();
    advance(1).await;
    assert_eq!(
        *bb.get::<f64>("echo/out/value").await.unwrap(),
        42.0,
        "unlinked input reads its own value"
    );
    agent.stop(petrel::actors::DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn runtime_links_are_checked_like_config_links() {
    let agent = start(CHAIN).await;
    let bb = agent.blackboard();
    let cycle = bb
        .link("a/in/value", "c/in/value")
        .await
        .unwrap_err()
        .to_string();
    assert_eq!(
        cycle,
        "link cycle: a/in/value -> c/in/value -> b/in/value -> a/in/value"
    );
    let types = bb
        .link("a/in/value", "src/params/period_ms")
        .await
        .unwrap_err()
        .to_string();
    assert_eq!(
        types,
        "cannot link `a/in/value` (f64) to `src/params/period_ms` (i64): the types differ"
    );
    let output = bb
        .link("a/out/value", "src/out/value")
        .await
        .unwrap_err()
        .to_string();
    assert_eq!(output, "cannot link `a/out/value` (output): only inputs, parameters and queue inputs can be linked");
    let remote = bb
        .link("a/in/value", "petrel://r2/src/out/value")
        .await
        .unwrap_err()
        .to_string();
    assert!(
        remote.contains("names agent `r2`, but this is agent `r1`")
            && remote.contains("no `team:`"),
        "{remote}"
    );
    agent.stop(petrel::actors::DEFAULT_STOP_TIMEOUT).await;
}

/// The cycle a looping module is reported through is worked out from the links as they are
/// now: a module on none gets none (answered from the modules on cycles, kept until the links
/// change), and linking or unlinking changes the answer.
#[test]
fn the_feedback_cycle_follows_the_links_as_they_change() {
    let file = crate::support::config(
        r#"Agent(name: "r1", modules: [
            (name: "a", type: "test.echo", links: {"in/value": "b/out/value"}),
            (name: "b", type: "test.echo", links: {"in/value": "a/out/value"}),
            (name: "c", type: "test.echo", links: {"in/value": "b/out/value"}),
        ])"#,
    );
    let mut built = file.build(&crate::support::registry()).unwrap();
    let through_a = vec![
        "a/out/value → b/in/value".to_string(),
        "b/out/value → a/in/value".to_string(),
    ];
    assert_eq!(built.feedback_cycle("a"), Some(through_a.clone()));
    assert_eq!(built.feedback_cycle("c"), None);
    built.unlink("a/in/value").unwrap();
    assert_eq!(built.feedback_cycle("a"), None);
    assert_eq!(built.feedback_cycle("b"), None);
    built.link("c/in/value", "c/out/value").unwrap();
    assert_eq!(
        built.feedback_cycle("c"),
        Some(vec!["c/out/value → c/in/value".to_string()])
    );
    built.link("a/in/value", "b/out/value").unwrap();
    assert_eq!(built.feedback_cycle("a"), Some(through_a));
}
