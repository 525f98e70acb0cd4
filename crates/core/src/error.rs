//! The crate's error type: every failure names the file it concerns and what is wrong.

use crate::diagnostic::{Code, Diagnostic};
use std::fmt;
use std::path::{Path, PathBuf};

/// An error with the file it concerns (when there is one) and a one-line description.
#[derive(Debug, Clone, PartialEq)]
pub struct Error {
    /// The file the error is about, if any.
    pub path: Option<PathBuf>,
    /// Where in the file, when the reader knows (a USD prim or attribute path); empty
    /// otherwise. Shown before the message.
    pub location: String,
    /// What is wrong, in one line.
    pub message: String,
    /// Whether the request itself is invalid (the command line exits 2) or the run failed
    /// (exit 1).
    pub kind: ErrorKind,
    /// The diagnostic code of the problem, when the reader that failed gave one (a glTF
    /// validator code, `USD_INVALID_PATH`, ...); [`Error::code`] reads it.
    pub code: Option<Code>,
}

/// What kind of failure an [`Error`] is, for callers that act on it: the command line's exit
/// code, the Python package's exception class.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ErrorKind {
    /// The input or the run failed.
    Failure,
    /// The request cannot be carried out as asked: an invalid option value or combination, an
    /// output folder that cannot be written.
    Usage,
    /// The scene file does not exist (a failure like [`ErrorKind::Failure`] otherwise).
    NotFound,
}

/// Result type used throughout the crate.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// An error about `path`.
    pub fn in_file(path: impl AsRef<Path>, message: impl Into<String>) -> Self {
        Error {
            path: Some(path.as_ref().to_path_buf()),
            location: String::new(),
            message: message.into(),
            kind: ErrorKind::Failure,
            code: None,
        }
    }

    /// An error that concerns no particular file.
    pub fn msg(message: impl Into<String>) -> Self {
        Error {
            path: None,
            location: String::new(),
            message: message.into(),
            kind: ErrorKind::Failure,
            code: None,
        }
    }

    /// A usage error (see [`ErrorKind::Usage`]) that concerns no particular file.
    pub fn usage(message: impl Into<String>) -> Self {
        Error {
            kind: ErrorKind::Usage,
            ..Error::msg(message)
        }
    }

    /// An error about the part of a file at `location` (a prim or attribute path), that
    /// concerns no particular file yet ([`Error::with_path`] adds it).
    pub fn at(location: impl Into<String>, message: impl Into<String>) -> Self {
        Error {
            location: location.into(),
            ..Error::msg(message)
        }
    }

    /// `location: message`, or the message alone: the error without its file.
    pub fn detail(&self) -> String {
        if self.location.is_empty() {
            self.message.clone()
        } else {
            format!("{}: {}", self.location, self.message)
        }
    }

    /// The error as a warning diagnostic of a reader that reads on: its own code, else
    /// `code`, its location and message (the file left out: a warning is about the file
    /// being read).
    pub fn to_warning(&self, code: Code) -> Diagnostic {
        Diagnostic::warning(
            self.code.unwrap_or(code),
            self.location.clone(),
            self.message.clone(),
        )
    }

    /// The error a fail-fast reader stops with: `diagnostic`, about `path`, with its code.
    pub fn from_diagnostic(path: impl AsRef<Path>, diagnostic: &Diagnostic) -> Self {
        Error::at(diagnostic.location.clone(), diagnostic.text())
            .with_path(path)
            .with_code(diagnostic.code)
    }

    /// This error with the diagnostic code `code`.
    pub fn with_code(self, code: Code) -> Self {
        Error {
            code: Some(code),
            ..self
        }
    }

    /// The error's code: the one its reader gave, else `FAILED`, `USAGE` or `NOT_FOUND` by
    /// its [`ErrorKind`] (what the Python package's exceptions carry as `.code`).
    pub fn code(&self) -> Code {
        self.code.unwrap_or(match self.kind {
            ErrorKind::Failure => Code::Failed,
            ErrorKind::Usage => Code::Usage,
            ErrorKind::NotFound => Code::NotFound,
        })
    }

    /// This error marked as a usage error.
    pub fn as_usage(self) -> Self {
        self.with_kind(ErrorKind::Usage)
    }

    /// This error with kind `kind`.
    pub fn with_kind(self, kind: ErrorKind) -> Self {
        Error { kind, ..self }
    }

    /// This error with its message prefixed: `"{prefix}: {message}"` (the file it names, if
    /// any, is kept and still printed first; its location, if any, moves into the message
    /// after the prefix, so the text reads as before).
    pub fn context(mut self, prefix: impl fmt::Display) -> Self {
        self.message = format!("{prefix}: {}", self.detail());
        self.location.clear();
        self
    }

    /// Attaches `path` unless the error already names a file.
    pub fn with_path(mut self, path: impl AsRef<Path>) -> Self {
        if self.path.is_none() {
            self.path = Some(path.as_ref().to_path_buf());
        }
        self
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(path) = &self.path {
            write!(f, "{}: ", path.display())?;
        }
        f.write_str(&self.detail())
    }
}

impl std::error::Error for Error {}

/// The text of a caught panic's payload, for an error message.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> &str {
    payload
        .downcast_ref::<String>()
        .map(String::as_str)
        .or_else(|| payload.downcast_ref::<&str>().copied())
        .unwrap_or("unknown cause")
}
