//! Anton Paar exports: the single-test TXT (method header, `Measured values`, tab-separated
//! columns with decimal commas) and the multi-test side-by-side TXT
//! (`X_<test>_Time_[s]  Y_<test>_Fn_[mN]  X_<test>_Time_[s]  Y_<test>_Pd_[nm]` per test).

use crate::error::{ReadError, ReadErrorKind as K};
use crate::record::{Format, Meta, Quantity, Record};
use crate::table::{self, Cols, Sep};
use crate::text::{self, Dim};

/// A `key : value unit` (or `key= value unit`) header line: key, number, unit.
pub(crate) fn key_value(line: &str) -> Option<(String, Option<f64>, String)> {
    let i = line.find([':', '='])?;
    let key = line[..i].trim().to_owned();
    let rest = line[i + 1..].trim();
    let mut it = rest.split_whitespace();
    let first = it.next().unwrap_or("");
    match text::number(first, true) {
        Some(v) => {
            let unit = it.collect::<Vec<_>>().join(" ");
            let unit = unit
                .trim_start_matches('[')
                .trim_end_matches(']')
                .trim()
                .to_owned();
            Some((key, Some(v), unit))
        }
        None => Some((key, None, rest.to_owned())),
    }
}

/// The method header before `Measured values`.
fn header(lines: &[(usize, &str)], meta: &mut Meta) {
    let mut results = false;
    let mut time: Option<String> = None;
    for &(_, raw) in lines {
        let l = raw.trim();
        if l.is_empty() {
            continue;
        }
        if let Some(section) = l.strip_prefix('+') {
            let s = section.trim();
            results = s.ends_with("results");
            if let Some(instr) = s.strip_suffix("settings") {
                meta.instrument = Some(instr.trim().to_owned());
            }
            continue;
        }
        if !l.contains([':', '=']) {
            if l.ends_with("Loading") {
                meta.protocol.control = Some(l.to_owned());
            }
            continue;
        }
        let Some((key, value, unit)) = key_value(l) else {
            continue;
        };
        let k = key.to_ascii_lowercase();
        match (k.as_str(), value) {
            ("date", _) => meta.date = Some(after_colon(l)),
            ("time", _) => time = Some(after_colon(l)),
            (_, None) if k.contains("indenter") || k == "tip" => meta.tip = Some(unit),
            (_, Some(v)) if results => meta.results.push(Quantity::new(key, v, unit)),
            ("acquisition rate", Some(v)) => meta.acquisition_rate = Some(v),
            ("max depth", Some(v)) => meta.protocol.max_depth = scaled(v, &unit, Dim::Length),
            ("max load", Some(v)) => meta.protocol.max_load = scaled(v, &unit, Dim::Force),
            ("pause", Some(v)) | ("hold", Some(v)) => {
                meta.protocol.hold = scaled(v, &unit, Dim::Time)
            }
            ("loading rate", Some(v)) => {
                meta.protocol.loading_rate = rate("loading rate", v, &unit)
            }
            ("unloading rate", Some(v)) => {
                meta.protocol.unloading_rate = rate("unloading rate", v, &unit)
            }
            (_, Some(v)) if k.contains("radius") => meta.tip_radius = scaled(v, &unit, Dim::Length),
            (_, Some(v)) => meta.other.push(Quantity::new(key, v, unit)),
            _ => {}
        }
    }
    if let (Some(d), Some(t)) = (meta.date.as_mut(), time) {
        d.push(' ');
        d.push_str(&t);
    }
}

/// The text after the first `:` of a line, trimmed.
fn after_colon(l: &str) -> String {
    l.split_once(':').map_or("", |(_, v)| v).trim().to_owned()
}

/// A value in `unit` converted to internal units, when `unit` has dimension `dim`.
pub(crate) fn scaled(v: f64, unit: &str, dim: Dim) -> Option<f64> {
    match text::unit(unit) {
        Some((d, f)) if d == dim => Some(v * f),
        _ => None,
    }
}

/// A rate such as `20 mN/min` converted to `N/s` (or `mm/s`).
pub(crate) fn rate(name: &str, v: f64, unit: &str) -> Option<Quantity> {
    text::ratio_unit(unit).map(|(f, u)| Quantity::new(name, v * f, u))
}

/// Reads the single-test export.
pub(crate) fn read_single(file: &str, text: &str) -> Result<Record, ReadError> {
    let ls = text::lines(text);
    let Some(mv) = ls
        .iter()
        .position(|(_, l)| l.trim().eq_ignore_ascii_case("measured values"))
    else {
        return Err(ReadError::new(
            file,
            None,
            K::Format,
            "no 'Measured values' line",
            "an Anton Paar TXT export: a method header, 'Measured values', a column header and rows",
        ));
    };
    let mut meta = Meta {
        format: Format::AntonPaar,
        ..Meta::default()
    };
    header(&ls[..mv], &mut meta);
    let after = &ls[mv + 1..];
    let Some(hi) = after.iter().position(|(_, l)| !l.trim().is_empty()) else {
        return Err(ReadError::new(
            file,
            ls.get(mv).map(|&(n, _)| n),
            K::NoRows,
            "nothing after 'Measured values'",
            "a column header such as 'Time (s)\tPd (nm)\tFn (mN)' and rows of numbers",
        ));
    };
    let (hno, hline) = after[hi];
    let sep = Sep::of(hline);
    let layout = table::resolve(file, hno, &sep.split_header(hline))?;
    let cols = table::rows(file, &layout, &after[hi + 1..], sep)?;
    table::check(file, "measured values", &cols, Some(hno))?;
    Ok(Record {
        name: file.to_owned(),
        t: cols.t,
        h: cols.h,
        f: cols.f,
        segment: cols.segment,
        meta,
    })
}

/// One column of the multi-test header: `X_<test>_<quantity>_[<unit>]`.
#[derive(Debug)]
struct MultiCol {
    axis: char,
    test: String,
    quantity: String,
    unit: String,
    label: String,
}

fn multi_col(label: &str) -> Option<MultiCol> {
    let l = label.trim();
    let mut chars = l.chars();
    let axis = chars.next()?;
    let body = l.get(2..)?;
    if !matches!(axis, 'X' | 'Y') || l.get(1..2) != Some("_") {
        return None;
    }
    let (body, unit) = match body.strip_suffix(']').and_then(|b| b.rsplit_once('[')) {
        Some((b, u)) => (b.trim_end_matches('_'), u),
        None => (body, ""),
    };
    let (test, quantity) = body.rsplit_once('_')?;
    Some(MultiCol {
        axis,
        test: test.to_owned(),
        quantity: quantity.to_owned(),
        unit: unit.to_owned(),
        label: l.to_owned(),
    })
}

/// Whether a header line looks like the multi-test export.
pub(crate) fn is_multi_header(line: &str) -> bool {
    let fs = Sep::of(line).split(line);
    fs.first()
        .and_then(|f| multi_col(f))
        .is_some_and(|c| c.axis == 'X' && text::normalize(&c.quantity) == "time")
}

/// Where one test's numbers are: (time column, value column, factor) for force and depth.
#[derive(Debug)]
struct MultiTest {
    name: String,
    force: Option<(usize, usize, f64, String)>,
    depth: Option<(usize, usize, f64, String)>,
    time_factor: (f64, f64),
}

/// Reads the multi-test export; `test` is 1-based.
pub(crate) fn read_multi(
    file: &str,
    text: &str,
    test: Option<usize>,
) -> Result<Vec<Record>, ReadError> {
    let ls = text::lines(text);
    let Some(hi) = ls.iter().position(|(_, l)| !l.trim().is_empty()) else {
        return Err(ReadError::new(
            file,
            None,
            K::Empty,
            "no lines",
            "a header line then rows",
        ));
    };
    let (hno, hline) = ls[hi];
    let sep = Sep::of(hline);
    let labels = sep.split(hline);
    let mut tests: Vec<MultiTest> = Vec::new();
    let unit_err = |label: &str, unit: &str, dim: Dim| {
        ReadError::new(
            file,
            Some(hno),
            K::Units,
            format!("column '{label}' has unit '{unit}'"),
            format!("one of {}", dim.accepted()),
        )
    };
    for (j, label) in labels.iter().enumerate() {
        let Some(c) = multi_col(label) else {
            return Err(ReadError::new(
                file,
                Some(hno),
                K::Columns,
                format!(
                    "column {} '{label}' is not of the form X_<test>_<quantity>_[unit]",
                    j + 1
                ),
                "columns like 'X_test_Time_[s]' followed by 'Y_test_Fn_[mN]' or 'Y_test_Pd_[nm]'",
            ));
        };
        if c.axis != 'Y' {
            continue;
        }
        let q = text::quantity(&text::normalize(&c.quantity));
        let dim = match q {
            Some(text::Quantity::Force) => Dim::Force,
            Some(text::Quantity::Depth) => Dim::Length,
            _ => continue,
        };
        let x = j
            .checked_sub(1)
            .and_then(|i| labels.get(i))
            .and_then(|l| multi_col(l));
        let Some(x) = x.filter(|x| x.axis == 'X' && x.test == c.test) else {
            return Err(ReadError::new(
                file,
                Some(hno),
                K::Columns,
                format!("column '{}' is not preceded by its time column", c.label),
                format!("'X_{}_Time_[s]' just before it", c.test),
            ));
        };
        let (xd, xf) = text::unit(&x.unit).ok_or_else(|| unit_err(&x.label, &x.unit, Dim::Time))?;
        if xd != Dim::Time {
            return Err(unit_err(&x.label, &x.unit, Dim::Time));
        }
        let vf = scaled(1.0, &c.unit, dim).ok_or_else(|| unit_err(&c.label, &c.unit, dim))?;
        let idx = match tests.iter().position(|t| t.name == c.test) {
            Some(i) => i,
            None => {
                tests.push(MultiTest {
                    name: c.test.clone(),
                    force: None,
                    depth: None,
                    time_factor: (1.0, 1.0),
                });
                tests.len() - 1
            }
        };
        let Some(mt) = tests.get_mut(idx) else {
            continue;
        };
        let entry = Some((j - 1, j, vf, c.label.clone()));
        if dim == Dim::Force {
            if mt.force.is_none() {
                mt.force = entry;
                mt.time_factor.0 = xf;
            }
        } else if mt.depth.is_none() {
            mt.depth = entry;
            mt.time_factor.1 = xf;
        }
    }
    if tests.is_empty() {
        return Err(ReadError::new(
            file,
            Some(hno),
            K::Columns,
            "no test with force and depth columns",
            "pairs 'X_<test>_Time_[s]', 'Y_<test>_Fn_[mN]' and 'X_<test>_Time_[s]', 'Y_<test>_Pd_[nm]'",
        ));
    }
    let selected: Vec<usize> = match test {
        None => (0..tests.len()).collect(),
        Some(k) if k >= 1 && k <= tests.len() => vec![k - 1],
        Some(k) => return Err(test_index_error(file, k, &names(&tests))),
    };
    let mut out = Vec::new();
    for i in selected {
        let Some(mt) = tests.get(i) else { continue };
        let (Some(fc), Some(hc)) = (&mt.force, &mt.depth) else {
            return Err(ReadError::new(
                file,
                Some(hno),
                K::Columns,
                format!(
                    "test '{}' has {} but no {} column",
                    mt.name,
                    if mt.force.is_some() { "force" } else { "depth" },
                    if mt.force.is_some() { "depth" } else { "force" }
                ),
                "a force (Fn) and a depth (Pd) column for each test",
            ));
        };
        let mut c = Cols::default();
        let mut ended: Option<usize> = None;
        for &(no, line) in &ls[hi + 1..] {
            if line.trim().is_empty() {
                continue;
            }
            // blank-separated rows: runs of blanks are one separator (space-aligned columns);
            // empty trailing cells cannot be told apart there, tabs or semicolons can
            let fs: Vec<&str> = match sep {
                Sep::Tab => line.split('\t').collect(),
                Sep::Semicolon => line.split(';').collect(),
                Sep::Comma => line.split(',').collect(),
                Sep::Whitespace => line.split_whitespace().collect(),
            };
            let cells = [fc.0, fc.1, hc.0, hc.1].map(|j| fs.get(j).map_or("", |s| s.trim()));
            if cells.iter().all(|s| s.is_empty()) {
                ended.get_or_insert(no);
                continue;
            }
            if let Some(e) = ended {
                return Err(ReadError::new(
                    file,
                    Some(no),
                    K::FewFields,
                    format!(
                        "test '{}' has values again after its end at line {e}",
                        mt.name
                    ),
                    "each test's columns to end once, with blank cells after",
                ));
            }
            let dc = sep.decimal_comma();
            let tf = table::field(
                file,
                no,
                cells[0],
                labels.get(fc.0).copied().unwrap_or(""),
                mt.time_factor.0,
                dc,
            )?;
            let f = table::field(file, no, cells[1], &fc.3, fc.2, dc)?;
            let th = table::field(
                file,
                no,
                cells[2],
                labels.get(hc.0).copied().unwrap_or(""),
                mt.time_factor.1,
                dc,
            )?;
            let h = table::field(file, no, cells[3], &hc.3, hc.2, dc)?;
            if (tf - th).abs() > 1e-9 * tf.abs().max(1.0) {
                return Err(ReadError::new(
                    file,
                    Some(no),
                    K::Columns,
                    format!(
                        "test '{}': the force's time {tf} s differs from the depth's time {th} s",
                        mt.name
                    ),
                    "the same time in both time columns of a test",
                ));
            }
            c.t.push(tf);
            c.h.push(h);
            c.f.push(f);
            c.lines.push(no);
        }
        // a shorter test is padded by repeating its last row: drop the repeats
        while c.t.len() >= 2 {
            let n = c.t.len();
            if c.t[n - 1] == c.t[n - 2] && c.h[n - 1] == c.h[n - 2] && c.f[n - 1] == c.f[n - 2] {
                c.t.pop();
                c.h.pop();
                c.f.pop();
                c.lines.pop();
            } else {
                break;
            }
        }
        table::check(file, &format!("test '{}'", mt.name), &c, Some(hno))?;
        out.push(Record {
            name: format!("{file}: {}", mt.name),
            t: c.t,
            h: c.h,
            f: c.f,
            segment: None,
            meta: Meta {
                format: Format::AntonPaarMulti,
                test_name: Some(mt.name.clone()),
                ..Meta::default()
            },
        });
    }
    Ok(out)
}

fn names(tests: &[MultiTest]) -> Vec<String> {
    tests.iter().map(|t| t.name.clone()).collect()
}

/// The error of a test index outside `1..=names.len()`.
pub(crate) fn test_index_error(file: &str, k: usize, names: &[String]) -> ReadError {
    ReadError::new(
        file,
        None,
        K::TestIndex,
        format!(
            "test {k} does not exist: the file has {} test{} ({})",
            names.len(),
            if names.len() == 1 { "" } else { "s" },
            names
                .iter()
                .enumerate()
                .map(|(i, n)| format!("{} = {n}", i + 1))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        format!("a test index from 1 to {}", names.len()),
    )
}

/// The vendor's results of one test, from an Anton Paar results table (`_data.TXT`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TestResults {
    /// Test name as in the curve file: `<group>_<measurement>` (e.g. `HT_V_100mN_1`).
    pub test: String,
    /// Group as written.
    pub group: String,
    /// Measurement number as written.
    pub measurement: String,
    /// The results (`HIT (O&P)`, `EIT (O&P)`, `hm (O&P)`, `Fm (O&P)`, ...), as written.
    pub values: Vec<Quantity>,
}

/// Reads an Anton Paar results table: `Group  Measurement  Parameter  Unit  Value` rows.
pub(crate) fn read_results(file: &str, text: &str) -> Result<Vec<TestResults>, ReadError> {
    let ls = text::lines(text);
    let Some(hi) = ls.iter().position(|(_, l)| !l.trim().is_empty()) else {
        return Err(ReadError::new(
            file,
            None,
            K::Empty,
            "the file is empty",
            "a results table",
        ));
    };
    let (hno, hline) = ls[hi];
    let sep = Sep::of(hline);
    let header: Vec<String> = sep
        .split(hline)
        .iter()
        .map(|s| s.to_ascii_lowercase())
        .collect();
    if header != ["group", "measurement", "parameter", "unit", "value"] {
        return Err(ReadError::new(
            file,
            Some(hno),
            K::Format,
            format!("header '{}'", crate::csv::clip(hline)),
            "an Anton Paar results table with the header 'Group Measurement Parameter Unit Value'",
        ));
    }
    let mut out: Vec<TestResults> = Vec::new();
    for &(no, line) in &ls[hi + 1..] {
        if line.trim().is_empty() {
            continue;
        }
        let fs: Vec<&str> = line.split('\t').map(str::trim).collect();
        let [group, measurement, parameter, unit, value, ..] = fs[..] else {
            return Err(ReadError::new(
                file,
                Some(no),
                K::FewFields,
                format!("{} fields", fs.len()),
                "5 tab-separated fields: group, measurement, parameter, unit, value",
            ));
        };
        let v = table::field(file, no, value, "Value", 1.0, true)?;
        let q = Quantity::new(parameter, v, unit);
        match out.last_mut() {
            Some(r) if r.group == group && r.measurement == measurement => r.values.push(q),
            _ => out.push(TestResults {
                test: format!("{group}_{measurement}"),
                group: group.to_owned(),
                measurement: measurement.to_owned(),
                values: vec![q],
            }),
        }
    }
    Ok(out)
}
