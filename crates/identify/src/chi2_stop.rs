//! The statistical stop of a Levenberg-Marquardt fit whose data leave a parameter
//! undetermined ([`crate::StopReason::Chi2BelowSigma`]): the chi-square the fit could
//! still gain, by the Gauss-Newton model, measured in noise variances.
//!
//! With every parameter determined, [`crate::StopCriteria::step_sigma`] stops when the
//! steps are below a fraction `f` of every deviation. With one undetermined that rule does
//! not apply (the others' deviations are conditional on it, and a valley moves them
//! together), and the run used to crawl along the valley until the relative decrease fell
//! below `1e-10`. This rule stops it when both the last accepted step and the undamped
//! Gauss-Newton step from the new iterate change the fit's chi-square,
//! `chi2 = 2 J / sigma^2`, by less than `f^2`: the decrease the linearized model predicts
//! for the Gauss-Newton step (the minimum-norm one, over every direction the data see,
//! however weakly, and ignoring the bounds, so never less than any step the model allows)
//! is `|P r|^2 / sigma^2`, with `P` the projection onto the columns of the scaled
//! sensitivity matrix `S`. A determined parameter whose profile is quadratic moves by
//! `delta` of its deviation for a chi-square change of `delta^2`, so `f^2 = 0.01` is the
//! chi-square of a tenth of a deviation. The model can under-predict the decrease along
//! a curved valley: what this did to the determined parameters of the real records is
//! measured in docs/performance.md ("Free-only sensitivities and a chi-square stop").

use crate::identifiability::{Column, Identifiability, RANK_TOL};

/// The chi-square decrease `|P r|^2 / sigma^2` the undamped (minimum-norm) Gauss-Newton
/// step from a point with forces `forces` and Jacobian `jac` (physical, one row per datum;
/// data `target` with weights `weights`) predicts, in the scaled variables of `columns`, with `id` the identifiability summary
/// there (its singular values and right singular vectors of `S`). `sigma^2` is the noise
/// model's mean weighted variance (`2 J / (n - p)` for the residual model). `None` when
/// the variance or the singular values cannot serve.
pub(crate) fn predicted_chi2_decrease(
    jac: &[Vec<f64>],
    forces: &[f64],
    (weights, target): (&[f64], &[f64]),
    columns: &[Column],
    id: &Identifiability,
) -> Option<f64> {
    let var = noise_variance(id)?;
    let g = crate::subspace::scaled_gradient(jac, forces, (weights, target), columns);
    let s_max = id.singular_values.first().copied()?;
    if !(s_max > 0.0 && s_max.is_finite()) {
        return None;
    }
    // |P r|^2 = sum_j (u_j . r)^2 = sum_j (v_j . S^T r)^2 / s_j^2 over the numerical range
    let mut pr2 = 0.0;
    for (s, v) in id.singular_values.iter().zip(&id.directions) {
        if *s <= RANK_TOL * s_max {
            continue;
        }
        let vg: f64 = v.iter().zip(&g).map(|(a, b)| a * b).sum();
        pr2 += (vg / s) * (vg / s);
    }
    let out = pr2 / var;
    out.is_finite().then_some(out)
}

/// The noise variance the chi-square is measured in: the mean weighted variance the
/// summary gives an undetermined parameter's profile ([`Identifiability::profile_variance`],
/// `sigma^2 = 2 J / (n - p)` under the residual model), else `sigma^2`.
pub(crate) fn noise_variance(id: &Identifiability) -> Option<f64> {
    let undetermined = id
        .undetermined
        .iter()
        .filter_map(|n| id.names.iter().position(|m| m == n))
        .filter_map(|k| id.profile_variance.get(k).copied())
        .find(|v| v.is_finite() && *v > 0.0);
    undetermined
        .or(Some(id.sigma2))
        .filter(|v| v.is_finite() && *v > 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::NoiseModel;
    use crate::params::Scaling;

    fn column(index: usize) -> Column {
        Column {
            index,
            name: ["a", "b", "c"][index],
            scaling: Scaling::Linear,
            dc_dy: 1.0,
            lower: f64::NEG_INFINITY,
            upper: f64::INFINITY,
        }
    }

    /// `J = 1/2 sum w (M c - d)^2` and its minimum over the span of `basis` columns of `M`
    /// (normal equations of the basis, solved by Cramer's rule: a reference that shares
    /// no code with the SVD above).
    fn cost(m: &[[f64; 3]], w: &[f64], d: &[f64], c: &[f64; 3]) -> f64 {
        m.iter()
            .zip(w)
            .zip(d)
            .map(|((row, w), d)| {
                let f: f64 = row.iter().zip(c).map(|(a, b)| a * b).sum();
                0.5 * w * (f - d) * (f - d)
            })
            .sum()
    }

    fn min_cost_2(m: &[[f64; 3]], w: &[f64], d: &[f64], basis: [usize; 2]) -> f64 {
        let (i, j) = (basis[0], basis[1]);
        let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for ((row, w), d) in m.iter().zip(w).zip(d) {
            a11 += w * row[i] * row[i];
            a12 += w * row[i] * row[j];
            a22 += w * row[j] * row[j];
            b1 += w * row[i] * d;
            b2 += w * row[j] * d;
        }
        let det = a11 * a22 - a12 * a12;
        let x = (b1 * a22 - a12 * b2) / det;
        let y = (a11 * b2 - a12 * b1) / det;
        let mut c = [0.0; 3];
        c[i] = x;
        c[j] = y;
        cost(m, w, d, &c)
    }

    /// For linear residuals the Gauss-Newton step reaches the least-squares minimum: the
    /// predicted chi-square decrease times `sigma^2` is `2 (J(c) - J_min)`, also when a
    /// column repeats another (a parameter the data cannot tell from another, the
    /// minimum-norm step), where the minimum is that over the two independent columns.
    #[test]
    fn predicted_decrease_is_the_least_squares_decrease_for_linear_residuals() {
        let base: Vec<[f64; 2]> = (0..9)
            .map(|i| {
                let t = f64::from(i) / 8.0;
                [1.0 + t, t * t - 0.3 * t]
            })
            .collect();
        let d: Vec<f64> = (0..9).map(|i| (f64::from(i) * 0.7).sin() + 0.2).collect();
        let w: Vec<f64> = (0..9).map(|i| 1.0 + 0.25 * f64::from(i % 3)).collect();
        let c = [0.4, -0.8, 0.3];
        for repeated in [false, true] {
            // the third column: independent, or the first again
            let m: Vec<[f64; 3]> = base
                .iter()
                .enumerate()
                .map(|(i, r)| {
                    let third = if repeated {
                        r[0]
                    } else {
                        (f64::from(i as u32) * 0.37).cos()
                    };
                    [r[0], r[1], third]
                })
                .collect();
            let jac: Vec<Vec<f64>> = m.iter().map(|r| r.to_vec()).collect();
            let forces: Vec<f64> = m
                .iter()
                .map(|r| r.iter().zip(&c).map(|(a, b)| a * b).sum())
                .collect();
            let columns: Vec<Column> = (0..3).map(column).collect();
            let j = cost(&m, &w, &d, &c);
            let id =
                Identifiability::with_noise(&jac, &w, j, &c, &columns, NoiseModel::Residual, None);
            if repeated {
                assert!(
                    !id.undetermined.is_empty(),
                    "a repeated column is undetermined"
                );
            }
            let var = noise_variance(&id).unwrap();
            assert!((var - 2.0 * j / 6.0).abs() < 1e-14 * var);
            let pred =
                predicted_chi2_decrease(&jac, &forces, (&w, &d), &columns, &id).unwrap() * var;
            let j_min = if repeated {
                min_cost_2(&m, &w, &d, [0, 1])
            } else {
                // three independent columns: the weighted normal equations (Cholesky)
                let ata: Vec<Vec<f64>> = (0..3)
                    .map(|a| {
                        (0..3)
                            .map(|b| m.iter().zip(&w).map(|(r, w)| w * r[a] * r[b]).sum())
                            .collect()
                    })
                    .collect();
                let atb: Vec<f64> = (0..3)
                    .map(|a| {
                        m.iter()
                            .zip(&w)
                            .zip(&d)
                            .map(|((r, w), d)| w * r[a] * d)
                            .sum()
                    })
                    .collect();
                let x = crate::linalg::solve_spd(&ata, &atb).unwrap();
                cost(&m, &w, &d, &[x[0], x[1], x[2]])
            };
            let want = 2.0 * (j - j_min);
            assert!(
                (pred - want).abs() < 1e-10 * want.max(1e-300),
                "repeated {repeated}: {pred} vs {want}"
            );
        }
    }
}
