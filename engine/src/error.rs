//! Errors of the engine: every one names the file, line and column, or the missing name.

use std::fmt;
use std::path::PathBuf;

/// A position in a source file (1-based line and column).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// The file, as the virtual file system names it (e.g. `graphs/pt.ron`).
    pub file: String,
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub column: usize,
}

impl Location {
    /// The location of byte `offset` in `text` of `file`.
    pub fn at_offset(file: &str, text: &str, offset: usize) -> Self {
        let before = &text[..offset.min(text.len())];
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        Location {
            file: file.to_string(),
            line,
            column,
        }
    }

    /// The location of the first quoted occurrence of `name` in `text`, or the file start.
    pub fn of_name(file: &str, text: &str, name: &str) -> Self {
        let quoted = format!("\"{name}\"");
        let offset = text.find(&quoted).map_or(0, |o| o + 1);
        Self::at_offset(file, text, offset)
    }
}

impl Location {
    /// The location of the first map key `"name":` in `text`, or else of the first quoted
    /// occurrence of `name`.
    pub fn of_key(file: &str, text: &str, name: &str) -> Self {
        let quoted = format!("\"{name}\"");
        let mut from = 0;
        while let Some(i) = text[from..].find(&quoted) {
            let at = from + i;
            let rest = text[at + quoted.len()..].trim_start();
            if rest.starts_with(':') {
                return Self::at_offset(file, text, at + 1);
            }
            from = at + quoted.len();
        }
        Self::of_name(file, text, name)
    }
}

impl Location {
    /// The location of the first quoted `name` after the map key `"key":`, or of the key, or
    /// of the first quoted `name`.
    pub fn of_name_under_key(file: &str, text: &str, key: &str, name: &str) -> Self {
        let at_key = Self::of_key(file, text, key);
        let quoted_key = format!("\"{key}\"");
        if let Some(k) = text
            .find(&format!("{quoted_key}:"))
            .or_else(|| text.find(&format!("{quoted_key} :")))
        {
            if let Some(i) = text[k..].find(&format!("\"{name}\"")) {
                return Self::at_offset(file, text, k + i + 1);
            }
            return at_key;
        }
        Self::of_name(file, text, name)
    }
}

impl Location {
    /// The location of the first quoted `name` after the first `marker` (e.g. a field such
    /// as `outputs:`), or of the first quoted `name`.
    pub fn of_name_after(file: &str, text: &str, marker: &str, name: &str) -> Self {
        if let Some(m) = text.find(marker)
            && let Some(i) = text[m..].find(&format!("\"{name}\""))
        {
            return Self::at_offset(file, text, m + i + 1);
        }
        Self::of_name(file, text, name)
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.column)
    }
}

/// Everything that can go wrong while loading, compiling or running a frame graph.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be found or read.
    #[error("{path}: {message}")]
    Io {
        /// The file asked for.
        path: PathBuf,
        /// What went wrong, with where it was looked for.
        message: String,
    },
    /// Malformed RON (syntax or schema).
    #[error("{at}: {message}")]
    Parse {
        /// Where the parser stopped.
        at: Location,
        /// The parser's message.
        message: String,
    },
    /// A graph that parses but is not valid: unknown names, type mismatches, illegal fusion.
    #[error("{at}: {message}")]
    Invalid {
        /// Where the offending name stands.
        at: Location,
        /// What is wrong.
        message: String,
    },
    /// WGSL that naga rejects, or a pass whose WGSL does not match its declaration.
    #[error("{0}")]
    Shader(String),
    /// A missing adapter, feature or limit, or a device error.
    #[error("{0}")]
    Gpu(String),
    /// An error while running frames (bad inputs, overflow, mapping failure).
    #[error("{0}")]
    Runtime(String),
}

/// The engine's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An [`Error::Invalid`] located at the declaration `"name":` in `file`.
    pub fn invalid_at_key(file: &str, text: &str, name: &str, message: impl Into<String>) -> Self {
        Error::Invalid {
            at: Location::of_key(file, text, name),
            message: message.into(),
        }
    }

    /// An [`Error::Invalid`] located at the first occurrence of `name` in `file`.
    pub fn invalid_at_name(file: &str, text: &str, name: &str, message: impl Into<String>) -> Self {
        Error::Invalid {
            at: Location::of_name(file, text, name),
            message: message.into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locations_are_one_based() {
        let text = "ab\ncd \"x\"\n";
        let at = Location::of_name("f.ron", text, "x");
        assert_eq!((at.line, at.column), (2, 5));
        assert_eq!(Location::at_offset("f", text, 0).to_string(), "f:1:1");
        let text = "[\"s\"]\n{ \"s\" : 1 }";
        assert_eq!(Location::of_key("f", text, "s").line, 2);
    }
}
