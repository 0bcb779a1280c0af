//! A network partition made by a TCP proxy the test controls: both sides notice within the
//! lease, nothing blocks, items sent into the cut are counted as lost, and the team heals.

use std::sync::Arc;

use petrel::actors::team::{LinkStatus, TeamMembers};
use tokio::io::copy_bidirectional;
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::watch;

use crate::support::*;

/// Forwards connections from a free port to `target`. Cutting silences every connection
/// (open, but nothing passes) and refuses new ones; healing closes the silenced ones and
/// forwards again.
struct Proxy {
    port: u16,
    cut: watch::Sender<bool>,
}

impl Proxy {
    async fn start(target: u16) -> Proxy {
        let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let port = listener.local_addr().unwrap().port();
        let (cut, _) = watch::channel(false);
        let cut_rx = cut.subscribe();
        tokio::spawn(async move {
            loop {
                let Ok((mut inbound, _)) = listener.accept().await else {
                    return;
                };
                let mut cut = cut_rx.clone();
                if *cut.borrow() {
                    continue; // dropped: refused while partitioned
                }
                tokio::spawn(async move {
                    let Ok(mut outbound) = TcpStream::connect(("127.0.0.1", target)).await else {
                        return;
                    };
                    tokio::select! {
                        _ = copy_bidirectional(&mut inbound, &mut outbound) => return,
                        _ = cut.wait_for(|c| *c) => {}
                    }
                    // Cut: the sockets stay open but nothing passes (no FIN, no RST), like a
                    // pulled cable; both sides can only notice through the lease. They are
                    // closed when the cable is back.
                    let _ = cut.wait_for(|c| !*c).await;
                    drop((inbound, outbound));
                });
            }
        });
        Proxy { port, cut }
    }

    fn set_cut(&self, cut: bool) {
        self.cut.send_replace(cut);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_partition_is_seen_by_both_sides_counted_and_healed() {
    let team = team_name("partition");
    let (pa, pb) = (free_port(), free_port());
    let a = start(&agent_config("a", &team, pa, &[], "", r#"
        (name: "producer", type: "demo.producer", values: {"params/period_ms": 5, "params/batch": 2}),"#)).await;
    let proxy = Arc::new(Proxy::start(pa).await);
    // b reaches a only through the proxy.
    let b = start(&agent_config(
        "b",
        &team,
        pb,
        &[proxy.port],
        "",
        r#"
        (name: "consumer", type: "demo.consumer",
         links: {"in/items": "petrel://a/producer/out/items"}),"#,
    ))
    .await;
    let status = b
        .handle::<LinkStatus>("consumer/stats/links/in/items")
        .await;
    let received = b.handle::<i64>("consumer/out/received").await;
    wait_for(&status, "a live link", |s| s.state == "live").await;
    wait_for(&received, "items through the proxy", |n| *n > 50).await;
    let (a_members, b_members) = (
        a.handle::<TeamMembers>("_team/members").await,
        b.handle::<TeamMembers>("_team/members").await,
    );

    let cut = tokio::time::Instant::now();
    proxy.set_cut(true);
    wait_for(&b_members, "b alone", |l| names(l) == ["b"]).await;
    wait_for(&a_members, "a alone", |l| names(l) == ["a"]).await;
    eprintln!(
        "partition to `left` seen on both sides: {:?} (lease 1 s)",
        cut.elapsed()
    );
    wait_for(&status, "a stale link", |s| s.state == "stale").await;
    // Nothing blocks on the unreachable peer: the producer keeps producing.
    let next = a.handle::<i64>("producer/state/next").await;
    let during = next.value();
    wait_for(&next, "the producer going on during the cut", |n| {
        *n > during + 100
    })
    .await;

    proxy.set_cut(false);
    wait_for(&b_members, "the team healed", |l| names(l) == ["a", "b"]).await;
    let s = wait_for(
        &status,
        "the link live and counting what the cut lost",
        |s| s.state == "live" && s.dropped > 0,
    )
    .await;
    let duplicates = b.handle::<i64>("consumer/out/duplicates").await;
    assert_eq!(duplicates.value(), 0, "{s:?}");
    b.stop().await;
    a.stop().await;
}
