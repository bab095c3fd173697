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

/// The command-line flags the study layer's messages name, and the Python arguments
/// that take their place.
const FLAGS: [(&str, &str); 11] = [
    ("--max-iter", "max_iterations"),
    ("--no-refine", "refine=False"),
    ("--free", "free"),
    ("--fixed", "fixed"),
    ("--start", "start"),
    ("--method", "method"),
    ("--noise", "noise"),
    ("--seed", "seed"),
    ("--force", "force=True"),
    ("--data", "data"),
    ("--out", "out"),
];

/// A study-layer message in the words of the Python package: `--set a=1 --set b=2`
/// becomes `sets {a=1, b=2}`, each flag its argument (`--noise -1` becomes `noise=-1`,
/// `--force` `force=True`), and the hint to resume (a command-line option) says so.
pub fn python_words(msg: &str) -> String {
    let msg = msg.replace(
        "continue it with --resume, replace it with --force, or choose another --out",
        "replace it with force=True, choose another out, or continue it on the command line \
         (indentify identify ... --resume)",
    );
    // `--set A --set B` -> `sets {A, B}`
    let mut out = String::new();
    let mut rest = msg.as_str();
    while let Some(k) = rest.find("--set ") {
        out.push_str(&rest[..k]);
        rest = &rest[k..];
        let mut items = Vec::new();
        while let Some(tail) = rest.strip_prefix("--set ") {
            let end = tail
                .find(|c: char| c.is_whitespace() || c == ')' || c == ':' || c == ';')
                .unwrap_or(tail.len());
            items.push(tail[..end].to_string());
            rest = &tail[end..];
            match rest.strip_prefix(" --set ") {
                Some(_) => rest = &rest[1..],
                None => break,
            }
        }
        out.push_str(&format!("sets {{{}}}", items.join(", ")));
    }
    out.push_str(rest);
    for (flag, arg) in FLAGS {
        let mut done = String::new();
        let mut rest = out.as_str();
        while let Some(k) = rest.find(flag) {
            let after = &rest[k + flag.len()..];
            let boundary = !after.starts_with(|c: char| c.is_ascii_alphanumeric() || c == '-');
            done.push_str(&rest[..k]);
            if !boundary {
                done.push_str(flag);
                rest = after;
                continue;
            }
            done.push_str(arg);
            // `--noise -1 is ...` -> `noise=-1 is ...`
            let number = after.strip_prefix(' ').and_then(|t| {
                let end = t
                    .find(|c: char| c.is_whitespace() || c == ',')
                    .unwrap_or(t.len());
                t[..end].parse::<f64>().ok().map(|_| end)
            });
            match number {
                Some(end) if !arg.contains('=') => {
                    done.push('=');
                    done.push_str(&after[1..=end]);
                    rest = &after[1 + end..];
                }
                _ => rest = after,
            }
        }
        done.push_str(rest);
        out = done;
    }
    out
}

/// The study layer's error as the exception of its kind, in the Python package's words
/// ([`python_words`]).
pub fn study_error(e: StudyError) -> PyErr {
    let messages: Vec<String> = e.messages().iter().map(|m| python_words(m)).collect();
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
