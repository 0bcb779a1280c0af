//! The expression language: conditions and values over blackboard properties, shared by plan
//! bindings and the context subsystem.
//!
//! ```text
//! hw/out/odometry.x > 2.5 and not held(nav/out/blocked, 2s)
//! abs(localizer/out/pose.theta - 1.57) < 0.1 || age(petrel://r1/hw/out/scan) > 500ms
//! clamp(a/out/v * 2, -1, 1) != 0 && mode/params/name == "dock"
//! ```
//!
//! * Values: numbers (`1`, `2.5`; durations `500ms`, `2s`, `1.5s` are numbers of seconds),
//!   `true`/`false`, strings `"..."`, properties `module/path` or `petrel://agent/module/path`.
//!   A path is words joined by `/` **without spaces**: `a/out/x / b/out/y` divides, and
//!   `a/out/x-1` is the property `a/out/x-1` (write `a/out/x - 1`).
//! * Field access on structured values: `localizer/out/pose.theta`.
//! * Operators, loosest first: `or` `||`; `and` `&&`; `not` `!`; `< <= > >= == !=` (not
//!   chained); `+ -`; `* /`; unary `-`; `.field`.
//! * Functions: `abs(x)`, `min(a, b, ...)`, `max(a, b, ...)`, `clamp(x, lo, hi)`,
//!   `held(cond, 2s)` (cond true continuously for 2 s), `age(path)` (seconds since the last write).
//!
//! Use: [`parse`] then [`properties`] to learn which properties to look up; fill a [`TypeEnv`]
//! with their types; [`ExprSet::add`] type-checks (errors carry line and column) and adds;
//! feed property values with [`ExprSet::update`] and call [`ExprSet::evaluate`] with the
//! current time. Evaluation is incremental: only expressions reading a changed property (and
//! those using `held`/`age`) are evaluated again; [`ExprSet::next_deadline`] says when time
//! alone may change a result.

mod check;
mod clock;
mod engine;
mod eval;
mod lexer;
mod never;
mod parse;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_depth;
#[cfg(test)]
mod tests_time;
mod types;
mod value;

use std::fmt;

pub(crate) use clock::start_wall_clock;
pub use clock::{continue_from, Clock, MAX_CLOCK_S};
pub use engine::{ExprId, ExprSet, PropId};
pub use never::never_true;
pub use parse::{parse, Ast, AstKind, BinOp, Func};
pub use types::{Ty, TypeEnv};
pub use value::Value;

/// How deeply an expression may nest: parentheses, function calls, `not`/`!`, unary `-`, and
/// the operators of one chain (`a + b + c` is two levels) and field accesses (`p.a.b`) each
/// count one level. [`parse`] refuses deeper input with an error at the first level too many
/// ("nesting deeper than 256 levels"), so neither it nor the checker and evaluator, which
/// recurse over the tree, can exhaust the stack of the thread running them.
pub const MAX_DEPTH: usize = 256;

/// A byte range of the source.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Span {
    /// First byte.
    pub start: usize,
    /// One past the last byte.
    pub end: usize,
}

impl Span {
    /// The range `start..end`.
    pub fn new(start: usize, end: usize) -> Self {
        Span { start, end }
    }

    /// The range covering `self` and `other`.
    pub fn to(self, other: Span) -> Span {
        Span::new(self.start.min(other.start), self.end.max(other.end))
    }
}

/// A parse or type error at a line and column (1-based, in characters) of the expression.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{line}:{column}: {message}")]
pub struct ExprError {
    /// Line, from 1.
    pub line: u32,
    /// Column, from 1, in characters.
    pub column: u32,
    /// What is wrong and what was expected.
    pub message: String,
}

impl ExprError {
    /// An error at byte `offset` of `src`.
    pub fn at(src: &str, offset: usize, message: impl Into<String>) -> Self {
        let (line, column) = crate::line_column(src, offset);
        ExprError {
            line: line as u32,
            column: column as u32,
            message: message.into(),
        }
    }
}

/// An expression as an error message quotes it: control characters escaped, and at most 80
/// characters (a generated 200 KB expression made a 200 KB error line).
pub fn quoted(src: &str) -> String {
    const MAX: usize = 80;
    let mut out = String::new();
    for (i, c) in src.chars().enumerate() {
        if i == MAX {
            out.push('…');
            break;
        }
        match c.is_control() {
            true => out.extend(c.escape_default()),
            false => out.push(c),
        }
    }
    out
}

/// Every property an expression names (paths as written, each once, in order).
pub fn properties(ast: &Ast) -> Vec<String> {
    fn walk(a: &Ast, out: &mut Vec<String>) {
        match &a.kind {
            AstKind::Path(p) if !out.contains(p) => out.push(p.clone()),
            AstKind::Field(x, _) | AstKind::Neg(x) | AstKind::Not(x) => walk(x, out),
            AstKind::Bin(_, x, y) => {
                walk(x, out);
                walk(y, out);
            }
            AstKind::Call(_, args) => args.iter().for_each(|x| walk(x, out)),
            _ => {}
        }
    }
    let mut out = Vec::new();
    walk(ast, &mut out);
    out
}

impl fmt::Display for Span {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}..{}", self.start, self.end)
    }
}
