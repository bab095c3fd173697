//! The constrained tangent system shared by the direct solver, the adjoint sweep and the
//! forward sensitivities: `K = sum_g w_g B^T C_g B` on a fixed pattern, with the active
//! contact dofs prescribed, and a cache that skips re-assembly and re-factorization when
//! neither the tangent (linear laws: same parameters and step length) nor the active set
//! changed.
//!
//! Two ways to solve with prescribed dofs `C`:
//!
//! - **direct**: factorize `K` with the rows and columns of `C` replaced by their diagonal
//!   (one factorization per tangent and active set);
//! - **capacitance** (reusable tangents only: linear laws at a fixed step length): factorize
//!   the unconstrained `K` once, keep the columns `z_c = K^-1 e_c` of every dof that has been
//!   prescribed, and impose `x_C = xbar_C` by a multiplier: with `y = K^-1 b` (`b_C = 0`),
//!   `S mu = y_C - xbar_C`, `S = [z_c]_C` (small, dense, SPD), `x = y - sum_c mu_c z_c`. The
//!   contact zone growing by one node then costs one solve instead of one factorization,
//!   and the result is the direct one to round-off.

use std::collections::HashMap;

use indentify_fe::{FeError, SparseCholesky};
use indentify_laws::Mat4;

use crate::direct::Model;

/// `K` with Dirichlet rows/columns on a set of equations, factorized on demand.
#[derive(Debug)]
pub struct ConstrainedSystem {
    chol: SparseCholesky,
    k_values: Vec<f64>,
    k_constrained: Vec<f64>,
    constrained: Vec<bool>,
    scratch: Vec<f64>,
    /// Key of the tangent in `k_values` when it may be reused: (parameter bits, dt).
    k_key: Option<(Vec<u64>, f64)>,
    /// Constrained equations of the current factorization, when it may be reused.
    factor_for: Option<Vec<bool>>,
    /// Capacitance mode: `chol` holds the unconstrained `K` of `k_key`.
    base: bool,
    /// `K^-1 e_c` for the equations `c` prescribed so far (capacitance mode).
    columns: HashMap<usize, Vec<f64>>,
    /// The prescribed equations of `schur` (capacitance mode), increasing.
    schur_set: Vec<usize>,
    /// Dense Cholesky factor (row-major, lower) of `S = [K^-1]_CC` for `schur_set`.
    schur: Vec<f64>,
    /// Whether the last `factorize` chose the capacitance mode.
    capacitance: bool,
    /// Seconds spent assembling, factorizing and solving.
    pub seconds: [f64; 3],
}

impl ConstrainedSystem {
    /// Symbolic analysis of the model's pattern (once).
    ///
    /// # Errors
    /// [`FeError`] if the analysis fails.
    pub fn new(model: &Model) -> Result<ConstrainedSystem, FeError> {
        Ok(ConstrainedSystem {
            chol: SparseCholesky::analyse(&model.pattern)?,
            k_values: vec![0.0; model.pattern.nnz()],
            k_constrained: vec![0.0; model.pattern.nnz()],
            constrained: vec![false; model.dofs.n_eq],
            scratch: vec![0.0; model.dofs.n_eq],
            k_key: None,
            factor_for: None,
            base: false,
            columns: HashMap::new(),
            schur_set: Vec::new(),
            schur: Vec::new(),
            capacitance: false,
            seconds: [0.0; 3],
        })
    }

    /// Numeric factorizations done so far.
    pub fn factorizations(&self) -> usize {
        self.chol.n_factorizations
    }

    /// Unconstrained tangent values (lower-triangle CSC of [`Model::pattern`]).
    pub fn k_values(&self) -> &[f64] {
        &self.k_values
    }

    /// Sets the tangent from per-Gauss-point `tangents`. With `reuse = Some((c, dt))` (a
    /// linear law whose tangent depends only on the parameters and the step length) an
    /// identical key (dt equal to 1e-12 relative: schedule times carry round-off) keeps the
    /// assembled matrix and its factorizations. Returns `true` if it assembled.
    pub fn set_tangent(
        &mut self,
        model: &Model,
        tangents: &[Mat4],
        reuse: Option<(&[f64], f64)>,
    ) -> bool {
        let t0 = std::time::Instant::now();
        let key = reuse.map(|(c, dt)| (c.iter().map(|v| v.to_bits()).collect::<Vec<u64>>(), dt));
        let same = match (&key, &self.k_key) {
            (Some((p, dt)), Some((q, d))) => p == q && (dt - d).abs() <= 1e-12 * dt.abs(),
            _ => false,
        };
        if !same {
            model
                .pattern
                .assemble_b_c_b(&model.disc, tangents, &mut self.k_values);
            self.k_key = key;
            self.factor_for = None;
            self.base = false;
            self.columns.clear();
            self.schur_set.clear();
        }
        self.seconds[0] += t0.elapsed().as_secs_f64();
        !same
    }

    /// Marks the z-dofs of the active candidates as constrained.
    pub fn set_active(&mut self, model: &Model, active: &[bool]) {
        self.constrained.fill(false);
        for (k, _) in active.iter().enumerate().filter(|(_, a)| **a) {
            if let Some(e) = model.dofs.equation(2 * model.candidates[k] + 1) {
                self.constrained[e] = true;
            }
        }
    }

    /// Whether equation `e` is currently constrained.
    pub fn is_constrained(&self, e: usize) -> bool {
        self.constrained[e]
    }

    /// Factorizes the constrained tangent unless the cached factorization already is it
    /// (capacitance mode for reusable tangents with a moderate number of prescribed dofs,
    /// direct mode otherwise; see the module's documentation).
    ///
    /// # Errors
    /// [`FeError::NotPositiveDefinite`] if the constrained tangent is not SPD.
    pub fn factorize(&mut self, model: &Model) -> Result<(), FeError> {
        let n = self.constrained.len();
        let m = self.constrained.iter().filter(|&&c| c).count();
        // capacitance: reusable tangent, and the columns stay a small multiple of K's factor
        let capacitance = self.k_key.is_some() && m <= MAX_CAPACITANCE && m * n <= 20_000_000;
        if capacitance {
            return self.factorize_capacitance(m);
        }
        self.capacitance = false;
        if self.k_key.is_some() && self.factor_for.as_ref() == Some(&self.constrained) {
            return Ok(());
        }
        let t0 = std::time::Instant::now();
        model
            .pattern
            .constrain(&self.k_values, &self.constrained, &mut self.k_constrained);
        self.factor_for = None;
        self.base = false;
        self.columns.clear();
        self.schur_set.clear();
        self.chol.factorize(&self.k_constrained)?;
        if self.k_key.is_some() {
            self.factor_for = Some(self.constrained.clone());
        }
        self.seconds[1] += t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// The capacitance mode: the unconstrained factorization (once per tangent), the
    /// columns of newly prescribed dofs, and the small dense factor of `S`.
    fn factorize_capacitance(&mut self, m: usize) -> Result<(), FeError> {
        let t0 = std::time::Instant::now();
        self.capacitance = true;
        if !self.base {
            self.factor_for = None;
            self.columns.clear();
            self.schur_set.clear();
            self.chol.factorize(&self.k_values)?;
            self.base = true;
        }
        // the same prescribed set as the current factor (no allocation in that common case)
        let same = self.schur_set.len() == m && self.schur_set.iter().all(|&e| self.constrained[e]);
        if !same {
            let set: Vec<usize> = (0..self.constrained.len())
                .filter(|&e| self.constrained[e])
                .collect();
            let n = self.constrained.len();
            for &c in &set {
                if !self.columns.contains_key(&c) {
                    let mut z = vec![0.0; n];
                    z[c] = 1.0;
                    self.chol.solve_in_place(&mut z);
                    self.columns.insert(c, z);
                }
            }
            let mut l = vec![0.0; m * m];
            for (i, &ci) in set.iter().enumerate() {
                for (j, &cj) in set.iter().enumerate().take(i + 1) {
                    // symmetric up to round-off: average the two halves
                    let a = self.columns.get(&cj).map_or(0.0, |z| z[ci]);
                    let b = self.columns.get(&ci).map_or(0.0, |z| z[cj]);
                    l[i * m + j] = 0.5 * (a + b);
                }
            }
            dense_cholesky(&mut l, m).map_err(|k| {
                FeError::NotPositiveDefinite(format!(
                    "the contact capacitance matrix at prescribed equation {}",
                    set[k]
                ))
            })?;
            self.schur = l;
            self.schur_set = set;
        }
        self.seconds[1] += t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// Solves `K x = b` on the unconstrained equations with `x = xbar` on the constrained
    /// ones; `b` (equation vector) is overwritten by `x`; only the constrained entries of
    /// `xbar` are read.
    ///
    /// # Panics
    /// If [`ConstrainedSystem::factorize`] has not succeeded for the current tangent.
    pub fn solve_dirichlet(&mut self, model: &Model, b: &mut [f64], xbar: &[f64]) {
        let t0 = std::time::Instant::now();
        if self.capacitance {
            self.solve_capacitance(b, xbar);
            self.seconds[2] += t0.elapsed().as_secs_f64();
            return;
        }
        let n = b.len();
        let any = self.constrained.iter().any(|&c| c);
        if any {
            for e in 0..n {
                self.scratch[e] = if self.constrained[e] { xbar[e] } else { 0.0 };
            }
            let mut kx = std::mem::take(&mut self.scratch);
            let mut y = vec![0.0; n];
            model.pattern.sym_mul_add(&self.k_values, &kx, &mut y);
            for e in 0..n {
                b[e] = if self.constrained[e] {
                    self.k_constrained[model.pattern.diag[e]] * kx[e]
                } else {
                    b[e] - y[e]
                };
            }
            kx.iter_mut().for_each(|v| *v = 0.0);
            self.scratch = kx;
        }
        self.chol.solve_in_place(b);
        self.seconds[2] += t0.elapsed().as_secs_f64();
    }

    /// `x = K^-1 b - sum_c mu_c z_c` with `S mu = (K^-1 b)_C - xbar_C`, `b_C = 0`.
    fn solve_capacitance(&mut self, b: &mut [f64], xbar: &[f64]) {
        let set = &self.schur_set;
        for &c in set {
            b[c] = 0.0;
        }
        self.chol.solve_in_place(b);
        if set.is_empty() {
            return;
        }
        let m = set.len();
        let mut mu: Vec<f64> = set.iter().map(|&c| b[c] - xbar[c]).collect();
        dense_cholesky_solve(&self.schur, m, &mut mu);
        for (k, &c) in set.iter().enumerate() {
            if let Some(z) = self.columns.get(&c) {
                let f = mu[k];
                for (x, zi) in b.iter_mut().zip(z) {
                    *x -= f * zi;
                }
            }
        }
        for &c in set {
            b[c] = xbar[c];
        }
    }
}

/// Largest number of prescribed dofs handled by the capacitance mode.
const MAX_CAPACITANCE: usize = 256;

/// In-place Cholesky `A = L L^T` of the row-major `m x m` matrix whose lower triangle is
/// given; `Err(k)` at the first non-positive pivot.
fn dense_cholesky(a: &mut [f64], m: usize) -> Result<(), usize> {
    for j in 0..m {
        let mut d = a[j * m + j];
        for k in 0..j {
            d -= a[j * m + k] * a[j * m + k];
        }
        if !(d > 0.0) {
            return Err(j);
        }
        let d = d.sqrt();
        a[j * m + j] = d;
        for i in j + 1..m {
            let mut v = a[i * m + j];
            for k in 0..j {
                v -= a[i * m + k] * a[j * m + k];
            }
            a[i * m + j] = v / d;
        }
    }
    Ok(())
}

/// Solves `L L^T x = b` in place with the factor of [`dense_cholesky`].
fn dense_cholesky_solve(l: &[f64], m: usize, b: &mut [f64]) {
    for i in 0..m {
        let mut v = b[i];
        for k in 0..i {
            v -= l[i * m + k] * b[k];
        }
        b[i] = v / l[i * m + i];
    }
    for i in (0..m).rev() {
        let mut v = b[i];
        for k in i + 1..m {
            v -= l[k * m + i] * b[k];
        }
        b[i] = v / l[i * m + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Punch;
    use indentify_laws::{Elastic, Law, Vec4};
    use indentify_mesh::CylinderMesher;

    /// The capacitance solve equals the direct one to round-off, for growing and shrinking
    /// sets of prescribed dofs, and needs one factorization for all of them.
    #[test]
    fn capacitance_and_direct_solves_agree() {
        let mesh = CylinderMesher {
            radius: 1.0,
            height: 1.0,
            nr: 6,
            nz: 5,
            grading_r: 1.2,
            grading_z: 1.2,
        }
        .build()
        .unwrap();
        let model = Model::new(
            mesh,
            Punch::Cone {
                half_angle_deg: 68.0,
            },
        )
        .unwrap();
        let c = [20000.0, 0.3];
        let t = Elastic.tangent(&c, &Vec4::default(), 1.0).unwrap();
        let tangents = vec![t; model.disc.qp.len()];
        let n = model.dofs.n_eq;
        let b0: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0)
            .collect();
        let xbar: Vec<f64> = (0..n).map(|i| 1e-3 * ((i * 31) % 17) as f64).collect();
        let nc = model.candidates.len();
        let mut reusable = ConstrainedSystem::new(&model).unwrap();
        let mut direct = ConstrainedSystem::new(&model).unwrap();
        for k_active in [0, 1, 3, 4, 2, nc] {
            let active: Vec<bool> = (0..nc).map(|k| k < k_active).collect();
            reusable.set_tangent(&model, &tangents, Some((&c, 1.0)));
            reusable.set_active(&model, &active);
            reusable.factorize(&model).unwrap();
            direct.set_tangent(&model, &tangents, None);
            direct.set_active(&model, &active);
            direct.factorize(&model).unwrap();
            let (mut x1, mut x2) = (b0.clone(), b0.clone());
            reusable.solve_dirichlet(&model, &mut x1, &xbar);
            direct.solve_dirichlet(&model, &mut x2, &xbar);
            let scale = x2.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for e in 0..n {
                assert!(
                    (x1[e] - x2[e]).abs() <= 1e-10 * scale,
                    "{k_active} active: x[{e}] {} vs {}",
                    x1[e],
                    x2[e]
                );
                if direct.is_constrained(e) {
                    assert_eq!(x1[e], xbar[e]);
                }
            }
        }
        assert!(reusable.capacitance);
        assert_eq!(reusable.factorizations(), 1);
        assert_eq!(direct.factorizations(), 6);
    }
}
