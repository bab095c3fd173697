//! The report's data model: plain, serializable structs the CLI fills in.
//!
//! Every value is stored in internal units (mm, N, s, MPa); [`DisplayUnit`]s say how to
//! show them.

use serde::{Deserialize, Serialize};

use crate::adequacy::{Adequacy, Verdict};
use crate::error::ReportError;
use crate::fit::FitQuality;
use crate::units::DisplayUnit;

/// One identification run, everything the Markdown, JSON and figures show.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Title, the Markdown's first heading.
    pub title: String,
    /// Where the measured curve came from.
    pub source: Source,
    /// Constitutive law name ("maxwell", "norton-hoff").
    pub law: String,
    /// All law parameters, fixed and free, in the law's order.
    pub parameters: Vec<Parameter>,
    /// Correlation matrix of the free parameters, from the identifiability analysis.
    pub correlation: Option<Correlation>,
    /// Optimizer outcome and cost of the run.
    pub convergence: Convergence,
    /// Quality of the final fit, see [`FitQuality::compute`].
    pub fit: FitQuality,
    /// Preprocessing applied to the measured curve, in order.
    pub preprocessing: Vec<PreprocessingStep>,
    /// Measured and simulated curves.
    pub curves: Curves,
    /// One record per optimizer iteration (iteration 0 = start point).
    pub history: Vec<IterationRecord>,
    /// Figure files to link from the Markdown (paths relative to the Markdown file).
    pub figures: Vec<FigureLink>,
    /// Where the model is stretched beyond its validity, or the data fall short (shown
    /// first in the Markdown).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// The discretization error of the fit, when it was estimated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub discretization: Option<DiscretizationSummary>,
    /// What the data determine: singular values and directions of the scaled sensitivity
    /// matrix, the parameters left undetermined (shown in `## Identifiability`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub identifiability: Option<IdentifiabilitySummary>,
    /// Whether the residuals look like the record's own noise ([`Adequacy::assess`]; shown
    /// in `## Model adequacy`, and as a warning at the top when systematic).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adequacy: Option<Adequacy>,
}

/// The singular value decomposition of the scaled sensitivity matrix `S` (weighted
/// `dF/dy`, `y` the optimizer's scaled variables, `y = ln c` for log-scaled parameters) and
/// the parameters it leaves undetermined.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IdentifiabilitySummary {
    /// The free parameters, labelling the directions' components.
    pub names: Vec<String>,
    /// Singular values of `S` (N per unit of `y`), descending.
    pub singular_values: Vec<f64>,
    /// The right singular vector of each singular value (components in `names` order).
    pub directions: Vec<Vec<f64>>,
    /// Condition number of `S^T S` as text (`singular` beyond 1e16).
    pub condition: String,
    /// The weakest direction in words.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weakest: Option<String>,
    /// The parameters the data do not determine, with the reason.
    #[serde(default)]
    pub undetermined: Vec<Undetermined>,
    /// What to do about them (empty when every parameter is determined).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub advice: String,
}

/// A free parameter the data do not determine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Undetermined {
    /// Parameter name.
    pub name: String,
    /// Why, with the numbers.
    pub reason: String,
}

impl IdentifiabilitySummary {
    /// Whether parameter `name` is undetermined.
    pub fn is_undetermined(&self, name: &str) -> bool {
        self.undetermined.iter().any(|u| u.name == name)
    }
}

/// The fit's force re-computed on a refined discretization and the parameter shift it
/// implies (shown in the Markdown's `## Discretization error`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DiscretizationSummary {
    /// The refined mesh and steps, described.
    pub refined: String,
    /// RMS of the force change / F_max.
    pub rms_rel: f64,
    /// Largest force change (N).
    pub max_abs: f64,
    /// Parameter shift per law parameter (`None`: held or undetermined).
    pub shift: Vec<Option<f64>>,
    /// Wall time of the refined run (s).
    pub seconds: f64,
}

/// Origin of the measured curve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Source {
    /// Data file name as given by the user.
    pub file: String,
    /// Test (indent) name or number within the file.
    pub test: String,
    /// Instrument, tip and other metadata as name/value pairs, shown in this order.
    pub metadata: Vec<NameValue>,
}

/// A name/value pair of metadata ("tip", "Berkovich, 65.3°").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NameValue {
    /// Name.
    pub name: String,
    /// Value, already formatted with its unit.
    pub value: String,
}

impl NameValue {
    /// A name/value pair.
    pub fn new(name: impl Into<String>, value: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            value: value.into(),
        }
    }
}

/// Which bound an identified value sits on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BoundHit {
    /// At (or within the optimizer's tolerance of) the lower bound.
    Lower,
    /// At (or within the optimizer's tolerance of) the upper bound.
    Upper,
}

/// One law parameter: start, identified value, bounds, uncertainty.
///
/// `start`, `value`, `lower`, `upper` and `std_dev` are in internal units (MPa, MPa s,
/// ...); `unit` says how the Markdown shows them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Parameter {
    /// Symbol in ASCII ("E", "nu", "eta", "K", "m", "sY").
    pub name: String,
    /// Display unit (e.g. GPa with factor 1e-3 for E).
    pub unit: DisplayUnit,
    /// Start value of the optimization.
    pub start: f64,
    /// Final (identified) value; equals `start` for a fixed parameter.
    pub value: f64,
    /// Lower bound, `None` if unbounded below.
    pub lower: Option<f64>,
    /// Upper bound, `None` if unbounded above.
    pub upper: Option<f64>,
    /// Whether the final value is at a bound (the caller decides with its tolerance).
    pub at_bound: Option<BoundHit>,
    /// `true` if the parameter was held fixed (not identified).
    pub fixed: bool,
    /// Standard deviation of the identified value (internal units), if known.
    pub std_dev: Option<f64>,
}

/// Correlation matrix of (a subset of) the parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Correlation {
    /// Parameter names labelling rows and columns.
    pub names: Vec<String>,
    /// Row-major square matrix, `matrix[i][j]` = corr(names\[i\], names\[j\]).
    pub matrix: Vec<Vec<f64>>,
}

/// Optimizer outcome and work done.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Convergence {
    /// Why the optimizer stopped, in words ("gradient norm below 1e-8").
    pub stop_reason: String,
    /// Number of optimizer iterations.
    pub iterations: usize,
    /// Number of direct (forward) solves.
    pub forward_solves: usize,
    /// Number of adjoint solves (gradient evaluations).
    pub adjoint_solves: usize,
    /// Wall-clock time of the identification, seconds.
    pub wall_time_s: f64,
    /// Whether the optimizer met a convergence criterion (`None`: not stated).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub converged: Option<bool>,
}

/// One preprocessing step applied to the measured curve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PreprocessingStep {
    /// Short name ("zero-point", "thermal drift", "resample").
    pub name: String,
    /// What was done, with the numbers ("shifted h by -12.3 nm").
    pub description: String,
}

impl PreprocessingStep {
    /// A preprocessing step.
    pub fn new(name: impl Into<String>, description: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            description: description.into(),
        }
    }
}

/// What a fit compares with the data: the force (the punch driven by depth, the default)
/// or the depth (load control: the force prescribed, docs/theory.md §13).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Observable {
    /// The force is fitted (N); the depth is prescribed.
    #[default]
    Force,
    /// The depth is fitted (mm); the force is prescribed.
    Depth,
}

impl Observable {
    /// "force" or "depth".
    pub fn name(self) -> &'static str {
        match self {
            Observable::Force => "force",
            Observable::Depth => "depth",
        }
    }

    /// The symbol: "F" or "h".
    pub fn symbol(self) -> &'static str {
        match self {
            Observable::Force => "F",
            Observable::Depth => "h",
        }
    }

    /// Whether this is the default, [`Observable::Force`] (serde skips it).
    pub fn is_force(&self) -> bool {
        *self == Observable::Force
    }
}

/// Measured and simulated curves on the same time grid (internal units: s, mm, N).
///
/// The series `f_data`, `f_start` and `f_final` are the *observable's* ([`Curves::observable`]),
/// `h` the prescribed input's: under [`Observable::Force`] (depth control) `h` is the
/// prescribed depth (mm) and the `f_*` series are forces (N); under [`Observable::Depth`]
/// (load control) `h` is the force (N) at the result (the prescribed force on the
/// load-controlled steps) and the `f_*` series are depths (mm). [`Curves::depth_force`]
/// gives the (depth, force) pairs of a series whichever is observed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Curves {
    /// What is fitted: the force (default, not serialized) or the depth.
    #[serde(default, skip_serializing_if = "Observable::is_force")]
    pub observable: Observable,
    /// How depths are shown (see [`DisplayUnit::auto_depth`]).
    pub depth_unit: DisplayUnit,
    /// How forces are shown (see [`DisplayUnit::auto_force`]).
    pub force_unit: DisplayUnit,
    /// Time, s.
    pub t: Vec<f64>,
    /// The prescribed series: the depth (mm), or under [`Observable::Depth`] the force (N).
    pub h: Vec<f64>,
    /// The measured observable: force (N), or depth (mm) under [`Observable::Depth`].
    pub f_data: Vec<f64>,
    /// The simulated observable with the start parameters (`None` if not computed).
    pub f_start: Option<Vec<f64>>,
    /// The simulated observable with the identified parameters.
    pub f_final: Vec<f64>,
}

impl Curves {
    /// Curves with depth and force units chosen from the data
    /// ([`DisplayUnit::auto_depth`], [`DisplayUnit::auto_force`]).
    pub fn with_auto_units(
        t: Vec<f64>,
        h: Vec<f64>,
        f_data: Vec<f64>,
        f_start: Option<Vec<f64>>,
        f_final: Vec<f64>,
    ) -> Self {
        let max_abs = |v: &[f64]| {
            v.iter()
                .filter(|x| x.is_finite())
                .fold(0.0_f64, |m, x| m.max(x.abs()))
        };
        Self {
            observable: Observable::Force,
            depth_unit: DisplayUnit::auto_depth(max_abs(&h)),
            force_unit: DisplayUnit::auto_force(max_abs(&f_data)),
            t,
            h,
            f_data,
            f_start,
            f_final,
        }
    }

    /// Load-controlled curves ([`Observable::Depth`]): `force` the force at the result (N),
    /// `h_data`, `h_start`, `h_final` the measured and simulated depths (mm); units chosen
    /// from the force and the measured depth.
    pub fn depth_observed(
        t: Vec<f64>,
        force: Vec<f64>,
        h_data: Vec<f64>,
        h_start: Option<Vec<f64>>,
        h_final: Vec<f64>,
    ) -> Self {
        let max_abs = |v: &[f64]| {
            v.iter()
                .filter(|x| x.is_finite())
                .fold(0.0_f64, |m, x| m.max(x.abs()))
        };
        Self {
            observable: Observable::Depth,
            depth_unit: DisplayUnit::auto_depth(max_abs(&h_data)),
            force_unit: DisplayUnit::auto_force(max_abs(&force)),
            t,
            h: force,
            f_data: h_data,
            f_start: h_start,
            f_final: h_final,
        }
    }

    /// The display unit of the observable (the force's or the depth's).
    pub fn observed_unit(&self) -> &DisplayUnit {
        match self.observable {
            Observable::Force => &self.force_unit,
            Observable::Depth => &self.depth_unit,
        }
    }

    /// The display unit of the prescribed series `h`.
    pub fn prescribed_unit(&self) -> &DisplayUnit {
        match self.observable {
            Observable::Force => &self.depth_unit,
            Observable::Depth => &self.force_unit,
        }
    }

    /// The (depth, force) series of one observable series (`f_data`, `f_start` or
    /// `f_final`) beside `h`: `(h, series)` when the force is observed, `(series, h)` when
    /// the depth is.
    pub fn depth_force<'a>(&'a self, series: &'a [f64]) -> (&'a [f64], &'a [f64]) {
        match self.observable {
            Observable::Force => (&self.h, series),
            Observable::Depth => (series, &self.h),
        }
    }

    /// Checks that all series have the length of `t`.
    ///
    /// # Errors
    /// [`ReportError::Length`] naming the first series that differs.
    pub fn check_lengths(&self) -> Result<(), ReportError> {
        let n = self.t.len();
        let mut series: Vec<(&'static str, usize)> = vec![
            ("curves.h", self.h.len()),
            ("curves.f_data", self.f_data.len()),
            ("curves.f_final", self.f_final.len()),
        ];
        if let Some(s) = &self.f_start {
            series.push(("curves.f_start", s.len()));
        }
        for (what, got) in series {
            if got != n {
                return Err(ReportError::Length {
                    what,
                    expected: n,
                    got,
                });
            }
        }
        Ok(())
    }
}

/// One optimizer iteration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IterationRecord {
    /// Iteration number (0 = start point).
    pub iteration: usize,
    /// Cost J (least-squares force misfit).
    pub cost: f64,
    /// Norm of the gradient of J (in the optimizer's scaled variables), if known.
    pub grad_norm: Option<f64>,
    /// Values of all parameters, same order as [`Report::parameters`], internal units.
    pub params: Vec<f64>,
}

/// A figure file to link from the Markdown.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FigureLink {
    /// Caption / alt text.
    pub caption: String,
    /// Path relative to the Markdown file.
    pub path: String,
}

impl FigureLink {
    /// A figure link.
    pub fn new(caption: impl Into<String>, path: impl Into<String>) -> Self {
        Self {
            caption: caption.into(),
            path: path.into(),
        }
    }
}

impl Report {
    /// What makes the result less than it looks, one clause each (empty when nothing):
    /// the stop when not converged, systematic residuals, parameters the discretization
    /// moves by more than their standard deviation, undetermined parameters, values at a
    /// bound. The Markdown's top and every force figure show them.
    pub fn caveats(&self) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(converged) = self.convergence.converged
            && !converged
        {
            out.push(format!("NOT converged ({})", self.convergence.stop_reason));
        }
        if let Some(a) = &self.adequacy
            && a.verdict == Verdict::Systematic
        {
            // the verdict with the tests that fired and their thresholds
            out.push(format!(
                "{}: the σ assume a law that fits",
                a.short().trim_start_matches("adequacy: ")
            ));
        }
        if let Some(d) = &self.discretization {
            let moved: Vec<String> =
                self.parameters
                    .iter()
                    .zip(&d.shift)
                    .filter_map(|(p, s)| {
                        let (s, sd) = ((*s)?, p.std_dev?);
                        (!p.fixed && sd > 0.0 && s.abs() > sd && !self.is_undetermined(&p.name))
                            .then(|| {
                                format!(
                                    "{} by {} σ",
                                    p.name,
                                    crate::units::fmt_sig_n(s.abs() / sd, 2)
                                )
                            })
                    })
                    .collect();
            if !moved.is_empty() {
                out.push(format!(
                    "discretization error beyond σ: a refined mesh moves {}",
                    moved.join(", ")
                ));
            }
        }
        let undetermined: Vec<&str> = self
            .parameters
            .iter()
            .filter(|p| !p.fixed && self.is_undetermined(&p.name))
            .map(|p| p.name.as_str())
            .collect();
        if !undetermined.is_empty() {
            let determined = self
                .parameters
                .iter()
                .any(|p| !p.fixed && !self.is_undetermined(&p.name));
            out.push(format!(
                "undetermined: {}{}",
                undetermined.join(", "),
                match (determined, undetermined.len()) {
                    (false, _) => "",
                    (true, 1) => " (the other σ hold it fixed: conditional, can be far too small)",
                    (true, _) => {
                        " (the other σ hold them fixed: conditional, can be far too small)"
                    }
                }
            ));
        }
        let bound: Vec<String> = self
            .parameters
            .iter()
            .filter(|p| !p.fixed)
            .filter_map(|p| {
                p.at_bound.map(|b| {
                    format!(
                        "{} at its {} bound",
                        p.name,
                        if b == BoundHit::Lower {
                            "lower"
                        } else {
                            "upper"
                        }
                    )
                })
            })
            .collect();
        if !bound.is_empty() {
            out.push(bound.join(", "));
        }
        out
    }

    /// The report as one pretty-printed JSON object.
    ///
    /// Non-finite numbers become `null` (JSON has no NaN); such a report does not read
    /// back with [`Report::from_json`]. Finite numbers read back bit for bit.
    ///
    /// # Errors
    /// [`ReportError::Json`] if serialization fails.
    pub fn to_json(&self) -> Result<String, ReportError> {
        serde_json::to_string_pretty(self).map_err(|e| ReportError::Json(e.to_string()))
    }

    /// A report read back from [`Report::to_json`].
    ///
    /// # Errors
    /// [`ReportError::Json`] if the text is not a report.
    pub fn from_json(text: &str) -> Result<Self, ReportError> {
        serde_json::from_str(text).map_err(|e| ReportError::Json(e.to_string()))
    }
}
