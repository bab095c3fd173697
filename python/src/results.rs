//! The result classes handed to Python: [`Record`] (a read instrument record),
//! [`GradientResult`] (`J` and `dJ/dc`) and [`IdentifyResult`] (an identification's
//! parameters, uncertainties, fit and history), their fields numpy arrays, dicts and floats.

use indentify_study::IterationRecord;
use indentify_study::gradient::GradientOutcome;
use indentify_study::identify::IdentifyOutcome;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};

use crate::convert::{array, to_python};

/// An instrumented-indentation record: time `t` (s), depth `h` (mm), force `F` (N) and
/// segment ids, with what the file says about the test (`metadata`) and the preprocessing
/// steps applied (`applied`).
#[pyclass(module = "indentify", frozen)]
pub struct Record {
    /// The test's name (file name, with the test for multi-test files).
    #[pyo3(get)]
    pub name: String,
    pub t: Vec<f64>,
    pub h: Vec<f64>,
    pub f: Vec<f64>,
    pub segment: Option<Vec<u32>>,
    meta: Py<PyAny>,
    applied: Py<PyAny>,
}

impl Record {
    /// The record with its metadata and preprocessing account as Python objects.
    pub fn new(
        py: Python<'_>,
        r: indentify_study::records::Record,
        applied: &[indentify_study::records::Applied],
    ) -> PyResult<Record> {
        Ok(Record {
            meta: to_python(py, &r.meta)?.unbind(),
            applied: to_python(py, &applied)?.unbind(),
            name: r.name,
            t: r.t,
            h: r.h,
            f: r.f,
            segment: r.segment,
        })
    }
}

#[pymethods]
impl Record {
    /// Time (s), float64 array.
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        array(py, &self.t)
    }

    /// Depth into the surface (mm), float64 array.
    #[getter]
    fn h<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        array(py, &self.h)
    }

    /// Force (N), float64 array.
    #[getter(F)]
    fn force<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        array(py, &self.f)
    }

    /// Segment id of each sample (uint32 array), or None when the file gives none and no
    /// segmentation ran.
    #[getter]
    fn segment<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<u32>>> {
        self.segment.as_ref().map(|s| PyArray1::from_slice(py, s))
    }

    /// What the file says about the test: format, instrument, tip, protocol (rates, maximum
    /// load and depth, hold), date, vendor results, ... (a dict; internal units where the
    /// field says converted).
    #[getter]
    fn metadata(&self, py: Python<'_>) -> Py<PyAny> {
        self.meta.clone_ref(py)
    }

    /// The preprocessing steps applied, in order: dicts with `step`, `description` and
    /// `values` (a list of `{name, value, unit}`).
    #[getter]
    fn applied(&self, py: Python<'_>) -> Py<PyAny> {
        self.applied.clone_ref(py)
    }

    /// Number of samples.
    fn __len__(&self) -> usize {
        self.t.len()
    }

    fn __repr__(&self) -> String {
        let max = |v: &[f64]| v.iter().copied().fold(f64::NAN, f64::max);
        format!(
            "Record({:?}, {} samples, t <= {} s, h_max = {:.4e} mm, F_max = {:.4e} N)",
            self.name,
            self.t.len(),
            self.t.last().copied().unwrap_or(f64::NAN),
            max(&self.h),
            max(&self.f)
        )
    }
}

/// The misfit `J = 1/2 sum (F - F_data)^2` (N^2) at the configuration's law values and its
/// gradient `dJ/dc` by the discrete adjoint. Unpacks as `J, gradient = indentify.gradient(...)`.
#[pyclass(module = "indentify", frozen)]
pub struct GradientResult {
    /// The misfit (N^2).
    #[pyo3(get, name = "J")]
    j: f64,
    /// `{name: dJ/dc}` in the law's order (N^2 per parameter unit).
    #[pyo3(get)]
    gradient: Py<PyDict>,
    /// `{name: value}`: the point.
    #[pyo3(get)]
    params: Py<PyDict>,
    /// `{name: unit}`.
    #[pyo3(get)]
    units: Py<PyDict>,
    /// Parameter names in the law's order.
    #[pyo3(get)]
    names: Vec<&'static str>,
    /// Wall time of the forward run (s).
    #[pyo3(get)]
    forward_seconds: f64,
    /// Wall time of the adjoint sweep (s).
    #[pyo3(get)]
    adjoint_seconds: f64,
}

impl GradientResult {
    /// From the study layer's outcome.
    pub fn new(py: Python<'_>, o: &GradientOutcome) -> PyResult<GradientResult> {
        let named = |values: &[f64]| -> PyResult<Py<PyDict>> {
            let d = PyDict::new(py);
            for (n, v) in o.names.iter().zip(values) {
                d.set_item(n, v)?;
            }
            Ok(d.unbind())
        };
        let units = PyDict::new(py);
        for (n, u) in o.names.iter().zip(&o.units) {
            units.set_item(n, u)?;
        }
        Ok(GradientResult {
            j: o.j,
            gradient: named(&o.gradient)?,
            params: named(&o.params)?,
            units: units.unbind(),
            names: o.names.clone(),
            forward_seconds: o.forward_seconds,
            adjoint_seconds: o.adjoint_seconds,
        })
    }
}

#[pymethods]
impl GradientResult {
    /// `(J, gradient)`, for `J, g = indentify.gradient(...)`.
    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let t = PyTuple::new(
            py,
            [
                self.j.into_pyobject(py)?.into_any(),
                self.gradient.bind(py).clone().into_any(),
            ],
        )?;
        Ok(t.try_iter()?.into_any())
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "GradientResult(J={:e}, gradient={})",
            self.j,
            self.gradient
                .bind(py)
                .repr()
                .map_or_else(|_| "?".into(), |r| r.to_string())
        )
    }
}

/// One iteration as a dict: `iteration`, `params` ({name: value}), `J`, `grad_norm`,
/// `forward_solves`, `adjoint_solves`, `sensitivity_solves`, `seconds`.
pub fn iteration_dict<'py>(
    py: Python<'py>,
    names: &[&'static str],
    r: &IterationRecord,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("iteration", r.iteration)?;
    let params = PyDict::new(py);
    for (n, v) in names.iter().zip(&r.params) {
        params.set_item(n, v)?;
    }
    d.set_item("params", params)?;
    d.set_item("J", r.cost)?;
    d.set_item("grad_norm", r.grad_norm)?;
    d.set_item("forward_solves", r.forward_solves)?;
    d.set_item("adjoint_solves", r.adjoint_solves)?;
    d.set_item("sensitivity_solves", r.sensitivity_solves)?;
    d.set_item("seconds", r.seconds)?;
    Ok(d)
}

/// The result of an identification.
#[pyclass(module = "indentify", name = "Result", frozen)]
pub struct IdentifyResult {
    /// `{name: value}` of every law parameter at the end (free and held).
    #[pyo3(get)]
    params: Py<PyDict>,
    /// `{name: standard deviation}` (Gauss-Newton, parameter units); None for a held
    /// parameter or one the data do not determine.
    #[pyo3(get)]
    std: Py<PyDict>,
    /// Correlation matrix of the free parameters (float64, p x p; 0 x 0 without the
    /// identifiability summary).
    #[pyo3(get)]
    correlation: Py<PyAny>,
    /// The names of the correlation matrix's rows and columns.
    #[pyo3(get)]
    correlation_names: Vec<&'static str>,
    /// Whether a convergence criterion was met with every free parameter determined.
    #[pyo3(get)]
    converged: bool,
    /// The free parameters the data do not determine (no deviation, NaN correlations; a
    /// run that stops there is not converged).
    #[pyo3(get)]
    undetermined: Vec<&'static str>,
    /// Why the run stopped, in words.
    #[pyo3(get)]
    stop_reason: String,
    /// The curves at the schedule times: float64 arrays `t` (s), `h` (mm), `F_data`,
    /// `F_fit` (at the result), `F_start` (at the start) (N).
    #[pyo3(get)]
    fit: Py<PyDict>,
    /// One dict per iteration (see the `progress` callback).
    #[pyo3(get)]
    history: Py<PyList>,
    /// Every parameter in detail: dicts with `name`, `unit`, `free`, `start`, `value`,
    /// `lower`, `upper`, `at_lower`, `at_upper`.
    #[pyo3(get)]
    parameters: Py<PyList>,
    /// `{name: bool}`: which parameters were identified.
    #[pyo3(get)]
    free: Py<PyDict>,
    /// `{name: (lower, upper)}` of the free parameters.
    #[pyo3(get)]
    bounds: Py<PyDict>,
    /// The misfit at the end and at the start (N^2).
    #[pyo3(get, name = "J")]
    j: f64,
    /// The misfit at the start (N^2).
    #[pyo3(get, name = "J_start")]
    j_start: f64,
    /// Iterations done.
    #[pyo3(get)]
    iterations: usize,
    /// Forward solves.
    #[pyo3(get)]
    forward_solves: usize,
    /// Adjoint sweeps.
    #[pyo3(get)]
    adjoint_solves: usize,
    /// The optimizer's wall time (s).
    #[pyo3(get)]
    seconds: f64,
    /// The whole pipeline's wall time (set-up, optimizer, fit curves; s).
    #[pyo3(get)]
    wall_seconds: f64,
    /// The law's name.
    #[pyo3(get)]
    law: &'static str,
    /// The method's name.
    #[pyo3(get)]
    method: &'static str,
    /// Where the data came from.
    #[pyo3(get)]
    data: String,
    /// R², RMS (N), relative RMS, largest residual (N) and points of the final fit (a dict;
    /// None when not computable).
    #[pyo3(get)]
    quality: Py<PyAny>,
    /// The law values that generated synthesized data (a dict), or None for real data.
    #[pyo3(get)]
    truth: Py<PyAny>,
    /// The report directory's files (`result`, `history`, `fit`, `report`), or None.
    #[pyo3(get)]
    files: Py<PyAny>,
    /// A joint fit's tests (empty for a one-test configuration), in the configuration's
    /// order: dicts `name`, `data`, `weight` (w_k), `default_weight` (bool), `wJ` (its
    /// share w_k J_k of the final cost), `quality` (as `Result.quality`), `fit` (its
    /// curves, as `Result.fit`) and `oliver_pharr` (as `Result.oliver_pharr`, for that
    /// test's record). `Result.fit` then holds every test's curves end to end.
    #[pyo3(get)]
    tests: Py<PyList>,
    /// The Oliver-Pharr analysis of the fitted record beside the FE result, as result.json's
    /// `oliver_pharr`: a dict `E`, `H`, `Er` (MPa), `S` (N/mm), `hc`, `hmax` (mm), `Fmax`
    /// (N), `strain_rate`, `srs`, `nu`, `tip`, `E_fe` (the fitted E), `E_difference_pct`,
    /// `why_they_differ`; a record that cannot be analysed gives the dict without the values
    /// and `skipped` with the reason. None when there is no record (synthesized data) and for
    /// a joint fit (each of `Result.tests` has its own).
    #[pyo3(get)]
    oliver_pharr: Py<PyAny>,
    /// The closed-form start of `identify(start="closed-form")`, as result.json's `start`:
    /// a dict `method`, `values` and `half_space` (lists of `[name, value]`), `rms_rel`,
    /// `seconds` and `notes` (why no closed form applies, a value clamped); None otherwise.
    #[pyo3(get)]
    start: Py<PyAny>,
    /// The discretization check (the fit re-run on a 2x refined mesh with twice the
    /// steps): a dict `mesh`, `steps` (the refined discretization in words), `rms` (N),
    /// `rms_rel`, `max_abs` (N) of the force change, `shift` and `relative_shift`
    /// ({name: value, None for a held or undetermined parameter}), `exceeds_std` (the
    /// names whose shift exceeds their standard deviation) and `seconds`; None with
    /// `refine=False`, after an interruption, or when the refined run failed (then a
    /// caveat says so).
    #[pyo3(get)]
    discretization: Py<PyAny>,
    /// What makes the result less than it looks, one short clause each (systematic
    /// residuals, discretization shifts beyond the deviations, undetermined parameters,
    /// values at a bound); empty when there is nothing to add.
    #[pyo3(get)]
    caveats: Vec<String>,
}

/// The O&P values beside the FE result as result.json's dict (None without).
fn op_dict(
    py: Python<'_>,
    b: Option<&indentify_study::op_beside::OpBeside>,
) -> PyResult<Py<PyAny>> {
    Ok(match b {
        Some(b) => to_python(py, b)?.unbind(),
        None => py.None(),
    })
}

/// The discretization check as a dict (None when not run).
fn discretization_dict(py: Python<'_>, o: &IdentifyOutcome) -> PyResult<Py<PyAny>> {
    let Some(d) = &o.discretization else {
        return Ok(py.None());
    };
    let dict = PyDict::new(py);
    dict.set_item("mesh", &d.mesh)?;
    dict.set_item("steps", &d.steps)?;
    dict.set_item("rms", d.rms)?;
    dict.set_item("rms_rel", d.rms_rel)?;
    dict.set_item("max_abs", d.max_abs)?;
    let shift = PyDict::new(py);
    let relative = PyDict::new(py);
    let mut exceeds = Vec::new();
    for (k, name) in o.names.iter().enumerate() {
        shift.set_item(name, d.shift.get(k).copied().flatten())?;
        relative.set_item(name, d.relative_shift.get(k).copied().flatten())?;
        if let (Some(Some(s)), Some(sd)) = (d.shift.get(k), o.std_dev(name)) {
            if s.abs() > sd {
                exceeds.push(*name);
            }
        }
    }
    dict.set_item("shift", shift)?;
    dict.set_item("relative_shift", relative)?;
    dict.set_item("exceeds_std", exceeds)?;
    dict.set_item("seconds", d.seconds)?;
    Ok(dict.into_any().unbind())
}

/// A fit quality as a dict (None when not computable).
fn quality_dict(py: Python<'_>, q: Option<&indentify_study::FitQuality>) -> PyResult<Py<PyAny>> {
    Ok(match q {
        Some(q) => {
            let d = PyDict::new(py);
            d.set_item("r2", q.r2)?;
            d.set_item("rms", q.rms)?;
            d.set_item("rms_rel", q.rms_rel)?;
            d.set_item("max_abs", q.max_abs)?;
            d.set_item("n", q.n)?;
            d.into_any().unbind()
        }
        None => py.None(),
    })
}

/// Curves as a dict of arrays `t`, `h`, `F_data`, `F_fit`, `F_start`.
fn fit_dict<'py>(
    py: Python<'py>,
    f: &indentify_study::identify::FitCurves,
) -> PyResult<Bound<'py, PyDict>> {
    let fit = PyDict::new(py);
    fit.set_item("t", array(py, &f.t))?;
    fit.set_item("h", array(py, &f.h))?;
    fit.set_item("F_data", array(py, &f.f_data))?;
    fit.set_item("F_fit", array(py, &f.f_final))?;
    fit.set_item("F_start", array(py, &f.f_start))?;
    Ok(fit)
}

impl IdentifyResult {
    /// From the study layer's outcome.
    pub fn new(py: Python<'_>, o: &IdentifyOutcome) -> PyResult<IdentifyResult> {
        let r = &o.result;
        let params = PyDict::new(py);
        let std = PyDict::new(py);
        let free = PyDict::new(py);
        let bounds = PyDict::new(py);
        let parameters = PyList::empty(py);
        for p in &r.params {
            params.set_item(p.name, p.value)?;
            std.set_item(p.name, if p.free { o.std_dev(p.name) } else { None })?;
            free.set_item(p.name, p.free)?;
            if p.free {
                bounds.set_item(p.name, (p.lower, p.upper))?;
            }
            let d = PyDict::new(py);
            d.set_item("name", p.name)?;
            d.set_item("unit", p.unit)?;
            d.set_item("free", p.free)?;
            d.set_item("start", p.start)?;
            d.set_item("value", p.value)?;
            d.set_item("lower", p.lower)?;
            d.set_item("upper", p.upper)?;
            d.set_item("at_lower", p.at_lower)?;
            d.set_item("at_upper", p.at_upper)?;
            parameters.append(d)?;
        }
        let (correlation, correlation_names) = match &r.identifiability {
            Some(i) if !i.names.is_empty() => (
                PyArray2::from_vec2(py, &i.correlation)
                    .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?
                    .into_any(),
                i.names.clone(),
            ),
            _ => (
                numpy::PyArray2::<f64>::zeros(py, [0, 0], false).into_any(),
                Vec::new(),
            ),
        };
        let fit = fit_dict(py, &o.fit)?;
        let tests = PyList::empty(py);
        for t in &o.tests {
            let d = PyDict::new(py);
            d.set_item("name", &t.name)?;
            d.set_item("data", &t.data)?;
            d.set_item("weight", t.weight)?;
            d.set_item("default_weight", t.default_weight)?;
            d.set_item("wJ", t.cost)?;
            d.set_item("quality", quality_dict(py, t.quality.as_ref())?)?;
            d.set_item("fit", fit_dict(py, &t.fit)?)?;
            d.set_item("oliver_pharr", op_dict(py, t.oliver_pharr.as_ref())?)?;
            tests.append(d)?;
        }
        let history = PyList::empty(py);
        for rec in &r.history {
            history.append(iteration_dict(py, &o.names, rec)?)?;
        }
        let quality = quality_dict(py, o.quality.as_ref())?;
        let truth = match &o.truth {
            Some(t) => {
                let d = PyDict::new(py);
                for (n, v) in o.names.iter().zip(t) {
                    d.set_item(n, v)?;
                }
                d.into_any().unbind()
            }
            None => py.None(),
        };
        let files = match &o.files {
            Some(f) => to_python(py, f)?.unbind(),
            None => py.None(),
        };
        Ok(IdentifyResult {
            params: params.unbind(),
            std: std.unbind(),
            correlation: correlation.unbind(),
            correlation_names,
            converged: o.converged(),
            undetermined: r
                .identifiability
                .as_ref()
                .map_or_else(Vec::new, |i| i.undetermined.clone()),
            stop_reason: r.stop_reason.to_string(),
            fit: fit.unbind(),
            history: history.unbind(),
            parameters: parameters.unbind(),
            free: free.unbind(),
            bounds: bounds.unbind(),
            j: r.cost,
            j_start: r.initial_cost,
            iterations: r.iterations,
            forward_solves: r.forward_solves,
            adjoint_solves: r.adjoint_solves,
            seconds: r.seconds,
            wall_seconds: o.wall_seconds,
            law: o.law,
            method: r.method.name(),
            data: o.data.clone(),
            quality,
            truth,
            files,
            tests: tests.unbind(),
            oliver_pharr: op_dict(py, o.oliver_pharr.as_ref())?,
            start: match &o.start {
                Some(c) => to_python(py, c)?.unbind(),
                None => py.None(),
            },
            discretization: discretization_dict(py, o)?,
            caveats: o.caveats(),
        })
    }
}

#[pymethods]
impl IdentifyResult {
    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "Result({} {}, params={}, J={:e}, iterations={}, converged={}, stop_reason={:?})",
            self.law,
            self.method,
            self.params
                .bind(py)
                .repr()
                .map_or_else(|_| "?".into(), |r| r.to_string()),
            self.j,
            self.iterations,
            if self.converged { "True" } else { "False" },
            self.stop_reason
        )
    }
}
