//! Measured (or synthetic) force curves read from CSV: the `t,h,F,...` files that
//! `indentify simulate` writes, or any CSV with at least the columns `t` (s) and `F` (N),
//! with errors that name the file, the line and what was expected.

use std::path::Path;

use anyhow::{Context, Result, anyhow, bail};
use indentify_identify::ForceRecord;

/// A force curve as read from a file: times (s, strictly increasing), forces (N) and,
/// when the file has an `h` column, depths (mm).
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    /// The file name, for messages.
    pub name: String,
    /// Times (s).
    pub t: Vec<f64>,
    /// Depths (mm), if the file has a column `h`.
    pub h: Option<Vec<f64>>,
    /// Forces (N).
    pub f: Vec<f64>,
}

/// Finds column `want` in the header: the exact name, else the only case-insensitive match.
fn column(header: &[String], want: &str) -> Option<usize> {
    header.iter().position(|c| c == want).or_else(|| {
        let mut hits = header
            .iter()
            .enumerate()
            .filter(|(_, c)| c.eq_ignore_ascii_case(want));
        match (hits.next(), hits.next()) {
            (Some((i, _)), None) => Some(i),
            _ => None,
        }
    })
}

/// Reads a curve: a header line naming the columns (at least `t` and `F`; `h` is read when
/// present; any other column is ignored), then one row per time. Blank lines and lines
/// starting with `#` are skipped; spaces around fields are ignored.
///
/// # Errors
/// An unreadable file; a missing header or column; a row with too few fields, a field that
/// is not a finite number, or a time that does not follow the previous one (each with
/// `file:line`); fewer than 2 rows.
pub fn read_curve(path: &Path) -> Result<Curve> {
    let name = path.display().to_string();
    let text =
        std::fs::read(path).with_context(|| format!("cannot read the data file `{name}`"))?;
    parse_curve(&text, &name)
}

/// [`read_curve`] on the bytes of a file called `name`.
///
/// The column separator of a CSV file: `;` or a tab when the first line that is not a
/// comment has those and no comma (files written with a decimal comma, spreadsheets),
/// `,` otherwise.
fn delimiter(bytes: &[u8]) -> u8 {
    let first = bytes
        .split(|&b| b == b'\n')
        .find(|l| !l.starts_with(b"#") && !l.iter().all(u8::is_ascii_whitespace))
        .unwrap_or(&[]);
    if first.contains(&b',') {
        b','
    } else if first.contains(&b';') {
        b';'
    } else if first.contains(&b'\t') {
        b'\t'
    } else {
        b','
    }
}

/// # Errors
/// As [`read_curve`].
pub fn parse_curve(bytes: &[u8], name: &str) -> Result<Curve> {
    let expected = "a header line naming the columns, at least `t` (s) and `F` (N), as \
                    `indentify simulate` writes: t,h,F,a";
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .delimiter(delimiter(bytes))
        .from_reader(bytes);
    let header_record = reader
        .headers()
        .map_err(|e| anyhow!("{name}: {}", csv_error(&e)))?
        .clone();
    let header_line = header_record.position().map_or(1, csv::Position::line);
    let header: Vec<String> = header_record
        .iter()
        .map(|s| s.trim_start_matches('\u{feff}').to_string())
        .collect();
    if header.iter().all(String::is_empty) {
        bail!("`{name}` is empty: expected {expected}");
    }
    let find = |want: &str| {
        column(&header, want).ok_or_else(|| {
            anyhow!(
                "{name}:{header_line}: the header `{}` has no column `{want}`: expected {expected}",
                header.join(",")
            )
        })
    };
    let (it, i_f) = (find("t")?, find("F")?);
    let ih = column(&header, "h");
    let needed = 1 + it.max(i_f).max(ih.unwrap_or(0));
    let (mut t, mut f, mut h) = (Vec::new(), Vec::new(), Vec::new());
    let mut previous_line = header_line;
    for record in reader.records() {
        let record = record.map_err(|e| anyhow!("{name}: {}", csv_error(&e)))?;
        let line = record.position().map_or(0, csv::Position::line);
        if record.len() < needed {
            bail!(
                "{name}:{line}: {} field{} `{}`, expected {} (the header names {} columns: {})",
                record.len(),
                if record.len() == 1 { "" } else { "s" },
                record.iter().collect::<Vec<_>>().join(","),
                header.len(),
                header.len(),
                header.join(",")
            );
        }
        let number = |i: usize, unit: &str| -> Result<f64> {
            let field = &record[i];
            let v: f64 = field.parse().map_err(|_| {
                anyhow!(
                    "{name}:{line}: column `{}` holds `{field}`, expected a number ({unit})",
                    header[i]
                )
            })?;
            if !v.is_finite() {
                bail!(
                    "{name}:{line}: column `{}` holds `{field}`, expected a finite number ({unit})",
                    header[i]
                );
            }
            Ok(v)
        };
        let tv = number(it, "s")?;
        let fv = number(i_f, "N")?;
        if let Some(ih) = ih {
            h.push(number(ih, "mm")?);
        }
        if let Some(&last) = t.last() {
            if !(tv > last) {
                bail!(
                    "{name}:{line}: t = {tv} s does not follow t = {last} s of line \
                     {previous_line}: times must strictly increase"
                );
            }
        }
        t.push(tv);
        f.push(fv);
        previous_line = line;
    }
    if t.len() < 2 {
        bail!(
            "`{name}` has {} data row{}: at least 2 are needed (the force is interpolated \
             linearly between rows)",
            t.len(),
            if t.len() == 1 { "" } else { "s" }
        );
    }
    Ok(Curve {
        name: name.to_string(),
        t,
        h: ih.map(|_| h),
        f,
    })
}

/// A csv error without the crate's own position prefix, with the line.
fn csv_error(e: &csv::Error) -> String {
    match e.kind() {
        csv::ErrorKind::Utf8 { pos, err } => format!(
            "{}: the file is not UTF-8 text ({err})",
            pos.as_ref().map_or(0, csv::Position::line)
        ),
        csv::ErrorKind::Io(err) => format!("cannot read: {err}"),
        _ => e.to_string(),
    }
}

impl Curve {
    /// Time range `[first, last]` (s).
    pub fn span(&self) -> (f64, f64) {
        (self.t[0], self.t[self.t.len() - 1])
    }

    /// Checks that the curve covers the simulated times `[t0, t1]` of `config` (with the
    /// library's round-off allowance, `1e-9` of the curve's span).
    ///
    /// # Errors
    /// The two ranges, when the curve starts after `t0` or ends before `t1`.
    pub fn check_covers(&self, t0: f64, t1: f64, config: &str) -> Result<()> {
        let (a, b) = self.span();
        let tol = 1e-9 * (b - a).abs();
        if t0 < a - tol || t1 > b + tol {
            bail!(
                "the data `{}` cover t in [{a}, {b}] s, but the simulation of `{config}` runs \
                 over [{t0}, {t1}] s: the data must cover the whole simulated history (shorten \
                 `history.segments` or give a longer record)",
                self.name
            );
        }
        Ok(())
    }

    /// The curve as the identification library's record.
    ///
    /// # Errors
    /// What the library rejects (already excluded by [`read_curve`]).
    pub fn record(&self) -> Result<ForceRecord> {
        ForceRecord::new(self.t.clone(), self.f.clone())
            .with_context(|| format!("invalid data `{}`", self.name))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        format!("{:#}", parse_curve(text.as_bytes(), "d.csv").unwrap_err())
    }

    #[test]
    fn semicolons_and_tabs_separate_columns_too() {
        for sep in [";", "\t"] {
            let text = format!("t{sep}h{sep}F\n0{sep}0{sep}0\n1{sep}0.1{sep}2.5\n");
            let c = parse_curve(text.as_bytes(), "x.csv").unwrap();
            assert_eq!(c.f, [0.0, 2.5], "{sep:?}");
        }
    }

    #[test]
    fn reads_the_simulate_format_and_ignores_extra_columns() {
        let c = parse_curve(b"t,h,F,a\n0,0,0,0\n0.5,0.05,12.5,0.01\n1,0.1,40,0.1\n", "d").unwrap();
        assert_eq!(c.t, [0.0, 0.5, 1.0]);
        assert_eq!(c.f, [0.0, 12.5, 40.0]);
        assert_eq!(c.h.as_deref(), Some(&[0.0, 0.05, 0.1][..]));
        let c = parse_curve(b"# from a test\nF , t\n\n1, 0\n 2 ,1\n", "d").unwrap();
        assert_eq!((c.t, c.f, c.h), (vec![0.0, 1.0], vec![1.0, 2.0], None));
    }

    #[test]
    fn errors_name_file_line_and_what_was_expected() {
        let e = err("t,h,a\n0,0,0\n");
        assert!(e.contains("d.csv:1:") && e.contains("no column `F`"), "{e}");
        let e = err("t,h,F,a\n0,0,0,0\n1,0.1,x,0\n");
        assert!(e.contains("d.csv:3:") && e.contains("`F` holds `x`"), "{e}");
        let e = err("t,h,F,a\n0,0,0,0\n1,0.1\n");
        assert!(e.contains("d.csv:3:") && e.contains("2 fields"), "{e}");
        let e = err("t,F\n0,0\n1,1\n1,2\n");
        assert!(
            e.contains("d.csv:4:") && e.contains("strictly increase"),
            "{e}"
        );
        let e = err("t,F\n0,NaN\n");
        assert!(e.contains("d.csv:2:") && e.contains("finite"), "{e}");
        let e = err("t,F\n0,0\n");
        assert!(e.contains("1 data row") && e.contains("at least 2"), "{e}");
        let e = err("");
        assert!(e.contains("empty"), "{e}");
    }

    #[test]
    fn coverage_names_both_ranges() {
        let c = parse_curve(b"t,F\n0,0\n2,1\n", "d.csv").unwrap();
        c.check_covers(0.0, 2.0, "x.ron").unwrap();
        let e = c.check_covers(0.0, 3.0, "x.ron").unwrap_err().to_string();
        assert!(e.contains("[0, 2] s") && e.contains("[0, 3] s"), "{e}");
    }
}
