//! Conversions between Python objects and the study layer's inputs and outputs: the
//! `config` argument (path, RON text or dict), `sets`, paths, in-memory data written to a
//! temporary curve file, dicts to and from `serde_json::Value`, and numpy arrays.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use indentify_study::ConfigSource;
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::Value;

use crate::errors::{config_error, data_error};
use crate::results::Record;

/// The Python type name of `obj`, for messages.
pub fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map_or_else(|_| "?".to_string(), |n| n.to_string())
}

/// A path argument: `str` or `os.PathLike` (`bytes` paths are decoded as UTF-8).
///
/// # Errors
/// `TypeError` naming `what` for anything else (a list, a number, ...).
pub fn path_arg(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<PathBuf> {
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(PathBuf::from(s.to_cow()?.as_ref()));
    }
    if obj.hasattr("__fspath__")? {
        let p = obj.call_method0("__fspath__")?;
        if let Ok(s) = p.cast::<PyString>() {
            return Ok(PathBuf::from(s.to_cow()?.as_ref()));
        }
        if let Ok(b) = p.extract::<Vec<u8>>() {
            return Ok(PathBuf::from(String::from_utf8_lossy(&b).into_owned()));
        }
    }
    Err(PyTypeError::new_err(format!(
        "{what}: expected a path (str or os.PathLike), got {}",
        type_name(obj)
    )))
}

/// The `config` argument: `None` (the embedded R1 default), a path, RON text (a string
/// containing `(`) or a dict with the RON structure.
///
/// # Errors
/// `TypeError` for another type; `ConfigError` for a dict holding a value that has no
/// RON equivalent (NaN, a set, ...).
pub fn config_source(obj: Option<&Bound<'_, PyAny>>) -> PyResult<ConfigSource> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(ConfigSource::Default);
    };
    if let Ok(s) = obj.cast::<PyString>() {
        let text = s.to_cow()?;
        // RON text always holds `(`; a path rarely does, and then it names a file
        return Ok(
            if text.contains('(') && !std::path::Path::new(text.as_ref()).is_file() {
                ConfigSource::Text {
                    text: text.into_owned(),
                    name: "<RON string>".to_string(),
                }
            } else {
                ConfigSource::Path(PathBuf::from(text.as_ref()))
            },
        );
    }
    if obj.hasattr("__fspath__")? {
        return Ok(ConfigSource::Path(path_arg(obj, "config")?));
    }
    if is_mapping(obj)? {
        let value = to_json(obj, "config")?;
        check_paths(&value)?;
        return Ok(ConfigSource::Value {
            value,
            name: "<dict>".to_string(),
        });
    }
    Err(PyTypeError::new_err(format!(
        "config: expected a path (str or os.PathLike), RON text or a dict, got {}",
        type_name(obj)
    )))
}

/// Reads a dict configuration once here to name the dotted path of a wrong value (the
/// study layer's message names the type but not the field); validation stays the study
/// layer's.
///
/// # Errors
/// `ConfigError`: "cannot read the configuration `<dict>`", then `path: what is wrong`.
fn check_paths(value: &Value) -> PyResult<()> {
    match serde_path_to_error::deserialize::<_, indentify_study::config::Config>(value.clone()) {
        Ok(_) => Ok(()),
        Err(e) => {
            let path = e.path().to_string();
            let inner = e.into_inner().to_string();
            Err(crate::errors::config_errors(vec![
                "cannot read the configuration `<dict>`".to_string(),
                if path.is_empty() || path == "." {
                    inner
                } else {
                    format!("`{path}`: {inner}")
                },
            ]))
        }
    }
}

/// Whether `obj` is a dict or another `collections.abc.Mapping`.
fn is_mapping(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
    if obj.is_instance_of::<PyDict>() {
        return Ok(true);
    }
    let abc = obj.py().import("collections.abc")?;
    obj.is_instance(&abc.getattr("Mapping")?)
}

/// `sets`: a dict of dotted paths to values (or a list of `"path=value"` strings) as the
/// `path=value` strings of `--set`.
///
/// # Errors
/// `TypeError` for another type, a non-string key, or a value that is not a scalar.
pub fn sets_arg(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(Vec::new());
    };
    if is_mapping(obj)? {
        let mut out = Vec::new();
        for item in obj.call_method0("items")?.try_iter()? {
            let (k, v): (Bound<'_, PyAny>, Bound<'_, PyAny>) = item?.extract()?;
            let key: String = k.extract().map_err(|_| {
                PyTypeError::new_err(format!(
                    "sets: keys are dotted paths (str), got {}",
                    type_name(&k)
                ))
            })?;
            out.push(format!("{key}={}", scalar_text(&v, &key)?));
        }
        return Ok(out);
    }
    if obj.is_instance_of::<PyString>() {
        return Err(PyTypeError::new_err(
            "sets: expected a dict {\"law.E\": 25000} or a list of \"path=value\" strings, got str",
        ));
    }
    match obj.extract::<Vec<String>>() {
        Ok(v) => Ok(v),
        Err(_) => Err(PyTypeError::new_err(format!(
            "sets: expected a dict {{\"law.E\": 25000}} or a list of \"path=value\" strings, got {}",
            type_name(obj)
        ))),
    }
}

/// A scalar as `--set` text: `true`/`false`, integers as written, floats in Rust's
/// shortest round-trip form, strings as they are.
fn scalar_text(v: &Bound<'_, PyAny>, key: &str) -> PyResult<String> {
    if let Ok(b) = v.cast::<PyBool>() {
        return Ok(b.is_true().to_string());
    }
    if v.is_instance_of::<PyInt>() || (!v.is_instance_of::<PyFloat>() && v.hasattr("__index__")?) {
        return Ok(v.call_method0("__index__")?.str()?.to_cow()?.into_owned());
    }
    if v.is_instance_of::<PyFloat>() || v.hasattr("__float__")? {
        let x: f64 = v.extract()?;
        return Ok(format!("{x}"));
    }
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(s.to_cow()?.into_owned());
    }
    Err(PyTypeError::new_err(format!(
        "sets[{key:?}]: expected a number, a bool or a string, got {}",
        type_name(v)
    )))
}

/// A Python value (dicts with string keys, lists, tuples, numbers, strings, bools, None,
/// numpy arrays and scalars) as JSON; `at` is its path in messages.
///
/// # Errors
/// `ConfigError` for a non-finite float; `TypeError` for a non-string key or another type.
pub fn to_json(obj: &Bound<'_, PyAny>, at: &str) -> PyResult<Value> {
    if obj.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if obj.is_instance_of::<PyInt>() {
        if let Ok(i) = obj.extract::<i64>() {
            return Ok(Value::from(i));
        }
        if let Ok(u) = obj.extract::<u64>() {
            return Ok(Value::from(u));
        }
    }
    if obj.is_instance_of::<PyFloat>() || obj.is_instance_of::<PyInt>() {
        return float_json(obj.extract::<f64>()?, at);
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Value::String(s.to_cow()?.into_owned()));
    }
    if is_mapping(obj)? {
        let mut map = serde_json::Map::new();
        for item in obj.call_method0("items")?.try_iter()? {
            let (k, v): (Bound<'_, PyAny>, Bound<'_, PyAny>) = item?.extract()?;
            let key: String = k.extract().map_err(|_| {
                PyTypeError::new_err(format!(
                    "{at}: dict keys must be str, got {}",
                    type_name(&k)
                ))
            })?;
            let value = to_json(&v, &format!("{at}.{key}"))?;
            map.insert(key, value);
        }
        return Ok(Value::Object(map));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let mut items = Vec::new();
        for (i, item) in obj.try_iter()?.enumerate() {
            items.push(to_json(&item?, &format!("{at}.{i}"))?);
        }
        return Ok(Value::Array(items));
    }
    // numpy arrays and scalars: their Python equivalents
    if obj.hasattr("tolist")? && obj.hasattr("dtype")? {
        return to_json(&obj.call_method0("tolist")?, at);
    }
    if obj.hasattr("__index__")? {
        return to_json(&obj.call_method0("__index__")?, at);
    }
    if obj.hasattr("__float__")? {
        return float_json(obj.extract::<f64>()?, at);
    }
    Err(PyTypeError::new_err(format!(
        "{at}: cannot use a {} in a configuration (expected dict, list, tuple, str, int, float, \
         bool or None)",
        type_name(obj)
    )))
}

fn float_json(x: f64, at: &str) -> PyResult<Value> {
    serde_json::Number::from_f64(x)
        .map(Value::Number)
        .ok_or_else(|| {
            config_error(format!(
                "`{at}` = {x} is not allowed: expected a finite number"
            ))
        })
}

/// JSON as Python: dicts, lists, floats, ints, strings, bools and None.
pub fn from_json<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_pyobject(py)?.into_any()
            } else if let Some(u) = n.as_u64() {
                u.into_pyobject(py)?.into_any()
            } else {
                n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any()
            }
        }
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(a) => {
            let list = PyList::empty(py);
            for x in a {
                list.append(from_json(py, x)?)?;
            }
            list.into_any()
        }
        Value::Object(m) => {
            let dict = PyDict::new(py);
            for (k, x) in m {
                dict.set_item(k, from_json(py, x)?)?;
            }
            dict.into_any()
        }
    })
}

/// A serializable value as Python (through JSON).
pub fn to_python<'py, T: serde::Serialize>(py: Python<'py>, v: &T) -> PyResult<Bound<'py, PyAny>> {
    let value = serde_json::to_value(v)
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    from_json(py, &value)
}

/// A float64 numpy array of `v`.
pub fn array<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyAny> {
    PyArray1::from_slice(py, v).into_any()
}

/// A temporary curve file that is removed when dropped.
pub struct TempCurve(PathBuf);

impl TempCurve {
    /// Its path.
    pub fn path(&self) -> PathBuf {
        self.0.clone()
    }
}

impl Drop for TempCurve {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// The `data` argument: a path, or in-memory data written to a temporary `t,h,F` (or
/// `t,F`) file in mm, N, s: a [`Record`], a dict with `t`, `F` and optionally `h`, or an
/// array of shape `(n, 2)` (`t, F`) or `(n, 3)` (`t, h, F`).
///
/// # Errors
/// `TypeError` for another type; `DataError` for a wrong shape, columns of different
/// lengths, fewer than 2 rows or a value that is not finite.
pub fn data_arg(obj: Option<&Bound<'_, PyAny>>) -> PyResult<(Option<PathBuf>, Option<TempCurve>)> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok((None, None));
    };
    if obj.is_instance_of::<PyString>() || obj.hasattr("__fspath__")? {
        return Ok((Some(path_arg(obj, "data")?), None));
    }
    let columns: Vec<(&str, Vec<f64>)> = if let Ok(r) = obj.cast::<Record>() {
        let r = r.get();
        vec![("t", r.t.clone()), ("h", r.h.clone()), ("F", r.f.clone())]
    } else if is_mapping(obj)? {
        let mut cols = Vec::new();
        for key in ["t", "h", "F"] {
            match obj.get_item(key) {
                Ok(v) => cols.push((key, column(&v, &format!("data[{key:?}]"))?)),
                Err(_) if key == "h" => {}
                Err(_) => {
                    return Err(data_error(format!(
                        "data: the dict has no `{key}` column: expected the keys t (s), F (N) \
                         and optionally h (mm)"
                    )));
                }
            }
        }
        cols
    } else if obj.hasattr("__len__")? || obj.hasattr("__array__")? {
        let a = as_float_array(obj, "data")?;
        let shape = a.shape().to_vec();
        let names: &[&str] = match shape.as_slice() {
            [_, 2] => &["t", "F"],
            [_, 3] => &["t", "h", "F"],
            _ => {
                return Err(data_error(format!(
                    "data: expected an array of shape (n, 2) with columns t, F or (n, 3) with \
                     columns t, h, F; got shape {}",
                    shape_text(&shape)
                )));
            }
        };
        // row-major in the logical order, whatever the memory layout
        let values: Vec<f64> = a.readonly().as_array().iter().copied().collect();
        let k = names.len();
        names
            .iter()
            .enumerate()
            .map(|(j, n)| (*n, values.iter().skip(j).step_by(k).copied().collect()))
            .collect()
    } else {
        return Err(PyTypeError::new_err(format!(
            "data: expected a path, a Record, a dict with t and F arrays or an (n, 2) / (n, 3) \
             array, got {}",
            type_name(obj)
        )));
    };
    let n = columns[0].1.len();
    for (name, c) in &columns {
        if c.len() != n {
            return Err(data_error(format!(
                "data: the columns have different lengths (t: {n}, {name}: {})",
                c.len()
            )));
        }
        if let Some(i) = c.iter().position(|x| !x.is_finite()) {
            return Err(data_error(format!(
                "data: {name}[{i}] = {} is not allowed: expected finite numbers",
                c[i]
            )));
        }
    }
    if n < 2 {
        return Err(data_error(format!(
            "data: {n} rows: expected at least 2 (t, F)"
        )));
    }
    let mut text = columns
        .iter()
        .map(|(n, _)| *n)
        .collect::<Vec<_>>()
        .join(",");
    text.push('\n');
    for i in 0..n {
        let row: Vec<String> = columns.iter().map(|(_, c)| format!("{}", c[i])).collect();
        text.push_str(&row.join(","));
        text.push('\n');
    }
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let path = std::env::temp_dir().join(format!(
        "indentify-data-{}-{}.csv",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::write(&path, text).map_err(|e| {
        crate::errors::io_error(format!(
            "cannot write the data to `{}`: {e}",
            path.display()
        ))
    })?;
    let temp = TempCurve(path);
    Ok((Some(temp.path()), Some(temp)))
}

/// `obj` as a float64 numpy array (`numpy.asarray(obj, dtype=float64)`).
fn as_float_array<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let np = obj.py().import("numpy")?;
    let a = np
        .call_method1("asarray", (obj, np.getattr("float64")?))
        .map_err(|e| {
            data_error(format!(
                "{what}: cannot be read as an array of numbers: {e}"
            ))
        })?;
    Ok(a.cast_into::<PyArrayDyn<f64>>()?)
}

/// One 1-D column of numbers.
fn column(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    let a = as_float_array(obj, what)?;
    if a.ndim() != 1 {
        return Err(data_error(format!(
            "{what}: expected a 1-D array, got shape {}",
            shape_text(a.shape())
        )));
    }
    Ok(a.readonly().as_array().iter().copied().collect())
}

/// A shape as Python writes it: `(5,)`, `(31, 4)`.
fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}
