//! Errors of loading a scene, written for the person who edits the scene file: each names the
//! file and, where there is one, the dotted key, the value found and what is allowed.

use std::fmt;
use std::path::PathBuf;

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("{}: could not read the scene file: {cause}", file.display())]
    Io {
        file: PathBuf,
        /// Said in the message, not chained as a source: a printed chain would say it twice.
        cause: std::io::Error,
    },

    /// The file is not valid TOML. Line and column are 1-based.
    #[error("{}: line {line}, column {column}: TOML syntax error: {message}", file.display())]
    Syntax {
        file: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },

    /// Valid TOML that does not fit the schema: an unknown key, a missing key or a wrong type.
    /// `key` is the dotted path of where it happened (empty for the top level); `location` is the
    /// 1-based (line, column) in the file, absent when `--set` overrides rewrote the document.
    /// `set_by` is the override that wrote the key, when one did (and the error is told against
    /// it, the file only said for context).
    #[error(
        "{}{}: {}: {message}",
        Origin(file, set_by),
        Location(location),
        KeyPath(key)
    )]
    Schema {
        file: PathBuf,
        key: String,
        location: Option<(u32, u32)>,
        message: String,
        set_by: Option<Box<str>>,
    },

    /// A value outside its allowed range, or inconsistent with another one.
    #[error(
        "{}: invalid `{key}` = {value}; allowed: {allowed}",
        Origin(file, set_by)
    )]
    Invalid {
        file: PathBuf,
        key: String,
        value: String,
        allowed: String,
        set_by: Option<Box<str>>,
    },

    /// A malformed `--set dotted.key=value` argument.
    #[error("--set {arg:?}: {reason}")]
    Override { arg: String, reason: String },

    /// A mesh shape whose file does not exist (`path` is as resolved against the scene folder).
    #[error("{}: `{key}`: mesh file {} does not exist", Origin(file, set_by), path.display())]
    MissingMesh {
        file: PathBuf,
        key: String,
        path: PathBuf,
        set_by: Option<Box<str>>,
    },
}

/// Where an error is: the scene file, or the `--set` override that wrote the key, on that file.
struct Origin<'a>(&'a PathBuf, &'a Option<Box<str>>);

impl fmt::Display for Origin<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.1 {
            Some(arg) => write!(f, "--set {arg:?} on {}", self.0.display()),
            None => write!(f, "{}", self.0.display()),
        }
    }
}

/// Formats an optional (line, column) as `: line L, column C`.
struct Location<'a>(&'a Option<(u32, u32)>);

impl fmt::Display for Location<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some((line, column)) => write!(f, ": line {line}, column {column}"),
            None => Ok(()),
        }
    }
}

/// Formats a dotted key in backticks, or says "top level" for the empty one.
struct KeyPath<'a>(&'a str);

impl fmt::Display for KeyPath<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_empty() {
            f.write_str("top level")
        } else {
            write!(f, "`{}`", self.0)
        }
    }
}

pub use crate::interval::Number;
