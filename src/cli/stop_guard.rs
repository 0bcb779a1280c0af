//! The stop watchdog of `petrel run`.
//!
//! A module whose step loops on the CPU or blocks in a read holds its worker thread; with
//! `--workers 1` (or as many such modules as workers) nothing async runs any more: no timer, no
//! signal handler, no stop. So Ctrl-C, SIGTERM and `--for` are watched on a thread of their own
//! (with its own small runtime), which asks the agents to stop and, if their modules have not
//! stopped within the stop timeout (plus [`SLACK`]), names the modules still inside a step and
//! ends the process. A second Ctrl-C ends it at once.

use std::time::Duration;

use petrel_actors::{StepProbe, StepSample};
use tokio::sync::{mpsc, watch};
use tokio::time::Instant;

use super::EXIT_FAILED;

/// Time beyond the stop timeout for the last module's kill, the summary and the exit.
pub(crate) const SLACK: Duration = Duration::from_millis(500);

/// Exit code after a second Ctrl-C, as shells report a process ended by SIGINT.
const EXIT_INTERRUPTED: i32 = 130;

/// Why the watchdog asks the run to end.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct StopRequest {
    /// For people, as "stopping: {reason}".
    pub reason: String,
    /// Process exit code if nothing else goes wrong.
    pub code: u8,
}

enum Event {
    Watch(String, StepProbe),
    RunFor(Duration),
    Stopping,
    ModulesStopped,
}

/// The run's side of the watchdog.
pub(crate) struct StopGuard {
    events: mpsc::UnboundedSender<Event>,
    requests: watch::Receiver<Option<StopRequest>>,
}

impl StopGuard {
    /// Starts the watchdog thread; `limit` is the longest time a module may take to stop.
    pub fn start(limit: Duration) -> std::io::Result<Self> {
        let (events, event_rx) = mpsc::unbounded_channel();
        let (request_tx, requests) = watch::channel(None);
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()?;
        // The handlers are installed here, before this returns and any agent starts: installed
        // on the thread, a Ctrl-C sent as soon as the log says "agent started" could come first
        // and end the process the default way (seen under load).
        let signals = {
            use tokio::signal::unix::{signal, SignalKind};
            let _runtime = runtime.enter();
            signal(SignalKind::interrupt()).and_then(|i| Ok((i, signal(SignalKind::terminate())?)))
        };
        std::thread::Builder::new()
            .name("petrel-stop-guard".into())
            .spawn(move || runtime.block_on(watch_over(event_rx, request_tx, limit, signals)))?;
        Ok(StopGuard { events, requests })
    }

    /// Watches the steps of `agent`'s modules, to name those a stop waits for.
    pub fn watch(&self, agent: &str, probe: StepProbe) {
        let _ = self.events.send(Event::Watch(agent.to_string(), probe));
    }

    /// Asks for a stop once `duration` has passed (`--for`).
    pub fn run_for(&self, duration: Duration) {
        let _ = self.events.send(Event::RunFor(duration));
    }

    /// Waits for a stop request: a signal or the end of `--for`.
    pub async fn requested(&self) -> StopRequest {
        let mut requests = self.requests.clone();
        let request = requests
            .wait_for(Option::is_some)
            .await
            .ok()
            .and_then(|request| request.clone());
        match request {
            Some(request) => request,
            // The watchdog thread is gone: the process is ending anyway.
            None => std::future::pending().await,
        }
    }

    /// The modules are being stopped: from now on they have the stop timeout.
    pub fn stopping(&self) {
        let _ = self.events.send(Event::Stopping);
    }

    /// Every module has stopped or was killed: what follows (recordings, snapshots, teams) may
    /// take the time it needs.
    pub fn modules_stopped(&self) {
        let _ = self.events.send(Event::ModulesStopped);
    }
}

/// A stop under way: when it began, and what every module was doing when the stop timeout
/// ran out (taken then, so a step that began after the stop request still counts).
struct Stopping {
    since: Instant,
    at_timeout: Option<Vec<StepSample>>,
}

/// The watchdog thread's loop; ends when the modules have stopped or the run's side is gone.
async fn watch_over(
    mut events: mpsc::UnboundedReceiver<Event>,
    requests: watch::Sender<Option<StopRequest>>,
    timeout: Duration,
    signals: std::io::Result<(tokio::signal::unix::Signal, tokio::signal::unix::Signal)>,
) {
    let Ok((mut interrupts, mut terminations)) = signals else {
        tracing::error!(
            "cannot listen for Ctrl-C and SIGTERM: only --for and the agents end this run"
        );
        return;
    };
    let mut probes: Vec<(String, StepProbe)> = Vec::new();
    // `--for`: when, and the duration asked for.
    let mut run_until: Option<(Instant, Duration)> = None;
    let mut stop: Option<Stopping> = None;
    let begin = |stop: &mut Option<Stopping>| {
        stop.get_or_insert_with(|| Stopping {
            since: Instant::now(),
            at_timeout: None,
        });
    };
    let ask = |stop: &mut Option<Stopping>, reason: String| {
        requests.send_replace(Some(StopRequest { reason, code: 0 }));
        begin(stop);
    };
    loop {
        let deadline = match &stop {
            Some(Stopping {
                since,
                at_timeout: None,
            }) => Some(*since + timeout),
            Some(Stopping {
                since,
                at_timeout: Some(_),
            }) => Some(*since + timeout + SLACK),
            None => run_until.map(|(at, _)| at),
        };
        tokio::select! {
            event = events.recv() => match event {
                Some(Event::Watch(agent, probe)) => probes.push((agent, probe)),
                Some(Event::RunFor(d)) => run_until = Some((Instant::now() + d, d)),
                Some(Event::Stopping) => begin(&mut stop),
                Some(Event::ModulesStopped) | None => return,
            },
            _ = interrupts.recv() => match stop {
                Some(_) => {
                    eprintln!("interrupted again: exiting without waiting for the modules");
                    std::process::exit(EXIT_INTERRUPTED);
                }
                None => {
                    tracing::info!("stopping (Ctrl-C again to exit at once)");
                    ask(&mut stop, "interrupted".into());
                }
            },
            _ = terminations.recv() => ask(&mut stop, "terminated (SIGTERM)".into()),
            _ = sleep_until(deadline) => match &mut stop {
                Some(Stopping { at_timeout: at_timeout @ None, .. }) => {
                    *at_timeout = Some(sample(&probes));
                }
                Some(Stopping { at_timeout: Some(before), .. }) => {
                    let stuck = stuck_modules(&probes, before);
                    eprintln!("error: {}", forced_exit_message(timeout + SLACK, &stuck));
                    std::process::exit(EXIT_FAILED.into());
                }
                None => {
                    let ran = run_until.take().map(|(_, d)| d).unwrap_or_default();
                    ask(&mut stop, format!("ran for {}", humantime::format_duration(ran)));
                }
            },
        }
    }
}

async fn sleep_until(deadline: Option<Instant>) {
    match deadline {
        Some(at) => tokio::time::sleep_until(at).await,
        None => std::future::pending().await,
    }
}

fn sample(probes: &[(String, StepProbe)]) -> Vec<StepSample> {
    probes.iter().map(|(_, probe)| probe.sample()).collect()
}

/// `agent/module` for every module still inside the step it was in when the stop timeout ran out.
fn stuck_modules(probes: &[(String, StepProbe)], before: &[StepSample]) -> Vec<String> {
    probes
        .iter()
        .zip(before)
        .flat_map(|((agent, probe), before)| {
            probe
                .stuck_since(before)
                .into_iter()
                .map(move |module| format!("{agent}/{module}"))
        })
        .collect()
}

/// What the watchdog says when it ends the process.
fn forced_exit_message(limit: Duration, stuck: &[String]) -> String {
    let waited = humantime::format_duration(limit);
    match stuck {
        [] => format!(
            "the modules did not stop within {waited}, though none is inside a step; ending the process"
        ),
        _ => format!(
            "the modules did not stop within {waited}: ending the process, which kills {} (inside a step since the stop timeout ran out: a loop that never yields or a blocking call)",
            stuck.join(", ")
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_forced_exit_names_the_modules_that_hold_their_threads() {
        let message = forced_exit_message(
            Duration::from_millis(1500),
            &["r/spinner".into(), "r/reader".into()],
        );
        assert!(message.contains("within 1s 500ms"), "{message}");
        assert!(message.contains("kills r/spinner, r/reader"), "{message}");
        let none = forced_exit_message(Duration::from_secs(2), &[]);
        assert!(none.contains("none is inside a step"), "{none}");
    }
}
