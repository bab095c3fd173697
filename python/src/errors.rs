//! The package's exceptions: `indentify.Error` and its subclasses `ConfigError`,
//! `DataError`, `SolverError` and `IoError`, one per [`ErrorKind`] of the study layer, each
//! carrying the whole message chain (as the CLI prints it) and, as attributes, `messages`
//! (the chain, outermost first) and `kind` (`"config"`, `"data"`, `"solver"`, `"io"`).

use indentify_study::{Error as StudyError, ErrorKind};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::PyList;

create_exception!(
    indentify,
    Error,
    PyException,
    "Base class of indentify's errors. `str(e)` is the whole message chain (one line each, \
     outermost first, as the CLI prints it); `e.messages` is that chain as a list and `e.kind` \
     one of 'config', 'data', 'solver', 'io'."
);
create_exception!(
    indentify,
    ConfigError,
    Error,
    "An invalid configuration or option: RON syntax, an unknown key, a value out of range, a \
     `sets` path, a method or format name."
);
create_exception!(
    indentify,
    DataError,
    Error,
    "A data file or in-memory data that cannot be used: missing or unreadable file, malformed \
     rows, values that are not finite, a record that does not cover the simulated history."
);
create_exception!(
    indentify,
    SolverError,
    Error,
    "The solvers failed: a step that does not converge even after cutting, an adjoint failure."
);
create_exception!(
    indentify,
    IoError,
    Error,
    "An output cannot be written: an unwritable folder, a report folder holding another run."
);

/// An exception of class `T` with `messages` (joined by newlines) and `kind` attributes.
fn raise<T: pyo3::PyTypeInfo>(kind: &str, messages: Vec<String>) -> PyErr {
    let err = PyErr::new::<T, _>(messages.join("\n"));
    Python::attach(|py| {
        let value = err.value(py);
        if let Ok(list) = PyList::new(py, &messages) {
            let _ = value.setattr("messages", list);
        }
        let _ = value.setattr("kind", kind);
    });
    err
}

/// The study layer's error as the exception of its kind.
pub fn study_error(e: StudyError) -> PyErr {
    let messages = e.messages();
    match e.kind() {
        ErrorKind::Config => raise::<ConfigError>("config", messages),
        ErrorKind::Data => raise::<DataError>("data", messages),
        ErrorKind::Solver => raise::<SolverError>("solver", messages),
        ErrorKind::Io => raise::<IoError>("io", messages),
    }
}

/// A `ConfigError` with one message.
pub fn config_error(msg: impl Into<String>) -> PyErr {
    raise::<ConfigError>("config", vec![msg.into()])
}

/// A `ConfigError` with a message chain (outermost first).
pub fn config_errors(messages: Vec<String>) -> PyErr {
    raise::<ConfigError>("config", messages)
}

/// A `DataError` with one message.
pub fn data_error(msg: impl Into<String>) -> PyErr {
    raise::<DataError>("data", vec![msg.into()])
}

/// A `DataError` with a message chain (outermost first).
pub fn data_errors(messages: Vec<String>) -> PyErr {
    raise::<DataError>("data", messages)
}

/// A `SolverError` with one message.
pub fn solver_error(msg: impl Into<String>) -> PyErr {
    raise::<SolverError>("solver", vec![msg.into()])
}

/// An `IoError` with one message.
pub fn io_error(msg: impl Into<String>) -> PyErr {
    raise::<IoError>("io", vec![msg.into()])
}
