//! What the console and the Foxglove live view share: binding an address under the access
//! rules for it, serving a router until told to stop, and stopping within a grace period.

use std::net::SocketAddr;
use std::pin::pin;
use std::time::Duration;

use axum::Router;
use hyper::server::conn::http1;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::service::TowerToHyperService;
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::watch;
use tokio::task::{JoinHandle, JoinSet};

use crate::core::access::Access;
use crate::{ConsoleError, ConsoleOptions};

/// How long a stopping server waits for requests under way.
const STOP_GRACE: Duration = Duration::from_secs(1);

/// How long a client may take to send a request's header (from its first byte, or from the
/// end of the previous request on a kept-alive connection) before its connection is closed.
const HEADER_READ_TIMEOUT: Duration = Duration::from_secs(10);

/// How long the server waits after failing to accept a connection before trying again.
const ACCEPT_RETRY: Duration = Duration::from_millis(100);

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
        let (shutdown, stopped) = watch::channel(());
        let addr = self.addr;
        let task = tokio::spawn(accept(self.listener, app, stopped, what));
        tracing::info!(address = %addr, "{what} listening");
        Server {
            shutdown: Some(shutdown),
            task,
        }
    }
}

/// Accepts connections until told to stop, then lets those open finish their requests.
///
/// This is `axum::serve`'s loop, written out for one setting it does not offer: a header read
/// timeout. Without one, a client that sends half a request header and then nothing holds its
/// connection (and a file descriptor) for as long as it likes.
async fn accept(
    listener: TcpListener,
    app: Router,
    mut stopped: watch::Receiver<()>,
    what: &'static str,
) {
    let mut connections = JoinSet::new();
    loop {
        tokio::select! {
            _ = stopped.changed() => break,
            Some(_) = connections.join_next(), if !connections.is_empty() => {}
            accepted = listener.accept() => match accepted {
                Ok((stream, _)) => {
                    connections.spawn(connection(stream, app.clone(), stopped.clone()));
                }
                // Out of file descriptors, say: the listener stays; waiting lets connections
                // close rather than spinning on the same error.
                Err(e) => {
                    tracing::warn!(error = %e, "the {what} could not accept a connection");
                    tokio::time::sleep(ACCEPT_RETRY).await;
                }
            },
        }
    }
    drop(listener);
    while connections.join_next().await.is_some() {}
}

/// Serves one connection (HTTP/1, upgrades to WebSocket allowed) until it closes, or until a
/// stop, after which it answers the request under way and closes.
async fn connection(stream: TcpStream, app: Router, mut stopped: watch::Receiver<()>) {
    let mut http = http1::Builder::new();
    http.timer(TokioTimer::new())
        .header_read_timeout(HEADER_READ_TIMEOUT);
    let served = http
        .serve_connection(TokioIo::new(stream), TowerToHyperService::new(app))
        .with_upgrades();
    let mut served = pin!(served);
    tokio::select! {
        result = served.as_mut() => {
            if let Err(e) = result {
                tracing::debug!(error = %e, "a connection ended with an error");
            }
            return;
        }
        _ = stopped.changed() => served.as_mut().graceful_shutdown(),
    }
    let _ = served.await;
}

/// A server task and the signal that ends it.
pub(crate) struct Server {
    shutdown: Option<watch::Sender<()>>,
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

#[cfg(test)]
mod tests {
    use super::*;
    use axum::routing::get;
    use tokio::io::{AsyncReadExt, AsyncWriteExt};

    async fn serving() -> (Server, SocketAddr) {
        let options = ConsoleOptions {
            addr: "127.0.0.1:0".parse().unwrap(),
            token: None,
        };
        let binding = Binding::bind(&options).await.unwrap();
        let addr = binding.addr;
        let app = Router::new().route("/", get(|| async { "here" }));
        (binding.serve(app, "test server"), addr)
    }

    /// Reads until the peer closes, or `within` passes (`None`).
    async fn closed_within(stream: &mut TcpStream, within: Duration) -> Option<Vec<u8>> {
        let mut got = Vec::new();
        tokio::time::timeout(within, stream.read_to_end(&mut got))
            .await
            .ok()
            .map(|read| {
                read.unwrap();
                got
            })
    }

    // The paused clock jumps to the next timer whenever the runtime is idle, so the timeout
    // passes at once, while loopback bytes are still read as they come.
    #[tokio::test(start_paused = true)]
    async fn a_half_sent_header_is_cut_off_and_a_whole_request_answered() {
        let (mut server, addr) = serving().await;
        let mut slow = TcpStream::connect(addr).await.unwrap();
        slow.write_all(b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n")
            .await
            .unwrap();
        let early = HEADER_READ_TIMEOUT - Duration::from_secs(1);
        assert_eq!(
            closed_within(&mut slow, early).await,
            None,
            "open until the timeout"
        );
        let answer = closed_within(&mut slow, Duration::from_secs(60))
            .await
            .expect("the connection is closed past the header read timeout");
        assert!(
            !String::from_utf8_lossy(&answer).contains("here"),
            "no answer to half a request"
        );

        let mut whole = TcpStream::connect(addr).await.unwrap();
        whole
            .write_all(b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n")
            .await
            .unwrap();
        let answer = closed_within(&mut whole, Duration::from_secs(5))
            .await
            .expect("answered and closed");
        let answer = String::from_utf8_lossy(&answer);
        assert!(answer.starts_with("HTTP/1.1 200"), "{answer}");
        assert!(answer.ends_with("here"), "{answer}");
        server.stop().await;
        assert!(
            TcpStream::connect(addr).await.is_err(),
            "nothing listens after the stop"
        );
    }
}
