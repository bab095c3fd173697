//! The power-law fit of an unloading curve, `F = alpha (h - h_f)^m` (Oliver and Pharr
//! 1992; ISO 14577-1 Annex A), by least squares on the force.
//!
//! In scaled variables `x = h / h_max`, `y = F / F_max` the model is `y = a (x - p)^m`. For a
//! fixed `p` (= `h_f / h_max`), `ln y = ln a + m ln(x - p)` is linear: its least-squares
//! `(a, m)` are a closed form. The force misfit `sum (y - a (x - p)^m)^2` of these is
//! scanned over `p` on a logarithmic grid of distances below the shallowest fitted depth
//! (1e-7 to 3 `h_max`), refined by golden section around the best grid point, and the
//! three parameters are then polished together by Levenberg-Marquardt on the force
//! residuals (the least-squares solution on the force, which the log-space start is close
//! to). No starting guess is needed, and the fit cannot end with `h_f` above the data.

use serde::Serialize;

/// A fitted unloading `F = alpha (h - h_f)^m` with its quality.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PowerLaw {
    /// `alpha`, N/mm^m.
    pub alpha: f64,
    /// The exponent `m`.
    pub m: f64,
    /// The final depth `h_f`, mm.
    pub h_f: f64,
    /// Points fitted.
    pub n: usize,
    /// Lower and upper force of the fit range, N.
    pub f_range: (f64, f64),
    /// Root-mean-square force residual, N.
    pub rms: f64,
    /// Coefficient of determination of the force.
    pub r2: f64,
}

impl PowerLaw {
    /// `F(h)`, N (0 below `h_f`).
    pub fn force(&self, h: f64) -> f64 {
        if h <= self.h_f {
            0.0
        } else {
            self.alpha * (h - self.h_f).powf(self.m)
        }
    }

    /// `dF/dh(h)`, N/mm.
    pub fn slope(&self, h: f64) -> f64 {
        if h <= self.h_f {
            0.0
        } else {
            self.alpha * self.m * (h - self.h_f).powf(self.m - 1.0)
        }
    }
}

/// Closed-form log-space fit at fixed `p`: `(ln a, m)` and the force misfit, or `None`.
fn log_fit(x: &[f64], y: &[f64], p: f64) -> Option<(f64, f64, f64)> {
    let n = x.len() as f64;
    let (mut su, mut sv, mut suu, mut suv) = (0.0, 0.0, 0.0, 0.0);
    for (&xi, &yi) in x.iter().zip(y) {
        let u = (xi - p).ln();
        let v = yi.ln();
        su += u;
        sv += v;
        suu += u * u;
        suv += u * v;
    }
    let var = suu - su * su / n;
    if !(var > 1e-300) {
        return None;
    }
    let m = (suv - su * sv / n) / var;
    let la = (sv - m * su) / n;
    let a = la.exp();
    let mut cost = 0.0;
    for (&xi, &yi) in x.iter().zip(y) {
        let r = a * (xi - p).powf(m) - yi;
        cost += r * r;
    }
    cost.is_finite().then_some((la, m, cost))
}

/// Sum of squared force residuals of `y = a (x - p)^m`.
fn misfit(x: &[f64], y: &[f64], a: f64, m: f64, p: f64) -> f64 {
    x.iter()
        .zip(y)
        .map(|(&xi, &yi)| {
            let r = a * (xi - p).powf(m) - yi;
            r * r
        })
        .sum()
}

/// Solves the 3x3 system `A z = b` by Gaussian elimination with partial pivoting.
fn solve3(mut a: [[f64; 3]; 3], mut b: [f64; 3]) -> Option<[f64; 3]> {
    for c in 0..3 {
        let piv = (c..3).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))?;
        if !(a[piv][c].abs() > 1e-300) {
            return None;
        }
        a.swap(c, piv);
        b.swap(c, piv);
        for r in c + 1..3 {
            let f = a[r][c] / a[c][c];
            for k in c..3 {
                a[r][k] -= f * a[c][k];
            }
            b[r] -= f * b[c];
        }
    }
    let mut z = [0.0; 3];
    for r in (0..3).rev() {
        let mut s = b[r];
        for k in r + 1..3 {
            s -= a[r][k] * z[k];
        }
        z[r] = s / a[r][r];
    }
    z.iter().all(|v| v.is_finite()).then_some(z)
}

/// Fits `F = alpha (h - h_f)^m` to the points `(h, f)` (mm, N), scaled by `h_max`, `f_max`.
///
/// # Errors
/// A sentence saying why: fewer than 5 points, a force that does not fall with the depth,
/// no minimum of the misfit for `h_f` within 3 `h_max` below the data, an exponent outside
/// 0.5 to 6 (a power law does not describe the curve), non-finite values.
pub fn fit_power_law(h: &[f64], f: &[f64], h_max: f64, f_max: f64) -> Result<PowerLaw, String> {
    let n = h.len().min(f.len());
    if n < 5 {
        return Err(format!(
            "{n} points in the fit range; a power-law fit needs at least 5"
        ));
    }
    if !(h_max > 0.0 && f_max > 0.0 && h_max.is_finite() && f_max.is_finite()) {
        return Err(format!(
            "h_max = {h_max} mm and F_max = {f_max} N must be finite and positive"
        ));
    }
    let x: Vec<f64> = h[..n].iter().map(|v| v / h_max).collect();
    let y: Vec<f64> = f[..n].iter().map(|v| v / f_max).collect();
    if x.iter().chain(&y).any(|v| !v.is_finite()) || y.iter().any(|&v| !(v > 0.0)) {
        return Err("the fit range holds non-finite or non-positive forces".into());
    }
    // the force must fall with the depth: a positive least-squares slope of y on x
    let (mx, my) = (
        x.iter().sum::<f64>() / n as f64,
        y.iter().sum::<f64>() / n as f64,
    );
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (&xi, &yi) in x.iter().zip(&y) {
        sxy += (xi - mx) * (yi - my);
        sxx += (xi - mx) * (xi - mx);
        syy += (yi - my) * (yi - my);
    }
    if !(sxx > 0.0 && sxy > 0.0) {
        return Err(format!(
            "the force does not fall with the depth over the fit range (depth spread {:.3e} nm, force-depth covariance {:.3e}); expected an unloading curve",
            (sxx / n as f64).sqrt() * h_max * 1e6,
            sxy / n as f64
        ));
    }
    let x_min = x.iter().copied().fold(f64::INFINITY, f64::min);
    // grid over d = x_min - p, log-spaced
    const K: usize = 81;
    let (d_lo, d_hi) = (1e-7f64, 3.0f64);
    let step = (d_hi / d_lo).ln() / (K - 1) as f64;
    let d_at = |k: f64| d_lo * (step * k).exp();
    let cost_at = |k: f64| log_fit(&x, &y, x_min - d_at(k)).map_or(f64::INFINITY, |c| c.2);
    let mut best = (0usize, f64::INFINITY);
    for k in 0..K {
        let c = cost_at(k as f64);
        if c < best.1 {
            best = (k, c);
        }
    }
    if !best.1.is_finite() {
        return Err("the log-space fit fails for every h_f (the depths do not vary)".into());
    }
    if best.0 == K - 1 {
        return Err(format!(
            "the misfit keeps falling as h_f goes below 3 h_max ({:.1} nm): the curve is not a power law of (h - h_f) with a final depth near the data",
            -3.0 * h_max * 1e6 + x_min * h_max * 1e6
        ));
    }
    // golden section on k in [best - 1, best + 1]
    let lo = (best.0 as f64 - 1.0).max(0.0);
    let k = golden_section(cost_at, lo, best.0 as f64 + 1.0, 60, 0.0).best;
    let mut p = x_min - d_at(k);
    let Some((la, m0, _)) = log_fit(&x, &y, p) else {
        return Err("the log-space fit fails at its own optimum".into());
    };
    let (mut a, mut m) = (la.exp(), m0);
    // Levenberg-Marquardt on the force residuals
    let mut cost = misfit(&x, &y, a, m, p);
    let mut lambda = 1e-3;
    for _ in 0..100 {
        let mut jtj = [[0.0; 3]; 3];
        let mut jtr = [0.0; 3];
        for (&xi, &yi) in x.iter().zip(&y) {
            let d = xi - p;
            let pw = d.powf(m);
            let r = a * pw - yi;
            let j = [pw, a * pw * d.ln(), -a * m * pw / d];
            for r_ in 0..3 {
                jtr[r_] += j[r_] * r;
                for c in 0..3 {
                    jtj[r_][c] += j[r_] * j[c];
                }
            }
        }
        let mut improved = false;
        for _ in 0..20 {
            let mut aa = jtj;
            for i in 0..3 {
                aa[i][i] += lambda * jtj[i][i].max(1e-30);
            }
            let Some(z) = solve3(aa, [-jtr[0], -jtr[1], -jtr[2]]) else {
                lambda *= 10.0;
                continue;
            };
            let (na, nm, np) = (a + z[0], m + z[1], p + z[2]);
            let c = if na > 0.0 && np < x_min {
                misfit(&x, &y, na, nm, np)
            } else {
                f64::INFINITY
            };
            if c.is_finite() && c < cost {
                let rel = (cost - c) / cost.max(1e-300);
                a = na;
                m = nm;
                p = np;
                cost = c;
                lambda = (lambda * 0.3).max(1e-12);
                improved = rel > 1e-15;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    if !(m > 0.5 && m < 6.0) {
        return Err(format!(
            "the best power law has m = {m:.4}, outside 0.5 to 6: a power law does not describe this unloading"
        ));
    }
    let alpha = a * f_max / h_max.powf(m);
    let rms = (cost / n as f64).sqrt() * f_max;
    let r2 = if syy > 0.0 { 1.0 - cost / syy } else { 1.0 };
    let (f_lo, f_hi) = f[..n]
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), &v| {
            (l.min(v), u.max(v))
        });
    Ok(PowerLaw {
        alpha,
        m,
        h_f: p * h_max,
        n,
        f_range: (f_lo, f_hi),
        rms,
        r2,
    })
}

/// The end of a golden-section search: the last bracket and its better interior point.
pub(crate) struct Golden {
    /// The bracket's lower end.
    pub lo: f64,
    /// The bracket's upper end.
    pub hi: f64,
    /// The interior point with the lower value.
    pub best: f64,
}

/// Golden-section search for a minimum of `f` on `[lo, hi]`: at most `max_iter` reductions,
/// stopping once the bracket is shorter than `tol`.
pub(crate) fn golden_section(
    mut f: impl FnMut(f64) -> f64,
    mut lo: f64,
    mut hi: f64,
    max_iter: usize,
    tol: f64,
) -> Golden {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut k1, mut k2) = (hi - g * (hi - lo), lo + g * (hi - lo));
    let (mut c1, mut c2) = (f(k1), f(k2));
    for _ in 0..max_iter {
        if c1 <= c2 {
            hi = k2;
            k2 = k1;
            c2 = c1;
            k1 = hi - g * (hi - lo);
            c1 = f(k1);
        } else {
            lo = k1;
            k1 = k2;
            c1 = c2;
            k2 = lo + g * (hi - lo);
            c2 = f(k2);
        }
        if hi - lo < tol {
            break;
        }
    }
    Golden {
        lo,
        hi,
        best: if c1 <= c2 { k1 } else { k2 },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(alpha: f64, m: f64, hf: f64, h0: f64, h1: f64, n: usize) -> (Vec<f64>, Vec<f64>) {
        let h: Vec<f64> = (0..n)
            .map(|i| h0 + (h1 - h0) * i as f64 / (n - 1) as f64)
            .collect();
        let f = h.iter().map(|&v| alpha * (v - hf).powf(m)).collect();
        (h, f)
    }

    #[test]
    fn recovers_an_exact_power_law() {
        // 1 um deep, h_f 0.6 um, m 1.4, F_max 10 mN
        let (hf, m, hmax): (f64, f64, f64) = (6e-4, 1.4, 1e-3);
        let alpha = 1e-2 / (hmax - hf).powf(m);
        let (h, f) = curve(alpha, m, hf, 8e-4, 9.9e-4, 40);
        let p = fit_power_law(&h, &f, hmax, 1e-2).unwrap();
        assert!((p.m - m).abs() < 1e-6, "{p:?}");
        assert!((p.h_f - hf).abs() < 1e-10, "{p:?}");
        assert!((p.alpha / alpha - 1.0).abs() < 1e-5, "{p:?}");
        assert!(p.r2 > 0.999_999);
    }

    #[test]
    fn refuses_a_rising_curve_and_too_few_points() {
        let (h, f) = curve(1.0, 1.5, 0.0, 1e-3, 2e-3, 20);
        let f_rev: Vec<f64> = f.iter().rev().copied().collect();
        let e = fit_power_law(&h, &f_rev, 2e-3, f_rev[0]).unwrap_err();
        assert!(e.contains("does not fall"), "{e}");
        let e = fit_power_law(&h[..3], &f[..3], 2e-3, 1.0).unwrap_err();
        assert!(e.contains("at least 5"), "{e}");
    }
}
