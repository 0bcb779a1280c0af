//! Remote links: values and queues between agents, status, type mismatches, relinks.

use petrel::actors::team::LinkStatus;

use crate::support::*;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_remote_value_feeds_an_input_like_a_local_link() {
    let (a, b) = pair(
        "value",
        (
            "",
            r#"
        (name: "count", type: "demo.counter", values: {"params/period_ms": 5}),"#,
        ),
        (
            "",
            r#"
        (name: "scale", type: "demo.scale", values: {"params/factor": 2.0},
         links: {"in/value": "petrel://a/count/out/value"}),"#,
        ),
    )
    .await;
    let out = b.handle::<f64>("scale/out/value").await;
    wait_for(&out, "twice a remote count of 10", |v| *v >= 20.0).await;
    let status = b.handle::<LinkStatus>("scale/stats/links/in/value").await;
    let s = wait_for(&status, "a live link", |s| s.state == "live").await;
    assert_eq!(s.source, "petrel://a/count/out/value");
    assert!(s.received >= 1 && s.rejected == 0, "{s:?}");
    b.stop().await;
    a.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_link_to_an_agent_of_another_team_says_why_it_waits() {
    // Connected sessions, but team names that differ by one letter.
    let (pa, pb) = (free_port(), free_port());
    let (team_a, team_b) = (team_name("crew"), team_name("crow"));
    let count = r#"(name: "count", type: "demo.counter", values: {"params/period_ms": 5}),"#;
    let a = start(&agent_config("a", &team_a, pa, &[], "", count)).await;
    let scale = r#"(name: "scale", type: "demo.scale",
         links: {"in/value": "petrel://a/count/out/value"}),"#;
    let b = start(&agent_config("b", &team_b, pb, &[pa], "", scale)).await;
    let status = b.handle::<LinkStatus>("scale/stats/links/in/value").await;
    let s = wait_for(&status, "a link that says why it waits", |s| {
        !s.detail.is_empty()
    })
    .await;
    assert_eq!(s.state, "waiting", "{s:?}");
    assert!(
        s.detail.starts_with(&format!(
            "agent `a` is not in team `{team_b}`: not started yet, in a team of another name"
        )),
        "{s:?}"
    );
    b.stop().await;
    a.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_remote_queue_keeps_order_and_loses_nothing() {
    // Room for every item the test waits for and more: a queue drops its oldest items for a
    // reader that falls behind (counted, as a gap), and on a loaded machine the exporting task
    // (or the consumer) may not run for a while. This test is about the transport: order and no loss on the wire.
    let a_modules = r#"(name: "producer", type: "demo.producer",
        values: {"params/period_ms": 2, "params/batch": 5, "enabled": false},
        capacities: {"out/items": 100000}),"#;
    let b_modules = r#"(name: "consumer", type: "demo.consumer",
        links: {"in/items": (from: "petrel://a/producer/out/items", mode: on_change, reliability: reliable)},
        capacities: {"in/items": 100000}),"#;
    let (a, b) = pair("queue", ("", a_modules), ("", b_modules)).await;
    // The consumer counts gaps from item 0: produce only once the stream is open.
    let status = b
        .handle::<LinkStatus>("consumer/stats/links/in/items")
        .await;
    wait_for(&status, "an open queue stream", |s| s.state == "live").await;
    a.agent
        .blackboard()
        .set("producer/enabled", true)
        .await
        .unwrap();
    let received = b.handle::<i64>("consumer/out/received").await;
    wait_for(&received, "500 remote items", |n| *n >= 500).await;
    let gaps = b.handle::<i64>("consumer/out/gaps").await;
    let duplicates = b.handle::<i64>("consumer/out/duplicates").await;
    assert_eq!((gaps.value(), duplicates.value()), (0, 0));
    let s = status.get();
    assert_eq!(
        (s.state.as_str(), s.dropped, s.rejected),
        ("live", 0, 0),
        "{s:?}"
    );
    b.stop().await;
    a.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_type_mismatch_breaks_the_link_and_keeps_the_default() {
    // `count/enabled` is a bool; the scale's input is an f64.
    let b_modules = r#"(name: "scale", type: "demo.scale", values: {"in/value": 7.0},
        links: {"in/value": "petrel://a/count/enabled"}),"#;
    let a_modules = r#"(name: "count", type: "demo.counter"),"#;
    let (a, b) = pair("mismatch", ("", a_modules), ("", b_modules)).await;
    let status = b.handle::<LinkStatus>("scale/stats/links/in/value").await;
    let s = wait_for(&status, "a broken link", |s| s.state == "broken").await;
    assert!(
        s.detail.contains("bool") && s.detail.contains("f64"),
        "{s:?}"
    );
    assert!(s.rejected >= 1);
    let input = b.handle::<f64>("scale/in/value").await;
    assert_eq!(input.value(), 7.0, "the input keeps its value");
    b.stop().await;
    a.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_link_to_a_missing_property_says_so() {
    let (a, b) = pair(
        "missing",
        (
            "",
            r#"
        (name: "count", type: "demo.counter"),"#,
        ),
        (
            "",
            r#"
        (name: "scale", type: "demo.scale", links: {"in/value": "petrel://a/count/out/nope"}),"#,
        ),
    )
    .await;
    let status = b.handle::<LinkStatus>("scale/stats/links/in/value").await;
    let s = wait_for(&status, "a refused link", |s| s.state == "broken").await;
    assert!(s.detail.contains("out/nope"), "{s:?}");
    b.stop().await;
    a.stop().await;
}

#[tokio::test]
async fn a_snapshot_keeps_the_team_and_remote_links_with_their_settings() {
    use petrel::actors::team::{Mode, Reliability};
    let text = agent_config(
        "b",
        "snap",
        7000,
        &[7001],
        r#"remote_write: ["scale/params/*"]"#,
        r#"
        (name: "scale", type: "demo.scale",
         links: {"in/value": (from: "petrel://a/count/out/value", mode: periodic(ms: 200), reliability: best_effort)}),
        (name: "consumer", type: "demo.consumer",
         links: {"in/items": "petrel://a/producer/out/items"}, capacities: {"in/items": 1024}),"#,
    );
    let file = petrel::actors::ConfigFile::parse("b.ron", &text).unwrap();
    let agent = petrel::actors::Agent::start(&file, &registry())
        .await
        .unwrap();
    let snapshot = agent.snapshot().await.unwrap();
    agent.stop(std::time::Duration::from_secs(1)).await;
    let again = petrel::actors::ConfigFile::parse("snap.ron", &snapshot)
        .unwrap_or_else(|e| panic!("{e}\n{snapshot}"));
    assert_eq!(again.config.team, file.config.team, "{snapshot}");
    let link = &again.config.modules[0].links["in/value"];
    assert_eq!(link.url, "petrel://a/count/out/value");
    let qos = link.qos.expect("the long form");
    assert_eq!(
        (qos.mode, qos.reliability),
        (Mode::Periodic { ms: 200 }, Reliability::BestEffort)
    );
    // The queue the team feeds the consumer's input keeps its configured size.
    let consumer = &again.config.modules[1];
    assert_eq!(
        consumer.capacities.get("in/items"),
        Some(&1024),
        "{snapshot}"
    );
    again
        .build(&registry())
        .unwrap_or_else(|e| panic!("{e}\n{snapshot}"));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_lossy_link_gets_images_at_half_resolution_and_a_plain_one_gets_them_whole() {
    use petrel::actors::Image;
    let b_modules = r#"
        (name: "lossy", type: "test.probe", links: {"in/image": (from: "petrel://a/probe/out/image", lossy: true)}),
        (name: "whole", type: "test.probe", links: {"in/image": "petrel://a/probe/out/image"}),"#;
    let a_modules = r#"(name: "probe", type: "test.probe"),"#;
    let (a, b) = pair("lossy", ("", a_modules), ("", b_modules)).await;
    let lossy = b.handle::<Image>("lossy/in/image").await;
    let half = wait_for(&lossy, "a halved image", |i| i.width == 4).await;
    assert_eq!((half.width, half.height, half.data.len()), (4, 2, 8));
    // Each pixel is the mean of the four it stands for: (0 + 1 + 8 + 9) / 4 = 4.
    assert_eq!(half.data[0], 4);
    let whole = b.handle::<Image>("whole/in/image").await;
    let full = wait_for(&whole, "the whole image", |i| i.width == 8).await;
    assert_eq!(*full, test_image());
    b.stop().await;
    a.stop().await;
}
