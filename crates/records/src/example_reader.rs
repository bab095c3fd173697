//! The worked example of docs/adding-a-reader.md, compiled and tested so that the guide
//! cannot drift from the crate: a reader of a made-up "ExampleIndenter" export. Test-only:
//! it is not dispatched by [`crate::read`] (the guide lists what dispatching it takes).
//! Columns are separated by tabs (shown here as spaces):
//!
//! ```text
//! ExampleIndenter export v1
//! Tip: Berkovich
//! Date: 2026-11-26 10:00
//! [data]
//! Time (s)    Depth (nm)    Load (µN)
//! 0.0    0.0    0.0
//! 0.5    120.5    35.2
//! ```

use crate::error::{ReadError, ReadErrorKind as K};
use crate::record::{Format, Meta, Record};
use crate::table::{self, Sep};
use crate::text;

/// Whether the text is an ExampleIndenter export (the format detection's test).
pub(crate) fn is_example(lines: &[(usize, &str)]) -> bool {
    lines
        .iter()
        .find(|(_, l)| !l.trim().is_empty())
        .is_some_and(|(_, l)| l.trim().starts_with("ExampleIndenter export"))
}

/// Reads an ExampleIndenter export: the title line, `Key: value` lines, a `[data]` line,
/// a column header with units, then rows. Every error names the file and, where there is
/// one, the line.
pub(crate) fn read(file: &str, text: &str) -> Result<Record, ReadError> {
    let ls = text::lines(text);
    if !is_example(&ls) {
        return Err(ReadError::new(
            file,
            ls.first().map(|&(n, _)| n),
            K::Format,
            "the first line is not 'ExampleIndenter export ...'",
            "an ExampleIndenter export: its title line, 'Key: value' lines, '[data]', a \
             column header and rows",
        ));
    }
    let Some(d) = ls.iter().position(|(_, l)| l.trim() == "[data]") else {
        return Err(ReadError::new(
            file,
            None,
            K::Format,
            "no '[data]' line",
            "a '[data]' line before the column header",
        ));
    };
    // what the header says goes into the metadata, as written
    let mut meta = Meta {
        format: Format::Auto, // a dispatched reader sets its own `Format` variant
        ..Meta::default()
    };
    for &(_, line) in &ls[1..d] {
        if let Some((key, value)) = line.split_once(':') {
            match key.trim() {
                "Tip" => meta.tip = Some(value.trim().to_string()),
                "Date" => meta.date = Some(value.trim().to_string()),
                _ => {}
            }
        }
    }
    let Some(&(hno, header)) = ls.get(d + 1) else {
        return Err(ReadError::new(
            file,
            Some(ls[d].0),
            K::Columns,
            "nothing after '[data]'",
            "a column header naming time, depth and force with their units",
        ));
    };
    // the crate's table machinery: columns by name and unit (converted to s, mm, N), rows
    // parsed with line numbers, at least two rows and a time that never decreases
    let sep = Sep::of(header);
    let layout = table::resolve(file, hno, &sep.split_header(header))?;
    let cols = table::rows(file, &layout, &ls[d + 2..], sep)?;
    table::check(file, "[data]", &cols, Some(hno))?;
    Ok(Record {
        name: file.to_string(),
        t: cols.t,
        h: cols.h,
        f: cols.f,
        segment: cols.segment,
        meta,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fuzzing::{Mutation, mutate};
    use proptest::prelude::*;

    const FILE: &str = "ExampleIndenter export v1\nTip: Berkovich\nDate: 2026-11-26 10:00\n\
                        [data]\nTime (s)\tDepth (nm)\tLoad (µN)\n0.0\t0.0\t0.0\n\
                        0.5\t120.5\t35.2\n1.0\t250.0\t80.0\n";

    /// Units are converted to s, mm, N and the header's tip kept.
    #[test]
    fn reads_and_converts_units() {
        let r = read("ex.txt", FILE).unwrap();
        assert_eq!(r.t, [0.0, 0.5, 1.0]);
        assert!((r.h[2] - 250.0e-6).abs() < 1e-18); // nm -> mm
        assert!((r.f[1] - 35.2e-6).abs() < 1e-18); // µN -> N
        assert_eq!(r.meta.tip.as_deref(), Some("Berkovich"));
    }

    /// A bad field is reported with the file, its line and what was expected.
    #[test]
    fn a_bad_field_names_the_line() {
        let bad = FILE.replace("120.5", "12O.5");
        let e = read("ex.txt", &bad).unwrap_err();
        assert_eq!((e.kind, e.line), (K::NotANumber, Some(7)));
        assert!(
            e.to_string().starts_with("ex.txt:7: '12O.5' in column"),
            "{e}"
        );
        let e = read("ex.txt", &FILE.replace("[data]", "[dat]")).unwrap_err();
        assert_eq!(e.kind, K::Format);
    }

    fn mutation() -> impl Strategy<Value = Mutation> {
        prop_oneof![
            (any::<usize>(), any::<u8>()).prop_map(|(at, byte)| Mutation::Flip { at, byte }),
            any::<usize>().prop_map(|at| Mutation::Truncate { at }),
            any::<usize>().prop_map(|line| Mutation::DuplicateLine { line }),
            any::<usize>().prop_map(|line| Mutation::DeleteLine { line }),
            (any::<usize>(), any::<usize>()).prop_map(|(at, token)| Mutation::Insert { at, token }),
            (any::<usize>(), any::<usize>()).prop_map(|(at, which)| Mutation::Hugify { at, which }),
        ]
    }

    proptest! {
        /// Mutated files give a record or an error, never a panic, and a record is whole.
        #[test]
        fn mutated_files_never_panic(ms in proptest::collection::vec(mutation(), 1..5)) {
            let mut b = FILE.as_bytes().to_vec();
            for m in &ms {
                b = mutate(b, m);
            }
            if let Ok(r) = read("fuzz", &text::decode(&b)) {
                prop_assert!(r.len() >= 2 && r.t.windows(2).all(|w| w[1] >= w[0]));
                prop_assert!(r.t.iter().chain(&r.h).chain(&r.f).all(|x| x.is_finite()));
            }
        }
    }
}
