//! The Python examples of `docs/wire-format.md`, run against a running team with the
//! `eclipse-zenoh` package: a non-Rust client reads, follows and sets properties.
//! `.ci/run` installs the package; elsewhere, without it, the test says loudly that it skipped.

use std::process::Command;

use crate::support::*;

/// The ```python blocks of the wire-format guide.
fn snippets() -> Vec<String> {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/wire-format.md"))
        .expect("docs/wire-format.md");
    doc.split("```python\n")
        .skip(1)
        .map(|rest| rest.split("```").next().unwrap_or_default().to_string())
        .collect()
}

fn python_has_zenoh() -> bool {
    Command::new("python3")
        .args(["-c", "import zenoh"])
        .output()
        .is_ok_and(|o| o.status.success())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_python_examples_of_the_wire_format_guide_work() {
    let snippets = snippets();
    assert_eq!(
        snippets.len(),
        2,
        "the guide has a read and a write example"
    );
    if !python_has_zenoh() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must have python3 with eclipse-zenoh (installed by .ci/run)"
        );
        eprintln!("SKIPPED: the Python examples need python3 with `pip install eclipse-zenoh`");
        return;
    }
    let team = team_name("python");
    let (ps, pf) = (free_port(), free_port());
    let sensor = start(&agent_config(
        "sensor",
        &team,
        ps,
        &[],
        "",
        r#"
        (name: "signal", type: "demo.signal", values: {"params/sample_ms": 20}),"#,
    ))
    .await;
    let filter = start(&agent_config(
        "filter",
        &team,
        pf,
        &[ps],
        r#"remote_write: ["scale/params/*"]"#,
        r#"
        (name: "scale", type: "demo.scale", values: {"params/factor": 10.0, "params/offset": 10.0},
         links: {"in/value": "petrel://sensor/signal/out/value"}),"#,
    ))
    .await;
    let live = filter
        .handle::<petrel::actors::team::LinkStatus>("scale/stats/links/in/value")
        .await;
    wait_for(&live, "the filter's link live", |s| s.state == "live").await;
    let adapt = |code: &str| {
        code.replace("petrel/demo/", &format!("petrel/{team}/"))
            .replace("127.0.0.1:7450", &format!("127.0.0.1:{ps}"))
    };
    let run = |code: String| async move {
        let out = tokio::time::timeout(
            DEADLINE,
            tokio::process::Command::new("python3")
                .args(["-c", &code])
                .kill_on_drop(true)
                .output(),
        )
        .await
        .expect("the example finishes")
        .expect("python3 runs");
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(
            out.status.success(),
            "{stdout}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        stdout
    };

    let read = run(adapt(&snippets[0])).await;
    let lines: Vec<&str> = read.lines().collect();
    assert_eq!(lines.len(), 4, "{read}");
    assert!(
        lines[0].starts_with("f64 "),
        "the current value with its type: {read}"
    );
    for line in &lines[1..] {
        line.parse::<f64>()
            .unwrap_or_else(|_| panic!("a followed value: {read}"));
    }

    let write = run(adapt(&snippets[1])).await;
    let lines: Vec<&str> = write.lines().collect();
    assert_eq!(lines[0], "ok", "{write}");
    assert!(
        lines[1].contains("cannot be set from another agent"),
        "{write}"
    );
    assert_eq!(
        filter.handle::<f64>("scale/params/factor").await.value(),
        3.0
    );
    filter.stop().await;
    sensor.stop().await;
}
