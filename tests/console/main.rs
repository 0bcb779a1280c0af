//! The web console (`petrel run --console`): its API and WebSocket, its access rules, the
//! `petrel` binary's flags, and the page in a real headless browser.

mod api;
mod attach;
mod browser;
mod browser_attach;
mod cli;
mod foxglove;
mod map;
mod security;
mod support;
