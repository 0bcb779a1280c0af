//! Queues: many readers, each sees every item once in order; lagging readers count their losses.

use petrel::actors::DEFAULT_STOP_TIMEOUT;

use crate::support::{advance, start};

#[tokio::test(start_paused = true)]
async fn every_reader_sees_every_item_exactly_once_in_order() {
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "producer", type: "demo.producer", values: {"params/period_ms": 10, "params/batch": 7}),
            (name: "c1", type: "demo.consumer", links: {"in/items": "producer/out/items"}),
            (name: "c2", type: "demo.consumer", links: {"in/items": "producer/out/items"}),
            (name: "c3", type: "demo.consumer", links: {"in/items": "c2/in/items"}),
        ])"#,
    )
    .await;
    let bb = agent.blackboard().clone();
    advance(1005).await;
    bb.set("producer/enabled", false).await.unwrap();
    advance(20).await;
    let produced = *bb.get::<i64>("producer/state/next").await.unwrap();
    assert_eq!(produced, 700);
    for c in ["c1", "c2", "c3"] {
        let get = |p: &str| format!("{c}/{p}");
        assert_eq!(
            *bb.get::<i64>(&get("out/received")).await.unwrap(),
            produced,
            "{c} received all"
        );
        assert_eq!(
            *bb.get::<i64>(&get("out/gaps")).await.unwrap(),
            0,
            "{c} saw no gap"
        );
        assert_eq!(
            *bb.get::<i64>(&get("out/duplicates")).await.unwrap(),
            0,
            "{c} saw no duplicate"
        );
        assert_eq!(
            *bb.get::<i64>(&get("stats/dropped/in/items")).await.unwrap(),
            0
        );
    }
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

/// A producer that starts numbering over (a new process: its `state/next` back at 0) is no
/// source of duplicates: the consumer counts a restart and checks on from there.
#[tokio::test(start_paused = true)]
async fn numbers_that_go_back_are_a_producer_starting_over_not_duplicates() {
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "producer", type: "demo.producer", values: {"params/period_ms": 10, "params/batch": 5}),
            (name: "consumer", type: "demo.consumer", links: {"in/items": "producer/out/items"}),
        ])"#,
    )
    .await;
    let bb = agent.blackboard().clone();
    advance(505).await;
    bb.set("producer/enabled", false).await.unwrap();
    advance(20).await;
    bb.set("producer/state/next", 0_i64).await.unwrap();
    bb.set("producer/enabled", true).await.unwrap();
    advance(505).await;
    bb.set("producer/enabled", false).await.unwrap();
    advance(20).await;
    let count = |p: &'static str| {
        let bb = bb.clone();
        async move { *bb.get::<i64>(&format!("consumer/{p}")).await.unwrap() }
    };
    assert_eq!(count("out/restarts").await, 1);
    assert_eq!(count("out/duplicates").await, 0);
    assert_eq!(count("out/gaps").await, 0);
    assert_eq!(
        count("state/last").await,
        count("out/received").await - 250 - 1
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn a_lagging_reader_loses_the_oldest_items_and_the_loss_is_visible() {
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "producer", type: "demo.producer", values: {"params/period_ms": 10, "params/batch": 10},
             capacities: {"out/items": 16}),
            (name: "slow", type: "demo.consumer", values: {"enabled": false}, links: {"in/items": "producer/out/items"}),
            (name: "fast", type: "demo.consumer", links: {"in/items": "producer/out/items"}),
        ])"#,
    )
    .await;
    let bb = agent.blackboard().clone();
    advance(105).await;
    bb.set("producer/enabled", false).await.unwrap();
    advance(1).await;
    assert_eq!(*bb.get::<i64>("producer/state/next").await.unwrap(), 100);
    assert_eq!(
        *bb.get::<i64>("slow/stats/dropped/in/items").await.unwrap(),
        84,
        "drops counted while disabled"
    );
    bb.set("slow/enabled", true).await.unwrap();
    advance(1).await;
    assert_eq!(
        *bb.get::<i64>("slow/out/received").await.unwrap(),
        16,
        "the newest `capacity` items remain"
    );
    assert_eq!(
        *bb.get::<i64>("slow/out/gaps").await.unwrap(),
        84,
        "the consumer sees the hole in the numbering"
    );
    assert_eq!(
        *bb.get::<i64>("fast/out/received").await.unwrap(),
        100,
        "a reader keeping up loses nothing"
    );
    assert_eq!(
        *bb.get::<i64>("fast/stats/dropped/in/items").await.unwrap(),
        0
    );
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

#[tokio::test(start_paused = true)]
async fn every_reader_gets_the_pushed_image_itself_never_a_copy() {
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "camera", type: "test.image_source"),
            (name: "a", type: "test.image_sink", links: {"in/images": "camera/out/images"}),
            (name: "b", type: "test.image_sink", links: {"in/images": "camera/out/images"}),
        ])"#,
    )
    .await;
    let bb = agent.blackboard().clone();
    advance(55).await;
    bb.set("camera/enabled", false).await.unwrap();
    advance(20).await;
    let pushed = bb.get::<Vec<f64>>("camera/out/addresses").await.unwrap();
    assert!(pushed.len() >= 5, "{pushed:?}");
    for reader in ["a", "b"] {
        let seen = bb
            .get::<Vec<f64>>(&format!("{reader}/out/addresses"))
            .await
            .unwrap();
        assert_eq!(
            *seen, *pushed,
            "{reader} read the very bytes that were pushed"
        );
    }
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

/// A consumer linked while the stream runs (an agent joining a team late) counts gaps from the
/// first item it receives: the items sent before it was linked are not missing between two it
/// saw (the team demo's consumer reported `gaps 5` at every start).
#[tokio::test(start_paused = true)]
async fn a_consumer_linked_late_counts_no_gap_before_its_first_item() {
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "producer", type: "demo.producer", values: {"params/period_ms": 10}),
            (name: "c", type: "demo.consumer"),
        ])"#,
    )
    .await;
    let bb = agent.blackboard().clone();
    advance(105).await;
    bb.link("c/in/items", "producer/out/items").await.unwrap();
    advance(100).await;
    bb.set("producer/enabled", false).await.unwrap();
    advance(20).await;
    let produced = *bb.get::<i64>("producer/state/next").await.unwrap();
    let received = *bb.get::<i64>("c/out/received").await.unwrap();
    assert!(
        received > 0 && received < produced,
        "{received} of {produced}"
    );
    assert_eq!(*bb.get::<i64>("c/out/gaps").await.unwrap(), 0);
    assert_eq!(*bb.get::<i64>("c/state/last").await.unwrap(), produced - 1);
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

/// A tool or recorder that asks to follow a queue input is told which queue to follow: the
/// input holds no items of its own (it was told the input "cannot be set").
#[tokio::test(start_paused = true)]
async fn following_a_queue_input_names_the_queue_it_reads() {
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "producer", type: "demo.producer"),
            (name: "linked", type: "demo.consumer", links: {"in/items": "producer/out/items"}),
            (name: "alone", type: "demo.consumer"),
        ])"#,
    )
    .await;
    let bb = agent.blackboard();
    let linked = bb.tap("linked/in/items").await.err().unwrap().to_string();
    assert_eq!(
        linked,
        "`linked/in/items` is a queue input, which holds no items of its own: follow the queue it reads, `producer/out/items`"
    );
    let alone = bb.tap("alone/in/items").await.err().unwrap().to_string();
    assert!(alone.ends_with("(it is not linked to one)"), "{alone}");
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}

/// `petrel get` of a queue asks its agent for the queue's one value: the answer says a queue
/// carries items (it said the queue "cannot be set", about a read).
#[tokio::test(start_paused = true)]
async fn a_queue_asked_for_one_value_says_it_carries_items() {
    let agent = start(
        r#"Agent(name: "r1", modules: [
            (name: "producer", type: "demo.producer"),
            (name: "linked", type: "demo.consumer", links: {"in/items": "producer/out/items"}),
        ])"#,
    )
    .await;
    let bb = agent.blackboard();
    for (key, kind) in [
        ("producer/out/items", "queue output"),
        ("linked/in/items", "queue input"),
    ] {
        let refused = bb.any_handle(key).await.err().unwrap().to_string();
        assert_eq!(
            refused,
            format!("`{key}` is a {kind}: it carries items, not one value; `petrel echo` prints them as they come")
        );
    }
    agent.stop(DEFAULT_STOP_TIMEOUT).await;
}
