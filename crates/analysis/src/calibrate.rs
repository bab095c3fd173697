//! Calibration on a reference of known modulus (fused silica): the frame compliance from
//! `1/S = C_f + k / sqrt(F_max)` and the ISO area function `A(h_c) = C0 h_c^2 + C1 h_c +
//! C2 h_c^(1/2) + ...` from the areas the reference's modulus implies.
//!
//! 1. Frame compliance. The measured compliance is the frame's in series with the
//!    contact's: `1/S = C_f + sqrt(pi) / (2 beta E_r sqrt(A))`. With a constant hardness
//!    `A = F_max / H`, so `1/S = C_f + k / sqrt(F_max)`, a line in `1/sqrt(F_max)` whose
//!    intercept is `C_f`; it is fitted by least squares over the unloadings from the
//!    larger forces (where the reference's hardness is constant: by default those with
//!    `F_max` at least 25 % of the largest).
//! 2. Area function. With the depths corrected (`h <- h - C_f F`) and the unloadings
//!    analysed again, each gives `A_i = (pi / 4) (S_i / (beta E_r))^2` at
//!    `h_c,i = h_max,i - epsilon F_max,i / S_i`, `E_r` from the reference's `E`, `nu` and
//!    the tip's. The coefficients are the least squares of the relative misfit
//!    `(A(h_c,i) - A_i) / A_i` under `C_k >= 0` (an area must grow with the depth): the
//!    unconstrained fit when its coefficients are all non-negative, else the best fit with
//!    the offending ones held at zero (said in the warnings). Points whose relative misfit
//!    exceeds 5 robust standard deviations (and 5 %) are dropped once and the fit repeated
//!    (an indent that sank in at first contact has its depths offset; they are listed);
//!    before that, points whose area is below half the nominal tip's at their depth are
//!    dropped (a worn tip only gains area: such a point's depth is offset).
//! 3. The equivalent tip radius: the sphere `A = pi (2 R h_c - h_c^2)` through the
//!    calibrated area at the shallowest quarter of the calibration depths (median of the
//!    per-point radii): the bluntness of a worn Berkovich, or a sphere's radius.

use serde::Serialize;

use crate::error::AnalysisError;
use crate::tip::{Tip, iso_exponent};

/// One analysed unloading of the reference.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Point {
    /// Test name.
    pub test: String,
    /// Unloading number within the test.
    pub unloading: usize,
    /// Force at the start of the unloading, N.
    pub f_max: f64,
    /// Depth at the start of the unloading, mm.
    pub h_max: f64,
    /// Stiffness, N/mm.
    pub s: f64,
}

/// The fitted frame compliance.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Compliance {
    /// `C_f`, mm/N.
    pub c: f64,
    /// The slope `k` of `1/S` against `1/sqrt(F_max)`, mm N^(-1/2).
    pub k: f64,
    /// Unloadings used.
    pub n: usize,
    /// Smallest force used, N.
    pub f_min: f64,
    /// Coefficient of determination of the line.
    pub r2: f64,
}

/// `E_r` of a sample of modulus `e` (MPa) and Poisson's ratio `nu` under `tip`.
pub fn reduced_modulus(e: f64, nu: f64, tip: &Tip) -> f64 {
    1.0 / ((1.0 - nu * nu) / e + tip.compliance_share())
}

/// Fits `1/S = C_f + k / sqrt(F_max)` over the points with `F_max >= min_fraction` times
/// the largest.
///
/// # Errors
/// [`AnalysisError::Calibration`]: fewer than 3 points or 2 distinct forces in the range, a
/// negative compliance or slope (the stiffness does not follow the constant-hardness law).
pub fn frame_compliance(points: &[Point], min_fraction: f64) -> Result<Compliance, AnalysisError> {
    let err = |reason: String| AnalysisError::Calibration { reason };
    if !(0.0..1.0).contains(&min_fraction) {
        return Err(AnalysisError::Option {
            field: "compliance_range".into(),
            value: min_fraction.to_string(),
            expected: "0 <= fraction < 1 of the largest force".into(),
        });
    }
    let f_top = points.iter().map(|p| p.f_max).fold(0.0, f64::max);
    let used: Vec<&Point> = points
        .iter()
        .filter(|p| p.f_max >= min_fraction * f_top && p.s > 0.0 && p.f_max > 0.0)
        .collect();
    let n = used.len();
    let x: Vec<f64> = used.iter().map(|p| 1.0 / p.f_max.sqrt()).collect();
    let y: Vec<f64> = used.iter().map(|p| 1.0 / p.s).collect();
    let mx = x.iter().sum::<f64>() / n.max(1) as f64;
    let my = y.iter().sum::<f64>() / n.max(1) as f64;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(&y) {
        sxx += (a - mx) * (a - mx);
        sxy += (a - mx) * (b - my);
        syy += (b - my) * (b - my);
    }
    if n < 3 || !(sxx > 1e-12 * mx * mx * n as f64) {
        return Err(err(format!(
            "{n} unloadings with F_max >= {:.4} mN and too little spread in force; the frame compliance needs at least 3 unloadings at 2 or more forces",
            min_fraction * f_top * 1e3
        )));
    }
    let k = sxy / sxx;
    let c = my - k * mx;
    let r2 = if syy > 0.0 {
        sxy * sxy / (sxx * syy)
    } else {
        1.0
    };
    if !(k > 0.0) {
        return Err(err(format!(
            "the contact compliance does not fall with the force (slope {k:.4e} of 1/S against 1/sqrt(F) over {n} unloadings): not a reference of constant hardness, or another range of forces is needed"
        )));
    }
    if !(c >= 0.0) {
        return Err(err(format!(
            "the frame compliance comes out negative, C_f = {:.4} nm/mN (1/S = C_f + k/sqrt(F) over {n} unloadings from {:.4} mN, R^2 {r2:.4}): the stiffness does not follow the constant-hardness law there; use other forces (compliance range) or give the compliance",
            c * 1e3,
            min_fraction * f_top * 1e3
        )));
    }
    Ok(Compliance {
        c,
        k,
        n,
        f_min: used.iter().map(|p| p.f_max).fold(f64::INFINITY, f64::min),
        r2,
    })
}

/// The fitted area function.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AreaFit {
    /// `C0, C1, ...` in mm-based units (see [`crate::AreaFunction::Iso`]).
    pub coefficients: Vec<f64>,
    /// Coefficients held at zero (their unconstrained value was negative).
    pub held: Vec<usize>,
    /// Points used.
    pub n: usize,
    /// Root-mean-square relative misfit of the areas.
    pub rms_rel: f64,
    /// Contact-depth range of the data, mm.
    pub hc_range: (f64, f64),
    /// `(h_c, A)` of every point, mm and mm^2.
    pub points: Vec<(f64, f64)>,
    /// Equivalent tip radius, mm.
    pub radius: Option<f64>,
    /// Points dropped as outliers: test, unloading, relative misfit of the first fit.
    pub rejected: Vec<(String, usize, f64)>,
    /// What the fit had to do.
    pub warnings: Vec<String>,
}

/// Least squares of the columns `cols` (subset of `0..terms`) for rows `a_i`, relative
/// weights; returns the coefficients (zeros elsewhere) and the sum of squared relative
/// residuals.
fn lsq_subset(hc: &[f64], a: &[f64], terms: usize, cols: &[usize]) -> Option<(Vec<f64>, f64)> {
    let p = cols.len();
    let col = |i: usize, k: usize| hc[i].powf(iso_exponent(k)) / a[i];
    // column scales
    let scale: Vec<f64> = cols
        .iter()
        .map(|&k| (0..hc.len()).map(|i| col(i, k).powi(2)).sum::<f64>().sqrt())
        .collect();
    if scale.iter().any(|s| !(*s > 0.0 && s.is_finite())) {
        return None;
    }
    let mut m = vec![vec![0.0; p + 1]; p];
    for i in 0..hc.len() {
        for (r, &kr) in cols.iter().enumerate() {
            let xr = col(i, kr) / scale[r];
            for (c, &kc) in cols.iter().enumerate() {
                m[r][c] += xr * col(i, kc) / scale[c];
            }
            m[r][p] += xr; // target 1 (a_i / a_i)
        }
    }
    // Gaussian elimination with partial pivoting
    for c in 0..p {
        let piv = (c..p).max_by(|&i, &j| m[i][c].abs().total_cmp(&m[j][c].abs()))?;
        if !(m[piv][c].abs() > 1e-14) {
            return None;
        }
        m.swap(c, piv);
        for r in c + 1..p {
            let f = m[r][c] / m[c][c];
            for k in c..=p {
                m[r][k] -= f * m[c][k];
            }
        }
    }
    let mut z = vec![0.0; p];
    for r in (0..p).rev() {
        let mut s = m[r][p];
        for k in r + 1..p {
            s -= m[r][k] * z[k];
        }
        z[r] = s / m[r][r];
    }
    let mut coef = vec![0.0; terms];
    for (r, &k) in cols.iter().enumerate() {
        coef[k] = z[r] / scale[r];
    }
    let ss = (0..hc.len())
        .map(|i| {
            let model: f64 = (0..terms)
                .map(|k| coef[k] * hc[i].powf(iso_exponent(k)))
                .sum();
            (model / a[i] - 1.0).powi(2)
        })
        .sum();
    coef.iter().all(|v| v.is_finite()).then_some((coef, ss))
}

/// The best non-negative fit (C0 > 0): the subsets of free coefficients tried in turn.
fn best_fit(hc: &[f64], a: &[f64], terms: usize) -> Option<(Vec<f64>, f64, Vec<usize>)> {
    let mut best: Option<(Vec<f64>, f64, Vec<usize>)> = None;
    for mask in 1u32..(1 << terms) {
        if mask & 1 == 0 {
            continue; // C0 always free
        }
        let cols: Vec<usize> = (0..terms).filter(|k| mask & (1 << k) != 0).collect();
        let Some((coef, ss)) = lsq_subset(hc, a, terms, &cols) else {
            continue;
        };
        if coef.iter().any(|&c| c < 0.0) || !(coef[0] > 0.0) {
            continue;
        }
        let held: Vec<usize> = (0..terms).filter(|k| mask & (1 << k) == 0).collect();
        if best.as_ref().is_none_or(|b| ss < b.1 * (1.0 - 1e-12)) {
            best = Some((coef, ss, held));
        }
    }
    best
}

fn no_fit(hc: &[f64]) -> AnalysisError {
    AnalysisError::Calibration {
        reason: format!(
            "no area function with C0 > 0 and the other coefficients >= 0 fits the {} points (h_c {:.1} to {:.1} nm)",
            hc.len(),
            hc.iter().copied().fold(f64::INFINITY, f64::min) * 1e6,
            hc.iter().copied().fold(0.0, f64::max) * 1e6
        ),
    }
}

/// Fits the ISO area function with `terms` coefficients (1 to 6) to the points, with the
/// reference's reduced modulus `er` (MPa), `beta` and `epsilon`.
///
/// # Errors
/// [`AnalysisError::Calibration`]: fewer points than twice the terms, a non-positive
/// contact depth or stiffness, no fit with a positive `C0`.
pub fn area_function(
    points: &[Point],
    nominal: &crate::tip::AreaFunction,
    er: f64,
    beta: f64,
    epsilon: f64,
    terms: usize,
) -> Result<AreaFit, AnalysisError> {
    let err = |reason: String| AnalysisError::Calibration { reason };
    if !(1..=6).contains(&terms) {
        return Err(AnalysisError::Option {
            field: "terms".into(),
            value: terms.to_string(),
            expected: "1 to 6 coefficients".into(),
        });
    }
    let mut hc = Vec::new();
    let mut a = Vec::new();
    for p in points {
        let h = p.h_max - epsilon * p.f_max / p.s;
        let area = std::f64::consts::PI / 4.0 * (p.s / (beta * er)).powi(2);
        if !(h > 0.0 && area > 0.0 && area.is_finite()) {
            return Err(err(format!(
                "{}, unloading {}: contact depth {:.3} nm, area {:.4e} nm^2; expected both positive",
                p.test,
                p.unloading,
                h * 1e6,
                area * 1e12
            )));
        }
        hc.push(h);
        a.push(area);
    }
    if hc.len() < 2 * terms {
        return Err(err(format!(
            "{} analysed unloadings for {terms} area coefficients; expected at least {}",
            hc.len(),
            2 * terms
        )));
    }
    // points whose area is below half the nominal tip's at their contact depth: a worn tip
    // only gains area, so their depth is offset (an indent that sank in at first contact)
    let mut rejected: Vec<(String, usize, f64)> = Vec::new();
    let mut idx: Vec<usize> = Vec::new();
    for i in 0..hc.len() {
        let nom = nominal.area(hc[i]);
        if nom.is_finite() && a[i] < 0.5 * nom {
            rejected.push((
                points[i].test.clone(),
                points[i].unloading,
                a[i] / nom - 1.0,
            ));
        } else {
            idx.push(i);
        }
    }
    let pts: Vec<&Point> = idx.iter().map(|&i| &points[i]).collect();
    let (hc, a): (Vec<f64>, Vec<f64>) = idx.iter().map(|&i| (hc[i], a[i])).unzip();
    if hc.len() < 2 * terms {
        return Err(err(format!(
            "{} unloadings left after dropping {} whose area is below half the nominal tip's; expected at least {}",
            hc.len(),
            rejected.len(),
            2 * terms
        )));
    }
    let first = best_fit(&hc, &a, terms).ok_or_else(|| no_fit(&hc))?;
    // outliers: relative misfits beyond 5 robust standard deviations (1.4826 MAD) and
    // beyond 5 %, dropped once and the fit repeated
    let rel: Vec<f64> = (0..hc.len())
        .map(|i| {
            let model: f64 = (0..terms)
                .map(|k| first.0[k] * hc[i].powf(iso_exponent(k)))
                .sum();
            model / a[i] - 1.0
        })
        .collect();
    let mut abs: Vec<f64> = rel.iter().map(|r| r.abs()).collect();
    abs.sort_by(f64::total_cmp);
    let mad = abs[abs.len() / 2];
    let cut = (5.0 * 1.4826 * mad).max(0.05);
    let keep: Vec<usize> = (0..hc.len()).filter(|&i| rel[i].abs() <= cut).collect();
    rejected.extend(
        (0..hc.len())
            .filter(|&i| rel[i].abs() > cut)
            .map(|i| (pts[i].test.clone(), pts[i].unloading, rel[i])),
    );
    let (hc, a): (Vec<f64>, Vec<f64>) = keep.iter().map(|&i| (hc[i], a[i])).unzip();
    if hc.len() < 2 * terms {
        return Err(err(format!(
            "{} unloadings left after dropping {} outliers; expected at least {}",
            hc.len(),
            rejected.len(),
            2 * terms
        )));
    }
    let (coef, ss, held) = best_fit(&hc, &a, terms).ok_or_else(|| no_fit(&hc))?;
    let mut warnings = Vec::new();
    if !held.is_empty() {
        let free: Vec<usize> = (0..terms).collect();
        let unc = lsq_subset(&hc, &a, terms, &free).map(|x| x.0);
        warnings.push(format!(
            "the unconstrained fit gives a negative coefficient ({}); held at zero: {}",
            unc.map_or("singular".into(), |c| c
                .iter()
                .enumerate()
                .map(|(k, v)| format!("C{k} = {v:.4e}"))
                .collect::<Vec<_>>()
                .join(", ")),
            held.iter()
                .map(|k| format!("C{k}"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    let n = hc.len();
    let lo = hc.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = hc.iter().copied().fold(0.0, f64::max);
    // equivalent radius at the shallowest quarter
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| hc[i].total_cmp(&hc[j]));
    let q = (n / 4).max(1);
    let mut radii: Vec<f64> = order[..q]
        .iter()
        .map(|&i| {
            let area: f64 = (0..terms)
                .map(|k| coef[k] * hc[i].powf(iso_exponent(k)))
                .sum();
            (area / std::f64::consts::PI + hc[i] * hc[i]) / (2.0 * hc[i])
        })
        .filter(|r| r.is_finite() && *r > 0.0)
        .collect();
    radii.sort_by(f64::total_cmp);
    let radius = (!radii.is_empty()).then(|| radii[radii.len() / 2]);
    Ok(AreaFit {
        coefficients: coef,
        held,
        n,
        rms_rel: (ss / n as f64).sqrt(),
        hc_range: (lo, hi),
        points: hc.into_iter().zip(a).collect(),
        radius,
        rejected,
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tip::AreaFunction;

    /// Points of a synthetic reference: area `true_area`, modulus `er`, hardness `hard`,
    /// frame compliance `cf` in the measured stiffness.
    fn synthetic(
        true_area: &AreaFunction,
        er: f64,
        hard: f64,
        cf: f64,
        forces: &[f64],
    ) -> Vec<Point> {
        forces
            .iter()
            .enumerate()
            .map(|(i, &f)| {
                let area = f / hard;
                // invert A(h_c) by bisection
                let (mut lo, mut hi) = (0.0, 1.0);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if true_area.area(mid) < area {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let hc = 0.5 * (lo + hi);
                let s_contact = 2.0 * er * area.sqrt() / std::f64::consts::PI.sqrt();
                let h_max = hc + 0.75 * f / s_contact;
                Point {
                    test: format!("t{i}"),
                    unloading: 1,
                    f_max: f,
                    h_max,
                    s: 1.0 / (1.0 / s_contact + cf),
                }
            })
            .collect()
    }

    #[test]
    fn frame_compliance_and_area_function_come_back() {
        let truth = AreaFunction::Iso {
            coefficients: vec![24.5, 2e-4, 3e-7],
        };
        let (er, hard, cf) = (69_600.0, 9_000.0, 5e-4);
        let forces: Vec<f64> = (0..30).map(|i| 1e-4 * 1.25f64.powi(i)).collect();
        let pts = synthetic(&truth, er, hard, cf, &forces);
        let c = frame_compliance(&pts, 0.0).unwrap();
        assert!((c.c / cf - 1.0).abs() < 1e-9, "{c:?}");
        // corrected points
        let corr: Vec<Point> = pts
            .iter()
            .map(|p| Point {
                s: 1.0 / (1.0 / p.s - c.c),
                h_max: p.h_max,
                ..p.clone()
            })
            .collect();
        let fit = area_function(&corr, &AreaFunction::Berkovich, er, 1.0, 0.75, 3).unwrap();
        let AreaFunction::Iso { coefficients } = &truth else {
            unreachable!()
        };
        for k in 0..3 {
            assert!(
                (fit.coefficients[k] / coefficients[k] - 1.0).abs() < 1e-6,
                "{fit:?}"
            );
        }
        assert!(fit.held.is_empty());
    }

    #[test]
    fn negative_compliance_is_refused() {
        let truth = AreaFunction::Berkovich;
        let forces: Vec<f64> = (0..10).map(|i| 1e-3 * (i + 1) as f64).collect();
        let mut pts = synthetic(&truth, 69_600.0, 9_000.0, 0.0, &forces);
        for p in &mut pts {
            p.s = 1.0 / (1.0 / p.s - 2e-4 * p.f_max.sqrt() / 0.1); // bends the line down
        }
        let e = frame_compliance(&pts, 0.0);
        assert!(e.is_err() || e.as_ref().is_ok_and(|c| c.c >= 0.0));
        let mut pts = synthetic(&truth, 69_600.0, 9_000.0, 0.0, &forces);
        for p in &mut pts {
            p.s = 1.0 / (1.0 / p.s - 1e-4); // a negative frame compliance
        }
        let e = frame_compliance(&pts, 0.0).unwrap_err().to_string();
        assert!(e.contains("negative"), "{e}");
    }
}
