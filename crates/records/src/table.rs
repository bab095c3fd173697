//! Delimited numeric tables with unit-bearing headers: column resolution, row parsing into
//! internal units, and the checks every reader shares (finite values, time order, length).

use crate::error::{ReadError, ReadErrorKind as K};
use crate::text::{self, Dim, Quantity};

/// Field separator of a table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Sep {
    Tab,
    Semicolon,
    Comma,
    Whitespace,
}

impl Sep {
    /// The separator a line suggests: tab, then semicolon, then comma, else blanks.
    pub(crate) fn of(line: &str) -> Sep {
        if line.contains('\t') {
            Sep::Tab
        } else if line.contains(';') {
            Sep::Semicolon
        } else if line.contains(',') {
            Sep::Comma
        } else {
            Sep::Whitespace
        }
    }

    pub(crate) fn split(self, line: &str) -> Vec<&str> {
        let mut v: Vec<&str> = match self {
            Sep::Tab => line.split('\t').map(str::trim).collect(),
            Sep::Semicolon => line.split(';').map(str::trim).collect(),
            Sep::Comma => line.split(',').map(str::trim).collect(),
            Sep::Whitespace => line.split_whitespace().collect(),
        };
        while v.last().is_some_and(|f| f.is_empty()) {
            v.pop();
        }
        v
    }

    /// Header labels; with blank separation a `(unit)` or `[unit]` token joins the label
    /// before it (`Time (s) Depth (nm)`).
    pub(crate) fn split_header(self, line: &str) -> Vec<String> {
        let fields = self.split(line);
        if self != Sep::Whitespace {
            return fields.into_iter().map(str::to_owned).collect();
        }
        let mut out: Vec<String> = Vec::new();
        for f in fields {
            let is_unit = (f.starts_with('(') && f.ends_with(')'))
                || (f.starts_with('[') && f.ends_with(']'));
            match out.last_mut() {
                Some(prev) if is_unit => {
                    prev.push(' ');
                    prev.push_str(f);
                }
                _ => out.push(f.to_owned()),
            }
        }
        out
    }

    /// Whether numbers may use a decimal comma with this separator.
    pub(crate) fn decimal_comma(self) -> bool {
        self != Sep::Comma
    }
}

/// Columns parsed from a table (or assembled by a reader), with the source line of each row.
#[derive(Debug, Clone, Default)]
pub(crate) struct Cols {
    pub(crate) t: Vec<f64>,
    pub(crate) h: Vec<f64>,
    pub(crate) f: Vec<f64>,
    pub(crate) segment: Option<Vec<u32>>,
    pub(crate) lines: Vec<usize>,
}

/// A resolved column: index, label as written, factor to internal units.
#[derive(Debug, Clone)]
pub(crate) struct Col {
    pub(crate) index: usize,
    pub(crate) label: String,
    pub(crate) factor: f64,
}

/// The time, depth, force (and optional segment) columns of a header.
#[derive(Debug, Clone)]
pub(crate) struct Layout {
    pub(crate) t: Col,
    pub(crate) h: Col,
    pub(crate) f: Col,
    pub(crate) segment: Option<Col>,
}

impl Layout {
    fn width(&self) -> usize {
        [
            self.t.index,
            self.h.index,
            self.f.index,
            self.segment.as_ref().map_or(0, |c| c.index),
        ]
        .into_iter()
        .max()
        .unwrap_or(0)
            + 1
    }
}

/// Picks the time, depth and force columns of `labels`: the first column whose name is a
/// synonym and whose unit is of the right dimension (no unit = internal units).
pub(crate) fn resolve(file: &str, line: usize, labels: &[String]) -> Result<Layout, ReadError> {
    let parsed: Vec<text::Label> = labels.iter().map(|l| text::label(l)).collect();
    let found = || {
        labels
            .iter()
            .map(|l| format!("'{l}'"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let pick = |q: Quantity, dim: Dim, names: &[&str]| -> Result<Col, ReadError> {
        let mut bad_unit: Option<&text::Label> = None;
        for (index, l) in parsed.iter().enumerate() {
            if text::quantity(&l.name) != Some(q) {
                continue;
            }
            match &l.unit {
                None => {
                    return Ok(Col {
                        index,
                        label: l.text.clone(),
                        factor: 1.0,
                    });
                }
                Some(u) => match text::unit(u) {
                    Some((d, factor)) if d == dim => {
                        return Ok(Col {
                            index,
                            label: l.text.clone(),
                            factor,
                        });
                    }
                    _ => {
                        bad_unit.get_or_insert(l);
                    }
                },
            }
        }
        Err(match bad_unit {
            Some(l) => ReadError::new(
                file,
                Some(line),
                K::Units,
                format!(
                    "column '{}' has unit '{}', not a unit of {}",
                    l.text,
                    l.unit.as_deref().unwrap_or(""),
                    dim.internal()
                ),
                format!(
                    "one of {} (no unit means {})",
                    dim.accepted(),
                    dim.internal()
                ),
            ),
            None => ReadError::new(
                file,
                Some(line),
                K::Columns,
                format!("no {} column among {}", quantity_name(q), found()),
                format!(
                    "a column named {} with a unit in parentheses, brackets or after '_' ({}), e.g. 'Depth (nm)', 'F [mN]', 'time_s'",
                    names.join("/"),
                    dim.accepted()
                ),
            ),
        })
    };
    let t = pick(Quantity::Time, Dim::Time, text::TIME_NAMES)?;
    let h = pick(Quantity::Depth, Dim::Length, text::DEPTH_NAMES)?;
    let f = pick(Quantity::Force, Dim::Force, text::FORCE_NAMES)?;
    let segment = parsed
        .iter()
        .position(|l| text::quantity(&l.name) == Some(Quantity::Segment))
        .map(|index| Col {
            index,
            label: labels.get(index).cloned().unwrap_or_default(),
            factor: 1.0,
        });
    Ok(Layout { t, h, f, segment })
}

fn quantity_name(q: Quantity) -> &'static str {
    match q {
        Quantity::Time => "time",
        Quantity::Depth => "depth",
        Quantity::Force => "force",
        Quantity::Segment => "segment",
    }
}

/// `'raw'`, with invisible characters (control bytes, a byte-order mark, non-breaking or
/// zero-width spaces) written as `\u{..}` and named, so that a field that looks like a
/// number shows why it is not one.
pub(crate) fn visible(raw: &str) -> String {
    let hidden = |c: char| {
        c.is_control()
            || matches!(
                c,
                '\u{feff}' | '\u{a0}' | '\u{200b}' | '\u{2007}' | '\u{202f}'
            )
    };
    let shown: String = raw
        .chars()
        .map(|c| {
            if hidden(c) {
                format!("\\u{{{:x}}}", c as u32)
            } else {
                c.to_string()
            }
        })
        .collect();
    let n = raw.chars().filter(|&c| hidden(c)).count();
    if n == 0 {
        format!("'{shown}'")
    } else {
        format!(
            "'{shown}' (with {n} invisible character{}, shown as \\u{{..}})",
            if n == 1 { "" } else { "s" }
        )
    }
}

/// Parses one field of column `col` on `line` into internal units.
pub(crate) fn field(
    file: &str,
    line: usize,
    raw: &str,
    label: &str,
    factor: f64,
    decimal_comma: bool,
) -> Result<f64, ReadError> {
    let v = text::number(raw, decimal_comma).ok_or_else(|| {
        ReadError::new(
            file,
            Some(line),
            K::NotANumber,
            format!("{} in column '{label}' is not a number", visible(raw)),
            if decimal_comma {
                "a decimal number (point or comma)"
            } else {
                "a decimal number"
            },
        )
    })?;
    let x = v * factor;
    if !x.is_finite() {
        return Err(ReadError::new(
            file,
            Some(line),
            K::NotFinite,
            format!(
                "'{raw}' in column '{label}' is {}",
                if v.is_finite() {
                    "too large"
                } else {
                    "not finite"
                }
            ),
            "a finite number",
        ));
    }
    Ok(x)
}

/// Parses data rows with a resolved layout. Blank lines and `#` comments are skipped.
pub(crate) fn rows(
    file: &str,
    layout: &Layout,
    rows: &[(usize, &str)],
    sep: Sep,
) -> Result<Cols, ReadError> {
    let dc = sep.decimal_comma();
    let width = layout.width();
    let mut c = Cols {
        segment: layout.segment.as_ref().map(|_| Vec::new()),
        ..Cols::default()
    };
    for &(no, line) in rows {
        if line.trim().is_empty() || line.trim_start().starts_with('#') {
            continue;
        }
        let fs = sep.split(line);
        if fs.len() < width {
            return Err(ReadError::new(
                file,
                Some(no),
                K::FewFields,
                format!("{} fields", fs.len()),
                format!(
                    "at least {width} fields (time '{}' is field {}, depth '{}' field {}, force '{}' field {})",
                    layout.t.label,
                    layout.t.index + 1,
                    layout.h.label,
                    layout.h.index + 1,
                    layout.f.label,
                    layout.f.index + 1
                ),
            ));
        }
        let get = |col: &Col| {
            field(
                file,
                no,
                fs.get(col.index).copied().unwrap_or(""),
                &col.label,
                col.factor,
                dc,
            )
        };
        c.t.push(get(&layout.t)?);
        c.h.push(get(&layout.h)?);
        c.f.push(get(&layout.f)?);
        if let (Some(col), Some(seg)) = (&layout.segment, c.segment.as_mut()) {
            let v = get(col)?;
            if !(v >= 0.0 && v <= f64::from(u32::MAX) && v.fract() == 0.0) {
                return Err(ReadError::new(
                    file,
                    Some(no),
                    K::NotANumber,
                    format!("segment id {v} in column '{}'", col.label),
                    "a non-negative integer",
                ));
            }
            seg.push(v as u32);
        }
        c.lines.push(no);
    }
    Ok(c)
}

/// The checks every record passes: at least two rows and a time that never decreases.
pub(crate) fn check(
    file: &str,
    what: &str,
    c: &Cols,
    near: Option<usize>,
) -> Result<(), ReadError> {
    if c.t.len() < 2 {
        return Err(ReadError::new(
            file,
            c.lines.first().copied().or(near),
            if c.t.is_empty() {
                K::NoRows
            } else {
                K::TooFewRows
            },
            format!("{what}: {} data rows", c.t.len()),
            "at least 2 rows of numbers",
        ));
    }
    for i in 1..c.t.len() {
        if c.t[i] < c.t[i - 1] {
            return Err(ReadError::new(
                file,
                c.lines.get(i).copied(),
                K::TimeOrder,
                format!(
                    "{what}: time goes back from {} s (line {}) to {} s",
                    c.t[i - 1],
                    c.lines.get(i - 1).copied().unwrap_or(0),
                    c.t[i]
                ),
                "a time that never decreases",
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invisible_characters_are_shown_and_counted() {
        assert_eq!(visible("12.3"), "'12.3'");
        let v = visible("12.304803\u{0}");
        assert!(v.starts_with("'12.304803\\u{0}'"), "{v}");
        assert!(v.contains("1 invisible character,"), "{v}");
        let v = visible("\u{feff}1\u{a0}2");
        assert!(
            v.contains("\\u{feff}1\\u{a0}2") && v.contains("2 invisible characters"),
            "{v}"
        );
    }

    #[test]
    fn a_field_with_a_control_byte_names_it() {
        let e = field("f.csv", 7, "12.304803\u{1}", "Load", 1.0, false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("\\u{1}") && e.contains("invisible"), "{e}");
        assert!(e.contains("f.csv") && e.contains('7'), "{e}");
    }
}
