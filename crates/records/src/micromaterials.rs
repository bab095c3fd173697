//! Micro Materials NanoTest text exports: one indent per file, no header, three
//! tab-separated columns, time (s), depth (nm) and force (mN), the convention of the public
//! sample in docs/analysis.md ("Other vendors' exports"). The file states no units, so a
//! file is taken for one only when its first lines are all three tab-separated numbers
//! (a generic table has a header); the rows before the clock starts (the approach, at
//! t = 0) are kept as they are.

use crate::error::{ReadError, ReadErrorKind as K};
use crate::record::{Format, Meta, Record};
use crate::table::{self, Sep};
use crate::text;

/// The non-empty lines the detection looks at, and the fewest it needs.
const SNIFF: usize = 20;
const SNIFF_MIN: usize = 10;

/// The columns the format implies (the table machinery converts them to s, mm, N).
const COLUMNS: [&str; 3] = ["Time (s)", "Depth (nm)", "Load (mN)"];

fn numbers3(line: &str) -> bool {
    let fields: Vec<&str> = line.trim().split('\t').collect();
    fields.len() == 3
        && fields
            .iter()
            .all(|f| text::number(f.trim(), false).is_some_and(f64::is_finite))
}

/// Whether the text is a NanoTest export: its first non-empty lines (at least 10, up to
/// 20) are each three tab-separated finite numbers.
pub(crate) fn is_nanotest(lines: &[(usize, &str)]) -> bool {
    let first: Vec<&str> = lines
        .iter()
        .map(|(_, l)| *l)
        .filter(|l| !l.trim().is_empty())
        .take(SNIFF)
        .collect();
    first.len() >= SNIFF_MIN && first.iter().all(|l| numbers3(l))
}

/// Reads a NanoTest export. Every error names the file and, where there is one, the line.
pub(crate) fn read(file: &str, text: &str) -> Result<Record, ReadError> {
    let ls = text::lines(text);
    let Some(&(first, line)) = ls.iter().find(|(_, l)| !l.trim().is_empty()) else {
        return Err(ReadError::new(
            file,
            None,
            K::NoRows,
            "no rows",
            "rows of time (s), depth (nm) and force (mN), tab-separated",
        ));
    };
    if !numbers3(line) {
        return Err(ReadError::new(
            file,
            Some(first),
            K::Format,
            "the first line is not three tab-separated numbers",
            "a Micro Materials NanoTest export: no header, rows of time (s), depth (nm) and \
             force (mN) separated by tabs",
        ));
    }
    let labels: Vec<String> = COLUMNS.iter().map(|c| c.to_string()).collect();
    let layout = table::resolve(file, first, &labels)?;
    let cols = table::rows(file, &layout, &ls, Sep::Tab)?;
    table::check(file, "data", &cols, Some(first))?;
    Ok(Record {
        name: file.to_string(),
        t: cols.t,
        h: cols.h,
        f: cols.f,
        segment: cols.segment,
        meta: Meta {
            format: Format::MicroMaterials,
            ..Meta::default()
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file() -> String {
        let mut s = String::from("0.000000\t-12.5\t-0.001\n0.000000\t0.000000\t0.000000\n");
        for i in 1..=20 {
            let t = i as f64 * 0.5;
            s.push_str(&format!("{t:.6}\t{:.6}\t{:.6}\n", 25.0 * t, 0.1 * t * t));
        }
        s
    }

    /// Detected, read, and converted: nm to mm, mN to N; the approach at t = 0 kept.
    #[test]
    fn reads_and_converts_units() {
        let text = file();
        assert!(is_nanotest(&text::lines(&text)));
        let r = read("500nmXX 4.txt", &text).unwrap();
        assert_eq!(r.len(), 22);
        assert_eq!(r.meta.format, Format::MicroMaterials);
        assert!((r.h[0] + 12.5e-6).abs() < 1e-18);
        assert!((r.h[21] - 250.0e-6).abs() < 1e-15); // 250 nm
        assert!((r.f[21] - 10.0e-3).abs() < 1e-15); // 10 mN
    }

    /// A header, or too few rows, is not this format; a bad field names its line (mutated
    /// files of every format go through this reader in `tests/fuzz.rs`).
    #[test]
    fn headers_and_bad_fields() {
        let text = file();
        let headed = format!("Time (s)\tDepth (nm)\tLoad (mN)\n{text}");
        assert!(!is_nanotest(&text::lines(&headed)));
        let short: String = text.lines().take(5).map(|l| format!("{l}\n")).collect();
        assert!(!is_nanotest(&text::lines(&short)));
        let bad = text.replacen("25.000000", "25.0O0000", 1);
        let e = read("x.txt", &bad).unwrap_err();
        assert_eq!(e.kind, K::NotANumber);
        assert!(e.line.is_some());
        let e = read("x.txt", &headed).unwrap_err();
        assert_eq!(e.kind, K::Format);
    }
}
