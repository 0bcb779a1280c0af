//! The console's JSON API and WebSocket, called directly against a running demo agent.

use serde_json::json;

use crate::support::*;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_api_lists_modules_properties_and_links() {
    let agent = demo_agent().await;
    let console = console_for(&agent, None).await;
    let addr = console.local_addr();
    assert_ne!(addr.port(), 0, "the console reports the port it was given");
    assert_eq!(console.url(), format!("http://{addr}/"));

    let agents = get(addr, "/api/agents").await;
    assert_eq!(agents.status, 200, "{}", agents.body);
    let agents = agents.json();
    let robot = &agents["agents"][0];
    assert_eq!(robot["name"], "robot1");
    let modules: Vec<(&str, &str)> = robot["modules"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| (m["name"].as_str().unwrap(), m["type"].as_str().unwrap()))
        .collect();
    assert_eq!(
        modules,
        [("sensor", "demo.signal"), ("filter", "demo.scale")]
    );

    let props = get(addr, "/api/agents/robot1/properties").await.json();
    let find = |key: &str| {
        props["properties"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["key"] == key)
            .unwrap_or_else(|| panic!("{key} listed"))
            .clone()
    };
    assert_eq!(find("filter/params/factor")["writable"], true);
    assert_eq!(find("sensor/control/fault")["writable"], true);
    assert_eq!(find("sensor/out/value")["writable"], false);
    assert_eq!(find("filter/in/value")["link"], "sensor/out/value");

    let graph = get(addr, "/api/agents/robot1/graph").await.json();
    assert!(
        graph["links"].as_array().unwrap().contains(
            &json!({"from": "filter/in/value", "to": "sensor/out/value", "queue": false})
        ),
        "{graph}"
    );
    let value = get(addr, "/api/agents/robot1/value?key=filter/params/factor")
        .await
        .json();
    assert_eq!(
        (value["type"].clone(), value["json"].clone()),
        (json!("f64"), json!(10.0))
    );

    let unknown = get(addr, "/api/agents/robot9/properties").await;
    assert_eq!(unknown.status, 404);
    assert!(unknown.body.contains("agents: robot1"), "{}", unknown.body);
    let page = get(addr, "/").await;
    assert!(page.status == 200 && page.body.contains("<script src=\"app.js\">"));
    console.stop().await;
    agent.stop(None).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_websocket_pushes_a_value_as_it_changes() {
    let agent = demo_agent().await;
    let console = console_for(&agent, None).await;
    let mut socket = websocket(console.local_addr(), "/api/ws?agent=robot1", &[])
        .await
        .expect("a WebSocket on loopback without a token");
    send(
        &mut socket,
        json!({"watch": ["sensor/out/value", "no/such/key"]}),
    )
    .await;
    let first = next(&mut socket).await;
    assert!(
        first["errors"][0]
            .as_str()
            .unwrap()
            .starts_with("no/such/key"),
        "an unknown key is named: {first}"
    );
    // The sensor writes every 20 ms: two pushes with different versions and values.
    let mut seen = Vec::new();
    while seen.len() < 2 {
        let message = next(&mut socket).await;
        for v in message["values"].as_array().into_iter().flatten() {
            assert_eq!(v["key"], "sensor/out/value");
            seen.push((v["version"].as_u64().unwrap(), v["json"].as_f64().unwrap()));
        }
    }
    assert!(seen[1].0 > seen[0].0, "a newer version is pushed: {seen:?}");
    assert_ne!(seen[1].1, seen[0].1, "the value changed: {seen:?}");
    // Stopping the console closes its sockets (it does not wait for clients to leave).
    console.stop().await;
    let closed = async {
        while let Some(Ok(m)) = futures_util::StreamExt::next(&mut socket).await {
            if m.is_close() {
                return;
            }
        }
    };
    tokio::time::timeout(DEADLINE, closed)
        .await
        .expect("the socket closed when the console stopped");
    agent.stop(None).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_parameter_set_through_the_api_is_in_the_blackboard_and_other_writes_are_refused() {
    let agent = demo_agent().await;
    let console = console_for(&agent, None).await;
    let addr = console.local_addr();
    let set = |key: &str, value: &str| {
        let body = json!({"key": key, "value": value}).to_string();
        async move { http(addr, "POST", "/api/agents/robot1/set", &[], Some(&body)).await }
    };

    let ok = set("filter/params/factor", "2.5").await;
    assert_eq!(ok.status, 200, "{}", ok.body);
    assert_eq!(ok.json()["json"], 2.5);
    let factor = agent
        .blackboard()
        .get::<f64>("filter/params/factor")
        .await
        .unwrap();
    assert_eq!(*factor, 2.5);

    let bad = set("filter/params/factor", "\"fast\"").await;
    assert_eq!(bad.status, 400);
    assert!(
        bad.json()["error"]
            .as_str()
            .unwrap()
            .contains("filter/params/factor"),
        "{}",
        bad.body
    );
    assert_eq!(
        *agent
            .blackboard()
            .get::<f64>("filter/params/factor")
            .await
            .unwrap(),
        2.5
    );

    for forbidden in ["filter/out/value", "sensor/stats/steps", "filter/enabled"] {
        let refused = set(forbidden, "1").await;
        assert_eq!(refused.status, 403, "{forbidden}: {}", refused.body);
        assert!(
            refused.json()["error"]
                .as_str()
                .unwrap()
                .contains("only params/ and control/"),
            "{}",
            refused.body
        );
    }
    let unknown = set("filter/params/nope", "1").await;
    assert_eq!(unknown.status, 404, "{}", unknown.body);
    // Requests the API cannot read are answered in its own form, as bad requests.
    let post = |body: &'static str| http(addr, "POST", "/api/agents/robot1/set", &[], Some(body));
    let get_value = |query: &'static str| get(addr, query);
    for bad in [
        post("{\"key\": 1}").await,
        post("not json").await,
        get_value("/api/agents/robot1/value").await,
        get_value("/api/agents/robot1/value?key=").await,
        get_value("/api/agents/robot1/value?key=sensor").await,
        set("sensor", "1").await,
    ] {
        assert_eq!(bad.status, 400, "{}", bad.body);
        assert!(bad.json()["error"].is_string(), "{}", bad.body);
    }
    console.stop().await;
    agent.stop(None).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_plan_view_follows_the_marking_and_names_the_transitions_that_fired() {
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("m.plan");
    std::fs::write(&plan, "first; second\n").unwrap();
    let config = format!(
        r#"Agent(name: "robot1", modules: [
    (name: "sensor", type: "demo.signal", values: {{"params/sample_ms": 20}}),
    (name: "filter", type: "demo.scale", values: {{"params/factor": 10.0}},
     links: {{"in/value": "sensor/out/value"}}),
    (name: "mission", type: "mission.pnp", values: {{
        "params/plan": {plan:?},
        "params/actions": {{
            "first": (finished: "filter/params/factor > 50"),
            "second": (finished: "filter/params/factor > 500"),
        }},
    }}),
])"#
    );
    let file = petrel::actors::ConfigFile::parse("mission.ron", &config).unwrap();
    let agent = petrel::actors::Agent::start(&file, petrel::Petrel::new().registry())
        .await
        .unwrap();
    let loaded = petrel::plans::load_plan(&plan, None).unwrap();
    let mut source = petrel::console::AgentSource::new("robot1", agent.blackboard().clone());
    source.plans = vec![petrel::cli::console::plan_graph("mission", &loaded.plan)];
    let console = petrel::console::Console::start(
        petrel::console::ConsoleOptions {
            addr: "127.0.0.1:0".parse().unwrap(),
            token: None,
        },
        vec![source],
        petrel::console::LogTail::default(),
    )
    .await
    .unwrap();
    let addr = console.local_addr();

    // Wait, over the WebSocket, until the mission runs `first`.
    let mut socket = websocket(addr, "/api/ws?agent=robot1", &[]).await.unwrap();
    send(&mut socket, json!({"watch": ["mission/out/running"]})).await;
    wait_running(&mut socket, "first").await;
    let plans = get(addr, "/api/agents/robot1/plans").await.json();
    let p = &plans["plans"][0];
    assert_eq!(p["module"], "mission");
    assert!(p["places"].as_array().unwrap().len() >= 4, "{p}");
    assert!(
        p["places"]
            .as_array()
            .unwrap()
            .iter()
            .any(|x| x["role"] == "goal"),
        "{p}"
    );
    let marked: Vec<&str> = p["marking"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["place"].as_str().unwrap())
        .collect();
    assert_eq!(marked.len(), 1, "{p}");
    assert!(marked[0].contains("first"), "{p}");

    let body = json!({"key": "filter/params/factor", "value": "60.0"}).to_string();
    let set = http(addr, "POST", "/api/agents/robot1/set", &[], Some(&body)).await;
    assert_eq!(set.status, 200, "{}", set.body);
    wait_running(&mut socket, "second").await;
    let plans = get(addr, "/api/agents/robot1/plans").await.json();
    let firings = plans["plans"][0]["firings"].as_array().unwrap().clone();
    let named: Vec<&str> = firings
        .iter()
        .flat_map(|f| f["transitions"].as_array().unwrap())
        .map(|t| t.as_str().unwrap())
        .collect();
    assert!(
        named
            .iter()
            .any(|t| t.contains("first") && t.contains("end")),
        "the end of `first` is among the firings: {firings:?}"
    );
    console.stop().await;
    agent.stop(None).await;
}

/// Waits for the mission's `out/running` to be pushed as `want`.
async fn wait_running(socket: &mut Socket, want: &str) {
    loop {
        let m = next(socket).await;
        if m["values"][0]["json"] == want {
            return;
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_fault_injected_through_a_control_shows_as_supervisor_events() {
    let agent = demo_agent().await;
    let console = console_for(&agent, None).await;
    let addr = console.local_addr();
    let mut socket = websocket(addr, "/api/ws?agent=robot1", &[]).await.unwrap();
    send(&mut socket, json!({"watch": ["sensor/stats/restarts"]})).await;

    let body = json!({"key": "sensor/control/fault", "value": "\"panic\""}).to_string();
    let set = http(addr, "POST", "/api/agents/robot1/set", &[], Some(&body)).await;
    assert_eq!(set.status, 200, "controls are writable: {}", set.body);
    // The supervisor restarts the sensor...
    loop {
        let m = next(&mut socket).await;
        if m["values"][0]["json"].as_i64().unwrap_or(0) >= 1 {
            break;
        }
    }
    // ...and the console's reader of `_supervisor/events` has them (it reads on its own task:
    // ask until it has caught up, within the deadline).
    let deadline = tokio::time::Instant::now() + DEADLINE;
    let kinds = loop {
        let events = get(addr, "/api/agents/robot1/events").await.json();
        let kinds: Vec<String> = events["events"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|e| e["module"] == "sensor")
            .map(|e| e["kind"].as_str().unwrap().to_string())
            .collect();
        if kinds.iter().any(|k| k == "restarted") || tokio::time::Instant::now() > deadline {
            break kinds;
        }
        tokio::task::yield_now().await;
    };
    assert_eq!(kinds[..2], ["failed", "restarted"], "{kinds:?}");
    let modules = get(addr, "/api/agents").await.json();
    let sensor = &modules["agents"][0]["modules"][0];
    assert_eq!(
        (sensor["name"].clone(), sensor["restarts"].clone()),
        (json!("sensor"), json!(1))
    );
    console.stop().await;
    agent.stop(None).await;
}
