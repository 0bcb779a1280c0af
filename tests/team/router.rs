//! Client mode: agents that connect only to a zenoh router (the `zenohd` deployment), never
//! to each other, still share values and see each other as members.

use petrel::actors::team::{LinkStatus, TeamMembers};

use crate::support::*;

/// A zenoh router on loopback, as `zenohd` would run it (same library, router mode).
async fn router(port: u16) -> zenoh::Session {
    let mut config = zenoh::Config::default();
    for (key, value) in [
        ("mode", "\"router\"".to_string()),
        ("listen/endpoints", format!("[\"tcp/127.0.0.1:{port}\"]")),
        ("scouting/multicast/enabled", "false".into()),
        ("adminspace/enabled", "false".into()),
    ] {
        config.insert_json5(key, &value).expect("a router setting");
    }
    zenoh::open(config).await.expect("the router opens")
}

fn client_config(name: &str, team: &str, router: u16, modules: &str) -> String {
    format!(
        r#"Agent(
    name: "{name}",
    team: (name: "{team}", mode: client, connect: ["tcp/127.0.0.1:{router}"], lease_ms: 1000),
    modules: [{modules}],
)"#
    )
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn clients_of_a_router_share_values_and_membership() {
    let team = team_name("router");
    let port = free_port();
    let router = router(port).await;
    let a = start(&client_config(
        "a",
        &team,
        port,
        r#"(name: "count", type: "demo.counter", values: {"params/period_ms": 5}),"#,
    ))
    .await;
    let b = start(&client_config(
        "b",
        &team,
        port,
        r#"(name: "scale", type: "demo.scale", values: {"params/factor": 2.0},
            links: {"in/value": "petrel://a/count/out/value"}),"#,
    ))
    .await;
    let out = b.handle::<f64>("scale/out/value").await;
    wait_for(&out, "twice a remote count of 10", |v| *v >= 20.0).await;
    let status = b.handle::<LinkStatus>("scale/stats/links/in/value").await;
    wait_for(&status, "a live link", |s| s.state == "live").await;
    let members = b.handle::<TeamMembers>("_team/members").await;
    wait_for(&members, "both agents as members", |m| {
        names(m) == ["a", "b"]
    })
    .await;

    a.stop().await;
    wait_for(&members, "a gone", |m| names(m) == ["b"]).await;
    wait_for(&status, "a stale link", |s| s.state == "stale").await;
    b.stop().await;
    router.close().await.expect("the router closes");
}
