//! The Python package `indentify`: read instrument records, simulate indentation tests,
//! compute the misfit gradient and identify constitutive parameters from Python, with
//! numpy arrays in and out (float64; units N, mm, s, MPa).
//!
//! Every function maps its arguments onto the study layer ([`indentify_study`]), as the
//! CLI does, and runs it with the GIL released, so several calls run in parallel from
//! Python threads. An identification's `progress` callable is called with the GIL held
//! after every iteration; a Ctrl-C (SIGINT) is noticed there, stops the run after its
//! iteration and raises `KeyboardInterrupt`. The study layer's errors become
//! `indentify.ConfigError`, `DataError`, `SolverError` or `IoError` (all subclasses of
//! `indentify.Error`) with the CLI's whole message chain.
//!
//! Built by maturin (`pip install ./python`); the type stub is `python/indentify.pyi`.

mod analysis;
mod convert;
mod errors;
mod results;

use std::path::PathBuf;

use indentify_study::config::{MethodName, NoiseSetting, Overrides};
use indentify_study::design::{self as study_design, DesignOptions};
use indentify_study::gradient::{self as study_gradient, GradientOptions};
use indentify_study::identify::{self as study_identify, IdentifyOptions, Observer, RunInfo};
use indentify_study::simulate::{self as study_simulate, SimulateOptions};
use indentify_study::synthetic::{self, MapOptions};
use indentify_study::{Cancel, IterationRecord};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert::{array, config_source, data_arg, path_arg, sets_arg, type_name};
use crate::errors::{config_error, data_errors, solver_error, study_error};
use crate::results::{GradientResult, IdentifyResult, Record, iteration_dict};

/// Reads one instrumented-indentation record and preprocesses it.
///
/// `path`: the file (CSV, Anton Paar single or multi-test TXT, Hysitron TXT or .hld).
/// `format`: None or "auto" detects it; else "csv", "anton-paar", "anton-paar-multi",
/// "hysitron-txt", "hld", "micro-materials". `test`: the 1-based test of a multi-test file.
/// `preprocessing`: None for the defaults (zero point and segments), False for none, or a
/// dict with the `Preprocessing` structure of a configuration's `data.preprocessing`
/// (`drift`, `zero_point`, `compliance`, `segments`, `resample`), e.g.
/// `{"resample": {"n": 60}}`. Returns a `Record` (t in s, h in mm, F in N).
#[pyfunction]
#[pyo3(signature = (path, format=None, test=None, preprocessing=None))]
fn read_record(
    py: Python<'_>,
    path: &Bound<'_, PyAny>,
    format: Option<&str>,
    test: Option<i128>,
    preprocessing: Option<&Bound<'_, PyAny>>,
) -> PyResult<Record> {
    let path = path_arg(path, "path")?;
    let test = test
        .map(|t| count(t, "test", 1).map(|t| t as usize))
        .transpose()?;
    let format = match format {
        None => indentify_study::records::Format::Auto,
        Some(name) => indentify_study::records::Format::from_name(name).ok_or_else(|| {
            config_error(format!(
                "unknown format `{name}`: expected one of auto, csv, anton-paar, \
                 anton-paar-multi, hysitron-txt, hld, micro-materials"
            ))
        })?,
    };
    let prep = match preprocessing {
        None => Some(indentify_study::records::Preprocessing::default()),
        Some(p) if p.is_none() => Some(indentify_study::records::Preprocessing::default()),
        Some(p) if p.is_exact_instance_of::<pyo3::types::PyBool>() => {
            if p.is_truthy()? {
                Some(indentify_study::records::Preprocessing::default())
            } else {
                None
            }
        }
        Some(p) => {
            let value = convert::to_json(p, "preprocessing")?;
            Some(serde_json::from_value(value).map_err(|e| {
                config_error(format!(
                    "invalid preprocessing: {e}\n(expected a dict with the keys drift, \
                     zero_point, compliance, segments, resample, as in a configuration's \
                     data.preprocessing)"
                ))
            })?)
        }
    };
    let opts = indentify_study::records::ReadOptions { format, test };
    let read = py.detach(|| -> Result<_, Vec<String>> {
        let shown = path.display().to_string();
        let bytes = std::fs::read(&path).map_err(|e| {
            vec![
                format!("cannot read the data file `{shown}`"),
                e.to_string(),
            ]
        })?;
        let raw = indentify_study::records::read_one(&bytes, &shown, &opts)
            .map_err(|e| vec![format!("cannot read the record `{shown}`"), e.to_string()])?;
        match &prep {
            None => Ok((raw, Vec::new())),
            Some(p) => indentify_study::records::apply(&raw, p).map_err(|e| {
                vec![
                    format!("cannot preprocess `{shown}` (preprocessing)"),
                    e.to_string(),
                ]
            }),
        }
    });
    let (record, applied) = read.map_err(data_errors)?;
    Record::new(py, record, &applied)
}

/// Simulates the configuration's indentation test (the direct problem).
///
/// `config`: a path (str or os.PathLike) to a RON file, RON text (a string containing
/// "(" that is not an existing file's path), a dict with the RON structure (relative data
/// paths from the working directory), or None for the embedded R1 example. `sets`: a
/// dict of dotted paths to values overriding the configuration, e.g.
/// `{"law.E": 25000, "specimen.nr": 8}`. `noise`: a multiplicative noise amplitude
/// (F (1 + noise xi), xi uniform in [-1, 1]) with `seed`.
///
/// Returns a dict of float64 arrays at the schedule times: `t` (s), `h` (mm), `F` (N),
/// `a` (contact radius, mm). A step that fails even after cutting raises `SolverError`
/// whose `partial` attribute holds the curve up to the failure. `test`: the 1-based test
/// of a joint configuration (`tests: [...]`), required for one.
#[pyfunction]
#[pyo3(signature = (config=None, sets=None, noise=None, seed=1, test=None))]
fn simulate<'py>(
    py: Python<'py>,
    config: Option<&Bound<'py, PyAny>>,
    sets: Option<&Bound<'py, PyAny>>,
    noise: Option<f64>,
    seed: i128,
    test: Option<i128>,
) -> PyResult<Bound<'py, PyDict>> {
    let seed = count(seed, "seed", 0)?;
    let mut opts = SimulateOptions::new(config_source(config)?);
    opts.sets = sets_arg(sets)?;
    opts.test = test
        .map(|t| count(t, "test", 1).map(|t| t as usize))
        .transpose()?;
    opts.noise = noise.map(|a| (a, seed));
    let outcome = py
        .detach(|| study_simulate::run(&opts))
        .map_err(study_error)?;
    py.check_signals()?;
    let rows = &outcome.rows;
    let col = |f: fn(&indentify_study::output::CurveRow) -> f64| -> Vec<f64> {
        rows.iter().map(f).collect()
    };
    let d = PyDict::new(py);
    d.set_item("t", array(py, &col(|r| r.t)))?;
    d.set_item("h", array(py, &col(|r| r.h)))?;
    d.set_item("F", array(py, &col(|r| r.f)))?;
    d.set_item("a", array(py, &col(|r| r.a)))?;
    if let Some(why) = outcome.failure {
        let err = solver_error(format!(
            "the simulation of `{}` stopped early: {why}",
            outcome.config
        ));
        err.value(py).setattr("partial", d)?;
        return Err(err);
    }
    Ok(d)
}

/// The misfit `J = 1/2 sum_i (F_i - F_data_i)^2` (N^2) of the configuration's law values
/// against data, and its exact gradient `dJ/dc` by the discrete adjoint.
///
/// `data`: None (the configuration's `data` record), a path to a curve (CSV with `t`,
/// `F`) or record, a `Record`, a dict with `t`, `F` (and `h`) arrays, or an array of shape
/// (n, 2) / (n, 3). Returns a `GradientResult` (`J`, `gradient` {name: dJ/dc}, ...) that
/// unpacks as `J, grad = indentify.gradient(...)`. `test`: the 1-based test of a joint
/// configuration, required for one.
#[pyfunction]
#[pyo3(signature = (config=None, data=None, sets=None, test=None))]
fn gradient(
    py: Python<'_>,
    config: Option<&Bound<'_, PyAny>>,
    data: Option<&Bound<'_, PyAny>>,
    sets: Option<&Bound<'_, PyAny>>,
    test: Option<i128>,
) -> PyResult<GradientResult> {
    let (data, _temp) = data_arg(data)?;
    let mut opts = GradientOptions::new(config_source(config)?, data);
    opts.sets = sets_arg(sets)?;
    opts.test = test
        .map(|t| count(t, "test", 1).map(|t| t as usize))
        .transpose()?;
    let outcome = py
        .detach(|| study_gradient::run(&opts))
        .map_err(study_error)?;
    py.check_signals()?;
    GradientResult::new(py, &outcome)
}

/// Reports iterations to a Python callable and notices Ctrl-C.
struct PyObserver {
    callback: Option<Py<PyAny>>,
    names: Vec<&'static str>,
    cancel: Cancel,
    error: Option<PyErr>,
}

impl Observer for PyObserver {
    fn started(&mut self, info: &RunInfo) {
        self.names = info.names.clone();
    }

    fn iteration(&mut self, record: &IterationRecord) {
        if self.error.is_some() {
            return;
        }
        let outcome = Python::attach(|py| -> PyResult<()> {
            if let Some(cb) = &self.callback {
                cb.call1(py, (iteration_dict(py, &self.names, record)?,))?;
            }
            py.check_signals()
        });
        if let Err(e) = outcome {
            self.error = Some(e);
            self.cancel.raise();
        }
    }
}

/// Identifies the constitutive parameters of a configuration from data.
///
/// `config`, `sets`: as for `simulate`. `data`: as for `gradient`; None fits the
/// configuration's `data` record or, without one, its own curve simulated at its `law`
/// values (synthesized data, with `noise` and `seed`). `progress`: a callable receiving a
/// dict after every iteration (`iteration`, `params`, `J`, `grad_norm`, solve counts,
/// `seconds`); an exception it raises stops the run and is raised. `out`: a report
/// directory (result.json, history.csv, fit.csv, report and figures), `force` replacing
/// another run's. `method` ("bfgs", "lbfgs", "lbfgsb", "lm"), `max_iterations`, `free`
/// (names), `fixed` ({name: value or None}) and `start` ({name: value}, "oliver-pharr":
/// the free parameters' starts from the Oliver-Pharr analysis of the record, as
/// `first_guess`, or "closed-form": those a closed form covers from the pre-fit of the
/// curve's loading and hold, `Result.start`) override the configuration's `identify` section. `noise_model` replaces `identify.noise`, what the
/// standard deviations assume about the force noise: "Residual" (one variance, the
/// default), "RelativeEstimated", {"Relative": f} (standard deviation f |F|) or
/// {"Absolute": s} (N). A joint configuration (`tests: [...]`) is fitted as a whole;
/// `Result.tests` then holds each test's curves and fit quality.
///
/// Returns a `Result`. Ctrl-C stops the run after its current iteration and raises
/// `KeyboardInterrupt`.
#[pyfunction]
#[pyo3(signature = (
    config=None, data=None, sets=None, progress=None, *, out=None, force=false, method=None,
    max_iterations=None, free=None, fixed=None, start=None, noise=None, seed=1,
    noise_model=None, refine=true
))]
#[allow(clippy::too_many_arguments)]
fn identify(
    py: Python<'_>,
    config: Option<&Bound<'_, PyAny>>,
    data: Option<&Bound<'_, PyAny>>,
    sets: Option<&Bound<'_, PyAny>>,
    progress: Option<&Bound<'_, PyAny>>,
    out: Option<&Bound<'_, PyAny>>,
    force: bool,
    method: Option<&str>,
    max_iterations: Option<i128>,
    free: Option<&Bound<'_, PyAny>>,
    fixed: Option<&Bound<'_, PyAny>>,
    start: Option<&Bound<'_, PyAny>>,
    noise: Option<f64>,
    seed: i128,
    noise_model: Option<&Bound<'_, PyAny>>,
    refine: bool,
) -> PyResult<IdentifyResult> {
    let seed = count(seed, "seed", 0)?;
    let max_iterations = max_iterations
        .map(|n| count(n, "max_iterations", 0).map(|n| n as usize))
        .transpose()?;
    let callback = match progress.filter(|p| !p.is_none()) {
        Some(p) if p.is_callable() => Some(p.clone().unbind()),
        Some(p) => {
            return Err(PyTypeError::new_err(format!(
                "progress: expected a callable, got {}",
                type_name(p)
            )));
        }
        None => None,
    };
    let data_path =
        data.filter(|d| d.extract::<String>().is_ok() || d.hasattr("__fspath__").unwrap_or(false));
    let (data, _temp) = data_arg(data)?;
    let mut opts = IdentifyOptions::new(config_source(config)?);
    opts.sets = sets_arg(sets)?;
    opts.data = data;
    opts.out = match out.filter(|o| !o.is_none()) {
        Some(o) => Some(path_arg(o, "out")?),
        None => None,
    };
    opts.force = force;
    opts.figures = opts.out.is_some();
    opts.refine = refine;
    opts.noise = noise.map(|a| (a, seed));
    let start = start.filter(|s| !s.is_none());
    opts.closed_form_start =
        start.is_some_and(|s| s.extract::<String>().is_ok_and(|t| t == "closed-form"));
    opts.overrides = Overrides {
        free: names_arg(free, "free")?,
        fixed: fixed_arg(fixed)?,
        starts: match start {
            None => Vec::new(),
            Some(_) if opts.closed_form_start => Vec::new(),
            // the free parameters' starts from the Oliver-Pharr analysis of the record
            Some(s) if s.extract::<String>().is_ok_and(|t| t == "oliver-pharr") => {
                analysis::starts(config, data_path, sets)?
                    .starts
                    .into_iter()
                    .filter_map(|(n, v)| v.as_f64().map(|v| (n, v)))
                    .collect()
            }
            Some(s) => s
                .extract::<std::collections::HashMap<String, f64>>()
                .map_err(|_| {
                    PyTypeError::new_err(format!(
                        "start: expected a dict {{name: value}}, \"oliver-pharr\" or \"closed-form\", got {}",
                        type_name(s)
                    ))
                })?
                .into_iter()
                .collect(),
        },
        method: match method {
            None => None,
            Some(m) => {
                Some(MethodName::parse(m).map_err(|e| config_error(format!("method: {e}")))?)
            }
        },
        max_iterations,
        noise: match noise_model.filter(|n| !n.is_none()) {
            None => None,
            Some(n) => Some(noise_setting(n, "noise_model")?),
        },
        bfgs_start: None,
    };
    let cancel = opts.cancel.clone();
    let mut observer = PyObserver {
        callback,
        names: Vec::new(),
        cancel,
        error: None,
    };
    let outcome = py.detach(|| study_identify::run(&opts, &mut observer));
    if let Some(e) = observer.error {
        return Err(e);
    }
    let outcome = outcome.map_err(study_error)?;
    py.check_signals()?;
    IdentifyResult::new(py, &outcome)
}

/// A noise model given as "Residual", "RelativeEstimated", {"Relative": f} or
/// {"Absolute": s}, checked (a stated level must be a finite number > 0).
fn noise_setting(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<NoiseSetting> {
    let allowed = "\"Residual\", \"RelativeEstimated\", {\"Relative\": f} (standard deviation f |F|) \
                   or {\"Absolute\": s} (standard deviation s in N)";
    let value = convert::to_json(obj, what)?;
    let setting: NoiseSetting = serde_json::from_value(value.clone()).map_err(|_| {
        config_error(format!(
            "{what} = {value} is not allowed: expected {allowed}"
        ))
    })?;
    setting
        .check(what)
        .map_err(|e| config_error(format!("{e:#}")))?;
    Ok(setting)
}

/// Ranks the candidate protocols of a configuration's `design` section by the standard
/// deviations they would give at the nominal parameters (the `law` values) under the
/// section's stated noise, from forward sensitivities (no data needed); candidates are
/// evaluated in parallel on `jobs` threads (None: all cores).
///
/// `config`, `sets`: as for `simulate`; `free` (names) and `fixed` ({name: value or None}
/// or a list of names) choose which parameters count, as for `identify`. `out`: a folder
/// for design.json and design.md.
///
/// Returns a dict: `config`, `noise` (in words), `names` (free parameters), `nominal`
/// ({name: value}), `candidates` (in the configuration's order: dicts `name`, `tests`,
/// `n_data`, `std` and `rel_std` ({name: value}, inf when undetermined), `log_det`
/// (-inf when singular), `worst` ((name, relative deviation)), `undetermined`
/// ([(name, reason)]), `condition_number`, `weakest_direction`, `correlation` (numpy p x
/// p)), `rank_d` (candidate indices by decreasing log det, D-optimal) and `rank_worst`
/// (by increasing worst relative deviation), `table` (the CLI's table), `threads`,
/// `seconds`.
#[pyfunction]
#[pyo3(signature = (config=None, sets=None, *, free=None, fixed=None, out=None, jobs=None))]
fn design<'py>(
    py: Python<'py>,
    config: Option<&Bound<'py, PyAny>>,
    sets: Option<&Bound<'py, PyAny>>,
    free: Option<&Bound<'py, PyAny>>,
    fixed: Option<&Bound<'py, PyAny>>,
    out: Option<&Bound<'py, PyAny>>,
    jobs: Option<i128>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut opts = DesignOptions::new(config_source(config)?);
    opts.sets = sets_arg(sets)?;
    opts.overrides = Overrides {
        free: names_arg(free, "free")?,
        fixed: fixed_arg(fixed)?,
        ..Overrides::default()
    };
    opts.out = match out.filter(|o| !o.is_none()) {
        Some(o) => Some(path_arg(o, "out")?),
        None => None,
    };
    opts.jobs = jobs
        .map(|j| count(j, "jobs", 1).map(|j| j as usize))
        .transpose()?;
    let d = py
        .detach(|| study_design::run(&opts))
        .map_err(study_error)?;
    py.check_signals()?;
    let res = PyDict::new(py);
    res.set_item("config", &d.config)?;
    res.set_item("noise", &d.noise)?;
    res.set_item("names", d.names.clone())?;
    let nominal = PyDict::new(py);
    for (n, v) in &d.nominal {
        nominal.set_item(n, v)?;
    }
    res.set_item("nominal", nominal)?;
    let cands = PyList::empty(py);
    for c in &d.candidates {
        let cd = PyDict::new(py);
        cd.set_item("name", &c.name)?;
        cd.set_item("tests", c.tests.clone())?;
        cd.set_item("n_data", c.n_data)?;
        let std = PyDict::new(py);
        let rel = PyDict::new(py);
        for p in &c.params {
            std.set_item(p.name, p.std_dev)?;
            rel.set_item(p.name, p.rel_std_dev)?;
        }
        cd.set_item("std", std)?;
        cd.set_item("rel_std", rel)?;
        cd.set_item("log_det", c.log_det)?;
        cd.set_item("worst", c.worst)?;
        cd.set_item("undetermined", c.undetermined.clone())?;
        cd.set_item("condition_number", c.condition_number)?;
        cd.set_item("weakest_direction", c.weakest_direction.clone())?;
        let corr = if c.correlation.is_empty() {
            numpy::PyArray2::<f64>::zeros(py, [0, 0], false).into_any()
        } else {
            numpy::PyArray2::from_vec2(py, &c.correlation)
                .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?
                .into_any()
        };
        cd.set_item("correlation", corr)?;
        cands.append(cd)?;
    }
    res.set_item("candidates", cands)?;
    res.set_item("rank_d", d.rank_d.clone())?;
    res.set_item("rank_worst", d.rank_worst.clone())?;
    res.set_item("table", d.table())?;
    res.set_item("threads", d.threads)?;
    res.set_item("seconds", d.seconds)?;
    res.set_item(
        "files",
        d.files
            .iter()
            .map(|f| f.display().to_string())
            .collect::<Vec<_>>(),
    )?;
    Ok(res)
}

/// `fixed=`: a dict {name: value or None} or a list of names.
fn fixed_arg(fixed: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<(String, Option<f64>)>> {
    Ok(match fixed.filter(|f| !f.is_none()) {
        None => Vec::new(),
        Some(f) => match f.extract::<Vec<String>>() {
            Ok(names) if !f.is_instance_of::<pyo3::types::PyString>() => {
                names.into_iter().map(|n| (n, None)).collect()
            }
            _ if f.is_instance_of::<PyDict>() => {
                let mut out = Vec::new();
                for (k, v) in f.cast::<PyDict>()?.iter() {
                    let name: String = k.extract().map_err(|_| {
                        PyTypeError::new_err(format!(
                            "fixed: the keys are parameter names (str), got {} {}",
                            type_name(&k),
                            k.repr().map_or_else(|_| "?".into(), |r| r.to_string())
                        ))
                    })?;
                    let value = match v.is_none() {
                        true => None,
                        false => Some(v.extract::<f64>().map_err(|_| {
                            PyTypeError::new_err(format!(
                                "fixed[{name:?}] = {}: expected a number (the value to hold \
                                 {name} at) or None (its law value), got {}",
                                v.repr().map_or_else(|_| "?".into(), |r| r.to_string()),
                                type_name(&v)
                            ))
                        })?),
                    };
                    out.push((name, value));
                }
                out
            }
            _ => {
                return Err(PyTypeError::new_err(format!(
                    "fixed: expected a dict {{name: value or None}} or a list of names, got {}",
                    type_name(f)
                )));
            }
        },
    })
}

/// A list of parameter names (`free=`): a list or tuple of str, or one name as a str
/// (`free="E"` is `free=["E"]`).
fn names_arg(obj: Option<&Bound<'_, PyAny>>, what: &str) -> PyResult<Option<Vec<String>>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(None);
    };
    if let Ok(s) = obj.cast::<pyo3::types::PyString>() {
        return Ok(Some(vec![s.to_cow()?.into_owned()]));
    }
    let wrong = || {
        PyTypeError::new_err(format!(
            "{what}: expected a list of parameter names such as [\"E\", \"eta\"] (or one name \
             as a str), got {}",
            type_name(obj)
        ))
    };
    if !(obj.is_instance_of::<PyList>() || obj.is_instance_of::<pyo3::types::PyTuple>()) {
        return Err(wrong());
    }
    let mut names = Vec::new();
    for (i, item) in obj.try_iter()?.enumerate() {
        let item = item?;
        names.push(item.extract::<String>().map_err(|_| {
            PyTypeError::new_err(format!(
                "{what}[{i}] = {}: expected a parameter name (str), got {}",
                item.repr().map_or_else(|_| "?".into(), |r| r.to_string()),
                type_name(&item)
            ))
        })?);
    }
    Ok(Some(names))
}

/// An integer argument that must be at least `min` (0 or 1), as `u64`: a negative or too
/// small one is a `ConfigError` naming the argument and its range (not an
/// `OverflowError` without a name).
fn count(v: i128, what: &str, min: u64) -> PyResult<u64> {
    match u64::try_from(v) {
        Ok(n) if n >= min => Ok(n),
        _ => Err(config_error(format!(
            "{what} = {v} is not allowed: expected an integer {what} >= {min}"
        ))),
    }
}

/// Writes a synthetic two-phase Maxwell map into `dir`: an n x n grid of indents over a
/// round inclusion of phase B (E = 60000 MPa, eta = 8000 MPa s) in a matrix of phase A
/// (E = 20000 MPa, eta = 30000 MPa s), each curve simulated on R1's set-up (`coarse`: an
/// 8 x 8 mesh and 10 steps per segment) with multiplicative `noise` (seed `seed + k` for
/// indent k), as `records/<id>.csv` (t, h, F), `manifest.csv` and `base.ron` (identifies E
/// and eta by Levenberg-Marquardt from a start between the phases).
///
/// Returns a dict: `manifest` and `base` (paths as str), `indents` (a list of dicts `id`,
/// `data` (the record's path), `x`, `y` (mm), `phase` ("A" or "B")) and `phases`
/// ({"A": {"E": ..., "eta": ...}, "B": {...}}).
#[pyfunction]
#[pyo3(signature = (dir, n=10, noise=0.02, seed=1, coarse=false, spacing=0.05))]
fn make_map<'py>(
    py: Python<'py>,
    dir: &Bound<'py, PyAny>,
    n: i128,
    noise: f64,
    seed: i128,
    coarse: bool,
    spacing: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let dir: PathBuf = path_arg(dir, "dir")?;
    let n = count(n, "n", 1)? as usize;
    let seed = count(seed, "seed", 0)?;
    let opts = MapOptions {
        n,
        spacing,
        noise,
        seed,
        coarse,
    };
    let files = py
        .detach(|| synthetic::make_map(&dir, &opts))
        .map_err(study_error)?;
    let d = PyDict::new(py);
    d.set_item("manifest", files.manifest.display().to_string())?;
    d.set_item("base", files.base.display().to_string())?;
    let indents = PyList::empty(py);
    for (id, x, y, phase) in &files.indents {
        let i = PyDict::new(py);
        i.set_item("id", id)?;
        i.set_item(
            "data",
            dir.join("records")
                .join(format!("{id}.csv"))
                .display()
                .to_string(),
        )?;
        i.set_item("x", x)?;
        i.set_item("y", y)?;
        i.set_item("phase", phase.to_string())?;
        indents.append(i)?;
    }
    d.set_item("indents", indents)?;
    let phases = PyDict::new(py);
    for (name, (e, eta)) in [("A", synthetic::PHASE_A), ("B", synthetic::PHASE_B)] {
        let p = PyDict::new(py);
        p.set_item("E", e)?;
        p.set_item("eta", eta)?;
        phases.set_item(name, p)?;
    }
    d.set_item("phases", phases)?;
    Ok(d)
}

/// Reads, overrides and validates a configuration and returns it as a dict with the RON
/// structure (enum variants as `{"Cylinder": {...}}`), ready to modify and pass back as
/// `config`. A relative `data.file` is made absolute against the file's folder.
#[pyfunction]
#[pyo3(signature = (config=None, sets=None))]
fn load_config<'py>(
    py: Python<'py>,
    config: Option<&Bound<'py, PyAny>>,
    sets: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let source = config_source(config)?;
    let sets = sets_arg(sets)?;
    let mut cfg = source.load(&sets).map_err(study_error)?;
    if let Some(d) = &mut cfg.data {
        let p = d.path(cfg.base_dir.as_deref());
        d.file = std::path::absolute(&p).unwrap_or(p).display().to_string();
    }
    convert::to_python(py, &cfg)
}

/// Every registered law with its parameters (the names `sets={"law.NAME": ..}` and
/// `free`/`fixed` take), units, admissible ranges and kinds (hardening and rate forms,
/// lists of terms), as a list of dicts: the data of `indentify laws --json`, generated from
/// the laws registry.
#[pyfunction]
fn laws(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    let list = indentify_study::laws_list::laws().map_err(study_error)?;
    convert::to_python(py, &list)
}

/// The package: functions, result classes and exceptions.
#[pymodule]
fn indentify(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(read_record, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(gradient, m)?)?;
    m.add_function(wrap_pyfunction!(identify, m)?)?;
    m.add_function(wrap_pyfunction!(make_map, m)?)?;
    m.add_function(wrap_pyfunction!(design, m)?)?;
    m.add_function(wrap_pyfunction!(load_config, m)?)?;
    m.add_function(wrap_pyfunction!(laws, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::analyze, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::first_guess, m)?)?;
    m.add_class::<Record>()?;
    m.add_class::<GradientResult>()?;
    m.add_class::<IdentifyResult>()?;
    m.add("Error", py.get_type::<errors::Error>())?;
    m.add("ConfigError", py.get_type::<errors::ConfigError>())?;
    m.add("DataError", py.get_type::<errors::DataError>())?;
    m.add("SolverError", py.get_type::<errors::SolverError>())?;
    m.add("IoError", py.get_type::<errors::IoError>())?;
    Ok(())
}
