//! SIGHUP during `petrel run`: every context manager of every agent re-reads its rules.

use petrel_actors::Agent;

/// SIGHUPs received (on Unix; elsewhere, none ever arrive).
pub(super) struct Hangups {
    #[cfg(unix)]
    signals: Option<tokio::signal::unix::Signal>,
}

impl Hangups {
    pub(super) fn listen() -> Self {
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

/// On every SIGHUP, asks each `context.manager` of every agent to re-read its rules.
pub(super) async fn reload_on_hangup(hangups: Hangups, agents: &[Agent]) {
    #[cfg(unix)]
    {
        if let Some(mut hangups) = hangups.signals {
            while hangups.recv().await.is_some() {
                for agent in agents {
                    reload_contexts(agent).await;
                }
            }
        }
    }
    #[cfg(not(unix))]
    let _ = (hangups, agents);
    std::future::pending::<()>().await
}

/// Bumps `params/reload` of each of `agent`'s context managers.
async fn reload_contexts(agent: &Agent) {
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
                tracing::info!(agent = agent.name(), module = %m.name, "SIGHUP: reloading context rules")
            }
            Err(e) => {
                tracing::error!(agent = agent.name(), module = %m.name, error = %e, "SIGHUP: cannot ask for a reload")
            }
        }
    }
}
