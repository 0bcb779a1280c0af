//! What the console and the Foxglove live view share: binding an address under the access
//! rules for it, serving a router until told to stop, and stopping within a grace period.

use std::net::SocketAddr;
use std::time::Duration;

use axum::Router;
use tokio::net::TcpListener;
use tokio::sync::oneshot;
use tokio::task::JoinHandle;

use crate::core::access::Access;
use crate::{ConsoleError, ConsoleOptions};

/// How long a stopping server waits for requests under way.
const STOP_GRACE: Duration = Duration::from_secs(1);

/// A bound address and its access rules, not serving yet.
pub(crate) struct Binding {
    listener: TcpListener,
    /// The address bound (the port the system chose for port 0).
    pub addr: SocketAddr,
    pub access: Access,
}

impl Binding {
    /// The access rules for `options.addr` (a token generated when one is needed), then the
    /// address bound.
    pub async fn bind(options: &ConsoleOptions) -> Result<Binding, ConsoleError> {
        let addr = options.addr;
        let mut token_error = None;
        let access = Access::for_bind(addr, options.token.as_deref(), || {
            super::generate_token().unwrap_or_else(|e| {
                token_error = Some(e);
                String::new()
            })
        })
        .map_err(|source| ConsoleError::Bind { addr, source })?;
        if let Some(e) = token_error {
            return Err(ConsoleError::Token(e));
        }
        let listener = TcpListener::bind(addr)
            .await
            .map_err(|source| ConsoleError::Listen { addr, source })?;
        let addr = listener
            .local_addr()
            .map_err(|source| ConsoleError::Listen { addr, source })?;
        Ok(Binding {
            listener,
            addr,
            access,
        })
    }

    /// Serves `app` until [`Server::stop`]; `what` names the server in its logs.
    pub fn serve(self, app: Router, what: &'static str) -> Server {
        let (shutdown, stopped) = oneshot::channel::<()>();
        let task = tokio::spawn(async move {
            let serving = axum::serve(self.listener, app).with_graceful_shutdown(async move {
                let _ = stopped.await;
            });
            if let Err(e) = serving.await {
                tracing::error!(error = %e, "the {what} stopped serving");
            }
        });
        tracing::info!(address = %self.addr, "{what} listening");
        Server {
            shutdown: Some(shutdown),
            task,
        }
    }
}

/// A server task and the signal that ends it.
pub(crate) struct Server {
    shutdown: Option<oneshot::Sender<()>>,
    task: JoinHandle<()>,
}

impl Server {
    /// Asks the server to stop and waits at most [`STOP_GRACE`] for answers under way.
    pub async fn stop(&mut self) {
        if let Some(s) = self.shutdown.take() {
            let _ = s.send(());
        }
        if tokio::time::timeout(STOP_GRACE, &mut self.task)
            .await
            .is_err()
        {
            self.task.abort();
            let _ = (&mut self.task).await;
        }
    }
}
