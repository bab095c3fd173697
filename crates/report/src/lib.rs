//! Identification reports: Markdown and JSON summaries of a parameter identification,
//! and its figures (force-depth, force-time, convergence) as SVG and PNG.
//!
//! The crate depends on no other indentify crate: the CLI fills the plain data structs
//! of [`Report`] and asks for text or bytes back. Like every indentify library it does
//! no file IO. Values are stored in internal units (mm, N, s, MPa); each parameter and
//! the curves carry a [`DisplayUnit`] saying how to show them (nm and mN for a
//! nano-indentation, mm and N for a macroscopic test: see [`Curves::with_auto_units`]).
//!
//! Figures are drawn with plotters and the DejaVu Sans font embedded in the binary, so
//! PNGs render on machines without system fonts.

mod error;
mod fit;
mod markdown;
mod model;
mod plot;
mod units;

pub use error::ReportError;
pub use fit::FitQuality;
pub use model::{
    BoundHit, Convergence, Correlation, Curves, FigureLink, IterationRecord, NameValue, Parameter,
    PreprocessingStep, Report, Source,
};
pub use plot::{Figure, FigureSize};
pub use units::{DisplayUnit, fmt_axis_tick, fmt_sig, fmt_tick};
