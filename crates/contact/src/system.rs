//! The constrained tangent system shared by the direct solver, the adjoint sweep and the
//! forward sensitivities: `K = sum_g w_g B^T C_g B` on a fixed pattern, with the active
//! contact dofs prescribed, and a cache that skips re-assembly and re-factorization when
//! neither the tangent (linear laws: same parameters and step length) nor the active set
//! changed.

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

    /// Factorizes the constrained tangent unless the cached factorization already is it.
    ///
    /// # Errors
    /// [`FeError::NotPositiveDefinite`] if the constrained tangent is not SPD.
    pub fn factorize(&mut self, model: &Model) -> Result<(), FeError> {
        if self.k_key.is_some() && self.factor_for.as_ref() == Some(&self.constrained) {
            return Ok(());
        }
        let t0 = std::time::Instant::now();
        model
            .pattern
            .constrain(&self.k_values, &self.constrained, &mut self.k_constrained);
        self.factor_for = None;
        self.chol.factorize(&self.k_constrained)?;
        if self.k_key.is_some() {
            self.factor_for = Some(self.constrained.clone());
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
}
