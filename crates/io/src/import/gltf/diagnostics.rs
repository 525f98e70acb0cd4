//! How the document layer reports problems: one [`Diagnostic`] per problem (a stable code,
//! a severity, a JSON pointer and a line for a person), pushed into a [`Sink`].
//!
//! The importer reads through a [`FailFast`] sink (the first error ends the load); `raycast
//! check` reads through a sink that keeps everything. Both see the same codes, so they agree
//! on what loads without comparing message strings. Codes are the Khronos glTF-Validator's
//! where the meaning is the same.

use std::fmt;

/// How bad a diagnostic is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Severity {
    /// The document cannot be read as written (the importer stops).
    Error,
    /// Probably a mistake; reading goes on.
    Warning,
    /// Worth knowing.
    Info,
}

/// One problem found while reading a document.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostic {
    /// Stable code, e.g. `ACCESSOR_TOO_LONG`.
    pub code: &'static str,
    /// Error, warning or info.
    pub severity: Severity,
    /// JSON pointer of the offending property (empty for the whole file).
    pub pointer: String,
    /// One line for a person.
    pub message: String,
}

impl Diagnostic {
    /// An error diagnostic.
    pub fn error(
        code: &'static str,
        pointer: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Diagnostic {
            code,
            severity: Severity::Error,
            pointer: pointer.into(),
            message: message.into(),
        }
    }
}

impl Diagnostic {
    /// The same diagnostic, its message prefixed with where it was reached from (a
    /// primitive, a node), so that a fail-fast error names both.
    pub fn within(mut self, at: &str) -> Diagnostic {
        if !self.pointer.starts_with(at) && !self.message.contains("(read for ") {
            self.message = format!("{} (read for {at})", self.message);
        }
        self
    }
}

impl fmt::Display for Diagnostic {
    /// `pointer: message`, or the message alone for the whole file.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.pointer.is_empty() {
            f.write_str(&self.message)
        } else {
            write!(f, "{}: {}", self.pointer, self.message)
        }
    }
}

/// Where diagnostics go.
pub trait Sink {
    /// Records a diagnostic.
    fn push(&mut self, diagnostic: Diagnostic);

    /// True once the reader should stop (a fail-fast sink after its first error).
    fn stopped(&self) -> bool {
        false
    }
}

impl dyn Sink + '_ {
    /// Records an error.
    pub fn error(
        &mut self,
        code: &'static str,
        pointer: impl Into<String>,
        message: impl Into<String>,
    ) {
        self.push(Diagnostic::error(code, pointer, message));
    }

    /// Records a warning.
    pub fn warn(
        &mut self,
        code: &'static str,
        pointer: impl Into<String>,
        message: impl Into<String>,
    ) {
        self.push(Diagnostic {
            severity: Severity::Warning,
            ..Diagnostic::error(code, pointer, message)
        });
    }

    /// Records an info.
    pub fn info(
        &mut self,
        code: &'static str,
        pointer: impl Into<String>,
        message: impl Into<String>,
    ) {
        self.push(Diagnostic {
            severity: Severity::Info,
            ..Diagnostic::error(code, pointer, message)
        });
    }
}

impl Sink for Vec<Diagnostic> {
    fn push(&mut self, diagnostic: Diagnostic) {
        Vec::push(self, diagnostic);
    }
}

/// Keeps the first error and every warning and info; stops the reader at the first error.
/// The errors in [`READ_WITH_WARNING`] are kept as warnings.
#[derive(Debug, Default)]
pub struct FailFast {
    /// The first error, if any.
    pub error: Option<Diagnostic>,
    /// Warnings and infos, in order.
    pub notes: Vec<Diagnostic>,
}

/// Errors of the validator's that other readers read through (trimesh, three.js and Blender
/// read a GLB chunk whose length is not a multiple of 4, as older trimesh exporters wrote
/// them, by taking the next chunk right after its bytes): the importer reads on with a
/// warning, `raycast check` keeps the error.
pub const READ_WITH_WARNING: &[&str] = &["GLB_CHUNK_LENGTH_UNALIGNED"];

impl Sink for FailFast {
    fn push(&mut self, mut diagnostic: Diagnostic) {
        if diagnostic.severity == Severity::Error && READ_WITH_WARNING.contains(&diagnostic.code) {
            diagnostic.severity = Severity::Warning;
            diagnostic
                .message
                .push_str(": read anyway (`raycast check` reports it as an error)");
        }
        if diagnostic.severity != Severity::Error {
            self.notes.push(diagnostic);
        } else if self.error.is_none() {
            self.error = Some(diagnostic);
        }
    }

    fn stopped(&self) -> bool {
        self.error.is_some()
    }
}

/// Passes errors on to another sink and drops warnings and infos: the importer runs rules
/// shared with `raycast check` for their errors only.
pub struct ErrorsOnly<'s>(pub &'s mut dyn Sink);

impl Sink for ErrorsOnly<'_> {
    fn push(&mut self, diagnostic: Diagnostic) {
        if diagnostic.severity == Severity::Error {
            self.0.push(diagnostic);
        }
    }

    fn stopped(&self) -> bool {
        self.0.stopped()
    }
}

/// Drops everything (for reads whose failure the caller reports in its own words).
#[derive(Debug, Default)]
pub struct Ignore;

impl Sink for Ignore {
    fn push(&mut self, _: Diagnostic) {}
}
