//! Projected Levenberg-Marquardt on the forward-sensitivity Jacobian.
//!
//! Residuals `r_i = sqrt(kappa w_i / J_ref) (F_i - F_i^exp)` so that `f = |r|^2 / 2` is the
//! internal objective of [`crate::optimize`]; Jacobian `A_ik = sqrt(kappa w_i / J_ref)
//! dF_i/dc_k dc_k/dy_k` (scaled variables). Step: `(A^T A + lambda diag(A^T A)) d = -A^T r`
//! (Cholesky, nalgebra), trial `y + d` projected onto the box; accepted if `f` decreases
//! (then `lambda /= 3`), otherwise `lambda *= 4` and retry. Each accepted iterate costs one
//! forward solve and one sensitivity solve; each rejected trial one forward solve.

use crate::IdentifyError;
use nalgebra::{DMatrix, DVector};

use crate::linalg::{from_rows, norm_inf, solve_spd};
use crate::optimize::{GN_MAX_STEP, Monitor};

/// Residuals and scaled Jacobian at `y`: `(f, r, A, grad f)`.
type Linearization = (f64, Vec<f64>, DMatrix<f64>, Vec<f64>);

fn linearize(monitor: &Monitor<'_, '_>, y: &[f64]) -> Result<Linearization, IdentifyError> {
    let o = monitor.objective;
    let p = o.eval.borrow().problem();
    let c = o.param.to_physical(y);
    let forces = o.eval.borrow_mut().forces(&c)?;
    let jac = o.eval.borrow_mut().jacobian(&c)?;
    let s = o.kappa.get() / o.j_ref;
    let np = o.param.n_free();
    let mut r = Vec::new();
    let mut a = Vec::new();
    for i in 0..forces.len() {
        let w = p.weights[i];
        if w == 0.0 {
            continue;
        }
        let sw = (s * w).sqrt();
        r.push(sw * (forces[i] - p.target[i]));
        // the chain rule (dc/dy, zero outside the box) from the parameterization
        let row: Vec<f64> = o.param.scaled_gradient(y, &c, &jac[i]);
        a.push(row.iter().map(|v| sw * v).collect::<Vec<f64>>());
    }
    let f = 0.5 * r.iter().map(|v| v * v).sum::<f64>();
    let a = from_rows(&a, np);
    let g: Vec<f64> = a
        .tr_mul(&DVector::from_column_slice(&r))
        .iter()
        .copied()
        .collect();
    Ok((f, r, a, g))
}

/// The initial inverse Hessian of BFGS with [`crate::optimize::BfgsStart::GaussNewton`] at
/// `y`: `(A^T A + 1e-3 diag(A^T A))^-1` (the matrix of LM's first step; one forward and one
/// sensitivity solve, both cached), symmetrized, and scaled down when the step it gives,
/// `H grad f`, is longer than [`GN_MAX_STEP`] (infinity norm, scaled variables). When the
/// damped matrix is not numerically positive definite the identity is returned (the
/// paper's start).
pub(crate) fn gauss_newton_inverse(
    monitor: &Monitor<'_, '_>,
    y: &[f64],
) -> Result<Vec<Vec<f64>>, IdentifyError> {
    let np = y.len();
    let eye = || -> Vec<Vec<f64>> {
        (0..np)
            .map(|i| (0..np).map(|k| f64::from(u8::from(i == k))).collect())
            .collect()
    };
    let (_, _, a, g) = linearize(monitor, y)?;
    let mut m = a.tr_mul(&a);
    for k in 0..np {
        let d = m[(k, k)];
        m[(k, k)] += 1e-3 * d.max(1e-12 * (1.0 + d));
    }
    let Some(chol) = m.cholesky() else {
        return Ok(eye());
    };
    let inv = chol.inverse();
    let mut h: Vec<Vec<f64>> = (0..np)
        .map(|i| (0..np).map(|k| 0.5 * (inv[(i, k)] + inv[(k, i)])).collect())
        .collect();
    if h.iter().flatten().any(|v| !v.is_finite()) {
        return Ok(eye());
    }
    let step: Vec<f64> = h
        .iter()
        .map(|row| row.iter().zip(&g).map(|(u, v)| u * v).sum())
        .collect();
    let len = norm_inf(&step);
    if len > GN_MAX_STEP && len.is_finite() {
        let s = GN_MAX_STEP / len;
        h.iter_mut().flatten().for_each(|v| *v *= s);
    }
    Ok(h)
}

/// Runs LM from `y0`, reporting each accepted iterate to the monitor.
pub(crate) fn run(monitor: &Monitor<'_, '_>, y0: &[f64]) -> Result<(), IdentifyError> {
    let o = monitor.objective;
    let max_trials = monitor_max_trials(monitor);
    let mut y = o.param.project(y0);
    let (mut f, _, mut a, mut g) = linearize(monitor, &y)?;
    let np = y.len();
    let mut lambda = 1e-3;
    let mut iter = 0usize;
    loop {
        if monitor.iterate(iter, &y, f, &g).is_some() {
            return Ok(());
        }
        let ata = a.tr_mul(&a);
        let ata: Vec<Vec<f64>> = (0..np)
            .map(|i| (0..np).map(|k| ata[(i, k)]).collect())
            .collect();
        let mut accepted = false;
        for _ in 0..max_trials {
            let mut m = ata.clone();
            for k in 0..np {
                m[k][k] += lambda * ata[k][k].max(1e-12 * (1.0 + ata[k][k]));
            }
            let Some(d) = solve_spd(&m, &g) else {
                lambda *= 4.0;
                continue;
            };
            let trial: Vec<f64> = y.iter().zip(&d).map(|(v, dv)| v - dv).collect();
            let trial = o.param.project(&trial);
            let c = o.param.to_physical(&trial);
            let jt = o.eval.borrow_mut().cost(&c)?;
            let ft = o.kappa.get() * jt / o.j_ref;
            if ft < f {
                let (f1, _, a1, g1) = linearize(monitor, &trial)?;
                y = trial;
                f = f1;
                a = a1;
                g = g1;
                lambda = (lambda / 3.0).max(1e-12);
                accepted = true;
                break;
            }
            lambda *= 4.0;
        }
        if !accepted {
            return Err(IdentifyError::Stalled {
                iterations: iter,
                cost: f,
                reason: format!(
                    "Levenberg-Marquardt found no decrease in {max_trials} damped steps (lambda = {lambda:.1e})"
                ),
            });
        }
        iter += 1;
    }
}

fn monitor_max_trials(monitor: &Monitor<'_, '_>) -> usize {
    monitor.stop_criteria().max_line_search_evaluations
}
