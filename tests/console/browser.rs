//! The console page in a real browser: headless Chromium (Debian's `chromium`) loads the page
//! of a running demo, sees live values change, edits a parameter through the page's own form
//! and script, and the test reads the new value from the blackboard. The browser is driven over
//! the DevTools protocol on loopback; a screenshot is written to `target/tmp/console-page.png`.
//! Without Chromium the test says loudly that it was skipped.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;

use base64::Engine as _;
use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
use tokio_tungstenite::tungstenite::Message;

use crate::support::*;

/// Kills the browser however the test ends.
pub(crate) struct Browser(Child);

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

pub(crate) fn chromium() -> Option<&'static str> {
    ["chromium", "chromium-browser"].into_iter().find(|name| {
        Command::new(name)
            .arg("--version")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    })
}

/// Starts headless Chromium with its own profile and DevTools on a loopback port it picks;
/// returns the browser's DevTools WebSocket URL, read from the line Chromium prints.
pub(crate) fn start_browser(program: &str, profile: &std::path::Path) -> (Browser, String) {
    let mut child = Command::new(program)
        .args([
            "--headless",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--no-first-run",
            "--no-default-browser-check",
            "--disable-sync",
            "--metrics-recording-only",
            "--window-size=1400,1800",
            "--remote-debugging-address=127.0.0.1",
            "--remote-debugging-port=0",
        ])
        // Root (CI containers) cannot use Chromium's sandbox.
        .args(is_root().then_some("--no-sandbox"))
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg("about:blank")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("chromium starts");
    let stderr = child.stderr.take().unwrap();
    let browser = Browser(child);
    let (found, endpoint) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            if let Some(url) = line.strip_prefix("DevTools listening on ") {
                let _ = found.send(url.trim().to_string());
            }
        }
    });
    let url = endpoint
        .recv_timeout(DEADLINE)
        .expect("chromium printed its DevTools address in time");
    (browser, url)
}

fn is_root() -> bool {
    unsafe { libc::geteuid() == 0 }
}

/// A DevTools protocol session on one page (flat mode: the page's session id on each call).
pub(crate) struct DevTools {
    socket: tokio_tungstenite::WebSocketStream<tokio::net::TcpStream>,
    session: Option<String>,
    next_id: u64,
    /// Events received while waiting for answers, by method.
    events: Vec<String>,
}

impl DevTools {
    async fn connect(url: &str) -> DevTools {
        let host = url
            .strip_prefix("ws://")
            .and_then(|u| u.split('/').next())
            .expect("a ws:// URL");
        let stream = tokio::net::TcpStream::connect(host)
            .await
            .expect("connect to DevTools");
        let (socket, _) =
            tokio::time::timeout(DEADLINE, tokio_tungstenite::client_async(url, stream))
                .await
                .expect("DevTools handshake in time")
                .expect("DevTools handshake");
        DevTools {
            socket,
            session: None,
            next_id: 1,
            events: Vec::new(),
        }
    }

    /// A new page of the browser at `endpoint`, loaded from `url`.
    pub(crate) async fn open(endpoint: &str, url: &str) -> DevTools {
        let mut devtools = DevTools::connect(endpoint).await;
        let target = devtools
            .call("Target.createTarget", json!({"url": "about:blank"}))
            .await;
        let attached = devtools
            .call(
                "Target.attachToTarget",
                json!({"targetId": target["targetId"], "flatten": true}),
            )
            .await;
        devtools.session = Some(attached["sessionId"].as_str().unwrap().to_string());
        devtools.call("Page.enable", json!({})).await;
        devtools.call("Page.navigate", json!({"url": url})).await;
        devtools.event("Page.loadEventFired").await;
        devtools
    }

    /// The next DevTools message.
    async fn receive(&mut self, waiting_for: &str) -> Value {
        loop {
            let message = tokio::time::timeout(DEADLINE, self.socket.next())
                .await
                .unwrap_or_else(|_| panic!("{waiting_for}: nothing in time"))
                .expect("DevTools open")
                .expect("DevTools message");
            if let Message::Text(text) = message {
                return serde_json::from_str(&text).expect("DevTools JSON");
            }
        }
    }

    /// Waits for the event `method` (or finds it among those already received).
    async fn event(&mut self, method: &str) {
        while !self.events.iter().any(|e| e == method) {
            let message = self.receive(method).await;
            if let Some(m) = message["method"].as_str() {
                self.events.push(m.to_string());
            }
        }
    }

    /// Calls `method` and returns its result (events in between are kept by name).
    async fn call(&mut self, method: &str, params: Value) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        let mut message = json!({"id": id, "method": method, "params": params});
        if let Some(s) = &self.session {
            message["sessionId"] = json!(s);
        }
        self.socket
            .send(Message::Text(message.to_string().into()))
            .await
            .expect("send to DevTools");
        loop {
            let reply = self.receive(method).await;
            if let Some(m) = reply["method"].as_str() {
                self.events.push(m.to_string());
            }
            if reply["id"] == id {
                assert!(reply["error"].is_null(), "{method}: {reply}");
                return reply["result"].clone();
            }
        }
    }

    /// Evaluates `expression` in the page (awaiting a promise) and returns its value.
    pub(crate) async fn eval(&mut self, expression: &str) -> Value {
        let r = self
            .call(
                "Runtime.evaluate",
                json!({"expression": expression, "awaitPromise": true, "returnByValue": true}),
            )
            .await;
        assert!(r["exceptionDetails"].is_null(), "{expression}: {r}");
        r["result"]["value"].clone()
    }
}

/// A promise that resolves with `value()` once `ready()` holds, re-checked on every change of
/// the page (a MutationObserver: no polling), and rejects after 20 s.
pub(crate) fn when(ready: &str, value: &str) -> String {
    format!(
        r#"new Promise((resolve, reject) => {{
            const check = () => {{ try {{ if ({ready}) {{ observer.disconnect(); resolve({value}); }} }} catch (e) {{}} }};
            const observer = new MutationObserver(check);
            observer.observe(document, {{subtree: true, childList: true, attributes: true, characterData: true}});
            setTimeout(() => {{ observer.disconnect(); reject(new Error("timed out waiting for: " + {ready:?})); }}, 20000);
            check();
        }})"#
    )
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_real_browser_sees_live_values_and_edits_a_parameter() {
    let Some(program) = chromium() else {
        eprintln!("\n******** SKIPPED: the console's browser test needs Chromium (apt-get install chromium); .ci/run installs it ********\n");
        return;
    };
    let agent = demo_agent().await;
    let console = console_for(&agent, Some("browser-test-token-0123")).await;
    let profile = tempfile::tempdir().unwrap();
    let (_browser, endpoint) = start_browser(program, profile.path());
    let mut devtools = DevTools::open(&endpoint, &console.url()).await;

    // Live values: the sensor's value cell shows two different versions pushed by the server.
    let cell = r#"document.querySelector('tr[data-key="sensor/out/value"] td.value')"#;
    let first = devtools
        .eval(&when(
            &format!("{cell}.dataset.version"),
            &format!("{cell}.dataset.version"),
        ))
        .await;
    let later = devtools
        .eval(&when(
            &format!("{cell}.dataset.version !== {first}"),
            &format!("{cell}.dataset.version"),
        ))
        .await;
    assert_ne!(first, later, "the page shows the value changing");
    let status = devtools
        .eval("document.getElementById('status').textContent")
        .await;
    assert_eq!(status, "live");

    // Edit a parameter with the page's own form: type, click `set`, wait for its answer.
    let field = r#"document.querySelector('input.edit[data-key="filter/params/factor"]')"#;
    let button = r#"document.querySelector('button[data-key="filter/params/factor"]')"#;
    let note = r#"document.querySelector('tr[data-key="filter/params/factor"] .note')"#;
    devtools
        .eval(&format!("{field}.value = '7.25'; {button}.click(); true"))
        .await;
    let answer = devtools
        .eval(&when(
            &format!("{note}.textContent.startsWith('✓')"),
            &format!("{note}.textContent"),
        ))
        .await;
    assert_eq!(answer, "✓ 7.25");
    let factor = agent
        .blackboard()
        .get::<f64>("filter/params/factor")
        .await
        .unwrap();
    assert_eq!(*factor, 7.25, "the page's edit reached the blackboard");

    // The new value comes back to the page over the WebSocket.
    let factor_cell = r#"document.querySelector('tr[data-key="filter/params/factor"] td.value')"#;
    let shown = devtools
        .eval(&when(
            &format!("{factor_cell}.textContent === '7.25'"),
            &format!("{factor_cell}.textContent"),
        ))
        .await;
    assert_eq!(shown, "7.25");

    // A bad value: the error is shown next to the field, and the blackboard keeps 7.25.
    devtools
        .eval(&format!(
            "{field}.value = '\"fast\"'; {button}.click(); true"
        ))
        .await;
    let error = devtools
        .eval(&when(
            &format!("{note}.classList.contains('error')"),
            &format!("{note}.textContent"),
        ))
        .await;
    assert!(
        error.as_str().unwrap().contains("filter/params/factor"),
        "{error}"
    );
    assert_eq!(
        *agent
            .blackboard()
            .get::<f64>("filter/params/factor")
            .await
            .unwrap(),
        7.25
    );

    let shot = devtools
        .call("Page.captureScreenshot", json!({"format": "png"}))
        .await;
    let png = base64::engine::general_purpose::STANDARD
        .decode(shot["data"].as_str().unwrap())
        .unwrap();
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("console-page.png");
    std::fs::write(&path, &png).unwrap();
    eprintln!("console page screenshot: {}", path.display());
    console.stop().await;
    agent.stop(None).await;
}
