//! Hysitron (Bruker) records: the text export (`Number of Points = N`, then
//! `Depth (nm)  Load (µN)  Time (s) ...`, blank lines between load-function segments) and the native `.hld` (a `Key: value unit`
//! header with the load function, then `<section> Data Points: N` blocks).

use crate::anton_paar::{rate, scaled};
use crate::error::{ReadError, ReadErrorKind as K};
use crate::record::{Format, LoadSegment, Meta, Quantity, Record};
use crate::table::{self, Sep};
use crate::text::{self, Dim};

/// The declared point count of a `Number of Points = N` line.
fn points_line(line: &str) -> Option<&str> {
    let (k, v) = line.split_once('=')?;
    k.trim()
        .eq_ignore_ascii_case("number of points")
        .then_some(v.trim())
}

/// Whether the text looks like the Hysitron text export.
pub(crate) fn is_txt(lines: &[(usize, &str)]) -> bool {
    lines.iter().take(20).any(|(_, l)| points_line(l).is_some())
}

fn count(file: &str, no: usize, v: &str, what: &str) -> Result<usize, ReadError> {
    v.trim().parse::<usize>().map_err(|_| {
        ReadError::new(
            file,
            Some(no),
            K::PointCount,
            format!("'{v}' as the number of {what}"),
            "a non-negative integer",
        )
    })
}

fn count_error(file: &str, no: usize, what: &str, declared: usize, found: usize) -> ReadError {
    ReadError::new(
        file,
        Some(no),
        K::PointCount,
        format!("{what} declares {declared} points but {found} rows follow"),
        format!("{declared} rows of numbers after the column header"),
    )
}

/// Reads the text export; rows separated by blank lines get successive segment ids.
pub(crate) fn read_txt(file: &str, text: &str) -> Result<Record, ReadError> {
    let ls = text::lines(text);
    let Some(pi) = ls.iter().position(|(_, l)| points_line(l).is_some()) else {
        return Err(ReadError::new(
            file,
            None,
            K::Format,
            "no 'Number of Points = N' line",
            "a Hysitron text export: date, 'Number of Points = N', a column header and N rows",
        ));
    };
    let (pno, pline) = ls[pi];
    let declared = count(file, pno, points_line(pline).unwrap_or(""), "points")?;
    let date = ls[..pi]
        .iter()
        .find(|(_, l)| !l.trim().is_empty())
        .map(|(_, l)| l.trim().to_owned());
    let after = &ls[pi + 1..];
    let Some(hi) = after.iter().position(|(_, l)| !l.trim().is_empty()) else {
        return Err(ReadError::new(
            file,
            Some(pno),
            K::NoRows,
            "nothing after the point count",
            "a column header such as 'Depth (nm)\tLoad (µN)\tTime (s)' and rows",
        ));
    };
    let (hno, hline) = after[hi];
    let sep = Sep::of(hline);
    let layout = table::resolve(file, hno, &sep.split_header(hline))?;
    let cols = table::rows(file, &layout, &after[hi + 1..], sep)?;
    if cols.t.len() != declared {
        return Err(count_error(
            file,
            pno,
            "'Number of Points'",
            declared,
            cols.t.len(),
        ));
    }
    table::check(file, "data", &cols, Some(hno))?;
    // blank lines separate the load function's segments
    let mut id = 0u32;
    let mut ids = Vec::with_capacity(cols.lines.len());
    for (i, &no) in cols.lines.iter().enumerate() {
        if i > 0 && cols.lines.get(i - 1).is_some_and(|&prev| no > prev + 1) {
            id = id.saturating_add(1);
        }
        ids.push(id);
    }
    Ok(Record {
        name: file.to_owned(),
        t: cols.t,
        h: cols.h,
        f: cols.f,
        segment: (id > 0).then_some(ids),
        meta: Meta {
            format: Format::HysitronTxt,
            date,
            ..Meta::default()
        },
    })
}

/// The section name of a `<name> Data Points: N` line, and N as text.
fn section_line(line: &str) -> Option<(&str, &str)> {
    let (k, v) = line.split_once(':')?;
    let name = k.trim().strip_suffix("Data Points")?;
    Some((name.trim(), v.trim()))
}

/// Whether the text looks like an `.hld` file.
pub(crate) fn is_hld(lines: &[(usize, &str)]) -> bool {
    let first = lines.iter().find(|(_, l)| !l.trim().is_empty());
    first.is_some_and(|(_, l)| l.starts_with("File Version:") && l.contains("Hysitron"))
        || lines
            .iter()
            .any(|(_, l)| section_line(l).is_some_and(|(n, _)| n == "Test"))
}

/// `Key: value unit`: key, number, unit (or the whole value as text).
fn key_value(line: &str) -> Option<(&str, Option<f64>, &str)> {
    let (k, v) = line.split_once(':')?;
    let v = v.trim();
    let (num, unit) = v.split_once(char::is_whitespace).unwrap_or((v, ""));
    match text::number(num, false) {
        Some(x) => Some((k.trim(), Some(x), unit.trim())),
        None => Some((k.trim(), None, v)),
    }
}

const OTHER_KEYS: &[&str] = &[
    "Test Temp",
    "Test Humidity",
    "Contact Threshold",
    "Preload",
    "Tip Usable Depth",
    "Drift Monitor Time",
    "Drift Analysis Time",
    "Drift Intercept",
    "Drift RMSE",
    "Disp Shift",
    "Force Shift",
    "Lift Height",
    "Sig Avg Per Point",
];

fn header(lines: &[(usize, &str)], meta: &mut Meta) {
    let mut version: Option<String> = None;
    for &(_, l) in lines {
        let Some((key, value, unit)) = key_value(l) else {
            continue;
        };
        let text_value = || unit.to_owned();
        match (key, value) {
            ("File Version", _) => {
                version = Some(l.split_once(':').map_or("", |(_, v)| v).trim().to_owned())
            }
            ("System", _) => {
                meta.instrument = Some(l.split_once(':').map_or("", |(_, v)| v).trim().to_owned())
            }
            ("Time Stamp", _) => {
                meta.date = Some(l.split_once(':').map_or("", |(_, v)| v).trim().to_owned())
            }
            ("Tip ID", _) => {
                meta.tip = Some(l.split_once(':').map_or("", |(_, v)| v).trim().to_owned())
            }
            ("FB Mode", None) => meta.protocol.control = Some(text_value()),
            (k, Some(v)) if k.starts_with("Tip C") || k == "Tip B" => {
                meta.tip_area.push(Quantity::new(k, v, unit))
            }
            ("Machine Comp", Some(v)) => {
                meta.frame_compliance = text::ratio_unit(unit).map(|(f, _)| v * f)
            }
            ("Drift Rate", Some(v)) => {
                meta.drift_rate = rate("drift rate", v, unit).map(|q| q.value)
            }
            ("Maximum Demand", Some(v)) => {
                meta.protocol.max_load = scaled(v, unit, Dim::Force);
                meta.protocol.max_depth = scaled(v, unit, Dim::Length);
            }
            ("Segment Number", Some(v)) => meta.protocol.segments.push(LoadSegment {
                number: if (0.0..1e9).contains(&v) { v as u32 } else { 0 },
                kind: String::new(),
                t_begin: f64::NAN,
                t_end: f64::NAN,
                begin: f64::NAN,
                end: f64::NAN,
                unit: String::new(),
                points: None,
            }),
            (k, v) if k.starts_with("Segment ") => {
                let Some(s) = meta.protocol.segments.last_mut() else {
                    continue;
                };
                let demand = |x: f64| match text::unit(unit) {
                    Some((d, f)) if d != Dim::Time => (x * f, d.internal().to_owned()),
                    _ => (x, unit.to_owned()),
                };
                match (k, v) {
                    ("Segment Type", _) => {
                        s.kind = l.split_once(':').map_or("", |(_, v)| v).trim().to_owned()
                    }
                    ("Segment Begin Time", Some(x)) => {
                        s.t_begin = scaled(x, unit, Dim::Time).unwrap_or(x)
                    }
                    ("Segment End Time", Some(x)) => {
                        s.t_end = scaled(x, unit, Dim::Time).unwrap_or(x)
                    }
                    ("Segment Begin Demand", Some(x)) => (s.begin, s.unit) = demand(x),
                    ("Segment End Demand", Some(x)) => (s.end, s.unit) = demand(x),
                    ("Segment Points", Some(x)) if (0.0..1e9).contains(&x) => {
                        s.points = Some(x as u32)
                    }
                    _ => {}
                }
            }
            (k, Some(v)) if OTHER_KEYS.contains(&k) => meta.other.push(Quantity::new(k, v, unit)),
            _ => {}
        }
    }
    if let Some(v) = version {
        match &mut meta.instrument {
            Some(i) => {
                i.push_str(" (");
                i.push_str(&v);
                i.push(')');
            }
            None => meta.instrument = Some(v),
        }
    }
    let p = &mut meta.protocol;
    // the hold: the longest segment whose demand stays at the maximum
    p.hold = p
        .segments
        .iter()
        .filter(|s| s.unit == "N" && p.max_load.is_some_and(|m| s.begin == m && s.end == m))
        .map(|s| s.t_end - s.t_begin)
        .fold(None, |a: Option<f64>, d| Some(a.map_or(d, |a| a.max(d))));
}

/// Reads an `.hld` file: the record is the `Test Data Points` block.
pub(crate) fn read_hld(file: &str, text: &str) -> Result<Record, ReadError> {
    let ls = text::lines(text);
    let first_section = ls
        .iter()
        .position(|(_, l)| section_line(l).is_some())
        .unwrap_or(ls.len());
    let mut meta = Meta {
        format: Format::Hld,
        ..Meta::default()
    };
    header(&ls[..first_section], &mut meta);
    let mut test = None;
    let mut i = first_section;
    while let Some(&(no, line)) = ls.get(i) {
        let Some((name, n)) = section_line(line) else {
            i += 1;
            if line.trim().is_empty() {
                continue;
            }
            return Err(ReadError::new(
                file,
                Some(no),
                K::Format,
                format!("unexpected line '{}'", crate::csv::clip(line)),
                "'<section> Data Points: N', a column header and N rows",
            ));
        };
        let declared = count(file, no, n, "points")?;
        let Some(&(hno, hline)) = ls.get(i + 1) else {
            return Err(count_error(
                file,
                no,
                &format!("'{name} Data Points'"),
                declared,
                0,
            ));
        };
        let start = i + 2;
        let mut end = start;
        while ls.get(end).is_some_and(|&(_, l)| {
            let f = l.trim_start().split(['\t', ' ']).next().unwrap_or("");
            text::number(f, false).is_some()
        }) {
            end += 1;
        }
        if end - start != declared {
            return Err(count_error(
                file,
                no,
                &format!("'{name} Data Points'"),
                declared,
                end - start,
            ));
        }
        if name == "Test" {
            let sep = Sep::of(hline);
            let layout = table::resolve(file, hno, &sep.split_header(hline))?;
            let cols = table::rows(file, &layout, ls.get(start..end).unwrap_or(&[]), sep)?;
            table::check(file, "test data", &cols, Some(no))?;
            test = Some(cols);
        }
        meta.other.push(Quantity::new(
            format!("{name} Data Points"),
            declared as f64,
            "",
        ));
        i = end;
    }
    let Some(cols) = test else {
        return Err(ReadError::new(
            file,
            None,
            K::Format,
            "no 'Test Data Points: N' section",
            "an .hld file with a 'Test Data Points: N' block of time, displacement and force",
        ));
    };
    let segment = segment_ids(&cols.t, &meta.protocol.segments);
    Ok(Record {
        name: file.to_owned(),
        t: cols.t,
        h: cols.h,
        f: cols.f,
        segment,
        meta,
    })
}

/// The load-function segment of each sample, when the segments cover the test's time.
fn segment_ids(t: &[f64], segs: &[LoadSegment]) -> Option<Vec<u32>> {
    let first = segs.first()?;
    let last = segs.last()?;
    let (t0, t1) = (*t.first()?, *t.last()?);
    let tol = 0.01 * (last.t_end - first.t_begin).abs();
    if !(first.t_begin <= t0 + tol && last.t_end >= t1 - tol) {
        return None;
    }
    Some(
        t.iter()
            .map(|&x| {
                segs.iter()
                    .rev()
                    .find(|s| s.t_begin <= x)
                    .map_or(first.number, |s| s.number)
            })
            .collect(),
    )
}
