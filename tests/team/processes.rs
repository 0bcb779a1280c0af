//! The shipped demo team as three real processes: one is killed with SIGKILL, the others see
//! it leave and their links go stale; the restarted process rejoins and links are live again.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use petrel::actors::team::{LinkStatus, TeamMembers};

use crate::support::*;

/// A `petrel run` process, killed (SIGKILL) when dropped so a failing test leaves nothing.
struct Process(Child);

impl Process {
    fn run(config: &Path, log: &Path) -> Process {
        let log = std::fs::File::create(log).expect("a log file");
        let child = Command::new(env!("CARGO_BIN_EXE_petrel"))
            .arg("run")
            .arg(config)
            .args(["--for", "120s"])
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .expect("petrel starts");
        Process(child)
    }

    /// SIGKILL: no cleanup, no goodbye; the others must notice through the lease.
    fn kill(mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

impl Drop for Process {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A shipped demo config with its ports and team name replaced, written into `dir`.
fn demo_config(dir: &Path, name: &str, team: &str, ports: &[(u16, u16)]) -> PathBuf {
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("configs/team/{name}.ron"));
    let mut text = std::fs::read_to_string(&source).expect("the demo config");
    text = text.replace("name: \"demo\"", &format!("name: \"{team}\""));
    for (shipped, free) in ports {
        text = text.replace(
            &format!("127.0.0.1:{shipped}"),
            &format!("127.0.0.1:{free}"),
        );
    }
    let path = dir.join(format!("{name}.ron"));
    std::fs::write(&path, text).expect("write the config");
    path
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_killed_process_leaves_and_its_restart_rejoins_with_links_live_again() {
    let dir = tempfile::tempdir().unwrap();
    let team = team_name("processes");
    let (ps, pf, pd, po) = (free_port(), free_port(), free_port(), free_port());
    let ports = [(7450, ps), (7451, pf), (7452, pd)];
    let sensor = demo_config(dir.path(), "sensor", &team, &ports);
    let filter = demo_config(dir.path(), "filter", &team, &ports);
    let display = demo_config(dir.path(), "display", &team, &ports);
    let sensor_process = Process::run(&sensor, &dir.path().join("sensor.log"));
    let _filter_process = Process::run(&filter, &dir.path().join("filter.log"));
    let _display_process = Process::run(&display, &dir.path().join("display.log"));

    // This test's own agent watches the sensor's value and the filter's link to it.
    let observer = start(&agent_config(
        "observer",
        &team,
        po,
        &[ps, pf],
        "",
        r#"
        (name: "probe", type: "test.probe", links: {
            "in/value": "petrel://sensor/signal/out/value",
            "in/status": "petrel://filter/scale/stats/links/in/value"}),"#,
    ))
    .await;
    let members = observer.handle::<TeamMembers>("_team/members").await;
    let all = ["display", "filter", "observer", "sensor"];
    wait_for(&members, "the four agents", |l| names(l) == all).await;
    let own = observer
        .handle::<LinkStatus>("probe/stats/links/in/value")
        .await;
    let filters = observer.handle::<LinkStatus>("probe/in/status").await;
    wait_for(&own, "the observer's link live", |s| s.state == "live").await;
    wait_for(&filters, "the filter's link live", |s| s.state == "live").await;

    let killed = tokio::time::Instant::now();
    sensor_process.kill();
    let without = ["display", "filter", "observer"];
    wait_for(&members, "the sensor gone", |l| names(l) == without).await;
    eprintln!("SIGKILL to `left` seen: {:?} (lease 1 s)", killed.elapsed());
    wait_for(&own, "the observer's link stale", |s| s.state == "stale").await;
    wait_for(&filters, "the filter's link stale", |s| s.state == "stale").await;

    let _sensor_again = Process::run(&sensor, &dir.path().join("sensor-again.log"));
    wait_for(&members, "the sensor back", |l| names(l) == all).await;
    wait_for(&own, "the observer's link live again", |s| {
        s.state == "live"
    })
    .await;
    wait_for(&filters, "the filter's link live again", |s| {
        s.state == "live"
    })
    .await;
    observer.stop().await;
}
