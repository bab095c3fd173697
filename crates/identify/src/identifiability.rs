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
    /// Standard deviations (parameter units); `NaN` if `A^T A` is singular.
    pub std_dev: Vec<f64>,
    /// Relative standard deviations `std / |value|`.
    pub rel_std_dev: Vec<f64>,
    /// Correlation matrix (p x p).
    pub correlation: Vec<Vec<f64>>,
    /// Condition number of `D A^T A D` (ratio of extreme eigenvalues); `inf` if singular.
    pub condition_number: f64,
}

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
        let (std_dev, correlation) = match inverse(&rel) {
            Some(inv) => {
                let sd: Vec<f64> = (0..p)
                    .map(|a| (sigma2 * inv[a][a]).max(0.0).sqrt() * values[a].abs())
                    .collect();
                let corr = (0..p)
                    .map(|a| {
                        (0..p)
                            .map(|b| inv[a][b] / (inv[a][a] * inv[b][b]).sqrt())
                            .collect()
                    })
                    .collect();
                (sd, corr)
            }
            None => (vec![f64::NAN; p], vec![vec![f64::NAN; p]; p]),
        };
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
    }
}
