//! A rogue zenoh session on the team's keys: garbage, wrong types, a taken name, a flood.
//! Everything is refused and counted; no cell is corrupted; the team goes on.

use petrel::actors::team::{LinkStatus, Tap, TeamConfig, TeamMembers};
use petrel::team::zenoh_config;
use zenoh::qos::CongestionControl::Block;

use crate::support::*;

async fn rogue_session(team: &str, connect: u16) -> zenoh::Session {
    let config = TeamConfig {
        name: team.into(),
        mode: Default::default(),
        listen: vec![],
        connect: vec![format!("tcp/127.0.0.1:{connect}")],
        lease_ms: 1000,
        remote_write: vec![],
        scouting: false,
    };
    zenoh::open(zenoh_config(&config).unwrap()).await.unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn garbage_wrong_types_and_impostors_are_refused_and_counted() {
    let a_modules = r#"(name: "count", type: "demo.counter",
        values: {"params/period_ms": 20, "params/start": 5.0, "params/increment": 0.0}),"#;
    let b_modules = r#"(name: "probe", type: "test.probe",
        links: {"in/value": "petrel://a/count/out/value"}),"#;
    let (a, b) = pair("rogue", ("", a_modules), ("", b_modules)).await;
    let (team, pa) = (a.team_name.clone(), a.port);
    let status = b.handle::<LinkStatus>("probe/stats/links/in/value").await;
    let input = b.handle::<f64>("probe/in/value").await;
    wait_for(&status, "a live link", |s| s.state == "live").await;
    wait_for(&input, "a's value", |v| *v == 5.0).await;

    let rogue = rogue_session(&team, pa).await;
    let key = format!("petrel/{team}/a/count/out/value");
    let a_zid = a.team.zid().to_string();
    let samples: Vec<(&[u8], Option<String>)> = vec![
        (b"1.0", None),                    // no attachment
        (b"1.0", Some("nonsense".into())), // unreadable
        (
            b"1.0",
            Some(format!("v=1;seq=99;stamp_ns=0;type=Pose2;zid={a_zid}")),
        ), // wrong type
        (
            b"{{{",
            Some(format!("v=1;seq=100;stamp_ns=0;type=f64;zid={a_zid}")),
        ), // bad JSON
        (
            b"2.0",
            Some("v=1;seq=101;stamp_ns=0;type=f64;zid=0badc0de".into()),
        ), // impostor
    ];
    // Publish only once the rogue knows b's subscriber: samples sent before would go nowhere.
    let publisher = rogue
        .declare_publisher(key.clone())
        .congestion_control(Block)
        .await
        .unwrap();
    let matching = publisher.matching_listener().await.unwrap();
    if !publisher.matching_status().await.unwrap().matching() {
        let deadline = tokio::time::Instant::now() + DEADLINE;
        loop {
            let status = tokio::time::timeout_at(deadline, matching.recv_async()).await;
            if status
                .expect("the rogue never saw b's subscriber")
                .unwrap()
                .matching()
            {
                break;
            }
        }
    }
    for (payload, attachment) in samples {
        let put = publisher.put(payload.to_vec());
        match attachment {
            Some(a) => put.attachment(a).await.unwrap(),
            None => put.await.unwrap(),
        }
    }
    // A flood of garbage (sent reliably, so each one arrives): counted, bounded, and the link
    // stays usable.
    for i in 0..5000 {
        publisher.put(format!("flood {i}")).await.unwrap();
    }
    let s = wait_for(&status, "every rogue sample rejected", |s| {
        s.rejected >= 5005
    })
    .await;
    assert_eq!(
        s.rejected, 5005,
        "only the rogue's samples are rejected: {s:?}"
    );
    assert_eq!(
        input.value(),
        5.0,
        "no rogue value reached the input: {s:?}"
    );

    // The rogue claims a's name: refused, a stays a.
    let Ok(Tap::Queue(mut events)) = b.agent.blackboard().tap("_team/events").await else {
        panic!("_team/events is a queue");
    };
    let token = rogue
        .liveliness()
        .declare_token(format!("petrel/{team}/@alive/a/0badc0de"))
        .await
        .unwrap();
    let seen = events_until(&mut events, |e| e.kind == "rejected").await;
    let rejected = seen.iter().find(|e| e.kind == "rejected").unwrap();
    assert_eq!(rejected.agent, "a");
    let members = b.handle::<TeamMembers>("_team/members").await;
    assert_eq!(
        members
            .get()
            .0
            .iter()
            .map(|m| m.agent.as_str())
            .collect::<Vec<_>>(),
        ["a", "b"]
    );
    // a's next real value still arrives.
    a.agent
        .blackboard()
        .set("count/params/start", 7.0)
        .await
        .unwrap();
    wait_for(&input, "a's new value after the rogue", |v| *v == 7.0).await;
    // The status is written after the value: wait for it rather than read it at once.
    let s = wait_for(&status, "the link live again", |s| s.state == "live").await;
    assert_eq!((s.state.as_str(), s.rejected), ("live", 5005), "{s:?}");
    drop(token);
    rogue.close().await.unwrap();
    b.stop().await;
    a.stop().await;
}

/// A client that is not petrel (another zenoh program) reads a current value by query: the
/// reply says its encoding and type, as a stream sample does (docs/wire-format.md, Payloads).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_current_value_reply_says_its_encoding_like_a_stream_sample() {
    let modules = r#"(name: "count", type: "demo.counter",
        values: {"params/period_ms": 20, "params/start": 5.0, "params/increment": 0.0}),"#;
    let (a, b) = pair("encoding", ("", modules), ("", "")).await;
    let client = rogue_session(&a.team_name, a.port).await;
    let key = format!("petrel/{}/a/count/out/value", a.team_name);
    let replies = client
        .get(key.as_str())
        .timeout(std::time::Duration::from_secs(5))
        .await
        .unwrap();
    let reply = replies.recv_async().await.expect("a answers");
    let sample = reply.result().expect("a value");
    assert_eq!(sample.encoding().to_string(), "application/json;f64");
    let json = sample.payload().to_bytes();
    assert!(
        serde_json::from_slice::<f64>(&json).is_ok(),
        "a JSON number: {json:?}"
    );
    client.close().await.unwrap();
    b.stop().await;
    a.stop().await;
}
