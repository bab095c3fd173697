//! The crate's error type.

use thiserror::Error;

/// Everything that can go wrong while computing fit metrics or rendering a report.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ReportError {
    /// Two series that must pair up have different lengths.
    #[error("{what}: length {got}, expected {expected}")]
    Length {
        /// Which series.
        what: &'static str,
        /// The length it should have.
        expected: usize,
        /// The length it has.
        got: usize,
    },
    /// A series (or what is left of it after skipping non-finite points) is empty.
    #[error("{what}: no finite values to use")]
    Empty {
        /// Which series.
        what: &'static str,
    },
    /// A value that must be finite is NaN or infinite.
    #[error("{what}[{index}] = {value} is not finite")]
    NonFinite {
        /// Which series.
        what: &'static str,
        /// Index of the offending value.
        index: usize,
        /// The value.
        value: f64,
    },
    /// The measured force is constant, so R² (relative to its variance) is undefined.
    #[error("force data is constant ({value}): R² is undefined")]
    ConstantData {
        /// The constant value.
        value: f64,
    },
    /// A figure size outside 100..=4000 pixels per side.
    #[error("figure size {width}x{height} px: each side must be in 100..=4000")]
    Size {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// The embedded font could not be registered with plotters.
    #[error("embedded DejaVu Sans font could not be registered")]
    Font,
    /// plotters failed while drawing.
    #[error("drawing {figure}: {message}")]
    Draw {
        /// Which figure.
        figure: &'static str,
        /// plotters' message.
        message: String,
    },
    /// PNG encoding failed.
    #[error("PNG encoding: {0}")]
    Png(String),
    /// JSON serialization failed.
    #[error("JSON: {0}")]
    Json(String),
}
