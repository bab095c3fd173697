//! The crate's errors: [`ReadError`] (reading bytes into records) and [`PrepError`] (preprocessing).

use serde::Serialize;

/// What went wrong while reading, for callers that branch on it (the message says the rest).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum ReadErrorKind {
    /// The file holds no bytes (or only whitespace).
    Empty,
    /// No row of numbers was found.
    NoRows,
    /// A required column is missing, or a header is not understood.
    Columns,
    /// A unit is missing where one is needed, or not recognised.
    Units,
    /// A field is not a number.
    NotANumber,
    /// A field is NaN or infinite (also after unit conversion).
    NotFinite,
    /// Time decreases from one row to the next.
    TimeOrder,
    /// A row has fewer fields than the columns it must provide.
    FewFields,
    /// A declared number of points disagrees with the rows found.
    PointCount,
    /// The selected test does not exist, or a test must be selected.
    TestIndex,
    /// Fewer than two rows.
    TooFewRows,
    /// The content is not of the requested format.
    Format,
}

/// An error while reading a record; displays as `file:line: what is wrong; expected ...`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}{}: {message}; expected {expected}", line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct ReadError {
    /// The display name given to the reader (usually the file path).
    pub file: String,
    /// The 1-based line where the problem is, when known.
    pub line: Option<usize>,
    /// The category.
    pub kind: ReadErrorKind,
    /// What is wrong, with the offending values.
    pub message: String,
    /// What was expected instead.
    pub expected: String,
}

impl ReadError {
    pub(crate) fn new(
        file: &str,
        line: Option<usize>,
        kind: ReadErrorKind,
        message: impl Into<String>,
        expected: impl Into<String>,
    ) -> Self {
        Self {
            file: file.to_owned(),
            line,
            kind,
            message: message.into(),
            expected: expected.into(),
        }
    }
}

/// An error of a preprocessing step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PrepError {
    /// An option outside its admissible range.
    #[error("preprocessing: `{field}` = {value} is not allowed; expected {expected}")]
    Option {
        /// Field name as in the config (e.g. `resample.n`).
        field: &'static str,
        /// The offending value, as text.
        value: String,
        /// What is allowed.
        expected: String,
    },
    /// The force never rises through the contact threshold.
    #[error(
        "{record}: no contact: the force never exceeds the threshold {threshold_mn:.4e} mN above the baseline {baseline_mn:.4e} mN (the force spans {min_mn:.4e} to {max_mn:.4e} mN); expected a loading curve whose force rises{}",
        if *max_mn <= 0.0 { "; the force is never positive: is the force column's sign reversed (compression counted negative)?" } else { "" }
    )]
    NoContact {
        /// Record name.
        record: String,
        /// Threshold above the baseline, mN.
        threshold_mn: f64,
        /// Baseline force, mN.
        baseline_mn: f64,
        /// Maximum force, mN.
        max_mn: f64,
        /// Minimum force of the whole record, mN.
        min_mn: f64,
    },
    /// Too few points are left (after trimming, or for the requested resampling).
    #[error("{record}: {step}: {n} points left; expected at least {min}")]
    TooShort {
        /// Record name.
        record: String,
        /// The step that found it.
        step: &'static str,
        /// Points left.
        n: usize,
        /// Points needed.
        min: usize,
    },
    /// A step asked for a value from the file, and the file does not give it.
    #[error("{record}: {step}: the file gives no {what}; expected a value in the options")]
    NoHint {
        /// Record name.
        record: String,
        /// The step.
        step: &'static str,
        /// The missing hint.
        what: &'static str,
    },
    /// The record itself is inconsistent (lengths differ, values not finite, time decreasing).
    #[error("{record}: {what}; expected {expected}")]
    Record {
        /// Record name.
        record: String,
        /// What is wrong.
        what: String,
        /// What is expected.
        expected: String,
    },
}
