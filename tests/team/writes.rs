//! Remote writes: allowed by the owner's `remote_write` patterns, refused with a reason.

use petrel::actors::PropertyUrl;
use petrel::team::TeamError;

use crate::support::*;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn remote_writes_go_where_the_owner_allows_and_are_refused_elsewhere() {
    let a_modules = r#"
        (name: "count", type: "demo.counter", values: {"params/period_ms": 1000}),
        (name: "other", type: "demo.counter"),"#;
    let (a, b) = pair(
        "writes",
        (r#"remote_write: ["count/params/*"]"#, a_modules),
        ("", ""),
    )
    .await;
    let url = |s: &str| PropertyUrl::parse(s).unwrap();

    let increment = a.handle::<f64>("count/params/increment").await;
    // The first write may race b's discovery of a: retry only while nobody answers.
    let deadline = tokio::time::Instant::now() + DEADLINE;
    loop {
        match b
            .team
            .set(&url("petrel://a/count/params/increment"), &5.0)
            .await
        {
            Ok(()) => break,
            Err(TeamError::NoAnswer { .. }) if tokio::time::Instant::now() < deadline => continue,
            Err(e) => panic!("the write should be allowed: {e}"),
        }
    }
    assert_eq!(increment.value(), 5.0);

    let refused = |r: Result<(), TeamError>| match r {
        Err(TeamError::Refused(why)) => why,
        other => panic!("expected a refusal, got {other:?}"),
    };
    let why = refused(
        b.team
            .set(&url("petrel://a/other/params/increment"), &1.0)
            .await,
    );
    assert!(
        why.contains("does not allow") && why.contains("count/params/*"),
        "{why}"
    );
    let why = refused(b.team.set(&url("petrel://a/count/out/value"), &1.0).await);
    assert!(why.contains("only params/ and control/"), "{why}");
    let why = refused(
        b.team
            .set(
                &url("petrel://a/count/params/increment"),
                &"fast".to_string(),
            )
            .await,
    );
    assert!(why.contains("f64"), "{why}");
    let why = refused(b.team.set(&url("petrel://a/nope/params/x"), &1.0).await);
    assert!(why.contains("nope"), "{why}");
    assert_eq!(increment.value(), 5.0, "refused writes change nothing");

    // Modules write through their blackboard: a full URL of another agent is a remote write.
    let bb = b.agent.blackboard();
    bb.set("petrel://a/count/params/increment", 6.0)
        .await
        .unwrap();
    assert_eq!(increment.value(), 6.0);
    let e = bb
        .set("petrel://a/count/out/value", 1.0)
        .await
        .unwrap_err()
        .to_string();
    assert!(e.contains("only params/ and control/"), "{e}");
    b.stop().await;
    a.stop().await;
}
