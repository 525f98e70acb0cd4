//! How the document layer reports problems: one [`Diagnostic`] per problem (a stable code,
//! a severity, a JSON pointer as its location and a line for a person; core's one diagnostic
//! type), pushed into a [`Sink`].
//!
//! The importer reads through a [`FailFast`] sink (the first error ends the load); `raycast
//! check` reads through a sink that keeps everything. Both see the same codes, so they agree
//! on what loads without comparing message strings. Codes are the Khronos glTF-Validator's
//! where the meaning is the same.

pub use raycast_core::diagnostic::{Code, Diagnostic, Severity};

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
    pub fn error(&mut self, code: Code, pointer: impl Into<String>, message: impl Into<String>) {
        self.push(Diagnostic::error(code, pointer, message));
    }

    /// Records a warning.
    pub fn warn(&mut self, code: Code, pointer: impl Into<String>, message: impl Into<String>) {
        self.push(Diagnostic::warning(code, pointer, message));
    }

    /// Records an info.
    pub fn info(&mut self, code: Code, pointer: impl Into<String>, message: impl Into<String>) {
        self.push(Diagnostic::new(code, Severity::Info, pointer, message));
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
pub const READ_WITH_WARNING: &[Code] = &[Code::GlbChunkLengthUnaligned];

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
