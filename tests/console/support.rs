//! A demo agent with its console on loopback (port 0), and the smallest HTTP and WebSocket
//! clients that talk to it. Every wait has a deadline.

use std::net::SocketAddr;
use std::time::Duration;

use futures_util::{SinkExt, StreamExt};
use petrel::actors::{Agent, ConfigFile};
use petrel::console::{AgentSource, Console, ConsoleOptions, LogTail};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::WebSocketStream;

/// How long any one exchange with the console may take.
pub const DEADLINE: Duration = Duration::from_secs(30);

/// A sensor at 50 Hz, linked into a scaler: values that change all the time, and parameters.
pub const DEMO: &str = r#"Agent(name: "robot1", modules: [
    (name: "sensor", type: "demo.signal", values: {"params/sample_ms": 20, "params/period_s": 1.0}),
    (name: "filter", type: "demo.scale", values: {"params/factor": 10.0},
     links: {"in/value": "sensor/out/value"}),
])"#;

/// The demo agent, running.
pub async fn demo_agent() -> Agent {
    let file = ConfigFile::parse("demo.ron", DEMO).expect("the demo config parses");
    Agent::start(&file, petrel::Petrel::new().registry())
        .await
        .expect("the demo agent starts")
}

/// `agent` with a console on 127.0.0.1, any free port, and `token` if given.
pub async fn console_for(agent: &Agent, token: Option<&str>) -> Console {
    Console::start(
        ConsoleOptions {
            addr: "127.0.0.1:0".parse().unwrap(),
            token: token.map(str::to_string),
        },
        vec![AgentSource::new(agent.name(), agent.blackboard().clone())],
        LogTail::default(),
    )
    .await
    .expect("the console starts on loopback")
}

/// An HTTP answer: status and body.
pub struct Answer {
    pub status: u16,
    pub body: String,
}

impl Answer {
    /// The body as JSON.
    pub fn json(&self) -> serde_json::Value {
        serde_json::from_str(&self.body).unwrap_or_else(|e| panic!("not JSON ({e}): {}", self.body))
    }
}

/// Sends one HTTP/1.1 request with extra `headers` (the `Host` is the console's unless given)
/// and reads the whole answer (the connection closes after it).
pub async fn http(
    addr: SocketAddr,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: Option<&str>,
) -> Answer {
    let exchange = async {
        let mut stream = TcpStream::connect(addr).await.expect("connect");
        let mut request = format!("{method} {path} HTTP/1.1\r\nConnection: close\r\n");
        if !headers.iter().any(|(k, _)| k.eq_ignore_ascii_case("host")) {
            request.push_str(&format!("Host: {addr}\r\n"));
        }
        for (k, v) in headers {
            request.push_str(&format!("{k}: {v}\r\n"));
        }
        if let Some(body) = body {
            request.push_str(&format!(
                "Content-Type: application/json\r\nContent-Length: {}\r\n",
                body.len()
            ));
        }
        request.push_str("\r\n");
        request.push_str(body.unwrap_or_default());
        stream.write_all(request.as_bytes()).await.expect("send");
        let mut raw = Vec::new();
        stream.read_to_end(&mut raw).await.expect("read");
        let raw = String::from_utf8_lossy(&raw).into_owned();
        let (head, body) = raw.split_once("\r\n\r\n").expect("an HTTP answer");
        let status = head
            .split_whitespace()
            .nth(1)
            .and_then(|s| s.parse().ok())
            .expect("a status code");
        Answer {
            status,
            body: body.to_string(),
        }
    };
    tokio::time::timeout(DEADLINE, exchange)
        .await
        .expect("the console answered in time")
}

/// `GET path` with no extra headers.
pub async fn get(addr: SocketAddr, path: &str) -> Answer {
    http(addr, "GET", path, &[], None).await
}

/// A WebSocket to the console.
pub type Socket = WebSocketStream<TcpStream>;

/// Opens `path` as a WebSocket with extra `headers`; the error is the refused handshake.
pub async fn websocket(
    addr: SocketAddr,
    path: &str,
    headers: &[(&'static str, &str)],
) -> Result<Socket, tokio_tungstenite::tungstenite::Error> {
    let mut request = format!("ws://{addr}{path}").into_client_request()?;
    for (k, v) in headers {
        request.headers_mut().insert(*k, v.parse().unwrap());
    }
    let stream = TcpStream::connect(addr).await.expect("connect");
    let (socket, _) =
        tokio::time::timeout(DEADLINE, tokio_tungstenite::client_async(request, stream))
            .await
            .expect("the handshake ended in time")?;
    Ok(socket)
}

/// Sends a JSON message.
pub async fn send(socket: &mut Socket, message: serde_json::Value) {
    socket
        .send(Message::Text(message.to_string().into()))
        .await
        .expect("send on the socket");
}

/// The next JSON message, within the deadline.
pub async fn next(socket: &mut Socket) -> serde_json::Value {
    loop {
        let message = tokio::time::timeout(DEADLINE, socket.next())
            .await
            .expect("a message in time")
            .expect("the socket stays open")
            .expect("a readable message");
        if let Message::Text(text) = message {
            return serde_json::from_str(&text).expect("JSON");
        }
    }
}
