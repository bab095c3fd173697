//! `indentify.analyze`, `indentify.calibrate` and `indentify.first_guess`: the Oliver-Pharr
//! analysis, the tip calibration and the start values from the analysis
//! (`indentify_study::analyze`, `indentify_study::start_from_analysis`), returning dicts
//! with the keys of `indentify analyze --json` and `indentify calibrate --json` (internal
//! units: N, mm, N/mm, MPa, s).

use indentify_study::FitRange;
use indentify_study::analyze::{self as study_analyze, AnalyzeOptions, CalibrateOptions};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

use crate::convert::{self, config_source, path_arg, sets_arg, type_name};
use crate::errors::{config_error, study_error};

/// The tip: a name (`berkovich`, `cone:70.3`, `sphere:10` (radius in µm), `flat:50`) or a
/// tip file of `calibrate` (a path ending in `.ron`).
fn tip_arg(tip: &Bound<'_, PyAny>) -> PyResult<indentify_study::Tip> {
    let text: Option<String> = tip.extract().ok();
    match text {
        Some(t) if !t.ends_with(".ron") => {
            study_analyze::tip_from_name(&t).map_err(|e| config_error(format!("tip: {e}")))
        }
        _ => {
            let p = path_arg(tip, "tip")?;
            study_analyze::read_tip(&p).map_err(study_error)
        }
    }
}

fn fit_range_arg(v: Option<(f64, f64)>) -> PyResult<Option<FitRange>> {
    Ok(v.map(|(lower, upper)| FitRange { lower, upper }))
}

/// The Oliver-Pharr (ISO 14577) analysis of every test of an instrument file (or `test`,
/// from 1): a dict with the keys of `indentify analyze --json` (per test `E`, `H`, `Er`
/// in MPa, `S` in N/mm, `hc`, `hmax` in mm, `Fmax` in N, every unloading, the
/// preprocessing, the vendor's values; `tip.modulus` the tip's own modulus). `tip` is a
/// name (`"berkovich"`, `"cone:70.3"`, `"sphere:10"` with the radius in µm,
/// `"flat:50"`) or a tip file of `calibrate`; `epsilon` is `"tip"`, `"m"` or a number;
/// `fit_range` is `(lower, upper)` as fractions of `F_max`; `out` writes analysis.json,
/// analysis.csv and the figures there.
#[pyfunction]
#[pyo3(signature = (
    file, *, test=None, tip=None, nu=0.3, epsilon="tip", beta=1.0, fit_range=None,
    zero_point=None, out=None
))]
#[allow(clippy::too_many_arguments)]
pub fn analyze<'py>(
    py: Python<'py>,
    file: &Bound<'py, PyAny>,
    test: Option<usize>,
    tip: Option<&Bound<'py, PyAny>>,
    nu: f64,
    epsilon: &str,
    beta: f64,
    fit_range: Option<(f64, f64)>,
    zero_point: Option<bool>,
    out: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let mut o = AnalyzeOptions::new(path_arg(file, "file")?);
    o.test = test;
    if let Some(t) = tip.filter(|t| !t.is_none()) {
        o.tip = tip_arg(t)?;
    }
    o.nu = nu;
    o.epsilon = study_analyze::epsilon_from_name(epsilon)
        .map_err(|e| config_error(format!("epsilon: {e}")))?;
    o.beta = beta;
    o.fit_range = fit_range_arg(fit_range)?;
    o.zero_point = zero_point;
    o.out = match out.filter(|o| !o.is_none()) {
        Some(p) => Some(path_arg(p, "out")?),
        None => None,
    };
    let r = py.detach(|| study_analyze::run(&o)).map_err(study_error)?;
    convert::to_python(py, &r)
}

/// Calibrates the frame compliance and the ISO area function on a reference of known
/// Young's `modulus` (MPa: fused silica 72000) and Poisson's ratio `nu`: a dict with the
/// keys of `indentify calibrate --json` (`tip` the calibrated tip, `compliance`,
/// `compliance_used` in mm/N, `area`, `er`, `skipped`); `out` writes the tip file
/// (`analyze(..., tip=out)` and `punch: Calibrated(file: ...)` read it). `tests` selects
/// tests (from 1); `compliance` (mm/N) replaces the fitted one.
#[pyfunction]
#[pyo3(signature = (
    file, *, modulus, nu, out=None, tests=None, compliance=None, terms=3, beta=1.0,
    fit_range=None
))]
#[allow(clippy::too_many_arguments)]
pub fn calibrate<'py>(
    py: Python<'py>,
    file: &Bound<'py, PyAny>,
    modulus: f64,
    nu: f64,
    out: Option<&Bound<'py, PyAny>>,
    tests: Option<Vec<usize>>,
    compliance: Option<f64>,
    terms: usize,
    beta: f64,
    fit_range: Option<(f64, f64)>,
) -> PyResult<Bound<'py, PyAny>> {
    let mut o = CalibrateOptions::new(path_arg(file, "file")?, modulus, nu);
    o.out = match out.filter(|o| !o.is_none()) {
        Some(p) => Some(path_arg(p, "out")?),
        None => None,
    };
    o.tests = tests;
    o.compliance = compliance;
    o.terms = terms;
    o.beta = beta;
    o.fit_range = fit_range_arg(fit_range)?;
    let r = py
        .detach(|| study_analyze::calibrate(&o))
        .map_err(study_error)?;
    convert::to_python(py, &r)
}

/// The start values of a configuration's free parameters from the Oliver-Pharr analysis of
/// its record (or of `data`, a record file): a dict `{"starts": {name: value}, "op": {...},
/// "notes": [...]}`. `identify(config, start="oliver-pharr")` starts from these.
#[pyfunction]
#[pyo3(signature = (config=None, data=None, sets=None))]
pub fn first_guess<'py>(
    py: Python<'py>,
    config: Option<&Bound<'py, PyAny>>,
    data: Option<&Bound<'py, PyAny>>,
    sets: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let s = starts(config, data, sets)?;
    let value = serde_json::json!({
        "starts": s.starts.iter().cloned().collect::<serde_json::Map<String, serde_json::Value>>(),
        "op": s.guess.op,
        "notes": s.guess.notes,
    });
    convert::from_json(py, &value)
}

/// The analysis' starts as `(name, value)` (what `start="oliver-pharr"` uses).
pub fn starts(
    config: Option<&Bound<'_, PyAny>>,
    data: Option<&Bound<'_, PyAny>>,
    sets: Option<&Bound<'_, PyAny>>,
) -> PyResult<StartsJson> {
    let source = config_source(config)?;
    let sets = sets_arg(sets)?;
    let data = match data.filter(|d| !d.is_none()) {
        None => None,
        Some(d) if d.extract::<String>().is_ok() || d.hasattr("__fspath__")? => {
            Some(path_arg(d, "data")?)
        }
        Some(d) => {
            return Err(PyTypeError::new_err(format!(
                "data: the Oliver-Pharr start needs a record file (a path), got {}",
                type_name(d)
            )));
        }
    };
    let s = indentify_study::start_from_analysis::starts(&source, &sets, data.as_deref())
        .map_err(study_error)?;
    Ok(StartsJson {
        starts: s
            .starts
            .into_iter()
            .map(|(n, v)| (n, serde_json::json!(v)))
            .collect(),
        guess: s.guess,
    })
}

/// [`starts`]' result.
pub struct StartsJson {
    /// `(name, value)` of the free parameters.
    pub starts: Vec<(String, serde_json::Value)>,
    /// The guess.
    pub guess: indentify_study::first_guess::FirstGuess,
}
