//! petrel's web console: a page an operator watches and tunes running agents with, and the
//! JSON/WebSocket API it uses (which tests and scripts call directly).
//!
//! Functional core, imperative shell: [`core`] decides what is shown (JSON shapes, map
//! sources, plan firings), how often values are pushed, and who may do what; `shell` is a
//! thin axum server over agents' blackboards, or over remote agents reached through a team
//! ([`source`]: `petrel console` attaching to running agents). The page's HTML, JavaScript and CSS are
//! plain files embedded in the binary: nothing to build at install time.
//!
//! ```no_run
//! # async fn demo(agent: &petrel_actors::Agent) -> Result<(), petrel_console::ConsoleError> {
//! use petrel_console::{AgentSource, Console, ConsoleOptions, LogTail};
//! let console = Console::start(
//!     ConsoleOptions { addr: "127.0.0.1:0".parse().unwrap(), token: None },
//!     vec![AgentSource::new(agent.name(), agent.blackboard().clone())],
//!     LogTail::default(),
//! )
//! .await?;
//! println!("console at {}", console.url());
//! console.stop().await;
//! # Ok(()) }
//! ```

pub mod core;
pub mod live;
mod logs;
mod shell;
pub mod source;

use std::net::SocketAddr;

pub use crate::core::access::BindError;
pub use crate::core::plan::{PlaceView, PlanGraph, TransitionView};
pub use logs::{LogLine, LogTail, LOG_LINES};
pub use shell::{Console, FoxgloveServer};
pub use source::{AgentSource, Backend, RemoteAgent, RemoteEvent, RemoteSample, RemoteWatch};

/// Where the console listens, and its token.
#[derive(Debug, Clone)]
pub struct ConsoleOptions {
    /// The address to bind (port 0: any free port, see [`Console::local_addr`]).
    pub addr: SocketAddr,
    /// The token every request must carry; required beyond loopback, where one is generated
    /// when none is given.
    pub token: Option<String>,
}

/// Why the console did not start.
#[derive(Debug, thiserror::Error)]
pub enum ConsoleError {
    /// The address and token do not go together.
    #[error("--console {addr}: {source}")]
    Bind {
        /// The address asked for.
        addr: SocketAddr,
        /// What is wrong.
        source: BindError,
    },
    /// The address could not be bound.
    #[error("--console {addr}: cannot listen there: {source}")]
    Listen {
        /// The address asked for.
        addr: SocketAddr,
        /// The operating system's answer.
        source: std::io::Error,
    },
    /// No randomness for a token.
    #[error("cannot generate a console token: {0}")]
    Token(String),
}
