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

/// A fatal problem with user input. Displays as `file:line:col: message`, with any overlong
/// word of the message (an echoed token of a hostile file can be megabytes) shortened.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{loc}: {}", elide_long_words(message))]
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
        write!(
            f,
            "{}: warning: {}",
            self.loc,
            elide_long_words(&self.message)
        )
    }
}

/// Words (runs without whitespace) longer than this are shortened in messages.
const MAX_WORD_CHARS: usize = 64;

/// `message` with every word over [`MAX_WORD_CHARS`] characters cut to its first 40, an
/// ellipsis and how much was left out.
pub fn elide_long_words(message: &str) -> std::borrow::Cow<'_, str> {
    let long = |w: &str| w.chars().nth(MAX_WORD_CHARS).is_some();
    if !message.split_whitespace().any(long) {
        return message.into();
    }
    let mut out = String::new();
    let mut rest = message;
    while !rest.is_empty() {
        let ws = rest.len() - rest.trim_start().len();
        out.push_str(&rest[..ws]);
        rest = &rest[ws..];
        let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
        let word = &rest[..end];
        if long(word) {
            let keep: String = word.chars().take(40).collect();
            let left = word.chars().count() - 40;
            out.push_str(&format!("{keep}…[{left} more characters]"));
        } else {
            out.push_str(word);
        }
        rest = &rest[end..];
    }
    out.into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_words_are_elided_in_messages_and_short_ones_kept() {
        let token = "9".repeat(50_000_000);
        let e = LoadError::new(
            Loc::new(&Arc::new(PathBuf::from("a.obj")), 3, 7),
            format!("invalid number '{token}'  here"),
        );
        let shown = e.to_string();
        assert!(shown.len() < 200, "{} bytes", shown.len());
        assert!(
            shown.starts_with("a.obj:3:7: invalid number '9999"),
            "{shown}"
        );
        assert!(
            shown.ends_with("…[49999962 more characters]  here"),
            "{shown}"
        );
        let short = "expected 'x y z', found 'abc'";
        assert_eq!(elide_long_words(short), short);
    }
}
