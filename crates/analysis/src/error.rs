//! The crate's error: what went wrong with an option, a test or an unloading, in words that
//! name it and say why.

/// An error of the analysis or the calibration.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AnalysisError {
    /// An option outside its admissible range.
    #[error("`{field}` = {value} is not allowed; expected {expected}")]
    Option {
        /// Field name (e.g. `fit_range.lower`).
        field: String,
        /// The value, as text.
        value: String,
        /// What is allowed.
        expected: String,
    },
    /// A test that cannot be analysed (no unloading, too few samples, ...).
    #[error("{test}: {reason}")]
    Test {
        /// Test name.
        test: String,
        /// Why.
        reason: String,
    },
    /// One unloading that cannot be analysed (the power law does not fit, ...).
    #[error("{test}, unloading {unloading}: {reason}")]
    Unloading {
        /// Test name.
        test: String,
        /// 1-based unloading number within the test.
        unloading: usize,
        /// Why.
        reason: String,
    },
    /// A calibration that gives no usable result.
    #[error("calibration: {reason}")]
    Calibration {
        /// Why, with the numbers.
        reason: String,
    },
}
