//! Readers of real instrumented-indentation records, from bytes, and their preprocessing.
//!
//! The crate does no file IO: [`read`] and [`read_one`] take the file's bytes and a display
//! name (used in messages and as the record's name); the CLI reads the file. It depends on
//! no other indentify crate.
//!
//! # Formats
//!
//! | [`Format`] | what it reads | detected by |
//! |---|---|---|
//! | `Csv` | a header line then rows; comma, semicolon, tab or blank separated; decimal commas where the separator is not a comma; lines before the header are ignored, `#` lines skipped; an optional `segment` column | the fallback |
//! | `AntonPaar` | single-test TXT: method header (rates, max depth, pause, O&P results), `Measured values`, `Time (s) Pd (nm) Fn (mN) ... SegmentID` | a `Measured values` line |
//! | `AntonPaarMulti` | tests side by side: `X_<test>_Time_[s] Y_<test>_Fn_[mN] X_<test>_Time_[s] Y_<test>_Pd_[nm]`; a shorter test's trailing repeats of its last row are dropped | first header `X_..._Time_` |
//! | `HysitronTxt` | date, `Number of Points = N`, `Depth (nm) Load (µN) Time (s) ...`; blank lines between rows give segment ids | `Number of Points =` |
//! | `Kla` | KLA/Agilent/Keysight workbooks (`.xlsx`, `.xls`, read with `calamine`): a sheet per test `Test <N>` (names row, units row, samples), the `Results`, `Pre-Test Inputs`, `Post-Test Inputs` and `Cycles-GroupedByTest` sheets into the metadata | zip or OLE2 magic bytes |
//! | `Hld` | `Key: value unit` header (machine compliance, drift rate, tip area coefficients, load-function segments), then `<section> Data Points: N` blocks; the record is `Test Data` (`Time_s Disp_nm Force_µN`), each sample tagged with its load-function segment | `File Version: Hysitron` or `Test Data Points:` |
//!
//! The results table beside a multi-test file (`HT_V_100mN_data.TXT`: `Group Measurement
//! Parameter Unit Value`) reads with [`read_results`]; [`attach_results`] puts each test's
//! results into its record's `meta.results`.
//!
//! Bytes may be UTF-8 (BOM or not), UTF-16 with BOM, or Latin-1/cp1252 (the micro sign
//! `0xB5`); lines may end in CRLF, LF or CR.
//!
//! # Columns and units
//!
//! Column names (case-insensitive, `_`/`-` as blanks): time `t`, `time`, `time on sample`;
//! depth `h`, `depth`, `displacement`, `disp`, `pd`, `displacement into surface`; force
//! `f`, `force`, `load`, `fn`, `p`, `load on sample`; segment `segment`, `segmentid`.
//! Units go in parentheses, brackets or after a last `_` (`t [s]`, `Time (s)`,
//! `time_ms`, `Depth (nm)`, `h [µm]`, `Load (uN)`, `Force_µN`), or on a line of their own
//! under the names (`Time;Depth;Load` then `s;nm;mN`).
//! Accepted: nm, µm/um, mm, m; nN, µN/uN, mN, N, kN; ms, s, min, h. A column without a unit
//! is in internal units, so the `t,h,F,a` files of `indentify simulate` read as they are.
//! Everything is converted to **mm, N, s**; a column with another unit (`Depth (V)`) is
//! skipped when a usable one of the same quantity exists.
//!
//! # Errors
//!
//! A [`ReadError`] displays as `file:line: what is wrong; expected ...` and carries a
//! [`ReadErrorKind`]; no input makes a reader panic (fuzzed, `cargo xtask fuzz-readers`).
//!
//! # Preprocessing
//!
//! [`apply`] runs the steps of a [`Preprocessing`] (a RON-friendly options struct) in this
//! order, each optional, each returning an [`Applied`] account with numbers for the report:
//!
//! 1. [`prep::drift`]: `h <- h - rate t` (rate from the options or the file's hint);
//! 2. [`prep::zero_point`]: contact where the force rises through a threshold, `h` and `F`
//!    offsets subtracted, approach trimmed, `t = 0` at contact;
//! 3. [`prep::compliance`]: `h <- h - C F` (C from the options or the file's hint);
//! 4. [`prep::segments`]: load/hold/unload, mapped from the file's segment ids or detected;
//! 5. [`prep::resample`]: `n` points from `t = 0`, keeping segment boundaries and the peak
//!    depth, values averaged over each point's interval.
//!
//! ```
//! use indentify_records::{Preprocessing, ReadOptions, Resample, apply, read_one};
//!
//! // 1 s of approach, 10 s of loading to 10 mN, 10 s of unloading, 10 Hz, in nm and mN
//! let mut csv = String::from("Time (s);Depth (nm);Load (mN)\n");
//! for i in 0..=210 {
//!     let t = i as f64 * 0.1;
//!     let f = if t <= 1.0 { 0.0 } else if t <= 11.0 { t - 1.0 } else { 21.0 - t };
//!     let h = 50.0 * t.min(1.0) + 20.0 * f;
//!     csv.push_str(&format!("{t};{h};{f}\n").replace('.', ","));
//! }
//! let record = read_one(csv.as_bytes(), "curve.csv", &ReadOptions::default())?;
//! assert_eq!(record.len(), 211);
//! let p = Preprocessing {
//!     resample: Some(Resample { n: 41, min_per_segment: 5 }),
//!     ..Preprocessing::default()
//! };
//! let (r, steps) = apply(&record, &p)?;
//! assert_eq!(r.len(), 41);
//! assert_eq!(r.t[0], 0.0);
//! assert!((r.t[40] - 20.0).abs() < 1e-9); // contact at 1 s is t = 0
//! assert!((r.f_max() - 10e-3).abs() < 1e-12); // the peak is kept
//! for s in &steps {
//!     println!("{}: {}", s.step, s.description);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod anton_paar;
mod csv;
mod error;
#[cfg(test)]
mod example_reader;
pub mod fuzzing;
mod hysitron;
mod kla;
mod micromaterials;
pub mod prep;
mod record;
mod surface;
mod table;
mod text;

pub use anton_paar::TestResults;
pub use error::{PrepError, ReadError, ReadErrorKind};
pub use prep::{
    Applied, Control, Correction, MAX_RESAMPLE_POINTS, Phase, Preprocessing, Resample, Segments,
    Span, ZeroPoint, apply,
};
pub use record::{Format, LoadSegment, Meta, Protocol, Quantity, ReadOptions, Record};

use error::ReadErrorKind as K;

/// The format of `bytes` judged from the content (never [`Format::Auto`]):
///
/// - [`Format::Hld`]: the first line is `File Version: Hysitron ...`, or a
///   `Test Data Points: N` line exists;
/// - [`Format::HysitronTxt`]: a `Number of Points = N` line within the first 20 lines;
/// - [`Format::AntonPaarMulti`]: the first line starts with `X_<test>_Time_`;
/// - [`Format::AntonPaar`]: a `Measured values` line exists;
/// - [`Format::MicroMaterials`]: no header, the first 10-20 lines three tab-separated
///   numbers;
/// - [`Format::Csv`] otherwise.
pub fn detect(bytes: &[u8]) -> Format {
    if kla::is_workbook(bytes) {
        return Format::Kla;
    }
    detect_text(&text::decode(bytes))
}

fn detect_text(text: &str) -> Format {
    let ls = text::lines(text);
    if hysitron::is_hld(&ls) {
        Format::Hld
    } else if hysitron::is_txt(&ls) {
        Format::HysitronTxt
    } else if ls
        .iter()
        .find(|(_, l)| !l.trim().is_empty())
        .is_some_and(|(_, l)| anton_paar::is_multi_header(l))
    {
        Format::AntonPaarMulti
    } else if ls
        .iter()
        .any(|(_, l)| l.trim().eq_ignore_ascii_case("measured values"))
    {
        Format::AntonPaar
    } else if micromaterials::is_nanotest(&ls) {
        Format::MicroMaterials
    } else {
        Format::Csv
    }
}

/// Reads every test of a file (or the one selected by `opts.test`, 1-based).
///
/// `name` is used in messages and as the record's name (multi-test files append the test
/// name). Bytes may be UTF-8 (with or without BOM), UTF-16 with BOM, or Latin-1/cp1252;
/// lines may end in CRLF, LF or CR.
///
/// # Errors
///
/// A [`ReadError`] naming the file, the line where known, what is wrong and what was
/// expected: empty file, no rows of numbers, missing or unrecognised columns or units, a
/// field that is not a number or not finite, time going back, a row with too few fields,
/// a declared point count that disagrees with the rows, a test index out of range, fewer
/// than two rows.
pub fn read(bytes: &[u8], name: &str, opts: &ReadOptions) -> Result<Vec<Record>, ReadError> {
    if opts.format == Format::Kla || (opts.format == Format::Auto && kla::is_workbook(bytes)) {
        return kla::read(name, bytes, opts.test);
    }
    let text = text::decode(bytes);
    if text.trim().is_empty() {
        return Err(ReadError::new(
            name,
            None,
            K::Empty,
            "the file is empty",
            "a header and at least two rows of time, depth and force",
        ));
    }
    let format = match opts.format {
        Format::Auto => detect_text(&text),
        f => f,
    };
    let single = |r: Record| -> Result<Vec<Record>, ReadError> {
        match opts.test {
            None | Some(1) => Ok(vec![r]),
            Some(k) => Err(anton_paar::test_index_error(name, k, &[r.name])),
        }
    };
    match format {
        Format::Auto | Format::Csv => single(csv::read(name, &text)?),
        Format::AntonPaar => single(anton_paar::read_single(name, &text)?),
        Format::AntonPaarMulti => anton_paar::read_multi(name, &text, opts.test),
        Format::HysitronTxt => single(hysitron::read_txt(name, &text)?),
        Format::Hld => single(hysitron::read_hld(name, &text)?),
        Format::Kla => kla::read(name, bytes, opts.test),
        Format::MicroMaterials => single(micromaterials::read(name, &text)?),
    }
}

/// Reads exactly one record: the selected test, or the only one.
///
/// # Errors
///
/// Those of [`read`], and [`ReadErrorKind::TestIndex`] when the file holds several tests
/// and none is selected (the message lists them).
pub fn read_one(bytes: &[u8], name: &str, opts: &ReadOptions) -> Result<Record, ReadError> {
    let mut all = read(bytes, name, opts)?;
    if all.len() == 1 {
        if let Some(r) = all.pop() {
            return Ok(r);
        }
    }
    let list = all
        .iter()
        .enumerate()
        .map(|(i, r)| {
            format!(
                "{} = {}",
                i + 1,
                r.meta.test_name.as_deref().unwrap_or(&r.name)
            )
        })
        .collect::<Vec<_>>()
        .join(", ");
    Err(ReadError::new(
        name,
        None,
        K::TestIndex,
        format!(
            "the file holds {} tests ({list}) and none is selected",
            all.len()
        ),
        format!("a test index from 1 to {}", all.len()),
    ))
}

/// Reads an Anton Paar results table (the `_data.TXT` beside a multi-test curve file:
/// `Group  Measurement  Parameter  Unit  Value`), one [`TestResults`] per group and
/// measurement, in file order.
///
/// # Errors
///
/// A [`ReadError`]: empty file, another header, a row with fewer than 5 fields, a value
/// that is not a finite number.
pub fn read_results(bytes: &[u8], name: &str) -> Result<Vec<TestResults>, ReadError> {
    anton_paar::read_results(name, &text::decode(bytes))
}

/// Appends to each record's `meta.results` the results whose test name equals the record's
/// `meta.test_name`; returns how many records got results.
pub fn attach_results(records: &mut [Record], results: &[TestResults]) -> usize {
    let mut n = 0;
    for r in records.iter_mut() {
        let Some(name) = r.meta.test_name.as_deref() else {
            continue;
        };
        if let Some(tr) = results.iter().find(|x| x.test == name) {
            r.meta.results.extend(tr.values.iter().cloned());
            n += 1;
        }
    }
    n
}
