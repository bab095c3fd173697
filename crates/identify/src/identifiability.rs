//! How well each parameter is determined at the optimum, from the weighted sensitivity
//! Jacobian `A_ik = sqrt(w_i) dF_i/dc_k` of the free parameters (a linearization):
//!
//! - residual variance `sigma^2 = 2 J / (n - p)` (n data with non-zero weight, p free),
//! - covariance `Cov = sigma^2 (A^T A)^-1`, standard deviations `sqrt(Cov_kk)`,
//!   relative ones `sqrt(Cov_kk) / |c_k|`,
//! - correlations `Cov_kl / sqrt(Cov_kk Cov_ll)` (|.| near 1: the data constrain only a
//!   combination of the two parameters, the valley of the paper's Fig. 11),
//! - the condition number of the relative Fisher matrix `D A^T A D`, `D = diag(c)`
//!   (the same information on the log scale, independent of units).
//!
//! With exact synthetic data `J` is at round-off and so are the deviations; the
//! correlations and the condition number still tell which combinations are weakly seen.
//!
//! A parameter whose relative sensitivity `|c_k| ||A e_k||` is below
//! [`INSENSITIVE`] times the largest one does not act on the data at all (a yield stress
//! driven to zero, a viscosity so large the material never flows): it is listed in
//! [`Identifiability::unidentifiable`], its deviation is infinite, its correlations are
//! left at zero, and the others are computed without it. A Fisher matrix that is still
//! singular gives infinite deviations throughout, never NaN.

use crate::linalg::{inverse, normal_matrix, symmetric_eigenvalues};

/// The identifiability summary at a parameter point.
#[derive(Clone, Debug, PartialEq)]
pub struct Identifiability {
    /// Free parameter names.
    pub names: Vec<&'static str>,
    /// Their values.
    pub values: Vec<f64>,
    /// Data points with non-zero weight.
    pub n_data: usize,
    /// `sigma^2 = 2 J / (n - p)` (N^2).
    pub sigma2: f64,
    /// Standard deviations (parameter units); infinite for an unidentifiable parameter.
    pub std_dev: Vec<f64>,
    /// Relative standard deviations `std / |value|`.
    pub rel_std_dev: Vec<f64>,
    /// Correlation matrix (p x p).
    pub correlation: Vec<Vec<f64>>,
    /// Condition number of `D A^T A D` (ratio of extreme eigenvalues); `inf` if singular.
    pub condition_number: f64,
    /// Free parameters that do not act on the data (relative sensitivity below
    /// [`INSENSITIVE`] times the largest): not determined by these data at all.
    pub unidentifiable: Vec<&'static str>,
}

/// Relative sensitivity, as a fraction of the largest, under which a parameter counts as
/// not acting on the data.
pub const INSENSITIVE: f64 = 1e-7;

impl Identifiability {
    /// Computes the summary from the full Jacobian (`jac[i][k] = dF_i/dc_k`, all law
    /// parameters), the weights, the cost `J`, the full parameter vector and the indices
    /// and names of the free parameters.
    pub fn from_jacobian(
        jac: &[Vec<f64>],
        weights: &[f64],
        cost: f64,
        c: &[f64],
        free: &[usize],
        names: Vec<&'static str>,
    ) -> Identifiability {
        let p = free.len();
        let rows: Vec<Vec<f64>> = jac
            .iter()
            .zip(weights)
            .filter(|(_, w)| **w > 0.0)
            .map(|(r, w)| free.iter().map(|&k| w.sqrt() * r[k]).collect())
            .collect();
        let n = rows.len();
        let sigma2 = if n > p {
            2.0 * cost / (n - p) as f64
        } else {
            f64::NAN
        };
        let ata = normal_matrix(&rows, p);
        let values: Vec<f64> = free.iter().map(|&k| c[k]).collect();
        // relative Fisher matrix D A^T A D (log-scale sensitivities)
        let rel: Vec<Vec<f64>> = (0..p)
            .map(|a| (0..p).map(|b| ata[a][b] * values[a] * values[b]).collect())
            .collect();
        let ev = symmetric_eigenvalues(&rel);
        let condition_number = match (ev.first(), ev.last()) {
            (Some(&lo), Some(&hi)) if lo > 0.0 => hi / lo,
            _ => f64::INFINITY,
        };
        // invert the relative matrix (better conditioned than A^T A across units)
        // parameters that act on the data, and the Fisher matrix restricted to them
        let scale: Vec<f64> = (0..p).map(|a| rel[a][a].max(0.0).sqrt()).collect();
        let largest = scale.iter().copied().fold(0.0, f64::max);
        let kept: Vec<usize> = (0..p)
            .filter(|&a| scale[a] > INSENSITIVE * largest && scale[a].is_finite())
            .collect();
        let unidentifiable = (0..p)
            .filter(|a| !kept.contains(a))
            .map(|a| names[a])
            .collect();
        let sub: Vec<Vec<f64>> = kept
            .iter()
            .map(|&a| kept.iter().map(|&b| rel[a][b]).collect())
            .collect();
        let mut std_dev = vec![f64::INFINITY; p];
        let mut correlation: Vec<Vec<f64>> = (0..p)
            .map(|a| (0..p).map(|b| if a == b { 1.0 } else { 0.0 }).collect())
            .collect();
        if let Some(inv) = inverse(&sub)
            .filter(|inv| (0..kept.len()).all(|i| inv[i][i].is_finite() && inv[i][i] > 0.0))
        {
            for (i, &a) in kept.iter().enumerate() {
                std_dev[a] = (sigma2 * inv[i][i]).max(0.0).sqrt() * values[a].abs();
                for (j, &b) in kept.iter().enumerate() {
                    correlation[a][b] = inv[i][j] / (inv[i][i] * inv[j][j]).sqrt();
                }
            }
        }
        let rel_std_dev = std_dev
            .iter()
            .zip(&values)
            .map(|(s, v)| s / v.abs())
            .collect();
        Identifiability {
            names,
            values,
            n_data: n,
            sigma2,
            std_dev,
            rel_std_dev,
            correlation,
            condition_number,
            unidentifiable,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// For a linear model F = a x + b with known noise, the summary shall give the
    /// textbook least-squares covariance.
    #[test]
    fn linear_regression_covariance() {
        let x: Vec<f64> = (0..10).map(|i| i as f64).collect();
        // Jacobian of F_i = c0 x_i + c1 w.r.t. (c0, c1)
        let jac: Vec<Vec<f64>> = x.iter().map(|&xi| vec![xi, 1.0]).collect();
        let w = vec![1.0; 10];
        let cost = 0.5 * 8.0; // sum r^2 = 8 -> sigma^2 = 8 / 8 = 1
        let s =
            Identifiability::from_jacobian(&jac, &w, cost, &[2.0, 3.0], &[0, 1], vec!["a", "b"]);
        assert!((s.sigma2 - 1.0).abs() < 1e-14);
        // (A^T A)^-1 for x = 0..9: Sxx = 285, Sx = 45, n = 10, det = 825
        let var_a: f64 = 10.0 / 825.0;
        let var_b: f64 = 285.0 / 825.0;
        assert!((s.std_dev[0] - var_a.sqrt()).abs() < 1e-12);
        assert!((s.std_dev[1] - var_b.sqrt()).abs() < 1e-12);
        let corr = -45.0 / 825.0 / (var_a * var_b).sqrt();
        assert!((s.correlation[0][1] - corr).abs() < 1e-12);
        assert!((s.correlation[0][0] - 1.0).abs() < 1e-14);
        assert!(s.unidentifiable.is_empty());
    }

    #[test]
    fn a_parameter_without_effect_is_unidentifiable_and_the_others_still_computed() {
        // the regression of the test above plus a third parameter that acts on nothing
        let x: Vec<f64> = (0..10).map(|i| i as f64).collect();
        let jac: Vec<Vec<f64>> = x.iter().map(|&xi| vec![xi, 1.0, 1e-30]).collect();
        let w = vec![1.0; 10];
        let s = Identifiability::from_jacobian(
            &jac,
            &w,
            4.0,
            &[2.0, 3.0, 1.0],
            &[0, 1, 2],
            vec!["a", "b", "c"],
        );
        assert_eq!(s.unidentifiable, vec!["c"]);
        assert!(s.std_dev[2].is_infinite());
        // sigma^2 counts the three free parameters: 8 / 7
        let var_a: f64 = 10.0 / 825.0 * 8.0 / 7.0;
        assert!(
            (s.std_dev[0] - var_a.sqrt()).abs() < 1e-12,
            "{:?}",
            s.std_dev
        );
        assert!(s.correlation.iter().flatten().all(|v| v.is_finite()));
        assert_eq!(s.correlation[2][2], 1.0);
        assert_eq!(s.correlation[0][2], 0.0);
        // two parameters with the same effect: singular, infinite deviations, no NaN
        let jac: Vec<Vec<f64>> = x.iter().map(|&xi| vec![xi, xi]).collect();
        let s = Identifiability::from_jacobian(&jac, &w, 4.0, &[1.0, 1.0], &[0, 1], vec!["a", "b"]);
        assert!(s.std_dev.iter().all(|v| v.is_infinite()), "{:?}", s.std_dev);
        assert!(s.correlation.iter().flatten().all(|v| v.is_finite()));
    }
}
