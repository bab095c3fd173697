//! Dao et al. (2001)'s dimensionless functions of sharp indentation (Acta Materialia 49,
//! 3899-3918: a 70.3-degree cone, finite strain, Coulomb friction 0.15, J2 plasticity with
//! the power-law hardening `sigma = sY (1 + E eps_p / sY)^n`, `nu = 0.3`), their forward
//! algorithm, what a curve gives them ([`measure`]) and their reverse algorithm
//! ([`reverse`]: `E*`, the representative stress and `n` from the loading curvature, the
//! unloading slope and the work ratio or residual depth; docs/analysis.md, "Closed-form
//! starts for laws with a yield stress"). `cargo xtask dao` compares our finite element
//! runs with them (docs/validation-laws.md §9).
//!
//! The functions (their Appendix A, as publicly transcribed: docs/validation-laws.md §9
//! says how far they are checked; `x = ln(E*/sigma_r)`, `sigma_r = sigma(eps_p = 0.033)`
//! the representative stress, `E* = E/(1 - nu^2)` for the rigid tip used here):
//! - `Pi1 = C/sigma_r`, `C = P/h^2` on loading ([`pi1`]);
//! - `Pi2 = S/(E* h_m)`, `S` the initial unloading slope ([`pi2`]);
//! - `Pi4 = p_ave/E*` against `h_r/h_m`, `p_ave = P_m/A_m` the mean contact pressure at
//!   the maximum load ([`pi4`]);
//! - `Pi5 = W_p/W_t` against `h_r/h_m` ([`pi5`]).
//!
//! Forward ([`dao_forward`]): `C` and `S` from `Pi1`, `Pi2`; the contact area from
//! `S = c* E* sqrt(A_m)` (`c* = 1.1957` for the cone); `h_r/h_m` by inverting `Pi4`;
//! `W_p/W_t` from `Pi5`. Reverse ([`reverse`]): `h_r/h_m` (measured, or `Pi5` inverted at
//! the measured `W_p/W_t`); `Pi4` and `S = c* E* sqrt(A_m)` give
//! `E* = S^2 Pi4 / (c*^2 P_m)`; `Pi1` inverted gives `sigma_r`; `Pi2` inverted at that
//! `E*/sigma_r` gives `n`; `sY` solves `sigma_r = sY (1 + E 0.033 / sY)^n`.
//!
//! Pure numerics: no file IO, no finite element run.

/// Dao's representative plastic strain of the 70.3-degree cone.
pub const EPS_R: f64 = 0.033;
/// The cone's half-angle (deg): the area-equivalent cone of a Berkovich or Vickers tip.
pub const HALF_ANGLE_DEG: f64 = 70.3;
/// `c*` of `S = c* E* sqrt(A_m)` for the 70.3-degree cone in Dao's algorithms.
pub const C_STAR: f64 = 1.1957;
/// `h_r/h_m` at which `Pi4` vanishes (the end of its range).
pub const HR_HM_MAX: f64 = 0.9952495;
/// The range of `E*/sigma_r` searched when `Pi1` is inverted (Dao's materials span about
/// 10 to 1100; beyond `Pi1`'s cubic turns).
pub const ESTAR_OVER_SR_RANGE: (f64, f64) = (5.0, 2000.0);
/// The range of `n` searched when `Pi2` is inverted (Dao's materials: 0 to 0.5).
pub const N_RANGE: (f64, f64) = (0.0, 0.5);

/// Dao's flow stress `sY (1 + E p / sY)^n` (the law's `Power` hardening).
pub fn flow_stress(e: f64, sy: f64, n: f64, p: f64) -> f64 {
    sy * (1.0 + e * p / sy).powf(n)
}

/// The representative stress `sigma_r = sigma(eps_p = 0.033)`.
pub fn sigma_r(e: f64, sy: f64, n: f64) -> f64 {
    flow_stress(e, sy, n, EPS_R)
}

/// The indentation modulus of a rigid tip, `E/(1 - nu^2)`.
pub fn e_star(e: f64, nu: f64) -> f64 {
    e / (1.0 - nu * nu)
}

/// Dao's `Pi1`: `C/sigma_r` against `E*/sigma_r`.
pub fn pi1(estar_over_sr: f64) -> f64 {
    let x = estar_over_sr.ln();
    -1.131 * x.powi(3) + 13.635 * x.powi(2) - 30.594 * x + 29.267
}

/// Dao's `Pi2`: `S/(E* h_m)` against `E*/sigma_r` and `n`.
pub fn pi2(estar_over_sr: f64, n: f64) -> f64 {
    let x = estar_over_sr.ln();
    let c3 = -1.40557 * n.powi(3) + 0.77526 * n.powi(2) + 0.15830 * n - 0.06831;
    let c2 = 17.93006 * n.powi(3) - 9.22091 * n.powi(2) - 2.37733 * n + 0.86295;
    let c1 = -79.99715 * n.powi(3) + 40.55620 * n.powi(2) + 9.00157 * n - 2.54543;
    let c0 = 122.65069 * n.powi(3) - 63.88418 * n.powi(2) - 9.58936 * n + 6.20045;
    c3 * x.powi(3) + c2 * x.powi(2) + c1 * x + c0
}

/// Dao's `Pi4`: `p_ave/E*` against `h_r/h_m`.
pub fn pi4(hr_hm: f64) -> f64 {
    0.268536 * (HR_HM_MAX - hr_hm).max(0.0).powf(1.1142735)
}

/// Dao's `Pi5`: `W_p/W_t` against `h_r/h_m`.
pub fn pi5(hr_hm: f64) -> f64 {
    1.61217
        * (1.13111
            - 1.74756f64.powf(-1.49291 * hr_hm.powf(2.535334))
            - 0.075187 * hr_hm.powf(1.135826))
}

/// What Dao's functions predict for one material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DaoPrediction {
    /// `C = P/h^2` (MPa).
    pub c: f64,
    /// `S/(E* h_m)`.
    pub s_norm: f64,
    /// `p_ave/E*` (from `C`, `S` and `c*`).
    pub p_ave_norm: f64,
    /// `h_r/h_m` (`Pi4` inverted).
    pub hr_hm: f64,
    /// `W_p/W_t` (`Pi5` of that `h_r/h_m`).
    pub wp_wt: f64,
}

/// The root of the monotone `g` on `[lo, hi]` by 200 bisections (`g(lo)` and `g(hi)` of
/// opposite signs, or zero at one end).
fn bisect(g: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    let g_lo = g(lo);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if (g(mid) > 0.0) == (g_lo > 0.0) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// `h_r/h_m` of a normalized mean pressure `p_ave/E*` (`Pi4` inverted; 0 at or above
/// `Pi4(0)`).
pub fn pi4_inverse(p_ave_norm: f64) -> f64 {
    if p_ave_norm >= pi4(0.0) {
        0.0
    } else {
        bisect(|r| pi4(r) - p_ave_norm, 0.0, HR_HM_MAX)
    }
}

/// Dao's forward algorithm for `(E, nu, sY, n)` under a rigid tip.
pub fn dao_forward(e: f64, nu: f64, sy: f64, n: f64) -> DaoPrediction {
    let sr = sigma_r(e, sy, n);
    let es = e_star(e, nu);
    let c = sr * pi1(es / sr);
    let s_norm = pi2(es / sr, n);
    // h_m = 1: P_m = C, S = E* s_norm, A_m = (S / (c* E*))^2
    let a_m = (s_norm / C_STAR).powi(2);
    let p_ave_norm = c / a_m / es;
    let hr_hm = pi4_inverse(p_ave_norm);
    DaoPrediction {
        c,
        s_norm,
        p_ave_norm,
        hr_hm,
        wp_wt: pi5(hr_hm),
    }
}

/// Why a curve or a measurement gives no reverse analysis.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DaoError {
    /// The curve has no loading and unloading around its deepest point, or too few points.
    #[error("{0}")]
    Curve(String),
    /// A measured quantity outside the range Dao's functions cover.
    #[error("{what} = {value:.4} lies outside the range Dao's functions cover ({range})")]
    Range {
        /// The quantity (`W_p/W_t`, `C/E*`, ...).
        what: &'static str,
        /// Its value.
        value: f64,
        /// The range covered, in words.
        range: String,
    },
    /// An input outside its domain (a non-positive or non-finite value, `nu` outside
    /// (-1, 0.5)).
    #[error("{0}")]
    Input(String),
}

/// What [`measure`] reads off one loading-(hold-)unloading curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Features {
    /// Maximum depth (mm): the unloading's start.
    pub h_m: f64,
    /// Force at the unloading's start (N).
    pub p_m: f64,
    /// Force at the loading's end (N): `p_m` unless a hold relaxes or creeps.
    pub p_max: f64,
    /// `C` of `P = C h^2` fitted over the loading's `h >= h_m/2` (MPa).
    pub c: f64,
    /// Initial unloading slope (N/mm).
    pub s: f64,
    /// Residual depth where the unloading force reaches zero (mm); `None` when the
    /// unloading stops before.
    pub h_r: Option<f64>,
    /// Plastic work over total work (the loading's and hold's work against the
    /// unloading's); `None` when the unloading stops before zero force.
    pub wp_wt: Option<f64>,
    /// Sample of the loading's end (its first sample at the largest force).
    pub loading_end: usize,
    /// Sample of the unloading's start (the last sample at the deepest depth).
    pub unloading_start: usize,
}

/// Reads `C`, `S`, `h_r` and `W_p/W_t` off a curve (depths `h` in mm, forces `f` in N)
/// that loads to its deepest depth, may hold there, and unloads.
///
/// The loading is the curve up to its first sample at the largest force before the
/// deepest depth (a hold at constant force or depth is left out of `C`); `C` is the least
/// squares of `P = C h^2` over its samples with `h >= h_m/2`. The unloading starts at the
/// last sample at the deepest depth; `S` is the slope there of a quadratic in `h - h_m`
/// fitted to the unloading samples above `0.75 P_m` (at least the first 4). `h_r` is where
/// the unloading force first reaches zero (linear between the two samples around it); the
/// works are trapezoid sums.
///
/// # Errors
/// [`DaoError::Curve`]: lengths that differ, a non-finite sample, no loading (fewer than 3
/// samples) or unloading (fewer than 4) around the deepest depth, no force there, an
/// unloading whose top does not determine a slope.
pub fn measure(h: &[f64], f: &[f64]) -> Result<Features, DaoError> {
    let bad = |m: &str| Err(DaoError::Curve(m.to_string()));
    if h.len() != f.len() {
        return Err(DaoError::Curve(format!(
            "{} depths and {} forces",
            h.len(),
            f.len()
        )));
    }
    if let Some(k) = (0..h.len()).find(|&k| !(h[k].is_finite() && f[k].is_finite())) {
        return Err(DaoError::Curve(format!("sample {k} is not finite")));
    }
    if h.is_empty() {
        return bad("the curve has no samples");
    }
    // the first sample at the deepest depth, and the last one of that run (a hold at depth)
    let first_deep = (0..h.len()).fold(0, |b, i| if h[i] > h[b] { i } else { b });
    let mut i_m = first_deep;
    while i_m + 1 < h.len() && h[i_m + 1] >= h[first_deep] {
        i_m += 1;
    }
    if first_deep < 2 || i_m + 3 > h.len() {
        return bad("the curve has no loading and unloading around its deepest point");
    }
    let i_load = (0..=first_deep).fold(0, |b, i| if f[i] > f[b] { i } else { b });
    let (h_m, p_m) = (h[i_m], f[i_m]);
    if !(p_m > 0.0) {
        return Err(DaoError::Curve(format!(
            "no force at the deepest point ({p_m} N)"
        )));
    }
    // C: P = C h^2 by least squares over the loading's upper half
    let (mut num, mut den) = (0.0, 0.0);
    for k in (0..=i_load).filter(|&k| h[k] >= 0.5 * h_m) {
        num += f[k] * h[k] * h[k];
        den += h[k].powi(4);
    }
    if !(den > 0.0) {
        return bad("the loading has no sample above half the deepest depth");
    }
    let c = num / den;
    // S: slope at h_m of a quadratic in (h - h_m) through the unloading's top points
    let un = i_m..h.len();
    let mut top: Vec<usize> = un.clone().take_while(|&k| f[k] >= 0.75 * p_m).collect();
    if top.len() < 4 {
        top = un.clone().take(4).collect();
    }
    let s = quadratic_slope(h, f, &top).ok_or_else(|| {
        DaoError::Curve("the unloading's top points do not determine a slope".into())
    })?;
    // h_r: where the unloading force reaches zero
    let tol = 1e-9 * p_m;
    let (h_r, wp_wt) = match un.clone().find(|&k| f[k] <= tol) {
        Some(k) => {
            let (h0, f0, h1, f1) = (h[k - 1], f[k - 1], h[k], f[k]);
            let h_r = h0 + (h1 - h0) * (f0 - tol) / (f0 - f1);
            let trapezoid = |ks: std::ops::Range<usize>| -> f64 {
                ks.map(|j| 0.5 * (f[j] + f[j + 1]) * (h[j + 1] - h[j]))
                    .sum()
            };
            let w_t = trapezoid(0..i_m);
            let w_e = -trapezoid(i_m..h.len() - 1);
            (Some(h_r), Some((w_t - w_e) / w_t))
        }
        None => (None, None),
    };
    Ok(Features {
        h_m,
        p_m,
        p_max: f[i_load],
        c,
        s,
        h_r,
        wp_wt,
        loading_end: i_load,
        unloading_start: i_m,
    })
}

/// `dF/dh` at the first sample of `ks` from a least-squares quadratic in `h - h_0`.
fn quadratic_slope(h: &[f64], f: &[f64], ks: &[usize]) -> Option<f64> {
    let h0 = h[ks[0]];
    // normal equations of f = c0 + c1 x + c2 x^2
    let mut m = [[0.0f64; 3]; 3];
    let mut r = [0.0f64; 3];
    for &k in ks {
        let x = h[k] - h0;
        let v = [1.0, x, x * x];
        for i in 0..3 {
            r[i] += v[i] * f[k];
            for j in 0..3 {
                m[i][j] += v[i] * v[j];
            }
        }
    }
    let det3 = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(&m);
    if !(d.abs() > 0.0) {
        return None;
    }
    // Cramer's rule for c1
    let mut m1 = m;
    for i in 0..3 {
        m1[i][1] = r[i];
    }
    Some(det3(&m1) / d)
}

/// `h_r/h_m` of a work ratio `W_p/W_t` (`Pi5` inverted on `[0, 0.9952495]`).
///
/// # Errors
/// [`DaoError::Range`] when `W_p/W_t` lies outside `[Pi5(0), Pi5(0.9952495)]`
/// (`0.211` to `0.995`).
pub fn pi5_inverse(wp_wt: f64) -> Result<f64, DaoError> {
    let (lo, hi) = (pi5(0.0), pi5(HR_HM_MAX));
    if !(lo..=hi).contains(&wp_wt) {
        return Err(DaoError::Range {
            what: "W_p/W_t",
            value: wp_wt,
            range: format!("{lo:.3} to {hi:.3}"),
        });
    }
    Ok(bisect(|r| pi5(r) - wp_wt, 0.0, HR_HM_MAX))
}

/// What the reverse analysis measured from: the loading curvature, the unloading, and the
/// residual depth ratio (given, or from the work ratio).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReverseInput {
    /// `C = P/h^2` of the loading (MPa).
    pub c: f64,
    /// Initial unloading slope (N/mm).
    pub s: f64,
    /// Maximum depth (mm).
    pub h_m: f64,
    /// Force at the unloading's start (N).
    pub p_m: f64,
    /// `h_r/h_m`.
    pub hr_hm: f64,
}

impl ReverseInput {
    /// From a curve's [`Features`], `h_r/h_m` from the work ratio through `Pi5` (Dao's
    /// choice: the work is an integral, `h_r` a single point), or from the measured `h_r`
    /// when `from_work` is false.
    ///
    /// # Errors
    /// No `W_p/W_t` or `h_r` (an unloading that stops before zero force); a work ratio
    /// outside `Pi5`'s range.
    pub fn of(m: &Features, from_work: bool) -> Result<ReverseInput, DaoError> {
        let hr_hm = if from_work {
            let w = m.wp_wt.ok_or_else(|| {
                DaoError::Curve(
                    "the unloading does not reach zero force: no work ratio W_p/W_t".into(),
                )
            })?;
            pi5_inverse(w)?
        } else {
            m.h_r.ok_or_else(|| {
                DaoError::Curve("the unloading does not reach zero force: no residual depth".into())
            })? / m.h_m
        };
        Ok(ReverseInput {
            c: m.c,
            s: m.s,
            h_m: m.h_m,
            p_m: m.p_m,
            hr_hm,
        })
    }
}

/// The outcome of Dao's reverse algorithm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reverse {
    /// `E* = E/(1 - nu^2)` (MPa).
    pub e_star: f64,
    /// Young's modulus `E` (MPa) at the `nu` given.
    pub e: f64,
    /// The representative stress `sigma(0.033)` (MPa).
    pub sigma_r: f64,
    /// The hardening exponent.
    pub n: f64,
    /// Whether `Pi2` had no root in [`N_RANGE`] and `n` is the end nearest to one.
    pub n_clamped: bool,
    /// How many roots `Pi2` has in [`N_RANGE`] (more than one: `n` is the one nearest the
    /// hint, the ambiguity of Dao's `Pi2` at small `E*/sigma_r` and large `n`).
    pub n_roots: usize,
    /// The initial yield stress of the power form `sigma = sY (1 + E eps_p/sY)^n` (MPa).
    pub sy: f64,
    /// `h_r/h_m` used.
    pub hr_hm: f64,
    /// The contact area at the maximum load (mm^2), `(S/(c* E*))^2`.
    pub a_m: f64,
}

/// The roots of `Pi2(E*/sigma_r, n) = s_norm` in [`N_RANGE`], increasing: a grid of 50
/// intervals, each bracket bisected (an end that is a root to round-off counts).
pub fn pi2_roots(estar_over_sr: f64, s_norm: f64) -> Vec<f64> {
    let h = |n: f64| pi2(estar_over_sr, n) - s_norm;
    let tol = 1e-12 * s_norm.abs();
    let grid: Vec<f64> = (0..=50)
        .map(|i| N_RANGE.0 + (N_RANGE.1 - N_RANGE.0) * i as f64 / 50.0)
        .collect();
    let mut roots = Vec::new();
    for (i, w) in grid.windows(2).enumerate() {
        let (a, b) = (h(w[0]), h(w[1]));
        if i == 0 && a.abs() <= tol {
            roots.push(w[0]);
        }
        if b.abs() <= tol {
            roots.push(w[1]);
        } else if a.abs() > tol && (a > 0.0) != (b > 0.0) {
            roots.push(bisect(h, w[0], w[1]));
        }
    }
    roots
}

/// `sY` of the power form from its representative stress: the root of
/// `sY (1 + E 0.033/sY)^n = sigma_r` in `(0, sigma_r]` (increasing in `sY` for `n < 1`);
/// `sigma_r` itself for `n = 0`.
pub fn sy_of_sigma_r(e: f64, sigma_r: f64, n: f64) -> f64 {
    if n <= 0.0 {
        return sigma_r;
    }
    let g = |ln_sy: f64| (flow_stress(e, ln_sy.exp(), n, EPS_R) / sigma_r).ln();
    bisect(g, (sigma_r * 1e-12).ln(), sigma_r.ln()).exp()
}

/// Dao's reverse algorithm: `E*` from `h_r/h_m` (through `Pi4`) and `S`, `sigma_r` from
/// `C` (`Pi1` inverted), `n` from `S/(E* h_m)` (`Pi2` inverted at that `E*/sigma_r`), and
/// `sY` of the power form; `E = E* (1 - nu^2)`. Where `Pi2` has several roots in
/// [`N_RANGE`], `n` is the one nearest `n_hint` (the smallest without one).
///
/// # Errors
/// [`DaoError::Input`]: a value that is not finite and positive, `nu` outside (-1, 0.5),
/// `h_r/h_m` outside `[0, 0.9952495)`; [`DaoError::Range`]: `C/E*` outside what `Pi1`
/// covers over [`ESTAR_OVER_SR_RANGE`].
pub fn reverse(input: &ReverseInput, nu: f64, n_hint: Option<f64>) -> Result<Reverse, DaoError> {
    let ReverseInput {
        c,
        s,
        h_m,
        p_m,
        hr_hm,
    } = *input;
    for (what, v) in [("C", c), ("S", s), ("h_m", h_m), ("P_m", p_m)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(DaoError::Input(format!(
                "{what} = {v} must be finite and positive"
            )));
        }
    }
    if !(nu > -1.0 && nu < 0.5) {
        return Err(DaoError::Input(format!(
            "Poisson's ratio {nu} is outside (-1, 0.5)"
        )));
    }
    if !(0.0..HR_HM_MAX).contains(&hr_hm) {
        return Err(DaoError::Input(format!(
            "h_r/h_m = {hr_hm} is outside [0, {HR_HM_MAX})"
        )));
    }
    // Pi4 = P_m/(A_m E*) and S = c* E* sqrt(A_m)
    let e_star = s * s * pi4(hr_hm) / (C_STAR * C_STAR * p_m);
    let a_m = (s / (C_STAR * e_star)).powi(2);
    // C/E* = Pi1(x) e^(-x), decreasing in x = ln(E*/sigma_r) over the range
    let target = c / e_star;
    let g = |x: f64| pi1(x.exp()) * (-x).exp() - target;
    let (x_lo, x_hi) = (ESTAR_OVER_SR_RANGE.0.ln(), ESTAR_OVER_SR_RANGE.1.ln());
    if !(g(x_lo) >= 0.0 && g(x_hi) <= 0.0) {
        return Err(DaoError::Range {
            what: "C/E*",
            value: target,
            range: format!(
                "Pi1 over E*/sigma_r from {} to {}: {:.4} to {:.4}",
                ESTAR_OVER_SR_RANGE.0,
                ESTAR_OVER_SR_RANGE.1,
                g(x_hi) + target,
                g(x_lo) + target
            ),
        });
    }
    let x = bisect(g, x_lo, x_hi);
    let ratio = x.exp();
    let sigma_r = e_star / ratio;
    // n: the roots of Pi2(ratio, n) = S/(E* h_m) over N_RANGE, the one nearest the hint
    let s_norm = s / (e_star * h_m);
    let roots = pi2_roots(ratio, s_norm);
    let (n, n_clamped) = match roots.as_slice() {
        [] => {
            // no root: the end of the range whose residual is smallest
            let h = |n: f64| (pi2(ratio, n) - s_norm).abs();
            let (lo, hi) = N_RANGE;
            (if h(lo) <= h(hi) { lo } else { hi }, true)
        }
        [only] => (*only, false),
        many => {
            let hint = n_hint.unwrap_or(N_RANGE.0);
            let best = many
                .iter()
                .copied()
                .min_by(|a, b| (a - hint).abs().total_cmp(&(b - hint).abs()))
                .unwrap_or(many[0]);
            (best, false)
        }
    };
    let e = e_star * (1.0 - nu * nu);
    Ok(Reverse {
        e_star,
        e,
        sigma_r,
        n,
        n_clamped,
        n_roots: roots.len(),
        sy: sy_of_sigma_r(e, sigma_r, n),
        hr_hm,
        a_m,
    })
}
