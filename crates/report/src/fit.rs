//! Fit quality of a simulated force curve against the measured one.

use serde::{Deserialize, Serialize};

use crate::error::ReportError;

/// Quality of a force fit, all forces in N.
///
/// With residuals `r_i = F_model_i - F_data_i`, `i = 1..n`:
///
/// - `r2 = 1 - sum r_i^2 / sum (F_data_i - mean F_data)^2` (coefficient of determination:
///   1 for a perfect fit, 0 for a model no better than the mean, negative if worse),
/// - `rms = sqrt(sum r_i^2 / n)`,
/// - `rms_rel = rms / max |F_data_i|`,
/// - `max_abs = max |r_i|`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FitQuality {
    /// Coefficient of determination R² of the force.
    pub r2: f64,
    /// Root-mean-square force residual, N.
    pub rms: f64,
    /// RMS residual relative to the largest measured force magnitude (dimensionless).
    pub rms_rel: f64,
    /// Largest absolute force residual, N.
    pub max_abs: f64,
    /// Number of points compared.
    pub n: usize,
}

impl FitQuality {
    /// Fit quality of `f_model` against `f_data` (same length, same time grid).
    ///
    /// # Errors
    /// - [`ReportError::Length`] if the lengths differ,
    /// - [`ReportError::Empty`] if there are no points,
    /// - [`ReportError::NonFinite`] naming the first NaN/infinite value (a non-finite
    ///   model force is a failed simulation, not a point to skip),
    /// - [`ReportError::ConstantData`] if the data are constant (R² undefined).
    pub fn compute(f_data: &[f64], f_model: &[f64]) -> Result<Self, ReportError> {
        if f_model.len() != f_data.len() {
            return Err(ReportError::Length {
                what: "f_model",
                expected: f_data.len(),
                got: f_model.len(),
            });
        }
        let n = f_data.len();
        if n == 0 {
            return Err(ReportError::Empty { what: "f_data" });
        }
        for (what, v) in [("f_data", f_data), ("f_model", f_model)] {
            if let Some((index, &value)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
                return Err(ReportError::NonFinite { what, index, value });
            }
        }
        let mean = f_data.iter().sum::<f64>() / n as f64;
        let ss_tot: f64 = f_data.iter().map(|f| (f - mean) * (f - mean)).sum();
        let f_max = f_data.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
        if !(ss_tot > 0.0) || !(f_max > 0.0) {
            return Err(ReportError::ConstantData { value: f_data[0] });
        }
        let mut ss_res = 0.0;
        let mut max_abs = 0.0_f64;
        for (d, m) in f_data.iter().zip(f_model) {
            let r = m - d;
            ss_res += r * r;
            max_abs = max_abs.max(r.abs());
        }
        let rms = (ss_res / n as f64).sqrt();
        Ok(Self {
            r2: 1.0 - ss_res / ss_tot,
            rms,
            rms_rel: rms / f_max,
            max_abs,
            n,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-14 * (1.0 + b.abs())
    }

    #[test]
    fn perfect_fit_has_r2_one_and_zero_residuals() {
        let f = [0.0, 1.0, 4.0, 9.0];
        let q = FitQuality::compute(&f, &f).unwrap();
        assert_eq!(q.r2, 1.0);
        assert_eq!(q.rms, 0.0);
        assert_eq!(q.rms_rel, 0.0);
        assert_eq!(q.max_abs, 0.0);
        assert_eq!(q.n, 4);
    }

    #[test]
    fn constant_offset() {
        // data 0,1,2,3: mean 1.5, SS_tot = 5; offset 0.5: SS_res = 4 * 0.25 = 1.
        let d = [0.0, 1.0, 2.0, 3.0];
        let m = [0.5, 1.5, 2.5, 3.5];
        let q = FitQuality::compute(&d, &m).unwrap();
        assert!(close(q.r2, 0.8), "{}", q.r2);
        assert!(close(q.rms, 0.5));
        assert!(close(q.rms_rel, 0.5 / 3.0));
        assert!(close(q.max_abs, 0.5));
    }

    #[test]
    fn mean_model_has_r2_zero_and_worse_is_negative() {
        let d = [1.0, 3.0];
        let q = FitQuality::compute(&d, &[2.0, 2.0]).unwrap();
        assert!(close(q.r2, 0.0));
        assert!(close(q.rms, 1.0));
        assert!(close(q.rms_rel, 1.0 / 3.0));
        // Reversed curve: SS_res = 8, SS_tot = 2.
        let q = FitQuality::compute(&d, &[3.0, 1.0]).unwrap();
        assert!(close(q.r2, -3.0));
        assert!(close(q.max_abs, 2.0));
    }

    #[test]
    fn single_outlier_sets_max_abs() {
        let d = [0.0, 10.0, 20.0, 30.0];
        let m = [0.0, 10.0, 23.0, 30.0];
        let q = FitQuality::compute(&d, &m).unwrap();
        assert!(close(q.max_abs, 3.0));
        assert!(close(q.rms, 1.5)); // sqrt(9 / 4)
        assert!(close(q.rms_rel, 0.05));
        assert!(close(q.r2, 1.0 - 9.0 / 500.0));
    }

    #[test]
    fn bad_inputs_are_errors() {
        assert!(matches!(
            FitQuality::compute(&[1.0, 2.0], &[1.0]),
            Err(ReportError::Length { .. })
        ));
        assert!(matches!(
            FitQuality::compute(&[], &[]),
            Err(ReportError::Empty { .. })
        ));
        assert!(matches!(
            FitQuality::compute(&[1.0, 2.0], &[1.0, f64::NAN]),
            Err(ReportError::NonFinite {
                what: "f_model",
                index: 1,
                ..
            })
        ));
        assert!(matches!(
            FitQuality::compute(&[2.0, 2.0], &[1.0, 2.0]),
            Err(ReportError::ConstantData { .. })
        ));
    }
}
