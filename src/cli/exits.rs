//! How the agents of a `petrel run` end it: the first one that asks ends the run, except an
//! agent that dies ([`EXIT_DIED`](petrel_actors::EXIT_DIED)), which leaves alone, as its
//! process would under `kill -9`.

use std::future::Future;
use std::pin::Pin;
use std::task::Poll;

use petrel_actors::{outln, Agent, AgentExit};
use petrel_team::Team;

use super::RunArgs;

/// An agent's wait for the end of its run.
type ExitWait<'a> = Pin<Box<dyn Future<Output = AgentExit> + Send + 'a>>;

/// The first agent still alive that asks for the run to end, and which it is.
pub(super) async fn first_exit(agents: &[Agent], dead: &[bool]) -> (usize, AgentExit) {
    let mut waits: Vec<(usize, ExitWait<'_>)> = agents
        .iter()
        .enumerate()
        .filter(|(i, _)| !dead[*i])
        .map(|(i, a)| (i, Box::pin(a.finished()) as _))
        .collect();
    std::future::poll_fn(|cx| {
        for (i, wait) in waits.iter_mut() {
            if let Poll::Ready(exit) = wait.as_mut().poll(cx) {
                return Poll::Ready((*i, exit));
            }
        }
        Poll::Pending
    })
    .await
}

/// An agent of the run dies (a module asked with [`EXIT_DIED`](petrel_actors::EXIT_DIED)), as
/// its process would under `kill -9`: its team membership is dropped without a goodbye (the
/// others see its token go, as when a process dies), its modules are stopped, and the run goes
/// on without it. (The last agent of a process ends the process instead: see `run.rs`.)
pub(super) async fn die(agent: &Agent, reason: &str, teams: &mut Vec<Team>, args: &RunArgs) {
    tracing::warn!(agent = agent.name(), "agent dies: {reason}");
    outln!("agent `{}` died: {reason}", agent.name());
    if let Some(i) = teams.iter().position(|t| t.agent() == agent.name()) {
        drop(teams.remove(i));
    }
    agent.stop_modules(args.stop_timeout).await;
}
