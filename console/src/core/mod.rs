//! The pure core of the console: what it shows (JSON shapes), which properties feed the map,
//! the plan's marking and firings, push throttling, and the access rules. No server, no
//! clock, no actors: everything here is tested on plain values.

pub mod access;
pub mod foxglove;
pub mod map;
pub mod plan;
pub mod throttle;
pub mod view;
