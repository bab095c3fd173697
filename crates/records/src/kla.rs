//! KLA / Agilent / Keysight workbooks: InView and G200X `.xlsx`, NanoSuite `.xls`, read with
//! the `calamine` crate from the bytes.
//!
//! Layout (as `FusedSilica.xlsx` of examples/data/kla-fused-silica): one sheet per test,
//! named `Test <N>` (also `Test <N> Tagged`), whose first row names the columns (`Markers`,
//! `Time`, `Load`/`Load On Sample`, `Depth`/`Displacement Into Surface`, ...) and whose
//! second row holds their units (`s`, `mN`, `nm`); then the samples, a marker text
//! (`Surface Index`, `End Of Loading Index`, ...) in the first column of the sample it
//! marks. Summary sheets hold one row per test after a names row and a units row:
//! `Results` (the vendor's results, into `meta.results`), `Pre-Test Inputs` (the method:
//! target load, hold time, Poisson's ratio, ... into `meta.protocol` and `meta.other`),
//! `Post-Test Inputs` (acquisition rate). `Cycles-GroupedByTest` holds the vendor's values
//! per load cycle (`Cycle Su`, `Cycle Eu`, ...): they go into `meta.results` as
//! `<name> [cycle k]`. Markers go into `meta.other` as `marker: <text>` with the marked
//! sample's time (s, from the file's time origin).

use std::io::Cursor;

use calamine::{Data, Range, Reader, Sheets, open_workbook_auto_from_rs};

use crate::error::{ReadError, ReadErrorKind as K};
use crate::record::{Format, Meta, Quantity, Record};
use crate::text::{self, Dim};

/// Whether `bytes` look like a workbook: a zip archive (`.xlsx`: `PK\x03\x04`) or an OLE2
/// compound document (`.xls`: `D0 CF 11 E0 A1 B1 1A E1`).
pub(crate) fn is_workbook(bytes: &[u8]) -> bool {
    bytes.starts_with(b"PK\x03\x04")
        || bytes.starts_with(&[0xD0, 0xCF, 0x11, 0xE0, 0xA1, 0xB1, 0x1A, 0xE1])
}

/// A cell's text, trimmed (numbers written out), with the mis-decoded micro sign `Âµ`
/// (UTF-8 read as Latin-1 by the exporting program) repaired.
fn cell_text(d: &Data) -> String {
    let s = match d {
        Data::String(s) => s.trim().to_owned(),
        Data::Float(f) => f.to_string(),
        Data::Int(i) => i.to_string(),
        Data::Bool(b) => b.to_string(),
        _ => String::new(),
    };
    s.replace("Âµ", "µ").replace("Â²", "²")
}

/// A cell's number: a numeric cell, or a string that parses as one.
fn cell_number(d: &Data) -> Option<f64> {
    match d {
        Data::Float(f) => Some(*f),
        Data::Int(i) => Some(*i as f64),
        Data::String(s) => text::number(s.trim(), false),
        _ => None,
    }
}

/// The test number of a sheet named `Test <N>` (`Test 3 Tagged` too).
fn test_number(sheet: &str) -> Option<usize> {
    let rest = sheet.trim().strip_prefix("Test")?.trim_start();
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    if digits.is_empty() {
        return None;
    }
    let tail = rest[digits.len()..].trim();
    if !(tail.is_empty() || tail.eq_ignore_ascii_case("tagged")) {
        return None;
    }
    digits.parse().ok()
}

fn normalize(s: &str) -> String {
    s.trim()
        .to_ascii_lowercase()
        .replace(['_', '-'], " ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

/// The column of a quantity among the names of a test sheet.
fn column(names: &[String], wanted: &[&str]) -> Option<usize> {
    wanted
        .iter()
        .find_map(|w| names.iter().position(|n| normalize(n) == *w))
}

/// A 1-based spreadsheet row for messages (the range may start below row 1).
fn sheet_row(range: &Range<Data>, i: usize) -> usize {
    range.start().map_or(i, |(r, _)| r as usize + i) + 1
}

/// Time, depth, force (s, mm, N) and the markers of a test sheet.
type Samples = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<Quantity>);

fn read_test(file: &str, sheet: &str, range: &Range<Data>) -> Result<Samples, ReadError> {
    let at = |_: usize| format!("{file} [{sheet}]");
    let rows: Vec<&[Data]> = range.rows().collect();
    if rows.len() < 4 {
        return Err(ReadError::new(
            &at(0),
            None,
            K::NoRows,
            format!("the sheet has {} rows", rows.len()),
            "a names row, a units row and at least two samples",
        ));
    }
    let names: Vec<String> = rows[0].iter().map(cell_text).collect();
    let units: Vec<String> = rows[1].iter().map(cell_text).collect();
    let want = [
        (Dim::Time, &["time", "time on sample"][..], "Time"),
        (
            Dim::Force,
            &["load on sample", "load", "force"][..],
            "Load On Sample or Load",
        ),
        (
            Dim::Length,
            &["displacement into surface", "depth", "displacement"][..],
            "Displacement Into Surface or Depth",
        ),
    ];
    let mut cols = [(0usize, 0.0f64); 3];
    for (q, (dim, aliases, shown)) in want.iter().enumerate() {
        let Some(c) = column(&names, aliases) else {
            return Err(ReadError::new(
                &at(0),
                Some(sheet_row(range, 0)),
                K::Columns,
                format!("no {shown} column among {:?}", names),
                "columns Time, Load and Depth (or Load On Sample, Displacement Into Surface) in the first row, their units in the second",
            ));
        };
        let u = units.get(c).cloned().unwrap_or_default();
        let factor = match text::unit(&u) {
            Some((d, f)) if d == *dim => f,
            _ => {
                return Err(ReadError::new(
                    &at(0),
                    Some(sheet_row(range, 1)),
                    K::Units,
                    format!("column '{}' has unit '{u}'", names[c]),
                    format!("one of {}", dim.accepted()),
                ));
            }
        };
        cols[q] = (c, factor);
    }
    let (mut t, mut h, mut f) = (Vec::new(), Vec::new(), Vec::new());
    let mut markers = Vec::new();
    for (i, row) in rows.iter().enumerate().skip(2) {
        let get = |q: usize| {
            row.get(cols[q].0)
                .and_then(cell_number)
                .map(|v| v * cols[q].1)
        };
        let (Some(ti), Some(hi), Some(fi)) = (get(0), get(2), get(1)) else {
            if row.iter().all(|d| matches!(d, Data::Empty)) || get(0).is_none() {
                continue;
            }
            return Err(ReadError::new(
                &at(0),
                Some(sheet_row(range, i)),
                K::NotANumber,
                "a sample with a time but no number for the load or the depth".to_string(),
                "numbers in the Time, Load and Depth columns",
            ));
        };
        if !(ti.is_finite() && hi.is_finite() && fi.is_finite()) {
            return Err(ReadError::new(
                &at(0),
                Some(sheet_row(range, i)),
                K::NotFinite,
                format!("a value is not finite (t {ti}, h {hi}, F {fi})"),
                "finite numbers",
            ));
        }
        if let Some(&last) = t.last() {
            if ti < last {
                return Err(ReadError::new(
                    &at(0),
                    Some(sheet_row(range, i)),
                    K::TimeOrder,
                    format!("time goes back from {last} s to {ti} s"),
                    "a time that never decreases",
                ));
            }
        }
        let marker = cell_text(row.first().unwrap_or(&Data::Empty));
        if cols.iter().all(|c| c.0 != 0) && !marker.is_empty() && cell_number(&row[0]).is_none() {
            markers.push(Quantity::new(format!("marker: {marker}"), ti, "s"));
        }
        t.push(ti);
        h.push(hi);
        f.push(fi);
    }
    if t.len() < 2 {
        return Err(ReadError::new(
            &at(0),
            None,
            K::TooFewRows,
            format!("{} samples", t.len()),
            "at least two rows of time, load and depth",
        ));
    }
    Ok((t, h, f, markers))
}

/// The rows of a summary sheet keyed by test number: `(names, units, rows)`; the test is
/// the first column's number.
struct Summary {
    names: Vec<String>,
    units: Vec<String>,
    rows: Vec<(usize, Vec<Data>)>,
}

fn summary(range: &Range<Data>) -> Option<Summary> {
    let rows: Vec<&[Data]> = range.rows().collect();
    if rows.len() < 3 {
        return None;
    }
    let names: Vec<String> = rows[0].iter().map(cell_text).collect();
    let units: Vec<String> = rows[1].iter().map(cell_text).collect();
    let rows = rows[2..]
        .iter()
        .filter_map(|r| {
            let k = r.first().and_then(cell_number)?;
            (k >= 1.0 && k.fract() == 0.0 && k < 1e6).then(|| (k as usize, r.to_vec()))
        })
        .collect();
    Some(Summary { names, units, rows })
}

fn apply_summary(meta: &mut Meta, s: &Summary, test: usize, results: bool) {
    let Some((_, row)) = s.rows.iter().find(|(k, _)| *k == test) else {
        return;
    };
    for (j, d) in row.iter().enumerate().skip(1) {
        let (Some(v), Some(name)) = (cell_number(d), s.names.get(j)) else {
            continue;
        };
        let name = name.trim().to_owned();
        if name.is_empty() || !v.is_finite() {
            continue;
        }
        let unit = s
            .units
            .get(j)
            .map_or(String::new(), |u| u.trim().to_owned());
        let key = normalize(&name);
        let dim = text::unit(&unit);
        match key.as_str() {
            "target load" => {
                meta.protocol.max_load = dim.filter(|d| d.0 == Dim::Force).map(|d| v * d.1)
            }
            "hold maximum load time" => {
                meta.protocol.hold = dim.filter(|d| d.0 == Dim::Time).map(|d| v * d.1)
            }
            "data aquisition rate" | "data acquisition rate" if unit.eq_ignore_ascii_case("hz") => {
                meta.acquisition_rate = Some(v)
            }
            _ => {}
        }
        let q = Quantity::new(name, v, unit);
        if results {
            meta.results.push(q);
        } else {
            meta.other.push(q);
        }
    }
}

/// The vendor's per-cycle values of `Cycles-GroupedByTest`: a `Test <N>` row, then one row
/// per cycle (`N:k` in the first column).
fn cycles(range: &Range<Data>, test: usize) -> Vec<Quantity> {
    let rows: Vec<&[Data]> = range.rows().collect();
    if rows.len() < 3 {
        return Vec::new();
    }
    let names: Vec<String> = rows[0].iter().map(cell_text).collect();
    let units: Vec<String> = rows[1].iter().map(cell_text).collect();
    let mut out = Vec::new();
    for r in &rows[2..] {
        let first = cell_text(r.first().unwrap_or(&Data::Empty));
        let Some((a, b)) = first.split_once(':') else {
            continue;
        };
        if a.trim().parse::<usize>().ok() != Some(test) {
            continue;
        }
        let Ok(cycle) = b.trim().parse::<usize>() else {
            continue;
        };
        for (j, d) in r.iter().enumerate().skip(1) {
            if let (Some(v), Some(n)) = (cell_number(d), names.get(j)) {
                if v.is_finite() && !n.is_empty() {
                    out.push(Quantity::new(
                        format!("{n} [cycle {cycle}]"),
                        v,
                        units.get(j).cloned().unwrap_or_default(),
                    ));
                }
            }
        }
    }
    out
}

/// Reads every test of a workbook (or the 1-based `test`-th).
pub(crate) fn read(
    file: &str,
    bytes: &[u8],
    test: Option<usize>,
) -> Result<Vec<Record>, ReadError> {
    // the workbook parser (calamine) can panic on a malformed file (an arithmetic overflow
    // in its cell references, found by `tests/fuzz.rs`): a bad file is an error, never a
    // panic of the caller
    std::panic::catch_unwind(|| read_workbook(file, bytes, test)).unwrap_or_else(|_| {
        Err(ReadError::new(
            file,
            None,
            K::Format,
            "not a readable workbook (the workbook parser failed on a malformed part)",
            "an .xlsx or .xls workbook as KLA/Agilent/Keysight software writes it",
        ))
    })
}

/// [`read`] without its guard against the parser's panics.
fn read_workbook(file: &str, bytes: &[u8], test: Option<usize>) -> Result<Vec<Record>, ReadError> {
    let mut wb: Sheets<Cursor<&[u8]>> =
        open_workbook_auto_from_rs(Cursor::new(bytes)).map_err(|e| {
            ReadError::new(
                file,
                None,
                K::Format,
                format!("not a readable workbook ({e})"),
                "an .xlsx or .xls workbook as KLA/Agilent/Keysight software writes it",
            )
        })?;
    let names = wb.sheet_names();
    let mut tests: Vec<(usize, String)> = names
        .iter()
        .filter_map(|n| test_number(n).map(|k| (k, n.clone())))
        .collect();
    tests.sort();
    tests.dedup_by_key(|x| x.0);
    if tests.is_empty() {
        return Err(ReadError::new(
            file,
            None,
            K::Format,
            format!(
                "a workbook of unknown layout: no sheet named 'Test <N>' among {:?}",
                names
            ),
            "a KLA/Agilent/Keysight workbook with one sheet per test ('Test 1', 'Test 2', ...)",
        ));
    }
    let chosen: Vec<&(usize, String)> = match test {
        None => tests.iter().collect(),
        Some(k) if k >= 1 && k <= tests.len() => vec![&tests[k - 1]],
        Some(k) => {
            let shown: Vec<String> = tests.iter().map(|t| t.1.clone()).collect();
            return Err(crate::anton_paar::test_index_error(file, k, &shown));
        }
    };
    let mut range_of = |name: &str| -> Option<Range<Data>> {
        names
            .iter()
            .find(|n| normalize(n) == name)
            .and_then(|n| wb.worksheet_range(n).ok())
    };
    let results = range_of("results").as_ref().and_then(summary);
    let pre = range_of("pre test inputs").as_ref().and_then(summary);
    let post = range_of("post test inputs").as_ref().and_then(summary);
    let cyc = range_of("cycles groupedbytest");
    let mut out = Vec::new();
    for (k, sheet) in chosen {
        let range = wb.worksheet_range(sheet).map_err(|e| {
            ReadError::new(
                &format!("{file} [{sheet}]"),
                None,
                K::Format,
                format!("the sheet cannot be read ({e})"),
                "a worksheet of numbers",
            )
        })?;
        let (t, h, f, markers) = read_test(file, sheet, &range)?;
        let mut meta = Meta {
            format: Format::Kla,
            test_name: Some(sheet.clone()),
            ..Meta::default()
        };
        meta.protocol.control = Some("Load Control".into());
        if let Some(s) = &results {
            apply_summary(&mut meta, s, *k, true);
        }
        if let Some(s) = &pre {
            apply_summary(&mut meta, s, *k, false);
        }
        if let Some(s) = &post {
            apply_summary(&mut meta, s, *k, false);
        }
        if let Some(c) = &cyc {
            meta.results.extend(cycles(c, *k));
        }
        meta.other.extend(markers);
        out.push(Record {
            name: format!("{file}: {sheet}"),
            t,
            h,
            f,
            segment: None,
            meta,
        });
    }
    Ok(out)
}
