//! The study layer's error: a message chain (what failed, then why, each naming the
//! field, file or line) with a kind, so that front ends map it onto their own error
//! classes (the CLI's exit status, Python's `ConfigError` / `DataError` / `SolverError`).

use std::fmt;

/// What kind of input or stage an error comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorKind {
    /// The configuration: syntax, a field out of range, a `--set` path, an option.
    Config,
    /// A data file: unreadable, malformed, not covering the history.
    Data,
    /// The solvers: a step that fails even after cutting, an adjoint failure.
    Solver,
    /// Writing outputs: an unwritable directory, a report folder that holds another run.
    Io,
}

impl ErrorKind {
    /// `config`, `data`, `solver`, `io`.
    pub fn name(self) -> &'static str {
        match self {
            ErrorKind::Config => "config",
            ErrorKind::Data => "data",
            ErrorKind::Solver => "solver",
            ErrorKind::Io => "io",
        }
    }
}

/// An error of the study layer: its [`ErrorKind`] and the message chain (outermost first).
pub struct Error {
    kind: ErrorKind,
    inner: anyhow::Error,
}

/// `Result` with the study layer's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An error of `kind` around `inner` (its message chain is kept).
    pub fn new(kind: ErrorKind, inner: impl Into<anyhow::Error>) -> Error {
        Error {
            kind,
            inner: inner.into(),
        }
    }

    /// An error of `kind` with the message `msg`.
    pub fn msg(kind: ErrorKind, msg: impl fmt::Display) -> Error {
        Error::new(kind, anyhow::anyhow!("{msg}"))
    }

    /// The kind.
    pub fn kind(&self) -> ErrorKind {
        self.kind
    }

    /// The messages, outermost first.
    pub fn messages(&self) -> Vec<String> {
        self.inner.chain().map(|e| e.to_string()).collect()
    }

    /// Adds an outer message, keeping the kind.
    pub fn context(self, msg: impl fmt::Display + Send + Sync + 'static) -> Error {
        Error {
            kind: self.kind,
            inner: self.inner.context(msg),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.inner)
    }
}

impl fmt::Debug for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} error: {:?}", self.kind.name(), self.inner)
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.inner.source()
    }
}

/// Gives a kind to the errors of a result.
pub trait Classify<T> {
    /// The error, if any, as an [`Error`] of `kind`.
    ///
    /// # Errors
    /// The error of `self`, classified.
    fn kind(self, kind: ErrorKind) -> Result<T>;
}

impl<T, E: Into<anyhow::Error>> Classify<T> for std::result::Result<T, E> {
    fn kind(self, kind: ErrorKind) -> Result<T> {
        self.map_err(|e| Error::new(kind, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chain_and_the_kind_survive_context() {
        let e: Result<()> = Err(anyhow::anyhow!("inner cause"))
            .map_err(|e: anyhow::Error| e.context("middle"))
            .kind(ErrorKind::Data);
        let e = e.unwrap_err().context("outer");
        assert_eq!(e.kind(), ErrorKind::Data);
        assert_eq!(e.messages(), ["outer", "middle", "inner cause"]);
        assert_eq!(e.to_string(), "outer");
        let any: anyhow::Error = e.into();
        assert_eq!(any.chain().count(), 3);
    }
}
