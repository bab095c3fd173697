//! Text helpers shared by the readers: decoding (UTF-8, Latin-1, UTF-16 with BOM), lines,
//! numbers with decimal commas, units and unit-bearing column labels.

/// Decodes bytes: a UTF-8 or UTF-16 byte-order mark is honoured; valid UTF-8 is taken as is;
/// anything else is Latin-1 (each byte one char, which also keeps cp1252's `µ` = 0xB5).
pub(crate) fn decode(bytes: &[u8]) -> String {
    if let Some(rest) = bytes.strip_prefix(b"\xEF\xBB\xBF") {
        return decode_8bit(rest);
    }
    let utf16 = |rest: &[u8], le: bool| -> String {
        let units = rest.chunks_exact(2).map(|c| {
            if le {
                u16::from_le_bytes([c[0], c[1]])
            } else {
                u16::from_be_bytes([c[0], c[1]])
            }
        });
        char::decode_utf16(units)
            .map(|c| c.unwrap_or(char::REPLACEMENT_CHARACTER))
            .collect()
    };
    if let Some(rest) = bytes.strip_prefix(b"\xFF\xFE") {
        return utf16(rest, true);
    }
    if let Some(rest) = bytes.strip_prefix(b"\xFE\xFF") {
        return utf16(rest, false);
    }
    decode_8bit(bytes)
}

fn decode_8bit(bytes: &[u8]) -> String {
    match std::str::from_utf8(bytes) {
        Ok(s) => s.to_owned(),
        Err(_) => bytes.iter().map(|&b| char::from(b)).collect(),
    }
}

/// Splits text into `(1-based line number, line)` with `\r\n`, `\n` or lone `\r` endings.
pub(crate) fn lines(text: &str) -> Vec<(usize, &str)> {
    let parts: Vec<&str> = if !text.contains('\n') && text.contains('\r') {
        text.split('\r').collect()
    } else {
        text.split('\n')
            .map(|l| l.strip_suffix('\r').unwrap_or(l))
            .collect()
    };
    let mut out: Vec<(usize, &str)> = parts
        .into_iter()
        .enumerate()
        .map(|(i, l)| (i + 1, l))
        .collect();
    // a final newline makes no extra line
    if out.last().is_some_and(|(_, l)| l.is_empty()) {
        out.pop();
    }
    out
}

/// Parses a number; with `decimal_comma` a `,` is read as the decimal point. Leading and
/// trailing blanks are ignored. NaN and infinities parse (the caller rejects them by name).
pub(crate) fn number(field: &str, decimal_comma: bool) -> Option<f64> {
    let s = field.trim();
    if s.is_empty() {
        return None;
    }
    if decimal_comma && s.contains(',') {
        s.replace(',', ".").parse().ok()
    } else {
        s.parse().ok()
    }
}

/// The physical dimension of a unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Dim {
    Length,
    Force,
    Time,
}

impl Dim {
    pub(crate) fn accepted(self) -> &'static str {
        match self {
            Dim::Length => "nm, µm (um), mm, m",
            Dim::Force => "nN, µN (uN), mN, N, kN",
            Dim::Time => "ms, s, min, h",
        }
    }
    pub(crate) fn internal(self) -> &'static str {
        match self {
            Dim::Length => "mm",
            Dim::Force => "N",
            Dim::Time => "s",
        }
    }
}

/// A unit's dimension and factor to internal units (mm, N, s): `nm` -> (Length, 1e-6).
pub(crate) fn unit(u: &str) -> Option<(Dim, f64)> {
    let n: String = u
        .trim()
        .chars()
        .map(|c| if c == 'µ' || c == 'μ' { 'u' } else { c })
        .collect();
    let f = match n.as_str() {
        "nm" => (Dim::Length, 1e-6),
        "um" => (Dim::Length, 1e-3),
        "mm" => (Dim::Length, 1.0),
        "m" => (Dim::Length, 1e3),
        "nN" => (Dim::Force, 1e-9),
        "uN" => (Dim::Force, 1e-6),
        "mN" => (Dim::Force, 1e-3),
        "N" => (Dim::Force, 1.0),
        "kN" => (Dim::Force, 1e3),
        "ms" => (Dim::Time, 1e-3),
        "s" | "sec" => (Dim::Time, 1.0),
        "min" => (Dim::Time, 60.0),
        "h" => (Dim::Time, 3600.0),
        _ => return None,
    };
    Some(f)
}

/// A ratio unit such as `mN/min` or `nm/µN`: its factor to internal units and the internal
/// unit's name (`N/s`, `mm/N`).
pub(crate) fn ratio_unit(u: &str) -> Option<(f64, String)> {
    let (a, b) = u.split_once('/')?;
    let (da, fa) = unit(a)?;
    let (db, fb) = unit(b)?;
    Some((fa / fb, format!("{}/{}", da.internal(), db.internal())))
}

/// Whether a header field is only a unit (`nm`, `(mN)`, `[s]`): a line of units under the
/// names.
pub(crate) fn is_unit_only(field: &str) -> bool {
    let f = field.trim();
    let inner = f
        .strip_prefix('(')
        .and_then(|x| x.strip_suffix(')'))
        .or_else(|| f.strip_prefix('[').and_then(|x| x.strip_suffix(']')))
        .unwrap_or(f);
    unit(inner).is_some() || other_unit(inner)
}

/// Units that are recognisably units but of no use here (volts, percent, ...): a label
/// ending in `_V` is a column `Disp` in volts, not a column named `Disp_V`.
fn other_unit(u: &str) -> bool {
    matches!(
        u.trim().to_ascii_lowercase().as_str(),
        "v" | "mv" | "%" | "hz" | "pj" | "nj" | "mpa" | "gpa" | "deg" | "c" | "a"
    )
}

/// A column label split into its name and unit: `Depth (nm)`, `t [s]`, `time_ms`,
/// `Force_µN`, `F` (no unit).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Label {
    pub(crate) text: String,
    pub(crate) name: String,
    pub(crate) unit: Option<String>,
}

pub(crate) fn label(text: &str) -> Label {
    let t = text.trim();
    let mk = |name: &str, unit: Option<&str>| Label {
        text: t.to_owned(),
        name: normalize(name),
        unit: unit.map(|u| u.trim().to_owned()),
    };
    for (open, close) in [('(', ')'), ('[', ']')] {
        if let Some(body) = t.strip_suffix(close) {
            if let Some(i) = body.rfind(open) {
                return mk(&body[..i], Some(&body[i + open.len_utf8()..]));
            }
        }
    }
    if let Some((name, u)) = t.rsplit_once('_') {
        if !name.trim().is_empty() && (unit(u).is_some() || other_unit(u)) {
            return mk(name, Some(u));
        }
    }
    mk(t, None)
}

/// Lower case, `_`/`-` as blanks, blanks collapsed, trailing `_`/blanks trimmed.
pub(crate) fn normalize(name: &str) -> String {
    name.to_lowercase()
        .replace(['_', '-'], " ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

/// What a column holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Quantity {
    Time,
    Depth,
    Force,
    Segment,
}

pub(crate) const TIME_NAMES: &[&str] = &["t", "time", "zeit", "time on sample"];
pub(crate) const DEPTH_NAMES: &[&str] = &[
    "h",
    "depth",
    "displacement",
    "disp",
    "pd",
    "penetration",
    "penetration depth",
    "indentation depth",
    "displacement into surface",
];
pub(crate) const FORCE_NAMES: &[&str] = &[
    "f",
    "force",
    "load",
    "fn",
    "p",
    "normal force",
    "normal load",
    "load on sample",
];
pub(crate) const SEGMENT_NAMES: &[&str] = &["segment", "segmentid", "segment id", "seg"];

/// The quantity a normalized column name stands for.
pub(crate) fn quantity(name: &str) -> Option<Quantity> {
    let n = name.trim();
    if TIME_NAMES.contains(&n) {
        Some(Quantity::Time)
    } else if DEPTH_NAMES.contains(&n) {
        Some(Quantity::Depth)
    } else if FORCE_NAMES.contains(&n) {
        Some(Quantity::Force)
    } else if SEGMENT_NAMES.contains(&n) {
        Some(Quantity::Segment)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_split_name_and_unit() {
        let l = label("Depth (nm)");
        assert_eq!((l.name.as_str(), l.unit.as_deref()), ("depth", Some("nm")));
        let l = label("t [s]");
        assert_eq!((l.name.as_str(), l.unit.as_deref()), ("t", Some("s")));
        let l = label("time_ms");
        assert_eq!((l.name.as_str(), l.unit.as_deref()), ("time", Some("ms")));
        let l = label("Force_µN");
        assert_eq!((l.name.as_str(), l.unit.as_deref()), ("force", Some("µN")));
        let l = label("Disp_V");
        assert_eq!((l.name.as_str(), l.unit.as_deref()), ("disp", Some("V")));
        let l = label("F");
        assert_eq!((l.name.as_str(), l.unit), ("f", None));
        let l = label("Piezo Extension_nm");
        assert_eq!(l.name, "piezo extension");
    }

    #[test]
    fn units_convert_to_mm_n_s() {
        assert_eq!(unit("nm"), Some((Dim::Length, 1e-6)));
        assert_eq!(unit("µN"), Some((Dim::Force, 1e-6)));
        assert_eq!(unit("μm"), Some((Dim::Length, 1e-3)));
        assert_eq!(unit("min"), Some((Dim::Time, 60.0)));
        assert_eq!(unit("V"), None);
        let (f, u) = ratio_unit("nm/µN").unwrap();
        assert!((f - 1.0).abs() < 1e-15 && u == "mm/N");
    }

    #[test]
    fn decoding_tolerates_latin1_bom_and_line_ends() {
        assert_eq!(decode(b"Load (\xB5N)"), "Load (µN)");
        assert_eq!(decode(b"\xEF\xBB\xBFa"), "a");
        assert_eq!(decode(b"\xFF\xFEa\x00"), "a");
        assert_eq!(lines("a\r\nb\n"), vec![(1, "a"), (2, "b")]);
        assert_eq!(lines("a\rb"), vec![(1, "a"), (2, "b")]);
        assert_eq!(number(" 2,5 ", true), Some(2.5));
        assert_eq!(number("2,5", false), None);
    }
}
