//! Levenberg-Marquardt steps in the determined subspace while a parameter is undetermined
//! ([`crate::LmStrategy::subspace`], [`crate::StopReason::SubspaceBelowSigma`]).
//!
//! Where the identifiability summary at an iterate says `n_u` parameters are undetermined,
//! the damped step `(A^T A + lambda D) d = -A^T r` is solved in the subspace orthogonal to
//! the right singular vectors of the `n_u` smallest singular values of the scaled
//! sensitivity matrix (`d = Q z`, `(Q^T (A^T A + lambda D) Q) z = -Q^T A^T r`, `Q` the
//! other right singular vectors): at `lambda = 0` the truncated-SVD (minimum-norm)
//! Gauss-Newton step, the standard regularization of an ill-posed least-squares problem.
//! The fit no longer walks the flat direction; where it ends along the valley is set by the
//! start and the determined directions. The decision is taken again at every iterate:
//! where every parameter is determined, full steps; and where the Gauss-Newton model
//! predicts that the flat directions alone would lower the chi-square `2 J / sigma^2` by
//! [`FLAT_CHI2`] or more (the point lies outside the 2-sigma profile region along them: a
//! plateau far from the optimum, not a valley), full steps too, so that a parameter
//! undetermined far from the optimum is not frozen there.
//!
//! The run then ends by the statistical stop on the determined combinations
//! ([`determined_steps_below`]): the last step and the next truncated Gauss-Newton step move
//! every determined combination (the step projected off the undetermined directions, each
//! determined parameter over its conditional deviation, as `crate::valley_stop` measures)
//! by less than `step_sigma` of its deviation. The outcome stays undetermined (the summary
//! and the intervals are those at the end point). Measured in docs/performance.md ("Steps
//! in the determined subspace"); off by default.

use crate::identifiability::{Column, Identifiability, RANK_TOL};
use crate::linalg::solve_spd;
use crate::valley_stop::determined_move;

/// The chi-square decrease the Gauss-Newton model may predict along the undetermined
/// directions for the steps to stay off them: 4, the chi-square of two deviations (the
/// summary's intervals are 2-sigma ones), so the iterate lies inside the profile region
/// the intervals report along those directions.
pub const FLAT_CHI2: f64 = 4.0;

/// `S^T r` for `S_ik = sqrt(w_i) dF_i/dc_k dc_k/dy_k` and `r_i = sqrt(w_i) (F_i - F_i^exp)`
/// (physical Jacobian `jac`, one row per datum), in the order of `columns`.
pub(crate) fn scaled_gradient(
    jac: &[Vec<f64>],
    forces: &[f64],
    (weights, target): (&[f64], &[f64]),
    columns: &[Column],
) -> Vec<f64> {
    let mut g = vec![0.0; columns.len()];
    for ((row, w), (f, d)) in jac.iter().zip(weights).zip(forces.iter().zip(target)) {
        if *w <= 0.0 {
            continue;
        }
        let r = w * (f - d);
        for (gk, col) in g.iter_mut().zip(columns) {
            *gk += r * row[col.index] * col.dc_dy;
        }
    }
    g
}

/// The number of undetermined directions of `id` when they can serve: at least one
/// undetermined parameter, fewer than all, and a right singular vector for each parameter.
fn flat_count(id: &Identifiability) -> Option<usize> {
    let n = id.names.len();
    let n_u = id.undetermined.len();
    (n_u > 0 && n_u < n && id.directions.len() == n && id.singular_values.len() == n).then_some(n_u)
}

/// The chi-square decrease `sum_j (v_j . g)^2 / s_j^2 / var` the Gauss-Newton model
/// predicts along the `n_u` weakest right singular directions of `id` (those numerically
/// null skipped), with `g = S^T r` in `id`'s scaling ([`scaled_gradient`]) and `var` the
/// noise variance. `None` where it cannot be computed.
pub(crate) fn flat_chi2(id: &Identifiability, g: &[f64], var: f64) -> Option<f64> {
    let n_u = flat_count(id)?;
    let n = id.names.len();
    let s_max = id.singular_values.first().copied()?;
    if !(s_max > 0.0 && s_max.is_finite() && var > 0.0 && var.is_finite()) || g.len() != n {
        return None;
    }
    let mut sum = 0.0;
    for j in n - n_u..n {
        let s = id.singular_values[j];
        if s <= RANK_TOL * s_max {
            continue;
        }
        let vg: f64 = id.directions[j].iter().zip(g).map(|(a, b)| a * b).sum();
        sum += (vg / s) * (vg / s);
    }
    let out = sum / var;
    out.is_finite().then_some(out)
}

/// The basis of the determined subspace at an iterate with summary `id` (the right
/// singular vectors of the `n - n_u` largest singular values, orthonormal, over the free
/// parameters' scaled variables), or `None` for full steps: every parameter determined,
/// all undetermined, or the flat directions' predicted chi-square decrease ([`flat_chi2`],
/// `g` and `var` as there) not below [`FLAT_CHI2`] or not computable.
pub(crate) fn determined_basis(id: &Identifiability, g: &[f64], var: f64) -> Option<Vec<Vec<f64>>> {
    let n_u = flat_count(id)?;
    let n = id.names.len();
    flat_chi2(id, g, var).filter(|c| *c < FLAT_CHI2)?;
    Some(id.directions[..n - n_u].to_vec())
}

/// The damped step restricted to the span of `basis` (rows: orthonormal vectors over the
/// scaled variables): `d = Q z` with `(Q^T M Q) z = Q^T g`, `M = ata + lambda diag(ata)`
/// (the diagonal floored as LM's solve does). `None` when the restricted matrix is not
/// numerically positive definite.
pub(crate) fn restricted_solve(
    ata: &[Vec<f64>],
    lambda: f64,
    g: &[f64],
    basis: &[Vec<f64>],
) -> Option<Vec<f64>> {
    let n = g.len();
    let m = basis.len();
    // M Q, column by column
    let mq: Vec<Vec<f64>> = basis
        .iter()
        .map(|q| {
            (0..n)
                .map(|i| {
                    let off: f64 = (0..n).map(|k| ata[i][k] * q[k]).sum();
                    off + lambda * ata[i][i].max(1e-12 * (1.0 + ata[i][i])) * q[i]
                })
                .collect()
        })
        .collect();
    let reduced: Vec<Vec<f64>> = (0..m)
        .map(|a| {
            (0..m)
                .map(|b| basis[a].iter().zip(&mq[b]).map(|(x, y)| x * y).sum())
                .collect()
        })
        .collect();
    let rhs: Vec<f64> = basis
        .iter()
        .map(|q| q.iter().zip(g).map(|(x, y)| x * y).sum())
        .collect();
    let z = solve_spd(&reduced, &rhs)?;
    let d: Vec<f64> = (0..n)
        .map(|i| basis.iter().zip(&z).map(|(q, zj)| q[i] * zj).sum())
        .collect();
    d.iter().all(|v| v.is_finite()).then_some(d)
}

/// Whether the step from `prev` to `c` (physical values of the free parameters, in `id`'s
/// order; no such test without `prev`) and the truncated Gauss-Newton step from `c`,
/// `dy = -sum_j v_j (v_j . g) / s_j^2` over the determined directions (`g` as in
/// [`flat_chi2`]) and projected onto the bounds of `columns`, move every determined
/// combination by less than `fraction` of its conditional deviation
/// ([`crate::valley_stop`]'s measure). A determined parameter on a bound that the step
/// pushes out by `fraction` of its deviation or more is not called converged (as
/// `step_sigma`). False where anything cannot be computed.
pub(crate) fn determined_steps_below(
    id: &Identifiability,
    columns: &[Column],
    g: &[f64],
    fraction: f64,
    prev: Option<&[f64]>,
    c: &[f64],
) -> bool {
    let Some(n_u) = flat_count(id) else {
        return false;
    };
    let n = id.names.len();
    if columns.len() != n || c.len() != n || g.len() != n {
        return false;
    }
    let mut dy = vec![0.0; n];
    for j in 0..n - n_u {
        let s = id.singular_values[j];
        if !(s > 0.0 && s.is_finite()) {
            return false;
        }
        let v = &id.directions[j];
        let a: f64 = v.iter().zip(g).map(|(x, y)| x * y).sum::<f64>() / (s * s);
        for (d, x) in dy.iter_mut().zip(v) {
            *d -= a * x;
        }
    }
    let mut next = c.to_vec();
    for k in 0..n {
        let col = &columns[k];
        let raw = dy[k] * col.dc_dy;
        next[k] = (c[k] + raw).clamp(col.lower, col.upper);
        let at_bound = next[k] == col.lower || next[k] == col.upper;
        if at_bound && !id.undetermined.contains(&id.names[k]) {
            let sd = id.std_dev[k];
            if !(sd.is_finite() && sd > 0.0) || raw.abs() >= fraction * sd {
                return false;
            }
        }
    }
    let ahead = determined_move(id, c, &next).is_some_and(|m| m < fraction);
    let last = prev.is_none_or(|p| determined_move(id, p, c).is_some_and(|m| m < fraction));
    ahead && last
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::NoiseModel;
    use crate::params::Scaling;

    fn columns(n: usize) -> Vec<Column> {
        (0..n)
            .map(|index| Column {
                index,
                name: ["a", "b", "c"][index],
                scaling: Scaling::Linear,
                dc_dy: 1.0,
                lower: f64::NEG_INFINITY,
                upper: f64::INFINITY,
            })
            .collect()
    }

    /// The restricted solve at `lambda = 0` on a basis of the leading right singular
    /// vectors is the truncated-SVD step: orthogonal to the dropped direction, and the
    /// same as the pseudo-inverse formula `sum_j v_j (v_j . g) / s_j^2` computed from the
    /// eigenvectors of a diagonal `A^T A` (a reference that shares no code with it).
    #[test]
    fn restricted_solve_is_the_truncated_svd_step() {
        // A^T A = diag(4, 1, 1e-10) rotated by a known orthonormal matrix R
        let c = 0.6;
        let s = 0.8;
        let r = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
        let eig = [4.0, 1.0, 1e-10];
        let ata: Vec<Vec<f64>> = (0..3)
            .map(|i| {
                (0..3)
                    .map(|k| (0..3).map(|j| r[i][j] * eig[j] * r[k][j]).sum())
                    .collect()
            })
            .collect();
        let g = vec![1.0, -2.0, 3.0];
        // eigenvectors: the columns of R
        let v: Vec<Vec<f64>> = (0..3).map(|j| (0..3).map(|i| r[i][j]).collect()).collect();
        let d = restricted_solve(&ata, 0.0, &g, &v[..2]).expect("positive definite");
        let mut want = [0.0; 3];
        for j in 0..2 {
            let vg: f64 = v[j].iter().zip(&g).map(|(a, b)| a * b).sum();
            for i in 0..3 {
                want[i] += v[j][i] * vg / eig[j];
            }
        }
        for i in 0..3 {
            assert!((d[i] - want[i]).abs() < 1e-12, "{d:?} {want:?}");
        }
        let along: f64 = v[2].iter().zip(&d).map(|(a, b)| a * b).sum();
        assert!(along.abs() < 1e-14, "{along}");
        // the whole basis at lambda = 0 solves the full system
        let full = restricted_solve(&ata, 0.0, &g, &v).expect("positive definite");
        for i in 0..3 {
            let lhs: f64 = (0..3).map(|k| ata[i][k] * full[k]).sum();
            assert!((lhs - g[i]).abs() < 1e-9, "{lhs} {}", g[i]);
        }
    }

    /// Residuals `x_i a + eps x_i^2 b - d_i`: with `eps` tiny, `b` is undetermined and the
    /// determined basis is the one direction along `a`; with `eps = 1` every parameter is
    /// determined and there is no basis (full steps).
    #[test]
    fn basis_only_where_a_parameter_is_undetermined() {
        let xs: Vec<f64> = (0..20).map(|i| 0.1 + f64::from(i) * 0.05).collect();
        let d: Vec<f64> = xs
            .iter()
            .enumerate()
            .map(|(i, x)| 2.0 * x + 0.01 * (f64::from(i as u32) * 1.7).sin())
            .collect();
        for (eps, flat) in [(1e-9, true), (1.0, false)] {
            let jac: Vec<Vec<f64>> = xs.iter().map(|x| vec![*x, eps * x * x]).collect();
            let forces: Vec<f64> = xs.iter().map(|x| x * 2.0 + eps * x * x).collect();
            let w = vec![1.0; xs.len()];
            let j: f64 = forces
                .iter()
                .zip(&d)
                .map(|(f, d)| 0.5 * (f - d) * (f - d))
                .sum();
            let cols = columns(2);
            let id = Identifiability::with_noise(
                &jac,
                &w,
                j,
                &[2.0, 1.0],
                &cols,
                NoiseModel::Residual,
                None,
            );
            let g = scaled_gradient(&jac, &forces, (&w, &d), &cols);
            let basis = determined_basis(&id, &g, id.sigma2);
            assert_eq!(basis.is_some(), flat, "eps {eps}: {:?}", id.undetermined);
            if let Some(b) = basis {
                assert_eq!(b.len(), 1);
                assert!((b[0][0].abs() - 1.0).abs() < 1e-6, "{b:?}");
            }
        }
    }
}
