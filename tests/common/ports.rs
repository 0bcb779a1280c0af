//! Ports for agents to listen on, shared by the team tests and the team benches.

/// A free TCP port on 127.0.0.1 for an agent of a test or bench to listen on.
///
/// Not port 0's answer: the kernel hands out the same ephemeral range for outgoing
/// connections, so a port found free that way can become some zenoh session's local end
/// before the agent it was meant for binds it (a flaky "agent should join"). Ports come from
/// below the ephemeral range instead, each at most once per test process, checked free when
/// handed out; the start is spread by the process id so binaries run one after another do
/// not retrace each other's steps.
pub fn free_port() -> u16 {
    use std::sync::atomic::{AtomicU32, Ordering};
    const SPAN: u32 = 12_000;
    static NEXT: AtomicU32 = AtomicU32::new(0);
    let low = ephemeral_low().saturating_sub(SPAN).max(1024);
    let spread = std::process::id() % SPAN;
    for _ in 0..SPAN {
        let port = low + (spread + NEXT.fetch_add(1, Ordering::Relaxed)) % SPAN;
        let port = u16::try_from(port).expect("below the ephemeral range");
        if std::net::TcpListener::bind(("127.0.0.1", port)).is_ok() {
            return port;
        }
    }
    panic!("no free port below the ephemeral range");
}

/// The first port of the kernel's ephemeral range (Linux's default when it cannot be read).
fn ephemeral_low() -> u32 {
    std::fs::read_to_string("/proc/sys/net/ipv4/ip_local_port_range")
        .ok()
        .and_then(|r| r.split_whitespace().next()?.parse().ok())
        .unwrap_or(32_768)
}
