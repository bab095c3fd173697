//! Identification reports: Markdown and JSON summaries of a parameter identification,
//! and its figures (force-depth, force-time, convergence) as SVG and PNG.
//!
//! The crate depends on no other indentify crate: the CLI fills the plain data structs
//! of [`Report`] and asks for text or bytes back. Like every indentify library it does
//! no file IO. Values are stored in internal units (mm, N, s, MPa); each parameter and
//! the curves carry a [`DisplayUnit`] saying how to show them (nm and mN for a
//! nano-indentation, mm and N for a macroscopic test: see [`Curves::with_auto_units`]).
//!
//! The cost around a fit has its own figures: [`ProfileFigure`] (profile likelihoods)
//! and [`CostMapFigure`] (2D cost maps with contour lines).
//!
//! Figures are drawn with plotters and the DejaVu Sans font embedded in the binary, so
//! PNGs render on machines without system fonts.
//!
//! # Example
//!
//! ```
//! use indentify_report::{
//!     Convergence, Curves, DisplayUnit, Figure, FigureSize, FitQuality, IterationRecord,
//!     Parameter, PreprocessingStep, Report, Source,
//! };
//!
//! // A 2 µm, 10 mN Maxwell test (internal units: s, mm, N, MPa).
//! let t = vec![0.0, 1.0, 2.0, 3.0];
//! let h = vec![0.0, 1e-3, 2e-3, 2e-3];
//! let f_data = vec![0.0, 2.6e-3, 10.1e-3, 9.0e-3];
//! let f_final = vec![0.0, 2.5e-3, 10.0e-3, 9.1e-3];
//! let fit = FitQuality::compute(&f_data, &f_final)?;
//! let report = Report {
//!     title: "Maxwell identification".into(),
//!     source: Source { file: "test.csv".into(), test: "1".into(), metadata: vec![] },
//!     law: "maxwell".into(),
//!     parameters: vec![Parameter {
//!         name: "E".into(),
//!         unit: DisplayUnit::new("GPa", 1e-3), // shown = MPa * 1e-3
//!         start: 100e3,
//!         value: 72e3,
//!         lower: Some(1e3),
//!         upper: Some(1e6),
//!         at_bound: None,
//!         fixed: false,
//!         std_dev: None,
//!     }],
//!     correlation: None,
//!     convergence: Convergence {
//!         stop_reason: "gradient below tolerance".into(),
//!         iterations: 1,
//!         forward_solves: 2,
//!         adjoint_solves: 2,
//!         wall_time_s: 0.5,
//!         converged: Some(true),
//!     },
//!     fit,
//!     preprocessing: vec![PreprocessingStep::new("zero point", "none needed")],
//!     // Depth in nm and force in mN, chosen from the data.
//!     curves: Curves::with_auto_units(t, h, f_data, None, f_final),
//!     history: vec![
//!         IterationRecord { iteration: 0, cost: 1e-5, grad_norm: Some(1.0), params: vec![100e3] },
//!         IterationRecord { iteration: 1, cost: 1e-9, grad_norm: Some(1e-4), params: vec![72e3] },
//!     ],
//!     figures: vec![Figure::ForceDepth.link("force_depth.svg")],
//!     warnings: Vec::new(),
//!     discretization: None,
//!     identifiability: None,
//!     adequacy: None,
//! };
//!
//! let md = report.to_markdown();
//! assert!(md.contains("| E | 72.00 |"));
//! let svg = report.figure_svg(Figure::ForceDepth, FigureSize::default())?;
//! assert!(svg.contains("depth h [nm]") && svg.contains("force F [mN]"));
//! let png: Vec<u8> = report.figure_png(Figure::Convergence, FigureSize { width: 600, height: 400 })?;
//! assert_eq!(&png[1..4], b"PNG");
//! let json = report.to_json()?;
//! # Ok::<(), indentify_report::ReportError>(())
//! ```

pub mod adequacy;
mod error;
mod explore;
mod fit;
mod lines;
mod map;
mod markdown;
mod model;
mod plot;
mod units;

pub use adequacy::{Adequacy, NoiseEstimate, Verdict};
pub use error::ReportError;
pub use explore::{CostMapFigure, ProfileFigure, contour_segments};
pub use fit::FitQuality;
pub use lines::{LineFigure, Series, Style};
pub use map::{MapData, MapFigure};
pub use model::{
    BoundHit, Convergence, Correlation, Curves, DiscretizationSummary, FigureLink,
    IdentifiabilitySummary, IterationRecord, NameValue, Observable, Parameter, PreprocessingStep,
    Report, Source, Undetermined,
};
pub use plot::{Figure, FigureSize};
pub use units::{DisplayUnit, fmt_axis_tick, fmt_log_tick, fmt_sig, fmt_tick};
