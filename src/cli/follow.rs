//! `petrel echo` and `petrel hz`: follow a property of a running agent as it changes.

use std::collections::VecDeque;
use std::process::ExitCode;
use std::time::Duration;

use petrel_team::{Client, TeamError, Update, Watch, WatchEvent};

use super::interrupt::Interrupt;
use super::rate::rate;
use super::remote::{attached, target, Reach};
use super::stdout::{self, sayln};

/// Stamps `hz` keeps by default: its figures are over the last this many changes.
pub(crate) const DEFAULT_WINDOW: u64 = 100;

/// Prints each value or queue item of `url` as it comes, `count` of them or until Ctrl-C.
pub(crate) fn echo(reach: &Reach, url: &str, count: Option<u64>, json: bool) -> ExitCode {
    let (url, team) = match target(reach, url) {
        Ok(t) => t,
        Err(code) => return code,
    };
    let recorded = reach.via.is_none();
    attached(&team, |client| async move {
        let mut interrupt = Interrupt::new();
        let mut watch = client.watch(&url).await?;
        let agent = url.agent().unwrap_or_default();
        let mut printed = 0;
        while count.is_none_or(|n| printed < n) {
            let update = tokio::select! {
                update = next_update(&mut watch) => update?,
                left = gone(&client, agent, recorded) => return Err(left),
                _ = interrupt.recv() => break,
            };
            sayln!("{}", line(&update, json));
            if stdout::failed() {
                break;
            }
            printed += 1;
        }
        if watch.dropped() > 0 {
            eprintln!(
                "{} updates dropped: they came faster than this terminal took them",
                watch.dropped()
            );
        }
        Ok(())
    })
}

/// Reports how often `url` changes: after `count` changes, or once a second until Ctrl-C,
/// over the last `window` changes.
pub(crate) fn hz(reach: &Reach, url: &str, window: u64, count: Option<u64>) -> ExitCode {
    let (url, team) = match target(reach, url) {
        Ok(t) => t,
        Err(code) => return code,
    };
    let recorded = reach.via.is_none();
    attached(&team, |client| async move {
        let mut interrupt = Interrupt::new();
        let mut watch = client.watch(&url).await?;
        let agent = url.agent().unwrap_or_default();
        // The first update is the current value, written whenever: not a change to time.
        tokio::select! {
            update = next_update(&mut watch) => update.map(drop)?,
            left = gone(&client, agent, recorded) => return Err(left),
        }
        let window = usize::try_from(window).unwrap_or(usize::MAX);
        let mut stamps = VecDeque::with_capacity(window);
        let mut report = tokio::time::interval(Duration::from_secs(1));
        report.tick().await;
        let mut seen = 0;
        // Kept across the reports (each second too, like the quiet it waits for): made again
        // only when a value comes.
        let mut quiet = std::pin::pin!(gone(&client, agent, recorded));
        loop {
            tokio::select! {
                update = next_update(&mut watch) => {
                    let update = update?;
                    quiet.set(gone(&client, agent, recorded));
                    if stamps.len() == window {
                        stamps.pop_front();
                    }
                    stamps.push_back(update.stamp_ns);
                    seen += 1;
                    if count == Some(seen) {
                        break;
                    }
                }
                _ = report.tick(), if count.is_none() => {
                    print_rate(stamps.make_contiguous());
                    if stdout::failed() {
                        break;
                    }
                }
                left = &mut quiet => {
                    print_rate(stamps.make_contiguous());
                    return Err(left);
                }
                _ = interrupt.recv() => break,
            }
        }
        print_rate(stamps.make_contiguous());
        Ok(())
    })
}

fn print_rate(stamps: &[u64]) {
    match rate(stamps) {
        Some(r) => sayln!("{r}"),
        None => sayln!("no change yet"),
    }
}

/// How long a follower waits without a value before it asks whether the agent still answers.
const QUIET: Duration = Duration::from_secs(1);

/// Resolves with an error once `agent` has gone quiet for [`QUIET`] and then does not answer
/// (its run ended, it was killed, or its thread is held). A follower would otherwise wait
/// without end, saying nothing, for an agent that may never come back. Made again at each
/// value, so an agent that keeps writing is never asked. `recorded`: the agent was found in
/// the records of the runs on this machine, which then tell whether its run ended.
async fn gone(client: &Client, agent: &str, recorded: bool) -> TeamError {
    loop {
        tokio::time::sleep(QUIET).await;
        if let Err(e) = client.info(agent).await {
            return super::remote::left_or(e, agent, recorded);
        }
    }
}

/// The next value or item of `watch`.
async fn next_update(watch: &mut Watch) -> Result<Update, TeamError> {
    loop {
        match watch.next().await {
            Some(WatchEvent::Update(u)) => return Ok(u),
            Some(WatchEvent::Opened) => continue,
            Some(WatchEvent::Refused(why)) => return Err(TeamError::Refused(why)),
            None => return Err(TeamError::Transport("the session closed".into())),
        }
    }
}

/// One printed update: the JSON value, or with `json` an object with its sequence number,
/// write stamp and type.
fn line(update: &Update, json: bool) -> String {
    let value = String::from_utf8_lossy(&update.json);
    match json {
        false => value.into_owned(),
        true => format!(
            r#"{{"seq":{},"stamp_ns":{},"type":{},"value":{value}}}"#,
            update.seq,
            update.stamp_ns,
            serde_json::Value::from(update.type_name.as_str())
        ),
    }
}

/// Whether the queue `key` is an event stream `petrel events` follows: supervisor and team
/// events, context changes (`out/changes`), plan firings (`out/firings`).
pub(crate) fn is_event_queue(key: &str) -> bool {
    matches!(key, "_supervisor/events" | "_team/events")
        || key.ends_with("/out/changes")
        || key.ends_with("/out/firings")
}

/// Prints the events of `agent` (or of every agent running here) as they happen: `count` of
/// them, or until Ctrl-C.
pub(crate) fn events(reach: &Reach, agent: Option<&str>, count: Option<u64>) -> ExitCode {
    let targets = match super::top::targets(reach, agent) {
        Ok(t) => t,
        Err(code) => return code,
    };
    if targets.is_empty() {
        // Following nothing would end at once and look like a quiet run.
        eprintln!("error: no `petrel run` is running on this machine for this user");
        return ExitCode::from(super::EXIT_FAILED);
    }
    let recorded = reach.via.is_none();
    super::top::with_clients(&targets, |clients| async move {
        let mut interrupt = Interrupt::new();
        let (tx, mut rx) = tokio::sync::mpsc::channel(1024);
        let (opened_tx, mut opened) = tokio::sync::mpsc::channel(64);
        let (mut watches, mut departures) = (Vec::new(), Vec::new());
        let (left_tx, mut left_rx) = tokio::sync::mpsc::channel(64);
        let mut following = 0;
        for (k, followed) in clients.iter().enumerate() {
            let (agent, client) = (&followed.agent, &followed.client);
            // One agent that ended or stopped answering meanwhile (killed as the tool
            // started) leaves the others followed.
            let info = match client.info(agent).await {
                Ok(info) => info,
                Err(e) if clients.len() > 1 => {
                    let e = super::remote::left_or(e, agent, recorded);
                    eprintln!("not following `{}`: {e}", followed.label);
                    continue;
                }
                Err(e) => return Err(e),
            };
            following += 1;
            let (clients, left_tx) = (clients.clone(), left_tx.clone());
            departures.push(tokio::spawn(async move {
                let followed = &clients[k];
                let left = gone(&followed.client, &followed.agent, recorded).await;
                let _ = left_tx.send(left).await;
            }));
            for p in &info.properties {
                if p.kind != "queue output" || !is_event_queue(&p.key) {
                    continue;
                }
                let url = petrel_actors::PropertyUrl::parse(&format!("petrel://{agent}/{}", p.key))
                    .map_err(|e| TeamError::Refused(e.to_string()))?;
                let mut watch = client.watch(&url).await?;
                let (tx, opened, source) = (
                    tx.clone(),
                    opened_tx.clone(),
                    format!("{}/{}", followed.label, p.key),
                );
                watches.push(tokio::spawn(async move {
                    while let Some(event) = watch.next().await {
                        let update = match event {
                            WatchEvent::Update(u) => u,
                            WatchEvent::Opened => {
                                // Later opens (another reader came) need no one to hear them.
                                let _ = opened.try_send(source.clone());
                                continue;
                            }
                            WatchEvent::Refused(_) => return,
                        };
                        if tx.send((source.clone(), update)).await.is_err() {
                            return;
                        }
                    }
                }));
            }
        }
        if following == 0 {
            return Err(TeamError::Refused(
                "no agent answered: nothing to follow".to_string(),
            ));
        }
        // Say when every stream is open, so a person (or a test) knows nothing is missed from
        // then on.
        drop(opened_tx);
        let streams = watches.len();
        let mut open = std::collections::BTreeSet::new();
        while open.len() < streams {
            match opened.recv().await {
                Some(source) => open.insert(source),
                None => break,
            };
        }
        let names: Vec<&str> = open.iter().map(String::as_str).collect();
        let plural = if streams == 1 { "" } else { "s" };
        eprintln!(
            "following {streams} event stream{plural}: {}",
            names.join(", ")
        );
        drop(tx);
        let mut printed = 0;
        let mut result = Ok(());
        while count.is_none_or(|n| printed < n) {
            tokio::select! {
                event = rx.recv() => match event {
                    Some((source, u)) => {
                        sayln!("{source}  {}", String::from_utf8_lossy(&u.json));
                        if stdout::failed() {
                            break;
                        }
                    }
                    None => break,
                },
                Some(left) = left_rx.recv() => {
                    following -= 1;
                    if following == 0 {
                        result = Err(left);
                        break;
                    }
                    eprintln!("{left}");
                    continue;
                }
                _ = interrupt.recv() => break,
            }
            printed += 1;
        }
        for w in watches.into_iter().chain(departures) {
            w.abort();
        }
        result
    })
}
