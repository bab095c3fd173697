//! Readers of real instrumented-indentation records, from bytes, and their preprocessing.
//!
//! TODO doc

mod anton_paar;
mod csv;
mod error;
mod hysitron;
pub mod prep;
mod record;
mod table;
mod text;

pub use error::{PrepError, ReadError, ReadErrorKind};
pub use prep::{
    Applied, Control, Correction, Phase, Preprocessing, Resample, Segments, Span, ZeroPoint, apply,
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
/// - [`Format::Csv`] otherwise.
pub fn detect(bytes: &[u8]) -> Format {
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
