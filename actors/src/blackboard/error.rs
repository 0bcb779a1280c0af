//! Why the blackboard refused a structure change.

use crate::ports::PropertyKind;

/// Why a structure change (link, value, declaration) was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum BlackboardError {
    /// No module of that name in the agent.
    #[error("no module `{module}` in agent `{agent}` (modules: {known})")]
    UnknownModule {
        /// The name asked for.
        module: String,
        /// The agent.
        agent: String,
        /// The modules it has.
        known: String,
    },
    /// The module has no such property.
    #[error("module `{module}` has no property `{path}`; it has: {known}")]
    UnknownProperty {
        /// The module.
        module: String,
        /// The path asked for.
        path: String,
        /// The module's properties.
        known: String,
    },
    /// The address does not parse or names another agent.
    #[error("{0}")]
    BadAddress(String),
    /// Only inputs, parameters and queue inputs can be linked.
    #[error(
        "cannot link `{key}` ({kind}): only inputs, parameters and queue inputs can be linked"
    )]
    NotLinkable {
        /// The property.
        key: String,
        /// Its kind.
        kind: PropertyKind,
    },
    /// Queue inputs link to queues, value properties to values.
    #[error("cannot link `{from}` ({from_kind}) to `{to}` ({to_kind}): a queue input links to a queue, a value to a value")]
    KindMismatch {
        /// Link source.
        from: String,
        /// Its kind.
        from_kind: PropertyKind,
        /// Link target.
        to: String,
        /// Its kind.
        to_kind: PropertyKind,
    },
    /// Linked properties must have the same type.
    #[error("cannot link `{from}` ({from_type}) to `{to}` ({to_type}): the types differ")]
    TypeMismatch {
        /// Link source.
        from: String,
        /// Its type.
        from_type: &'static str,
        /// Link target.
        to: String,
        /// Its type.
        to_type: &'static str,
    },
    /// The link would close a cycle.
    #[error("link cycle: {}", .0.join(" -> "))]
    Cycle(Vec<String>),
    /// A value does not fit the property.
    #[error("wrong value for `{key}`: expected {expected}: {reason}")]
    BadValue {
        /// The property.
        key: String,
        /// The type it has.
        expected: &'static str,
        /// What the conversion said.
        reason: String,
    },
    /// A numeric parameter set outside its declared range (or not a finite number).
    #[error("`{key}` = {value}: expected {range} ({doc})")]
    OutOfRange {
        /// The property.
        key: String,
        /// The value refused, as shown to people.
        value: String,
        /// What it accepts, as shown to people (`a value in 0.1..=10`).
        range: String,
        /// What the parameter is, in its module's words.
        doc: String,
    },
    /// A queue input asked for its items (a tool, a recorder): it has none of its own.
    #[error("`{key}` is a queue input, which holds no items of its own: follow the queue it reads{}", reads(.linked_to))]
    QueueInput {
        /// The property.
        key: String,
        /// The queue it is linked to, if any.
        linked_to: Option<String>,
    },
    /// A parameter its module reads only when it starts, written while the agent runs.
    #[error(
        "`{key}` is read once, when its module starts: a running agent does not change it (set it in the config; a context rule or plan binding cannot set it either)"
    )]
    ReadAtStart {
        /// The property.
        key: String,
    },
    /// The property cannot be set (stats, queues).
    #[error(
        "`{key}` ({kind}) cannot be set: only inputs, parameters, outputs, state and `enabled` can"
    )]
    NotSettable {
        /// The property.
        key: String,
        /// Its kind.
        kind: PropertyKind,
    },
    /// A queue was asked for one value.
    #[error("`{key}` is a {kind}: it carries items, not one value; `petrel echo` prints them as they come")]
    NotAValue {
        /// The property.
        key: String,
        /// Its kind.
        kind: PropertyKind,
    },
    /// Other properties link into the module being removed.
    #[error("module `{module}` cannot be removed: linked from {}", .links.join(", "))]
    InUse {
        /// The module.
        module: String,
        /// The properties that link into it.
        links: Vec<String>,
    },
    /// A module declared its properties wrongly.
    #[error("{0}")]
    Declaration(String),
    /// The blackboard actor is gone.
    #[error("the blackboard of this agent has stopped")]
    Stopped,
}

/// The queue a queue input reads, for a message.
fn reads(linked_to: &Option<String>) -> String {
    match linked_to {
        Some(queue) => format!(", `{queue}`"),
        None => " (it is not linked to one)".to_string(),
    }
}
