//! Built-in petrel functional modules.

pub mod demo;
