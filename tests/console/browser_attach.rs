//! The page of `petrel console` in headless Chromium: a remote agent's values change live in
//! it, and when the agent's run is SIGKILLed the page shows the agent left. Without Chromium
//! the test says loudly that it was skipped.

use crate::attach::run_and_attach;
use crate::browser::{chromium, start_browser, when, DevTools};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_attached_console_page_shows_live_values_and_an_agent_that_left() {
    let Some(program) = chromium() else {
        eprintln!("\n******** SKIPPED: the attached console's browser test needs Chromium (apt-get install chromium) ********\n");
        return;
    };
    let records = tempfile::tempdir().unwrap();
    let (mut run, console, addr) = run_and_attach(records.path());
    let profile = tempfile::tempdir().unwrap();
    let (_browser, endpoint) = start_browser(program, profile.path());
    let mut page = DevTools::open(&endpoint, &format!("http://{addr}/")).await;

    // Values come over the team and change in the page.
    let cell = r#"document.querySelector('tr[data-key="sensor/out/value"] td.value')"#;
    let first = page
        .eval(&when(
            &format!("{cell}.dataset.version"),
            &format!("{cell}.dataset.version"),
        ))
        .await;
    let later = page
        .eval(&when(
            &format!("{cell}.dataset.version !== {first}"),
            &format!("{cell}.dataset.version"),
        ))
        .await;
    assert_ne!(first, later, "the page shows the remote value changing");

    // The run dies without a word; the console says so, then the page does.
    run.child().kill().unwrap();
    run.child().wait().unwrap();
    console.wait_for("console: agent `robot1` left");
    let option = "document.querySelector('#agent option[value=\"robot1\"]').textContent";
    let status = "document.getElementById('status').textContent";
    let shown = page
        .eval(&when(
            &format!("{option} === 'robot1 (left)' && {status} === 'agent robot1 left'"),
            &format!("[{option}, {status}]"),
        ))
        .await;
    assert_eq!(
        shown,
        serde_json::json!(["robot1 (left)", "agent robot1 left"])
    );
}
