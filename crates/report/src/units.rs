//! Display units (label + factor from internal units) and number formatting.

use serde::{Deserialize, Serialize};

/// How a quantity stored in internal units (mm, N, s, MPa) is shown.
///
/// `shown = internal * factor`: for a depth in nm, `factor = 1e6` (1 mm = 1e6 nm); for a
/// modulus in GPa, `factor = 1e-3` (1 MPa = 1e-3 GPa).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DisplayUnit {
    /// Unit label as printed in tables and axis labels ("nm", "mN", "GPa", "MPa s", "-").
    pub label: String,
    /// Multiplier from the internal unit to the shown unit.
    pub factor: f64,
}

impl DisplayUnit {
    /// A unit with `label` and `shown = internal * factor`.
    pub fn new(label: impl Into<String>, factor: f64) -> Self {
        Self {
            label: label.into(),
            factor,
        }
    }

    /// The internal unit itself (factor 1), e.g. `DisplayUnit::internal("MPa")`.
    pub fn internal(label: impl Into<String>) -> Self {
        Self::new(label, 1.0)
    }

    /// Depth unit for a test whose largest depth is `h_max` mm: nm below 10 µm
    /// (nano-indentation), mm otherwise.
    pub fn auto_depth(h_max: f64) -> Self {
        if h_max.abs() < 0.01 {
            Self::new("nm", 1e6)
        } else {
            Self::internal("mm")
        }
    }

    /// Force unit for a test whose largest force is `f_max` N: mN below 1 N, N otherwise.
    pub fn auto_force(f_max: f64) -> Self {
        if f_max.abs() < 1.0 {
            Self::new("mN", 1e3)
        } else {
            Self::internal("N")
        }
    }

    /// `value` (internal units) in this unit.
    pub fn show(&self, value: f64) -> f64 {
        value * self.factor
    }
}

/// `x` with 4 significant digits; scientific notation outside 1e-3 <= |x| < 1e5.
///
/// Non-finite values print as `NaN`, `inf`, `-inf`.
pub fn fmt_sig(x: f64) -> String {
    fmt_sig_n(x, 4)
}

/// `x` with `sig` significant digits; scientific notation outside 1e-3 <= |x| < 1e5.
pub fn fmt_sig_n(x: f64, sig: usize) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x == 0.0 {
        return "0".to_string();
    }
    let sig = sig.max(1);
    let exp = x.abs().log10().floor() as i32;
    if (-3..5).contains(&exp) {
        let decimals = (sig as i32 - 1 - exp).max(0) as usize;
        // Rounding can carry into a new digit (9.9996 -> "10.000"); harmless.
        format!("{x:.decimals$}")
    } else {
        format!("{:.*e}", sig - 1, x)
    }
}

/// A compact axis-tick label: trailing zeros trimmed, scientific outside 1e-3..1e5.
pub fn fmt_tick(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    // Ticks are round numbers up to floating-point noise: 6 significant digits is enough.
    if x == 0.0 {
        return "0".to_string();
    }
    let exp = x.abs().log10().floor() as i32;
    if (-3..5).contains(&exp) {
        let decimals = (5 - exp).max(0) as usize;
        trim_zeros(&format!("{x:.decimals$}"))
    } else {
        fmt_sci(x)
    }
}

/// A tick label on a log axis spanning `lo..hi`: decimal if the whole axis lies in
/// 1e-3..1e5, scientific (`1e-4`, `2.5e6`) for every tick otherwise.
pub fn fmt_log_tick(x: f64, lo: f64, hi: f64) -> String {
    if lo >= 1e-3 && hi < 1e5 {
        fmt_tick(x)
    } else if x.is_finite() && x != 0.0 {
        fmt_sci(x)
    } else {
        fmt_tick(x)
    }
}

/// Scientific notation, 6 significant digits, trailing zeros trimmed (`2.5e6`, `1e-4`).
fn fmt_sci(x: f64) -> String {
    let s = format!("{x:.5e}");
    match s.split_once('e') {
        Some((m, e)) => format!("{}e{e}", trim_zeros(m)),
        None => s,
    }
}

/// A tick label on a linear axis whose largest magnitude is `axis_max`: one notation for
/// the whole axis (decimal if 1e-3 <= axis_max < 1e5, scientific otherwise), so that an
/// axis does not mix `2e-4` and `0.001`; round-off below 1e-9 of `axis_max` prints as 0.
pub fn fmt_axis_tick(x: f64, axis_max: f64) -> String {
    if !x.is_finite() || !axis_max.is_finite() || !(axis_max > 0.0) {
        return fmt_tick(x);
    }
    if x == 0.0 || x.abs() < 1e-9 * axis_max {
        return "0".to_string();
    }
    let exp = axis_max.log10().floor() as i32;
    if (-3..5).contains(&exp) {
        // Six significant digits of the largest tick.
        let decimals = (5 - exp).max(0) as usize;
        trim_zeros(&format!("{x:.decimals$}"))
    } else {
        fmt_tick(x)
    }
}

fn trim_zeros(s: &str) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_units_pick_nm_mn_for_nano_and_mm_n_for_macro() {
        assert_eq!(DisplayUnit::auto_depth(2e-3).label, "nm");
        assert_eq!(DisplayUnit::auto_force(10e-3).label, "mN");
        assert_eq!(DisplayUnit::auto_depth(0.1).label, "mm");
        assert_eq!(DisplayUnit::auto_force(300.0).label, "N");
        assert_eq!(DisplayUnit::auto_depth(2e-3).show(2e-3), 2000.0);
    }

    #[test]
    fn sig_formatting_switches_to_scientific_outside_1e_minus3_1e5() {
        assert_eq!(fmt_sig(200.0), "200.0");
        assert_eq!(fmt_sig(0.3), "0.3000");
        assert_eq!(fmt_sig(0.0012345), "0.001234");
        assert_eq!(fmt_sig(1.5e-5), "1.500e-5");
        assert_eq!(fmt_sig(2.5e5), "2.500e5");
        assert_eq!(fmt_sig(0.0), "0");
        assert_eq!(fmt_sig(f64::NAN), "NaN");
    }

    #[test]
    fn axis_ticks_share_one_notation() {
        assert_eq!(fmt_axis_tick(2e-4, 0.002), "0.0002");
        assert_eq!(fmt_axis_tick(0.0012, 0.002), "0.0012");
        assert_eq!(fmt_axis_tick(5.5e-17, 0.002), "0");
        assert_eq!(fmt_axis_tick(2e-5, 1e-4), "2e-5");
        assert_eq!(fmt_axis_tick(1e5, 2e5), "1e5");
        assert_eq!(fmt_axis_tick(0.30000000000000004, 1.0), "0.3");
        assert_eq!(fmt_axis_tick(250.0, 300.0), "250");
    }

    #[test]
    fn log_ticks_share_one_notation() {
        assert_eq!(fmt_log_tick(1e-3, 1e-9, 1e-2), "1e-3");
        assert_eq!(fmt_log_tick(0.01, 1e-3, 10.0), "0.01");
        assert_eq!(fmt_log_tick(100.0, 1.0, 1e6), "1e2");
    }

    #[test]
    fn ticks_are_trimmed() {
        assert_eq!(fmt_tick(0.30000000000000004), "0.3");
        assert_eq!(fmt_tick(2000.0), "2000");
        assert_eq!(fmt_tick(1e-5), "1e-5");
        assert_eq!(fmt_tick(2.5e6), "2.5e6");
        assert_eq!(fmt_tick(-0.001), "-0.001");
        assert_eq!(fmt_tick(1e-17), "1e-17");
    }
}
