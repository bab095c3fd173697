//! Formatting helpers shared by the pipelines and front ends: aligned text tables, JSON
//! objects that keep their keys in the order written, units of derivatives, significant
//! digits, byte counts.

use serde::Serialize;
use serde::ser::SerializeMap;

/// `{name: value}` serialized as a JSON object in the order of the entries (the
/// parameters in the law's order), `null` for a non-finite value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Named<T>(pub Vec<(String, T)>);

impl<T> Named<T> {
    /// From `(name, value)` pairs.
    pub fn new<'a>(pairs: impl IntoIterator<Item = (&'a str, T)>) -> Named<T> {
        Named(pairs.into_iter().map(|(n, v)| (n.to_string(), v)).collect())
    }
}

impl<T: Serialize> Serialize for Named<T> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

/// The unit of `dJ/dc` for `J` in N^2 and `c` in `unit` (`N^2/MPa`, `N^2/(MPa s)`, `N^2`
/// for a dimensionless parameter).
pub fn gradient_unit(unit: &str) -> String {
    match unit {
        "-" | "" => "N^2".into(),
        u if u.contains(' ') => format!("N^2/({u})"),
        u => format!("N^2/{u}"),
    }
}

/// Rows of cells as left-aligned columns separated by two spaces, each line prefixed by
/// `indent`; the first row is the header.
pub fn table(rows: &[Vec<String>], indent: &str) -> String {
    let ncol = rows.iter().map(Vec::len).max().unwrap_or(0);
    let widths: Vec<usize> = (0..ncol)
        .map(|c| {
            rows.iter()
                .filter_map(|r| r.get(c))
                .map(|s| s.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut out = String::new();
    for row in rows {
        let mut line = indent.to_string();
        for (c, cell) in row.iter().enumerate() {
            if c + 1 == row.len() {
                line.push_str(cell);
            } else {
                line.push_str(&format!("{cell:<w$}  ", w = widths[c]));
            }
        }
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

/// `name = value` of every parameter, comma-separated.
pub fn assignments(names: &[&str], values: &[f64]) -> String {
    names
        .iter()
        .zip(values)
        .map(|(n, v)| format!("{n} = {v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `v` with `digits` significant digits in plain decimal notation (`20000.000`,
/// `0.29100000`), or in exponent notation outside `[1e-4, 1e9)`.
pub fn sig(v: f64, digits: usize) -> String {
    if v == 0.0 || !v.is_finite() {
        return v.to_string();
    }
    let exp = v.abs().log10().floor() as i32;
    if !(-4..9).contains(&exp) {
        return format!("{v:.*e}", digits.saturating_sub(1));
    }
    let decimals = (digits as i32 - 1 - exp).max(0) as usize;
    format!("{v:.decimals$}")
}

/// Bytes as `12.3 MB`, `456 kB` or `789 B`.
pub fn bytes(n: usize) -> String {
    let v = n as f64;
    if v >= 1e6 {
        format!("{:.1} MB", v / 1e6)
    } else if v >= 1e3 {
        format!("{:.1} kB", v / 1e3)
    } else {
        format!("{n} B")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_keeps_order_and_writes_null_for_nan() {
        let n = Named::new([("eta", 1.0), ("E", f64::NAN)]);
        assert_eq!(
            serde_json::to_string(&n).unwrap(),
            r#"{"eta":1.0,"E":null}"#
        );
    }

    #[test]
    fn gradient_units_divide_n2() {
        assert_eq!(gradient_unit("MPa"), "N^2/MPa");
        assert_eq!(gradient_unit("MPa s"), "N^2/(MPa s)");
        assert_eq!(gradient_unit("-"), "N^2");
    }

    #[test]
    fn significant_digits() {
        assert_eq!(sig(20000.000123, 8), "20000.000");
        assert_eq!(sig(0.291, 4), "0.2910");
        assert_eq!(sig(1.5e-7, 3), "1.50e-7");
        assert_eq!(sig(0.0, 3), "0");
    }

    #[test]
    fn table_aligns_columns() {
        let t = table(
            &[
                vec!["a".into(), "bb".into(), "c".into()],
                vec!["ccc".into(), "d".into(), "e".into()],
            ],
            "  ",
        );
        assert_eq!(t, "  a    bb  c\n  ccc  d   e\n");
    }
}
