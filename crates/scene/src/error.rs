//! Source locations, load errors and warnings.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Where an element came from: file, 1-based line and column (0 = unknown).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Loc {
    pub file: Arc<PathBuf>,
    pub line: u32,
    pub col: u32,
}

impl Loc {
    pub fn new(file: &Arc<PathBuf>, line: u32, col: u32) -> Self {
        Loc {
            file: file.clone(),
            line,
            col,
        }
    }
    /// A location naming only a file.
    pub fn file(path: &Path) -> Self {
        Loc {
            file: Arc::new(path.to_path_buf()),
            line: 0,
            col: 0,
        }
    }
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if self.line > 0 {
            write!(f, ":{}", self.line)?;
            if self.col > 0 {
                write!(f, ":{}", self.col)?;
            }
        }
        Ok(())
    }
}

/// A fatal problem with user input. Displays as `file:line:col: message`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{loc}: {message}")]
pub struct LoadError {
    pub loc: Loc,
    pub message: String,
}

impl LoadError {
    pub fn new(loc: Loc, message: impl Into<String>) -> Self {
        LoadError {
            loc,
            message: message.into(),
        }
    }
}

pub type Result<T, E = LoadError> = std::result::Result<T, E>;

/// A non-fatal finding (ignored parameter, unsupported feature, substituted default).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Warning {
    pub loc: Loc,
    pub message: String,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: warning: {}", self.loc, self.message)
    }
}
