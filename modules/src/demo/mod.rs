//! Demo modules that exercise the runtime core.
