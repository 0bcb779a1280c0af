//! Many remote links: 1000 inputs of one agent, each linked to its own property of another.

use petrel::actors::team::LinkStatus;

use crate::support::*;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_thousand_remote_links_each_carry_their_own_value() {
    const N: usize = 1000;
    let counters: String = (0..N)
        .map(|i| format!(r#"(name: "c{i}", type: "demo.counter", values: {{"params/period_ms": 500, "params/start": {i}.0, "params/increment": 0.0}}),"#))
        .collect();
    let probes: String = (0..N)
        .map(|i| format!(r#"(name: "p{i}", type: "test.probe", links: {{"in/value": "petrel://a/c{i}/out/value"}}),"#))
        .collect();
    let (a, b) = pair("thousand", ("", &counters), ("", &probes)).await;
    for i in (0..N).rev() {
        let input = b.handle::<f64>(&format!("p{i}/in/value")).await;
        wait_for(&input, &format!("probe {i} to read c{i}"), |v| {
            *v == i as f64
        })
        .await;
    }
    for i in 0..N {
        let status = b
            .handle::<LinkStatus>(&format!("p{i}/stats/links/in/value"))
            .await;
        let s = status.get();
        assert_eq!(
            (s.state.as_str(), s.rejected),
            ("live", 0),
            "link {i}: {s:?}"
        );
    }
    b.stop().await;
    a.stop().await;
}
