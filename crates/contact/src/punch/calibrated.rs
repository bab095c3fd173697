//! A calibrated tip as an axisymmetric punch: the profile with the same projected area as
//! a given area function `A(h)` at every depth h above the tip (the worn, real tip of a
//! calibration instead of the ideal cone).
//!
//! The punch's surface at height h has the radius `a(h) = sqrt(A(h) / pi)` (a circle of
//! area `A(h)`), so the profile `phi(r)` is the depth that solves `A(phi) = pi r^2`. With
//! `A = C0 h^2` this is the cone `phi = r sqrt(pi / C0)` (`C0 = 24.5`: the 70.30 deg cone of
//! an ideal Berkovich); `A = pi (2 R h - h^2)` is the sphere of radius R; the ISO 14577
//! polynomial `C0 h^2 + C1 h + C2 h^(1/2) + ...` of a calibration is blunt at the tip and
//! a cone far from it. `A` must grow with the depth, so that the profile is a function.
//!
//! Vertical contact evaluates `phi(r)` exactly (safeguarded Newton on `A(h) = pi r^2`);
//! normal contact needs the surface's normal and curvature, and uses the tabulated profile
//! of [`AreaProfile::table`] (points at depths a ratio [`TABLE_RATIO`] apart from
//! [`TABLE_DEPTH_MIN`], vertices rounded as every tabulated profile's): its height differs
//! from the exact profile by less than 1e-4 of the depth (tested).
//!
//! The contact crate holds only the numbers; reading a tip file is the application's
//! (`punch: Calibrated(file: "TIP.ron")` in a configuration, resolved by `indentify-study`).

use crate::ContactError;

/// The shallowest tabulated depth of [`AreaProfile::table`] (mm): 0.1 nm.
pub const TABLE_DEPTH_MIN: f64 = 1e-7;
/// The deepest tabulated depth of [`AreaProfile::table`] (mm) for a tip without a depth
/// limit; beyond it the last segment is extended.
pub const TABLE_DEPTH_MAX: f64 = 1.0;
/// Ratio of consecutive tabulated depths of [`AreaProfile::table`].
pub const TABLE_RATIO: f64 = 1.03;

/// A projected-area function `A(h) = sum_k c_k h^(p_k)` (h in mm, A in mm^2), increasing
/// from `A(0) = 0` up to `depth_limit` (a sphere's radius; infinite for a tip that goes on
/// as a cone), and the axisymmetric profile it defines.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaProfile {
    /// `(c_k, p_k)`: coefficient (mm^(2 - p_k)) and exponent (> 0).
    terms: Vec<(f64, f64)>,
    /// Depth (mm) beyond which the tip has no surface: infinite, or where `A` stops growing.
    depth_limit: f64,
}

fn bad(field: &'static str, value: String, allowed: &str) -> ContactError {
    ContactError::Input {
        field,
        value,
        allowed: allowed.into(),
    }
}

impl AreaProfile {
    /// The area function with the terms `(c_k, p_k)` up to `depth_limit`.
    ///
    /// # Errors
    /// [`ContactError::Input`] naming `punch.area` for no terms, a coefficient that is not
    /// finite, an exponent that is not finite and > 0, a limit that is not > 0, or an area
    /// that does not grow with the depth (checked on 400 depths over 12 decades for terms
    /// with a negative coefficient; terms with coefficients >= 0 always grow).
    pub fn new(terms: Vec<(f64, f64)>, depth_limit: f64) -> Result<AreaProfile, ContactError> {
        if terms.is_empty() {
            return Err(bad(
                "punch.area",
                "no terms".into(),
                "at least one term c h^p",
            ));
        }
        for &(c, p) in &terms {
            if !c.is_finite() {
                return Err(bad(
                    "punch.area",
                    format!("coefficient {c}"),
                    "finite coefficients",
                ));
            }
            if !(p.is_finite() && p > 0.0) {
                return Err(bad(
                    "punch.area",
                    format!("exponent {p}"),
                    "finite exponents > 0",
                ));
            }
        }
        if !(depth_limit > 0.0) {
            return Err(bad(
                "punch.area",
                format!("depth limit {depth_limit} mm"),
                "a depth limit > 0 (infinite for none)",
            ));
        }
        if terms.iter().all(|&(c, _)| c == 0.0) {
            return Err(bad(
                "punch.area",
                "all coefficients 0".into(),
                "an area that grows with the depth",
            ));
        }
        let profile = AreaProfile { terms, depth_limit };
        if profile.terms.iter().any(|&(c, _)| c < 0.0) {
            let top = depth_limit.min(TABLE_DEPTH_MAX);
            for i in 0..400 {
                // 1e-12 top to (1 - 1e-9) top
                let h = top * 10f64.powf(-12.0 + 12.0 * i as f64 / 399.0) * (1.0 - 1e-9);
                let (a, da) = (profile.area(h), profile.slope(h));
                if !(a > 0.0 && da > 0.0) {
                    return Err(bad(
                        "punch.area",
                        format!("A({h:e} mm) = {a:e} mm^2 with dA/dh = {da:e} mm"),
                        "an area > 0 that grows with the depth up to the tip's depth limit",
                    ));
                }
            }
        }
        Ok(profile)
    }

    /// `A(h)`, mm^2 (`h >= 0`, mm).
    pub fn area(&self, h: f64) -> f64 {
        self.terms.iter().map(|&(c, p)| c * power(h, p)).sum()
    }

    /// `dA/dh`, mm.
    pub fn slope(&self, h: f64) -> f64 {
        self.terms
            .iter()
            .map(|&(c, p)| c * p * power(h, p - 1.0))
            .sum()
    }

    /// The depth (mm) beyond which the tip has no surface (infinite for none).
    pub fn depth_limit(&self) -> f64 {
        self.depth_limit
    }

    /// The profile's radius at the height `h` above the tip, `sqrt(A(h) / pi)` (mm); at and
    /// beyond the depth limit the radius there.
    pub fn radius(&self, h: f64) -> f64 {
        if !(h > 0.0) {
            return 0.0;
        }
        (self.area(h.min(self.depth_limit)) / std::f64::consts::PI).sqrt()
    }

    /// The profile `phi(r)` (mm): the depth with `A(phi) = pi r^2`; infinite beyond the
    /// radius at the depth limit (the tip ends in a vertical wall there).
    pub fn height(&self, r: f64) -> f64 {
        if !(r > 0.0) {
            return 0.0;
        }
        let target = std::f64::consts::PI * r * r;
        let limit = self.depth_limit;
        if limit.is_finite() {
            let a_limit = self.area(limit);
            if target > a_limit {
                return f64::INFINITY;
            }
            if target == a_limit {
                return limit;
            }
        }
        // bracket [lo, hi] with A(lo) <= target <= A(hi)
        let (mut lo, mut hi) = (0.0, r.min(limit));
        while self.area(hi) < target {
            lo = hi;
            hi = (2.0 * hi).min(limit);
            if !hi.is_finite() || hi > 1e300 {
                return f64::INFINITY;
            }
        }
        // safeguarded Newton from the upper end (from above on a convex area: monotone)
        let mut x = hi;
        for _ in 0..200 {
            let f = self.area(x) - target;
            if f == 0.0 {
                return x;
            }
            if f > 0.0 {
                hi = x;
            } else {
                lo = x;
            }
            let d = self.slope(x);
            let mut next = x - f / d;
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            if (next - x).abs() <= 4.0 * f64::EPSILON * x || next == lo || next == hi {
                return next;
            }
            x = next;
        }
        x
    }

    /// The profile at depths `TABLE_DEPTH_MIN * TABLE_RATIO^i` up to the depth limit (or
    /// [`TABLE_DEPTH_MAX`]), from the tip `(0, 0)`: radii and heights for a tabulated
    /// surface.
    pub fn table(&self) -> (Vec<f64>, Vec<f64>) {
        let top = self.depth_limit.min(TABLE_DEPTH_MAX);
        let mut r = vec![0.0];
        let mut z = vec![0.0];
        let mut h = TABLE_DEPTH_MIN.min(1e-6 * top);
        while h < top {
            r.push(self.radius(h));
            z.push(h);
            h *= TABLE_RATIO;
        }
        r.push(self.radius(top));
        z.push(top);
        (r, z)
    }

    /// In words: `A = 24.5 h^2 + ...` (h in mm, A in mm^2).
    pub fn describe(&self) -> String {
        let terms: Vec<String> = self
            .terms
            .iter()
            .map(|&(c, p)| format!("{c:.6e} h^{p}"))
            .collect();
        let mut s = format!("A = {} (mm)", terms.join(" + "));
        if self.depth_limit.is_finite() {
            s.push_str(&format!(" up to h = {} mm", self.depth_limit));
        }
        s
    }
}

fn power(h: f64, p: f64) -> f64 {
    if p == 2.0 {
        h * h
    } else if p == 1.0 {
        h
    } else if p == 0.5 {
        h.sqrt()
    } else {
        h.powf(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn the_profile_has_the_area_function_at_every_depth() {
        // a calibrated Berkovich: blunt at the tip, a cone beyond (nm-sized terms in mm)
        let a = AreaProfile::new(
            vec![(23.79, 2.0), (1.5e-4, 1.0), (2.69e4 * 1e-9, 0.5)],
            f64::INFINITY,
        )
        .unwrap();
        for h in [1e-7, 1e-6, 1e-5, 3e-5, 1e-4, 1e-3, 2e-3, 0.1] {
            let r = a.radius(h);
            assert!((PI * r * r / a.area(h) - 1.0).abs() < 1e-14, "{h}");
            let back = a.height(r);
            assert!((back / h - 1.0).abs() < 1e-13, "{h} {back}");
        }
        assert_eq!(a.height(0.0), 0.0);
    }

    #[test]
    fn c0_alone_is_the_cone() {
        let a = AreaProfile::new(vec![(24.5, 2.0)], f64::INFINITY).unwrap();
        let k = (PI / 24.5).sqrt();
        for r in [1e-9, 1e-6, 3.3e-4, 0.01, 0.7, 5.0] {
            let h = a.height(r);
            assert!((h / (r * k) - 1.0).abs() < 1e-15, "{r} {h}");
        }
    }

    #[test]
    fn a_sphere_area_ends_in_a_wall() {
        let radius = 0.01;
        let a = AreaProfile::new(vec![(2.0 * PI * radius, 1.0), (-PI, 2.0)], radius).unwrap();
        for r in [1e-5, 1e-3, 5e-3, 9.9e-3] {
            let exact: f64 = r * r / (radius + (radius * radius - r * r).sqrt());
            assert!((a.height(r) / exact - 1.0).abs() < 1e-12, "{r}");
        }
        assert!(a.height(0.0101).is_infinite());
        assert!((a.radius(0.02) - radius).abs() < 1e-15);
    }

    #[test]
    fn the_table_follows_the_profile() {
        let a = AreaProfile::new(vec![(23.79, 2.0), (2.69e4 * 1e-9, 0.5)], f64::INFINITY).unwrap();
        let (r, z) = a.table();
        assert!(r.windows(2).all(|w| w[1] > w[0]));
        assert!(z.windows(2).all(|w| w[1] > w[0]));
        // the chord between two tabulated points against the exact profile at the middle
        let mut worst: f64 = 0.0;
        for i in 1..r.len() - 1 {
            let rm = 0.5 * (r[i] + r[i + 1]);
            let chord = 0.5 * (z[i] + z[i + 1]);
            worst = worst.max(((chord - a.height(rm)) / z[i + 1]).abs());
        }
        assert!(worst < 1e-4, "{worst}");
    }

    #[test]
    fn bad_area_functions_name_the_field() {
        let e = |t: Vec<(f64, f64)>, l: f64| AreaProfile::new(t, l).unwrap_err().to_string();
        assert!(e(vec![], f64::INFINITY).contains("punch.area"));
        assert!(e(vec![(f64::NAN, 2.0)], f64::INFINITY).contains("coefficient NaN"));
        assert!(e(vec![(1.0, 0.0)], f64::INFINITY).contains("exponent 0"));
        assert!(e(vec![(0.0, 2.0)], f64::INFINITY).contains("all coefficients 0"));
        let shrinking = e(vec![(1.0, 1.0), (-5.0, 2.0)], f64::INFINITY);
        assert!(shrinking.contains("grows with the depth"), "{shrinking}");
        assert!(e(vec![(1.0, 2.0)], 0.0).contains("depth limit"));
    }
}
