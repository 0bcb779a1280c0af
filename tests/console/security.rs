//! The console's access rules over real requests: the token, Host and Origin checks, on the
//! API and the WebSocket.

use crate::support::*;

const TOKEN: &str = "s3cret-console-token";

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn with_a_token_every_request_without_it_is_refused() {
    let agent = demo_agent().await;
    let console = console_for(&agent, Some(TOKEN)).await;
    let addr = console.local_addr();
    assert_eq!(console.url(), format!("http://{addr}/?token={TOKEN}"));
    for path in [
        "/",
        "/app.js",
        "/api/agents",
        "/api/agents/robot1/properties",
        "/api/logs",
    ] {
        assert_eq!(
            get(addr, path).await.status,
            401,
            "{path} without the token"
        );
        let wrong = format!("{path}?token=s3cret-console-tokeN");
        assert_eq!(
            get(addr, &wrong).await.status,
            401,
            "{path} with a wrong token"
        );
        let bearer = format!("Bearer {TOKEN}");
        let with_header = http(addr, "GET", path, &[("Authorization", &bearer)], None).await;
        assert_eq!(with_header.status, 200, "{path} with the header");
        let with_query = get(addr, &format!("{path}?token={TOKEN}")).await;
        assert_eq!(with_query.status, 200, "{path} with the query");
    }
    let body = r#"{"key": "filter/params/factor", "value": "1.0"}"#;
    let refused = http(addr, "POST", "/api/agents/robot1/set", &[], Some(body)).await;
    assert_eq!(refused.status, 401);
    assert_eq!(
        *agent
            .blackboard()
            .get::<f64>("filter/params/factor")
            .await
            .unwrap(),
        10.0
    );

    let no_token = websocket(addr, "/api/ws?agent=robot1", &[]).await;
    assert!(
        no_token.is_err(),
        "a WebSocket without the token is refused"
    );
    let with_token = websocket(addr, &format!("/api/ws?agent=robot1&token={TOKEN}"), &[]).await;
    assert!(with_token.is_ok(), "{:?}", with_token.err());
    console.stop().await;
    agent.stop(None).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn another_origin_or_host_is_refused() {
    let agent = demo_agent().await;
    let console = console_for(&agent, None).await;
    let addr = console.local_addr();
    let own = format!("http://{addr}");
    let ok = http(addr, "GET", "/api/agents", &[("Origin", &own)], None).await;
    assert_eq!(ok.status, 200, "the console's own page: {}", ok.body);
    let localhost = format!("localhost:{}", addr.port());
    let ok = http(addr, "GET", "/api/agents", &[("Host", &localhost)], None).await;
    assert_eq!(ok.status, 200, "localhost names loopback too");

    let foreign = http(
        addr,
        "GET",
        "/api/agents",
        &[("Origin", "http://evil.example")],
        None,
    )
    .await;
    assert_eq!(foreign.status, 403);
    assert!(
        foreign
            .body
            .contains("Origin `http://evil.example` is not this console"),
        "{}",
        foreign.body
    );
    // A page of another site that rebinds its name to 127.0.0.1 sends its own Host.
    let rebound = format!("evil.example:{}", addr.port());
    let rebinding = http(addr, "GET", "/api/agents", &[("Host", &rebound)], None).await;
    assert_eq!(rebinding.status, 403);
    let body = r#"{"key": "filter/params/factor", "value": "1.0"}"#;
    let set = http(
        addr,
        "POST",
        "/api/agents/robot1/set",
        &[("Origin", "http://evil.example")],
        Some(body),
    )
    .await;
    assert_eq!(set.status, 403);
    assert_eq!(
        *agent
            .blackboard()
            .get::<f64>("filter/params/factor")
            .await
            .unwrap(),
        10.0
    );

    let socket = websocket(
        addr,
        "/api/ws?agent=robot1",
        &[("Origin", "http://evil.example")],
    )
    .await;
    assert!(
        socket.is_err(),
        "a WebSocket from another origin is refused"
    );
    let socket = websocket(addr, "/api/ws?agent=robot1", &[("Origin", &own)]).await;
    assert!(socket.is_ok(), "{:?}", socket.err());
    console.stop().await;
    agent.stop(None).await;
}
