//! The one error type of the crate.
//!
//! Every variant names the file it comes from (or the name given to an
//! in-memory source) and, where there is one, the location inside it, so the
//! CLI can print the error as is.

use std::path::PathBuf;

/// How deeply a plan input may nest: blocks and conditionals of a text plan, parentheses of a
/// condition, elements of a PNML file. Deeper input is refused with [`PlanError::TooDeep`] (or,
/// for a condition, a [`crate::CondError`]) at the first level too many, before any recursion
/// could exhaust the stack of the thread reading it; real plans stay far below it.
pub const MAX_DEPTH: usize = 256;

/// Anything that can go wrong while reading, compiling or loading a plan, a
/// rules file or a simulation script.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// The file could not be read (missing, not a regular file, too large...).
    #[error("{}: {message}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// The PNML file is not well-formed XML.
    #[error("{file}:{line}:{column}: malformed XML: {message}")]
    Xml {
        /// The file.
        file: String,
        /// 1-based line.
        line: u32,
        /// 1-based column.
        column: u32,
        /// What the XML parser expected.
        message: String,
    },
    /// The XML is well-formed but is not a Petri net as PNP writes it
    /// (missing net, arc between two places, unknown node id, bad marking...).
    #[error("{}{element}: {message}", at(file, *line, *column))]
    Pnml {
        /// The file.
        file: String,
        /// 1-based line of the element (0 when unknown).
        line: u32,
        /// 1-based column (0 when unknown).
        column: u32,
        /// The element concerned, e.g. `arc 'a3'` or `place 'p1'`.
        element: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A place or transition label could not be understood
    /// (e.g. a dotted word with an unknown function, or two guards).
    #[error("{}{kind} '{id}' with label '{label}': {message}", at(file, *line, *column))]
    Label {
        /// The file.
        file: String,
        /// 1-based line of the node (0 when unknown).
        line: u32,
        /// 1-based column (0 when unknown).
        column: u32,
        /// `place` or `transition`.
        kind: &'static str,
        /// The node id.
        id: String,
        /// The full label.
        label: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A transition guard does not parse.
    #[error("{}transition '{id}' with label '{label}': bad guard: {message}", at(file, *line, *column))]
    Guard {
        /// The file.
        file: String,
        /// 1-based line of the transition (0 when unknown).
        line: u32,
        /// 1-based column (0 when unknown).
        column: u32,
        /// The transition id.
        id: String,
        /// The full label.
        label: String,
        /// The condition parser's message, with the column inside the guard.
        message: String,
    },
    /// A syntax error in a text plan or a rules file.
    #[error("{file}:{line}:{column}: {message}")]
    Syntax {
        /// The file.
        file: String,
        /// 1-based line.
        line: u32,
        /// 1-based column.
        column: u32,
        /// What was found and what was expected.
        message: String,
    },
    /// The input nests deeper than [`MAX_DEPTH`] levels (text plan blocks and conditionals,
    /// PNML elements); the position is the first level too many.
    #[error("{file}:{line}:{column}: nesting deeper than {limit} levels")]
    TooDeep {
        /// The file.
        file: String,
        /// 1-based line.
        line: u32,
        /// 1-based column.
        column: u32,
        /// The limit, [`MAX_DEPTH`].
        limit: usize,
    },
    /// A bad line in a simulation script.
    #[error("{file}:{line}: {message}")]
    Script {
        /// The file.
        file: String,
        /// 1-based line.
        line: u32,
        /// What was found and what was expected.
        message: String,
    },
    /// Sub-plans nest deeper than [`MAX_DEPTH`] levels (each stepping level recurses once).
    #[error("{file}: sub-plans nest deeper than {limit} levels ({chain}); expected a shallower hierarchy")]
    SubPlansTooDeep {
        /// The file whose sub-plan is one level too many.
        file: String,
        /// The limit, [`MAX_DEPTH`].
        limit: usize,
        /// The start and the end of the chain of plan names, `a -> b -> ... -> z`.
        chain: String,
    },
    /// Sub-plans include each other.
    #[error("{file}: sub-plan '{name}' includes itself (through {chain})")]
    SubPlanCycle {
        /// The file that closes the cycle.
        file: String,
        /// The sub-plan name.
        name: String,
        /// The chain of plan names, `a -> b -> a`.
        chain: String,
    },
}

/// `file:line:column: `, or `file: ` where the place is unknown.
fn at(file: &str, line: u32, column: u32) -> String {
    match line {
        0 => format!("{file}: "),
        _ => format!("{file}:{line}:{column}: "),
    }
}

impl PlanError {
    /// The error with the place of the node it is about filled in, where it has none:
    /// `find` gives the line and column of the node with an id (the PNML reader knows them,
    /// the plan builder does not).
    pub(crate) fn located(mut self, find: impl Fn(&str) -> Option<(u32, u32)>) -> Self {
        let (id, line, column) = match &mut self {
            PlanError::Label {
                id, line, column, ..
            }
            | PlanError::Guard {
                id, line, column, ..
            } => (id.clone(), line, column),
            // `arc 'a3'`: the id is quoted in the element.
            PlanError::Pnml {
                element,
                line,
                column,
                ..
            } => match element.split('\'').nth(1) {
                Some(id) => (id.to_string(), line, column),
                None => return self,
            },
            _ => return self,
        };
        if *line == 0 {
            if let Some((l, c)) = find(&id) {
                (*line, *column) = (l, c);
            }
        }
        self
    }
}
