//! Error types for world files and parameters.
//!
//! Both name exactly what was wrong so that a user can fix a config without reading code:
//! a world file error names the file, the line (when there is one) and what was expected;
//! a parameter error names the parameter, the expected range and the value received.

use std::fmt;
use std::path::PathBuf;

/// A world file (ASCII grid, PGM image or map YAML) could not be read or parsed.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldFileError {
    /// The file that was being read.
    pub file: PathBuf,
    /// The 1-based line of the problem, when the problem is tied to a line.
    pub line: Option<usize>,
    /// The 1-based column (in characters) of the problem, when it is known.
    pub column: Option<usize>,
    /// What was wrong and what was expected instead.
    pub message: String,
}

impl WorldFileError {
    /// An error at `line` (1-based) of `file`.
    pub fn at(file: impl Into<PathBuf>, line: usize, message: impl Into<String>) -> Self {
        WorldFileError {
            file: file.into(),
            line: Some(line),
            column: None,
            message: message.into(),
        }
    }
    /// An error at `line`:`column` (both 1-based) of `file`.
    pub fn at_column(
        file: impl Into<PathBuf>,
        line: usize,
        column: usize,
        message: impl Into<String>,
    ) -> Self {
        WorldFileError {
            file: file.into(),
            line: Some(line),
            column: Some(column),
            message: message.into(),
        }
    }
    /// An error about `file` as a whole.
    pub fn file(file: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        WorldFileError {
            file: file.into(),
            line: None,
            column: None,
            message: message.into(),
        }
    }
}

impl fmt::Display for WorldFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let file = self.file.display();
        match (self.line, self.column) {
            (Some(line), Some(col)) => write!(f, "{file}:{line}:{col}: {}", self.message),
            (Some(line), None) => write!(f, "{file}:{line}: {}", self.message),
            _ => write!(f, "{file}: {}", self.message),
        }
    }
}

impl std::error::Error for WorldFileError {}

/// A parameter was out of its valid range.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamError {
    /// Parameter name as written in configs, e.g. `max_speed`.
    pub param: String,
    /// What was expected and what was received.
    pub message: String,
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "invalid parameter `{}`: {}", self.param, self.message)
    }
}

impl std::error::Error for ParamError {}

/// Checks that `value` is finite and strictly positive.
pub fn positive(param: &str, value: f64) -> Result<(), ParamError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ParamError {
            param: param.into(),
            message: format!(
                "expected a finite value > 0, got {}",
                petrel_actors::short_number(value)
            ),
        })
    }
}

/// Checks that `value` is finite and not negative.
pub fn non_negative(param: &str, value: f64) -> Result<(), ParamError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(ParamError {
            param: param.into(),
            message: format!(
                "expected a finite value >= 0, got {}",
                petrel_actors::short_number(value)
            ),
        })
    }
}

/// Checks that `value` is finite (any sign).
pub fn finite(param: &str, value: f64) -> Result<(), ParamError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(ParamError {
            param: param.into(),
            message: format!(
                "expected a finite value, got {}",
                petrel_actors::short_number(value)
            ),
        })
    }
}
