//! Generic delimited tables: a header line naming the columns (with units), then rows.

use crate::error::{ReadError, ReadErrorKind as K};
use crate::record::{Format, Meta, Record};
use crate::table::{self, Sep};
use crate::text;

/// Whether a line is a row of numbers (at least two fields).
pub(crate) fn is_numeric_row(line: &str) -> bool {
    numeric_with(line, row_sep(line))
}

/// Whether `line` splits by `sep` into at least two numbers.
fn numeric_with(line: &str, sep: Sep) -> bool {
    let fs = sep.split(line);
    fs.len() >= 2
        && fs
            .iter()
            .all(|f| text::number(f, sep.decimal_comma()).is_some())
}

/// The separator of a data row: [`Sep::of`], except that blank-separated numbers with
/// decimal commas (`1,5 10,2 0,3`) are blank-separated.
pub(crate) fn row_sep(line: &str) -> Sep {
    let sep = Sep::of(line);
    if sep == Sep::Comma && !numeric_with(line, Sep::Comma) && numeric_with(line, Sep::Whitespace) {
        Sep::Whitespace
    } else {
        sep
    }
}

fn skip(line: &str) -> bool {
    line.trim().is_empty() || line.trim_start().starts_with('#')
}

/// Reads a generic table. Lines before the header are ignored; the header is the last
/// non-blank line before the first row of numbers, or the two last when the last holds only
/// units (names above, units below).
pub(crate) fn read(file: &str, text: &str) -> Result<Record, ReadError> {
    let ls = text::lines(text);
    let Some(k) = ls.iter().position(|&(_, l)| !skip(l) && is_numeric_row(l)) else {
        let first = ls.iter().find(|(_, l)| !skip(l));
        return Err(ReadError::new(
            file,
            first.map(|&(n, _)| n),
            K::NoRows,
            format!(
                "no row of numbers in {} lines{}",
                ls.len(),
                first
                    .map(|(_, l)| format!(" (first line '{}')", clip(l)))
                    .unwrap_or_default()
            ),
            "a header line naming the columns, then rows of numbers",
        ));
    };
    let Some(&(hno, header)) = ls[..k].iter().rev().find(|(_, l)| !skip(l)) else {
        return Err(ReadError::new(
            file,
            ls.get(k).map(|&(n, _)| n),
            K::Columns,
            "no header line before the first row of numbers",
            "a header naming the columns, e.g. 't,h,F' (s, mm, N) or 'Time (s);Depth (nm);Load (mN)'",
        ));
    };
    let mut sep = Sep::of(header);
    let mut labels = sep.split_header(header);
    if labels.len() < 3 {
        let data_sep = ls.get(k).map_or(sep, |&(_, l)| row_sep(l));
        if data_sep != sep {
            sep = data_sep;
            labels = sep.split_header(header);
        }
    }
    // a line of units under the line of names: `Time;Depth;Load` then `s;nm;mN`
    let mut hno = hno;
    if labels.iter().all(|l| text::is_unit_only(l)) {
        let before = ls[..k].iter().rev().filter(|(_, l)| !skip(l)).nth(1);
        if let Some(&(nno, names)) = before {
            let names = sep.split_header(names);
            if names.len() == labels.len() {
                labels = names
                    .iter()
                    .zip(&labels)
                    .map(|(n, u)| {
                        let u = u
                            .trim()
                            .trim_start_matches(['(', '['])
                            .trim_end_matches([')', ']']);
                        format!("{n} ({u})")
                    })
                    .collect();
                hno = nno;
            }
        }
    }
    let layout = table::resolve(file, hno, &labels)?;
    let cols = table::rows(file, &layout, &ls[k..], sep)?;
    table::check(file, "table", &cols, Some(hno))?;
    Ok(Record {
        name: file.to_owned(),
        t: cols.t,
        h: cols.h,
        f: cols.f,
        segment: cols.segment,
        meta: Meta {
            format: Format::Csv,
            ..Meta::default()
        },
    })
}

/// The start of a line for messages (at most 40 chars).
pub(crate) fn clip(line: &str) -> String {
    // control characters escaped: a binary file must not send escape sequences to a terminal
    let s: String = line
        .trim()
        .chars()
        .take(40)
        .flat_map(|c| {
            if c.is_control() {
                c.escape_default().collect::<Vec<char>>()
            } else {
                vec![c]
            }
        })
        .collect();
    if line.trim().chars().count() > 40 {
        format!("{s}...")
    } else {
        s
    }
}
