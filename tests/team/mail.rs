//! Messages between modules of different agents: in order, every one, and failures counted.

use petrel::actors::team::OutboxStatus;

use crate::support::*;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn messages_arrive_in_order_and_undeliverable_ones_are_counted() {
    let (a, b) = pair(
        "mail",
        (
            "",
            r#"
        (name: "m", type: "test.mailer", values: {"params/to": "b/m"}),"#,
        ),
        (
            "",
            r#"
        (name: "m", type: "test.mailer"),"#,
        ),
    )
    .await;
    let members = a
        .handle::<petrel::actors::team::TeamMembers>("_team/members")
        .await;
    wait_for(&members, "b in a's team", |l| l.0.len() == 2).await;

    a.agent
        .blackboard()
        .set("m/in/send", 200_i64)
        .await
        .unwrap();
    let received = b.handle::<i64>("m/out/received").await;
    wait_for(&received, "200 messages at b", |n| *n == 200).await;
    assert_eq!(b.handle::<i64>("m/out/out_of_order").await.value(), 0);
    let outbox = a.handle::<OutboxStatus>("m/stats/outbox").await;
    wait_for(&outbox, "200 acknowledged", |s| s.delivered == 200).await;

    // To a module without an inbox, and to an agent that is not in the team.
    let bb = a.agent.blackboard();
    bb.set("m/params/to", "b/nope".to_string()).await.unwrap();
    bb.set("m/in/send", 1_i64).await.unwrap();
    let s = wait_for(&outbox, "a refusal", |s| s.refused == 1).await;
    assert!(s.detail.contains("nope"), "{s:?}");
    bb.set("m/params/to", "c/m".to_string()).await.unwrap();
    bb.set("m/in/send", 2_i64).await.unwrap();
    let s = wait_for(&outbox, "two drops", |s| s.dropped == 2).await;
    assert!(s.detail.contains("`c` is not in the team"), "{s:?}");
    assert_eq!((s.delivered, received.value()), (200, 200));
    b.stop().await;
    a.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_module_added_while_the_agent_runs_can_send_messages() {
    let (a, b) = pair(
        "mail-added",
        ("", r#"(name: "early", type: "demo.counter"),"#),
        ("", r#"(name: "m", type: "test.mailer"),"#),
    )
    .await;
    let members = a
        .handle::<petrel::actors::team::TeamMembers>("_team/members")
        .await;
    wait_for(&members, "b in a's team", |l| l.0.len() == 2).await;
    let late = petrel::actors::ModuleConfig {
        name: "late".into(),
        type_name: "test.mailer".into(),
        values: [("params/to".to_string(), ron::Value::String("b/m".into()))].into(),
        ..Default::default()
    };
    a.agent
        .modules()
        .add(late)
        .await
        .expect("the module is added");
    // Sent at once: the outbox is tapped when the module is declared, before the transport
    // has even heard of the module, so nothing is lost in between.
    let outbox = a.handle::<OutboxStatus>("late/stats/outbox").await;
    a.agent
        .blackboard()
        .set("late/in/send", 5_i64)
        .await
        .unwrap();
    let received = b.handle::<i64>("m/out/received").await;
    wait_for(&received, "5 messages from the late module", |n| *n == 5).await;
    wait_for(&outbox, "5 acknowledged", |s| s.delivered == 5).await;
    b.stop().await;
    a.stop().await;
}
