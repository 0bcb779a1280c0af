//! Who may use the console, and what they may change: the rules of issue 14's item 3, as
//! pure functions over the bound address and a request's headers.
//!
//! - Loopback by default; any other address needs a token (given, or generated and printed).
//! - With a token, every request must carry it (`Authorization: Bearer`, or `?token=` for the
//!   page and its WebSocket, which browsers cannot give headers).
//! - No cross-origin access: the `Host` must name the console itself (a DNS-rebinding page
//!   names its own host) and an `Origin`, when a browser sends one, must be the console's.
//! - Only `params/` and `control/` properties are writable.

use std::net::SocketAddr;

use petrel_actors::PropertyKind;

/// Why a bind address is refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum BindError {
    /// An empty token would let anyone in.
    #[error("the console token is empty; give one of at least {MIN_TOKEN_LEN} characters, or none on loopback")]
    EmptyToken,
    /// A short token is guessable.
    #[error("the console token is {0} characters long; give at least {MIN_TOKEN_LEN}")]
    ShortToken(usize),
    /// The token travels in URLs: only characters that need no escaping.
    #[error("the console token may hold only letters, digits, `-`, `_`, `.` and `~`; `{0}` is none of these")]
    TokenChar(char),
}

/// Shortest token accepted from the command line.
pub const MIN_TOKEN_LEN: usize = 16;

/// What the console asks of every request, decided once when it binds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Access {
    /// The token every request must present, if any.
    pub token: Option<String>,
    /// Whether the token was generated here (so the caller prints it).
    pub generated: bool,
}

impl Access {
    /// The access rules for a console bound to `addr`, with the token the user gave (if any);
    /// `generate` makes a fresh one when an address beyond loopback has none.
    pub fn for_bind(
        addr: SocketAddr,
        given: Option<&str>,
        generate: impl FnOnce() -> String,
    ) -> Result<Access, BindError> {
        match given {
            Some("") => Err(BindError::EmptyToken),
            Some(t) if t.chars().count() < MIN_TOKEN_LEN => {
                Err(BindError::ShortToken(t.chars().count()))
            }
            Some(t) if !t.chars().all(url_safe) => Err(BindError::TokenChar(
                t.chars().find(|c| !url_safe(*c)).unwrap_or(' '),
            )),
            Some(t) => Ok(Access {
                token: Some(t.to_string()),
                generated: false,
            }),
            None if addr.ip().is_loopback() => Ok(Access {
                token: None,
                generated: false,
            }),
            None => Ok(Access {
                token: Some(generate()),
                generated: true,
            }),
        }
    }

    /// Whether a request presenting `presented` (from its header or query) may go on.
    pub fn admits(&self, presented: Option<&str>) -> bool {
        match (&self.token, presented) {
            (None, _) => true,
            (Some(want), Some(got)) => same_secret(want.as_bytes(), got.as_bytes()),
            (Some(_), None) => false,
        }
    }
}

fn url_safe(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.' | '~')
}

/// Compares in time that depends only on the lengths, so a token is not guessed byte by byte.
fn same_secret(a: &[u8], b: &[u8]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// The token a request presents: `Authorization: Bearer T`, else `token=T` in its query.
pub fn presented_token<'a>(
    authorization: Option<&'a str>,
    query: Option<&'a str>,
) -> Option<&'a str> {
    if let Some(t) = authorization.and_then(|h| h.strip_prefix("Bearer ")) {
        return Some(t.trim());
    }
    query?
        .split('&')
        .find_map(|pair| pair.strip_prefix("token="))
}

/// Why a request's origin is refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum OriginError {
    /// No `Host` header (HTTP/1.1 requires one).
    #[error("the request names no Host")]
    NoHost,
    /// The `Host` is not the console's: a page of another site reaching it by DNS rebinding.
    #[error("Host `{0}` is not this console")]
    ForeignHost(String),
    /// A page of another origin calling the console.
    #[error("Origin `{0}` is not this console")]
    ForeignOrigin(String),
}

/// Checks `Host` and `Origin` against the bound address: the host must be the bound address
/// itself or, on loopback, `localhost`/`127.0.0.1`/`[::1]` (bound to every interface, any name)
/// with the bound port; an `Origin` must be `http://` followed by that same host.
pub fn check_origin(
    bound: SocketAddr,
    host: Option<&str>,
    origin: Option<&str>,
) -> Result<(), OriginError> {
    let host = host.ok_or(OriginError::NoHost)?;
    if !host_is_console(bound, host) {
        return Err(OriginError::ForeignHost(host.to_string()));
    }
    match origin {
        None => Ok(()),
        Some(o) if o.strip_prefix("http://") == Some(host) => Ok(()),
        Some(o) => Err(OriginError::ForeignOrigin(o.to_string())),
    }
}

/// The web pages allowed to open the Foxglove live view besides its own host: Foxglove's app.
/// The view is read-only (no parameters, no publishing), so this lets Foxglove's page read
/// what the view serves, and no other site.
pub const FOXGLOVE_ORIGINS: [&str; 2] = ["https://app.foxglove.dev", "https://studio.foxglove.dev"];

/// [`check_origin`] for the Foxglove live view: Foxglove's app may open it too.
pub fn check_foxglove_origin(
    bound: SocketAddr,
    host: Option<&str>,
    origin: Option<&str>,
) -> Result<(), OriginError> {
    match origin {
        Some(o) if FOXGLOVE_ORIGINS.contains(&o) => check_origin(bound, host, None),
        _ => check_origin(bound, host, origin),
    }
}

fn host_is_console(bound: SocketAddr, host: &str) -> bool {
    let port = bound.port().to_string();
    let Some((name, host_port)) = host.rsplit_once(':') else {
        return false;
    };
    if host_port != port {
        return false;
    }
    let name = name.trim_start_matches('[').trim_end_matches(']');
    if name == bound.ip().to_string() {
        return true;
    }
    match bound.ip() {
        ip if ip.is_loopback() => matches!(name, "localhost" | "127.0.0.1" | "::1"),
        // Bound to every interface: reached by any of the machine's names. Beyond loopback a
        // token is always required, and a rebinding page does not have it.
        ip if ip.is_unspecified() => true,
        _ => false,
    }
}

/// Whether the console may write a property of this kind: parameters and controls only, as
/// for `petrel set`.
pub fn writable(kind: PropertyKind) -> bool {
    matches!(kind, PropertyKind::Param | PropertyKind::Control)
}

/// [`writable`] for a kind as listings name it (`param`, `control`, `output`, ...): what a
/// remote agent's listing says.
pub fn writable_named(kind: &str) -> bool {
    matches!(kind, "param" | "control")
}

/// Why a write was refused, in words for the field it came from.
pub fn refusal(key: &str, kind: impl std::fmt::Display) -> String {
    format!(
        "`{key}` ({kind}) cannot be set from the console: only params/ and control/ properties can"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn addr(s: &str) -> SocketAddr {
        s.parse().unwrap()
    }

    #[test]
    fn foxgloves_app_may_open_the_live_view_and_other_sites_may_not() {
        let bound = addr("127.0.0.1:8765");
        let host = Some("127.0.0.1:8765");
        assert!(check_foxglove_origin(bound, host, Some("https://app.foxglove.dev")).is_ok());
        assert!(check_foxglove_origin(bound, host, None).is_ok());
        assert_eq!(
            check_foxglove_origin(bound, host, Some("https://evil.example")),
            Err(OriginError::ForeignOrigin("https://evil.example".into()))
        );
        assert!(check_foxglove_origin(
            bound,
            Some("evil.example:8765"),
            Some("https://app.foxglove.dev")
        )
        .is_err());
    }

    #[test]
    fn loopback_needs_no_token_and_other_addresses_get_one() {
        let local = Access::for_bind(addr("127.0.0.1:8080"), None, || unreachable!()).unwrap();
        assert_eq!(local.token, None);
        assert!(local.admits(None));
        let wide = Access::for_bind(addr("0.0.0.0:8080"), None, || "x".repeat(32)).unwrap();
        assert_eq!(
            (wide.token.as_deref(), wide.generated),
            (Some(&*"x".repeat(32)), true)
        );
        assert!(!wide.admits(None));
        assert!(!wide.admits(Some("wrong")));
        assert!(wide.admits(Some(&"x".repeat(32))));
    }

    #[test]
    fn a_given_token_is_enforced_even_on_loopback_and_must_be_long() {
        let given = "0123456789abcdef";
        let a = Access::for_bind(addr("127.0.0.1:1"), Some(given), || unreachable!()).unwrap();
        assert!(!a.admits(None));
        assert!(a.admits(Some(given)));
        assert!(!a.admits(Some("0123456789abcdeF")));
        assert_eq!(
            Access::for_bind(addr("127.0.0.1:1"), Some("short"), String::new),
            Err(BindError::ShortToken(5))
        );
        assert_eq!(
            Access::for_bind(addr("10.0.0.1:1"), Some(""), String::new),
            Err(BindError::EmptyToken)
        );
        assert_eq!(
            Access::for_bind(addr("10.0.0.1:1"), Some("0123456789abcdef&x"), String::new),
            Err(BindError::TokenChar('&'))
        );
    }

    #[test]
    fn the_token_comes_from_the_header_or_the_query() {
        assert_eq!(presented_token(Some("Bearer abc"), None), Some("abc"));
        assert_eq!(
            presented_token(None, Some("agent=a&token=xyz")),
            Some("xyz")
        );
        assert_eq!(presented_token(Some("Basic abc"), Some("a=1")), None);
        assert_eq!(presented_token(None, None), None);
    }

    #[test]
    fn only_the_consoles_own_host_and_origin_pass() {
        let bound = addr("127.0.0.1:8080");
        assert!(check_origin(bound, Some("127.0.0.1:8080"), None).is_ok());
        assert!(check_origin(bound, Some("localhost:8080"), Some("http://localhost:8080")).is_ok());
        assert_eq!(check_origin(bound, None, None), Err(OriginError::NoHost));
        assert_eq!(
            check_origin(bound, Some("evil.example:8080"), None),
            Err(OriginError::ForeignHost("evil.example:8080".into()))
        );
        assert_eq!(
            check_origin(bound, Some("127.0.0.1:8081"), None),
            Err(OriginError::ForeignHost("127.0.0.1:8081".into()))
        );
        assert_eq!(
            check_origin(bound, Some("127.0.0.1:8080"), Some("http://evil.example")),
            Err(OriginError::ForeignOrigin("http://evil.example".into()))
        );
        let wide = addr("192.0.2.7:9000");
        assert!(check_origin(wide, Some("192.0.2.7:9000"), Some("http://192.0.2.7:9000")).is_ok());
        assert!(check_origin(wide, Some("localhost:9000"), None).is_err());
        let every = addr("0.0.0.0:9000");
        assert!(check_origin(every, Some("robot.lan:9000"), Some("http://robot.lan:9000")).is_ok());
        assert!(check_origin(every, Some("robot.lan:9001"), None).is_err());
        assert!(check_origin(every, Some("robot.lan:9000"), Some("http://evil.example")).is_err());
    }

    #[test]
    fn only_params_and_controls_are_writable() {
        assert!(writable(PropertyKind::Param));
        assert!(writable(PropertyKind::Control));
        for kind in [
            PropertyKind::Input,
            PropertyKind::Output,
            PropertyKind::State,
            PropertyKind::Stats,
            PropertyKind::Enabled,
            PropertyKind::QueueIn,
            PropertyKind::QueueOut,
        ] {
            assert!(!writable(kind), "{kind}");
        }
    }
}
