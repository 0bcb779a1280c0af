//! The messages of a team plan, written as RON in a message body.
//!
//! Action names travel without the robot prefix (the recipient is the robot). `run` counts the
//! coordinator's starts of an action, so an answer to an earlier run that crosses a new start
//! on the way is recognised and dropped.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::label::CallKind;

/// One message between a coordinator and a robot's executor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum TeamMsg {
    /// Coordinator → robot: make `call` (`start`, `end`, `interrupt`, `resume`, `fail`) on
    /// `action`, for the coordinator's `run`-th start of it.
    Call {
        /// The action, without the robot prefix.
        action: String,
        /// The call, as in labels (`start`, ...).
        call: String,
        /// Which start of the action this is about (1 = the first).
        run: u64,
    },
    /// Robot → coordinator: `action`'s `run` finished (or failed).
    Done {
        /// The action, without the robot prefix.
        action: String,
        /// Which start of the action the answer is about.
        run: u64,
        /// Failed rather than finished.
        failed: bool,
    },
    /// Coordinator → robot: send me these conditions (names without the robot prefix) now and
    /// whenever they change.
    Watch {
        /// Condition names.
        conditions: Vec<String>,
    },
    /// Robot → coordinator: condition values that changed (all of them after a `Watch`).
    Conditions {
        /// Name (without the robot prefix) → value.
        values: BTreeMap<String, bool>,
    },
}

impl TeamMsg {
    /// The message body: one line of RON.
    pub fn encode(&self) -> String {
        ron::to_string(self).expect("team messages always serialize")
    }

    /// Reads a message body; the error says what was expected.
    pub fn decode(body: &str) -> Result<TeamMsg, String> {
        ron::from_str(body).map_err(|e| {
            format!("not a team plan message ({e}); expected Call(..), Done(..), Watch(..) or Conditions(..)")
        })
    }
}

/// A message to send: to `agent/module`, with its body.
#[derive(Debug, Clone, PartialEq)]
pub struct Outgoing {
    /// The recipient, `agent/module`.
    pub to: String,
    /// The encoded [`TeamMsg`].
    pub body: String,
}

/// A call's name as a message carries it.
pub(crate) fn call_name(kind: CallKind) -> &'static str {
    kind.as_str()
}

/// A call named in a message.
pub(crate) fn parse_call(name: &str) -> Result<CallKind, String> {
    CallKind::parse(name).ok_or_else(|| {
        format!("unknown call `{name}`; expected start, end, interrupt, resume or fail")
    })
}
