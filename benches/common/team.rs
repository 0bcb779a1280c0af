//! Agents on a team over TCP loopback, for the team benchmarks.

use petrel::actors::{Agent, ConfigFile};
use petrel::team::Team;

#[path = "../../tests/common/ports.rs"]
mod ports;
#[allow(unused_imports)] // benches without a team do not use it
pub use ports::free_port;

/// A team agent config listening on `port` and connecting to `connect`.
pub fn config(name: &str, team: &str, port: u16, connect: Option<u16>, modules: &str) -> String {
    let connect = connect.map_or(String::new(), |p| format!("\"tcp/127.0.0.1:{p}\""));
    format!(
        r#"Agent(name: "{name}",
            team: (name: "{team}", listen: ["tcp/127.0.0.1:{port}"], connect: [{connect}]),
            modules: [{modules}])"#
    )
}

/// Starts an agent and joins its team.
pub async fn start(text: &str) -> (Agent, Team) {
    let file = ConfigFile::parse("bench.ron", text).unwrap_or_else(|e| panic!("{e}"));
    let agent = Agent::start(&file, &super::registry())
        .await
        .unwrap_or_else(|e| panic!("{e}"));
    let team = Team::join(&agent, file.config.team.as_ref().unwrap())
        .await
        .unwrap_or_else(|e| panic!("{e}"));
    (agent, team)
}

/// A raw zenoh session on loopback: the floor petrel's team transport is measured against.
pub async fn raw_session(listen: Option<u16>, connect: Option<u16>) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    let list = |p: Option<u16>| match p {
        Some(p) => format!("[\"tcp/127.0.0.1:{p}\"]"),
        None => "[]".into(),
    };
    c.insert_json5("listen/endpoints", &list(listen)).unwrap();
    c.insert_json5("connect/endpoints", &list(connect)).unwrap();
    c.insert_json5("scouting/multicast/enabled", "false")
        .unwrap();
    zenoh::open(c).await.unwrap()
}

/// A 181-ray scan whose ranges depend on `i` (a fresh payload per scan).
pub fn scan(i: u64) -> petrel::actors::LaserScan {
    let ranges: Vec<f64> = (0..181)
        .map(|r| 1.0 + ((i + r) % 97) as f64 * 0.05)
        .collect();
    petrel::actors::LaserScan {
        angle_min: -std::f64::consts::FRAC_PI_2,
        angle_increment: std::f64::consts::PI / 180.0,
        range_max: 8.0,
        ranges: ranges.into(),
    }
}

/// This process's CPU time (all threads).
pub fn process_cpu() -> std::time::Duration {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes into the timespec we own.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    std::time::Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
}

/// `bench.scans`: every `params/period_ms` while `in/remaining` > 0, pushes a fresh 181-ray
/// scan into `out/scans` and counts `in/remaining` down in `out/sent`.
pub struct ScanSource {
    remaining: petrel::actors::Input<i64>,
    seen: u64,
    left: i64,
    sent: petrel::actors::Output<i64>,
    scans: petrel::actors::QueueWriter<petrel::actors::LaserScan>,
}

impl petrel::actors::Module for ScanSource {
    const TYPE: &'static str = "bench.scans";
    const DESCRIPTION: &'static str = "Pushes in/remaining fresh laser scans, one per period.";
    fn declare(ports: &mut petrel::actors::Ports) -> Self {
        ScanSource {
            remaining: ports.input("in/remaining", 0, "scans to push"),
            seen: 0,
            left: 0,
            sent: ports.output("out/sent", 0, "scans pushed"),
            scans: ports.queue_out("out/scans", 4096, "scans"),
        }
    }
    fn schedule(&self) -> petrel::actors::Schedule {
        petrel::actors::Schedule::every(std::time::Duration::from_millis(1))
            .on_change(&self.remaining)
    }
    async fn step(&mut self, _ctx: &mut petrel::actors::Context) -> anyhow::Result<()> {
        let r = self.remaining.read();
        if r.version != self.seen {
            self.seen = r.version;
            self.left += *r;
            return Ok(());
        }
        if self.left > 0 {
            self.left -= 1;
            let n = self.sent.value();
            self.scans.push(scan(n as u64));
            self.sent.set(n + 1);
        }
        Ok(())
    }
}

/// `bench.scan_sink`: counts the scans it reads (`out/received`) and the gaps in their
/// sequence numbers (`out/lost`).
pub struct ScanSink {
    scans: petrel::actors::QueueReader<petrel::actors::LaserScan>,
    received: petrel::actors::Output<i64>,
    lost: petrel::actors::Output<i64>,
    next: Option<u64>,
}

impl petrel::actors::Module for ScanSink {
    const TYPE: &'static str = "bench.scan_sink";
    const DESCRIPTION: &'static str = "Counts scans and the gaps between them.";
    fn declare(ports: &mut petrel::actors::Ports) -> Self {
        ScanSink {
            scans: ports.queue_in("in/scans", "scans"),
            received: ports.output("out/received", 0, "scans read"),
            lost: ports.output("out/lost", 0, "scans missing"),
            next: None,
        }
    }
    fn schedule(&self) -> petrel::actors::Schedule {
        petrel::actors::Schedule::new().on_items(&self.scans)
    }
    async fn step(&mut self, _ctx: &mut petrel::actors::Context) -> anyhow::Result<()> {
        let items = self.scans.drain();
        for item in &items {
            if let Some(next) = self.next {
                self.lost.set(self.lost.value() + (item.seq - next) as i64);
            }
            self.next = Some(item.seq + 1);
        }
        self.received
            .set(self.received.value() + items.len() as i64);
        Ok(())
    }
}
