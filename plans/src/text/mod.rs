//! The PNPgen-family text language.
//!
//! ```text
//! plan   := seq
//! seq    := item (';' item)* [';']
//! item   := ACTION ['|' SECONDS] ('!' rule '!')*     action, optionally timed
//!         | '<' COND '?' seq (':' COND '?' seq)* '>'  conditional
//!         | '{' seq '}' ('||' '{' seq '}')*          block / parallel branches
//!         | '{' seq '}' '*' N                         the block N times (1..=1000)
//!         | LABEL_x | GOTO_LABEL_x | restart_plan | fail_plan
//! ```
//! Execution rules (see [`crate::compile_text`] and the `rules` module)
//! come from a separate file or inline after an action between `!`s.
//!
//! The net has PNPgen's structure: `init` (1 token), then for each action
//! `A.start` -> `A.exec` -> `A.end` -> a plain place `Xn`, the last place
//! labelled `goal`. Choices where PNPgen's behaviour is not specified here:
//! * conditional branches get one `[COND]` transition each from the current
//!   place, in the order written, and are merged by `' '` transitions into a
//!   new place; parallel branches are forked and joined by `[]` transitions;
//! * `LABEL_x` names the current place; `GOTO_LABEL_x` adds a `' '`
//!   transition to it and ends the sequence (only a label may follow);
//!   `restart_plan` / `fail_plan` in a plan jump to `init` / the `fail` place;
//! * rules apply to the actions of the plan, not to recovery actions, in
//!   rule order then plan order; a trailing `*` on a recovery action name is
//!   accepted and dropped; a recovery must end with `restart_action`,
//!   `skip_action`, `restart_plan`, `fail_plan` or `goal`;
//! * lines whose first non-blank character is `#` are comments.

mod compile;
mod layout;
mod lexer;
mod parse;
mod rules;

pub use compile::compile_text;

/// 1-based line and character column of byte `offset` in `src`.
pub(crate) fn line_col(src: &str, offset: usize) -> (u32, u32) {
    let (line, column) = petrel_actors::line_column(src, offset);
    (line as u32, column as u32)
}

pub(crate) fn syntax_error(
    src: &str,
    file: &str,
    offset: usize,
    message: impl Into<String>,
) -> crate::PlanError {
    let (line, column) = line_col(src, offset);
    crate::PlanError::Syntax {
        file: file.to_string(),
        line,
        column,
        message: message.into(),
    }
}

/// The error for input nested deeper than [`crate::MAX_DEPTH`] levels at byte `offset`.
pub(crate) fn too_deep(src: &str, file: &str, offset: usize) -> crate::PlanError {
    let (line, column) = line_col(src, offset);
    crate::PlanError::TooDeep {
        file: file.to_string(),
        line,
        column,
        limit: crate::MAX_DEPTH,
    }
}
