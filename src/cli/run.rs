//! `petrel run`: start an agent, wait for Ctrl-C or `--for`, stop cleanly, summarise.

use std::process::ExitCode;

use petrel_actors::{status, Agent, ModuleRegistry, StartError};

use super::check::check_all;
use super::{bad_input, load, logging, RunArgs};

pub(crate) fn run(registry: &ModuleRegistry, args: RunArgs) -> ExitCode {
    logging::init(args.log_format);
    let file = match load(&args.config, &args.overlay) {
        Ok(file) => file,
        Err(errors) => return bad_input(&errors),
    };
    if let Err(errors) = check_all(&file, registry) {
        return bad_input(&errors);
    }
    let mut builder = tokio::runtime::Builder::new_multi_thread();
    if let Some(workers) = args.workers {
        builder.worker_threads(workers.into());
    }
    let runtime = match builder.enable_all().build() {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("error: cannot start the async runtime: {e}");
            return ExitCode::FAILURE;
        }
    };
    runtime.block_on(async move {
        // Listen before the agent starts, so a SIGHUP sent as soon as the rules are loaded is
        // a reload, not the default "terminate".
        let hangups = Hangups::listen();
        let agent = match Agent::start(&file, registry).await {
            Ok(agent) => agent,
            Err(StartError::Config(errors)) => return bad_input(&errors),
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::FAILURE;
            }
        };
        let forever = std::future::pending::<()>();
        let (why, mut code) = tokio::select! {
            exit = agent.finished() => (exit.reason, ExitCode::from(exit.code)),
            _ = tokio::signal::ctrl_c() => ("interrupted".to_string(), ExitCode::SUCCESS),
            _ = reload_on_hangup(hangups, &agent) => unreachable!("reloading never ends"),
            _ = async {
                match args.duration {
                    Some(d) => tokio::time::sleep(d).await,
                    None => forever.await,
                }
            } => (format!("ran for {}", humantime::format_duration(args.duration.unwrap_or_default())), ExitCode::SUCCESS),
        };
        tracing::info!(agent = agent.name(), "stopping: {why}");
        let summary = agent.stop_modules(args.stop_timeout).await;
        if let Some(path) = &args.snapshot_out {
            match agent
                .snapshot()
                .await
                .map_err(|e| e.to_string())
                .and_then(|s| std::fs::write(path, s).map_err(|e| e.to_string()))
            {
                Ok(()) => println!("snapshot written to {}", path.display()),
                Err(e) => {
                    eprintln!(
                        "error: could not write the snapshot to {}: {e}",
                        path.display()
                    );
                    code = ExitCode::FAILURE;
                }
            }
        }
        agent.shutdown().await;
        println!("\n{why}\n{summary}");
        if summary.modules.iter().any(|m| m.status == status::FAILED) {
            eprintln!("some modules failed: see the summary above and the log");
            code = ExitCode::FAILURE;
        }
        code
    })
}

/// SIGHUPs received (on Unix; elsewhere, none ever arrive).
struct Hangups {
    #[cfg(unix)]
    signals: Option<tokio::signal::unix::Signal>,
}

impl Hangups {
    fn listen() -> Self {
        #[cfg(unix)]
        {
            use tokio::signal::unix::{signal, SignalKind};
            let signals = signal(SignalKind::hangup())
                .inspect_err(|e| tracing::warn!(error = %e, "cannot listen for SIGHUP; reload context rules through params/reload"))
                .ok();
            Hangups { signals }
        }
        #[cfg(not(unix))]
        Hangups {}
    }
}

/// On every SIGHUP, asks each `context.manager` to re-read its rules (its `params/reload`).
async fn reload_on_hangup(hangups: Hangups, agent: &Agent) {
    #[cfg(unix)]
    {
        if let Some(mut hangups) = hangups.signals {
            while hangups.recv().await.is_some() {
                let summary = agent.summary().await;
                for m in summary
                    .modules
                    .iter()
                    .filter(|m| m.module_type == "context.manager")
                {
                    let key = format!("{}/params/reload", m.name);
                    let next = agent
                        .blackboard()
                        .get::<i64>(&key)
                        .await
                        .map_or(1, |n| *n + 1);
                    match agent.blackboard().set(&key, next).await {
                        Ok(()) => {
                            tracing::info!(module = %m.name, "SIGHUP: reloading context rules")
                        }
                        Err(e) => {
                            tracing::error!(module = %m.name, error = %e, "SIGHUP: cannot ask for a reload")
                        }
                    }
                }
            }
        }
    }
    #[cfg(not(unix))]
    let _ = (hangups, agent);
    std::future::pending::<()>().await
}
