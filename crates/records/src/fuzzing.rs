//! Mutations of instrument files for fuzzing the readers: the byte-level and line-level
//! edits that real files suffer (flipped bytes, truncations, duplicated or deleted lines,
//! inserted NaN/inf/huge numbers, separators and section headers, swapped columns, digits
//! turned into huge or non-finite numbers). Shared by the crate's proptest suite and
//! `cargo xtask fuzz-readers`; positions are taken modulo the sizes, so any values are valid.

use crate::record::Format;

/// Tokens inserted by [`Mutation::Insert`]: non-finite and huge numbers, separators, line
/// ends, micro signs in Latin-1 and UTF-8, a BOM, a decimal comma, units and the section
/// headers the format detection looks for.
pub const TOKENS: &[&[u8]] = &[
    b"NaN",
    b"inf",
    b"-inf",
    b"1e308",
    b"-1e308",
    b"9e999",
    b"-0",
    b"",
    b"\t",
    b",",
    b";",
    b"\r",
    b"\n",
    b"\r\n",
    b"\xB5",
    b"\xC2\xB5",
    b"\xEF\xBB\xBF",
    b"0,5",
    b"x",
    b"(nm)",
    b"[s]",
    b"_ms",
    b"Number of Points = 7",
    b"Test Data Points: 3",
    b"Drift Measurement Data Points: 2",
    b"Measured values",
    b"X_a_Time_[s]",
    b"Segment Number: 9",
    b"18446744073709551616",
];

/// Every format, `Auto` first.
pub const FORMATS: [Format; 8] = [
    Format::Auto,
    Format::Csv,
    Format::AntonPaar,
    Format::AntonPaarMulti,
    Format::HysitronTxt,
    Format::Hld,
    Format::Kla,
    Format::MicroMaterials,
];

/// One edit of a file; positions are reduced modulo the sizes they index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mutation {
    /// Byte `at` becomes `byte`.
    Flip {
        /// Position.
        at: usize,
        /// New value.
        byte: u8,
    },
    /// The file ends before byte `at`.
    Truncate {
        /// Position.
        at: usize,
    },
    /// Line `line` appears twice.
    DuplicateLine {
        /// Line index.
        line: usize,
    },
    /// Line `line` is gone.
    DeleteLine {
        /// Line index.
        line: usize,
    },
    /// [`TOKENS`]`[token]` is inserted before byte `at`.
    Insert {
        /// Position.
        at: usize,
        /// Index into [`TOKENS`].
        token: usize,
    },
    /// Fields `a` and `b` of line `line` (among the first 200: headers live there) swap.
    SwapColumns {
        /// Line index.
        line: usize,
        /// First field.
        a: usize,
        /// Second field.
        b: usize,
    },
    /// The first digit from byte `at` on becomes `1e300`, `NaN`, `inf` or `-1e300`.
    Hugify {
        /// Position.
        at: usize,
        /// Which replacement (modulo 4).
        which: usize,
    },
}

/// `(start, end)` byte spans of the lines of `b`, line ends included.
fn line_spans(b: &[u8]) -> Vec<(usize, usize)> {
    let mut v = Vec::new();
    let mut s = 0;
    for (i, &c) in b.iter().enumerate() {
        if c == b'\n' {
            v.push((s, i + 1));
            s = i + 1;
        }
    }
    if s < b.len() {
        v.push((s, b.len()));
    }
    v
}

/// `b` after the mutation `m` (unchanged when `m` has nothing to act on, e.g. a line edit
/// of an empty file).
pub fn mutate(mut b: Vec<u8>, m: &Mutation) -> Vec<u8> {
    let lines = line_spans(&b);
    match *m {
        Mutation::Flip { at, byte } if !b.is_empty() => {
            let k = at % b.len();
            b[k] = byte;
        }
        Mutation::Truncate { at } => b.truncate(at % (b.len() + 1)),
        Mutation::DuplicateLine { line } if !lines.is_empty() => {
            let (s, e) = lines[line % lines.len()];
            let l = b[s..e].to_vec();
            b.splice(e..e, l);
        }
        Mutation::DeleteLine { line } if !lines.is_empty() => {
            let (s, e) = lines[line % lines.len()];
            b.drain(s..e);
        }
        Mutation::Insert { at, token } => {
            let k = at % (b.len() + 1);
            b.splice(k..k, TOKENS[token % TOKENS.len()].iter().copied());
        }
        Mutation::SwapColumns { line, a, b: c } if !lines.is_empty() => {
            let (s, e) = lines[line % lines.len().min(200)];
            let text = b[s..e].to_vec();
            let sep = [b'\t', b';', b',']
                .into_iter()
                .find(|x| text.contains(x))
                .unwrap_or(b' ');
            let mut fields: Vec<&[u8]> = text.split(|&x| x == sep).collect();
            let n = fields.len();
            fields.swap(a % n, c % n);
            let joined = fields.join(&[sep][..]);
            b.splice(s..e, joined);
        }
        Mutation::Hugify { at, which } if !b.is_empty() => {
            let k = at % b.len();
            if let Some(d) = b[k..].iter().position(u8::is_ascii_digit) {
                let t = [&b"1e300"[..], b"NaN", b"inf", b"-1e300"][which % 4];
                b.splice(k + d..k + d + 1, t.iter().copied());
            }
        }
        _ => {}
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mutations_do_what_they_say() {
        let b = b"a,b\n1,2\n".to_vec();
        assert_eq!(mutate(b.clone(), &Mutation::Truncate { at: 3 }), b"a,b");
        assert_eq!(
            mutate(b.clone(), &Mutation::DuplicateLine { line: 1 }),
            b"a,b\n1,2\n1,2\n"
        );
        assert_eq!(
            mutate(b.clone(), &Mutation::DeleteLine { line: 0 }),
            b"1,2\n"
        );
        assert_eq!(
            mutate(
                b.clone(),
                &Mutation::SwapColumns {
                    line: 1,
                    a: 0,
                    b: 1
                }
            ),
            b"a,b\n2\n,1"
        );
        assert_eq!(
            mutate(b.clone(), &Mutation::Hugify { at: 4, which: 1 }),
            b"a,b\nNaN,2\n"
        );
        assert_eq!(mutate(Vec::new(), &Mutation::DeleteLine { line: 3 }), b"");
    }
}
