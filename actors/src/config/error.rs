//! Config errors located in their files, and reading and parsing RON files as petrel writes
//! them (shared by agent configs and context rules).

use std::fmt;
use std::path::{Path, PathBuf};

/// A problem in a config file, located in it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigError {
    /// The file.
    pub file: PathBuf,
    /// 1-based line (0 when unknown).
    pub line: usize,
    /// 1-based column (0 when unknown).
    pub column: usize,
    /// What is wrong and what was expected.
    pub message: String,
}

impl ConfigError {
    /// An error at byte `offset` of `text`, the contents of `file`.
    pub fn at(file: &Path, text: &str, offset: usize, message: String) -> Self {
        let (line, column) = crate::line_column(text, offset);
        ConfigError {
            file: file.into(),
            line,
            column,
            message,
        }
    }

    /// An error about `file` as a whole.
    pub fn in_file(file: &Path, message: String) -> Self {
        ConfigError {
            file: file.into(),
            line: 0,
            column: 0,
            message,
        }
    }

    /// A RON syntax error in `file` (whose contents are `text`); `what` names the kind of
    /// file for the reader.
    pub fn from_ron(file: &Path, text: &str, error: &ron::error::SpannedError, what: &str) -> Self {
        // Some of RON's own words are for programmers: say what to do instead.
        let code = match &error.code {
            ron::Error::IntegerOutOfBounds => {
                let at = crate::text_position::offset_of(
                    text,
                    error.span.start.line,
                    error.span.start.col,
                );
                let field = at.and_then(|at| field_before(text, at));
                format!(
                    "{}a whole number out of range for this field (counts and times in ms take 0 or more; see the field's documentation for its limit)",
                    field.map(|f| format!("`{f}`: ")).unwrap_or_default()
                )
            }
            ron::Error::ExceededRecursionLimit => {
                "nested too deeply (more than 128 levels of brackets)".to_string()
            }
            other => other.to_string(),
        };
        // At the end of the text the point of an error is that the text ended: a truncated
        // file, or one that holds nothing.
        let at = crate::text_position::offset_of(text, error.span.start.line, error.span.start.col);
        let at_end = at.is_none_or(|at| text.get(at..).is_none_or(|rest| rest.trim().is_empty()));
        let message = match () {
            _ if text.trim().is_empty() => {
                format!("the file is empty (nothing but whitespace); expected {what}")
            }
            _ if at_end => format!("the file ends too early: {code} (RON syntax of {what})"),
            _ => format!("{code} (RON syntax of {what})"),
        };
        ConfigError {
            file: file.into(),
            line: error.span.start.line,
            column: error.span.start.col,
            message,
        }
    }
}

/// The name of the struct field whose value starts at byte `at` of `text` (`name: <at>`), if
/// one does: RON's errors about a value do not say which field it is for.
fn field_before(text: &str, at: usize) -> Option<&str> {
    // RON points past a minus sign, at the digits.
    let before = text.get(..at)?.trim_end();
    let before = before.strip_suffix('-').unwrap_or(before).trim_end();
    let before = before.strip_suffix(':')?.trim_end();
    let start = before
        .rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .map_or(0, |i| i + 1);
    let name = &before[start..];
    (!name.is_empty() && !name.starts_with(|c: char| c.is_ascii_digit())).then_some(name)
}

impl ConfigError {
    /// The same place and message as a warning: `file:line:column: warning: message`.
    pub fn as_warning(&self) -> String {
        self.show("warning")
    }

    fn show(&self, severity: &str) -> String {
        let message = shown_message(&self.message);
        match self.line {
            0 => format!("{}: {severity}: {message}", self.file.display()),
            _ => format!(
                "{}:{}:{}: {severity}: {message}",
                self.file.display(),
                self.line,
                self.column,
            ),
        }
    }
}

/// The most characters of a message shown: a value or name that is megabytes long (a 20 MB
/// string parameter, a 100,000-digit number, a property path of 100,000 segments) was echoed
/// whole in its error.
const MAX_SHOWN_MESSAGE: usize = 2000;

/// `message`, cut at [`MAX_SHOWN_MESSAGE`] characters with what was left out counted.
fn shown_message(message: &str) -> std::borrow::Cow<'_, str> {
    match message.char_indices().nth(MAX_SHOWN_MESSAGE) {
        None => message.into(),
        Some((cut, _)) => {
            let left = message[cut..].chars().count();
            format!("{}… ({left} more characters)", &message[..cut]).into()
        }
    }
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.show("error"))
    }
}

/// Every problem found in a config, one per line when displayed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigErrors(pub Vec<ConfigError>);

impl fmt::Display for ConfigErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, e) in self.0.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{e}")?;
        }
        Ok(())
    }
}

impl std::error::Error for ConfigErrors {}

/// Reads a text file; `what` names it in the error ("config", "context rules").
/// Only a regular file is read, within the size limit of its kind
/// ([`crate::files::limits`]), its UTF-8 byte-order mark dropped.
pub fn read_text(path: &Path, what: &str) -> Result<String, ConfigError> {
    let limit = match what {
        "context rules" => crate::files::limits::RULES,
        _ => crate::files::limits::CONFIG,
    };
    crate::files::read_text(path, what, limit).map_err(|e| ConfigError::in_file(path, e))
}

/// Parses RON text as petrel writes its files: optional fields are written plainly
/// (`group: "nav"`, not `group: Some("nav")`). `what` names the kind of file in errors.
pub fn parse_ron<T: serde::de::DeserializeOwned>(
    path: &Path,
    text: &str,
    what: &str,
) -> Result<T, ConfigError> {
    let options =
        ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    options
        .from_str::<T>(text)
        .map_err(|e| ConfigError::from_ron(path, text, &e, what))
}
