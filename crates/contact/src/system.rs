//! The constrained tangent system shared by the direct solver, the adjoint sweep and the
//! forward sensitivities (these two through [`crate::RecordedContact`]; the solve modes
//! are private to this crate): `K = sum_g w_g B^T C_g B` on a fixed pattern, with the active
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
//!
//! Normal contact ([`crate::ContactKind::Normal`], `ConstrainedSystem::set_frames`):
//! the two dofs of an active node are rotated into the surface frame `(t, m)` (the same
//! pattern: both dofs of a node share their structure), `K~ = Q^T K Q + D` with the
//! curvature stiffness `D` on the tangential dof; the normal dof (in the `u_z` slot) is
//! the prescribed one, the tangential dof (in the `u_r` slot) stays free. Callers pass
//! and receive physical vectors: right-hand sides are rotated in and solutions out here;
//! `xbar` at the `u_z` equation of an active node is the prescribed `m . x`. The
//! capacitance mode then imposes the frames through a small dense LU system on the
//! columns `K^-1 e` of both dofs of the active nodes (the direct mode refactorizes when
//! a frame changes).

use std::collections::HashMap;

use indentify_fe::{ElementCache, FeError, Pattern, SolveScratch, SparseCholesky};
use indentify_laws::Mat4;

use crate::model::Model;
use crate::refresh::{PcgEvent, Refresh, RefreshRule};

/// `K` with Dirichlet rows/columns on a set of equations, factorized on demand.
#[derive(Debug)]
pub struct ConstrainedSystem {
    chol: SparseCholesky,
    k_values: Vec<f64>,
    k_constrained: Vec<f64>,
    /// Element matrices of the last per-point assembly, reused where tangents are unchanged.
    elements: ElementCache,
    constrained: Vec<bool>,
    /// Key of the tangent in `k_values` when it may be reused: (parameter bits, dt).
    k_key: Option<(Vec<u64>, f64)>,
    /// The one tangent of `k_key` when it was set uniform (an affine law): part of the
    /// key, so that a factorization handed from another system
    /// ([`ConstrainedSystem::exchange_factor`]) is reused only for the same matrix.
    k_tangent: Option<Mat4>,
    /// The next key comparison is exact (a uniform tangent's bits): a direct solver's
    /// first tangent after a factorization was handed over, so that it uses a handed
    /// factor only where it would have assembled the same `K` bit for bit.
    exact_next: bool,
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
    /// `chol` holds a valid factorization (possibly of an earlier matrix).
    factor_ok: bool,
    /// The next inexact solve runs preconditioned CG on `k_constrained` with `chol` (an
    /// earlier tangent's factor) instead of factorizing it.
    pcg: bool,
    /// When the factor is refreshed (`refresh.rs`).
    refresh: Refresh,
    /// PCG work vectors: r, z, p, q and a copy of the right-hand side.
    work: [Vec<f64>; 5],
    /// The last inexact solve ended in CG (its residual is `work[0]`), not in a direct
    /// solve (whose residual is round-off).
    cg_residual: bool,
    /// Preconditioned CG iterations.
    pub pcg_iterations: usize,
    /// Preconditioned CG solves (each Newton solve of a nonlinear law that did not
    /// factorize first, and load control's depth columns solved with the same factor).
    pub pcg_solves: usize,
    /// Solves where PCG did not converge in time and the matrix was factorized instead.
    pub pcg_fallbacks: usize,
    /// Seconds spent assembling, factorizing and solving.
    pub seconds: [f64; 3],
    /// Frames of the active nodes under normal contact (empty: vertical contact).
    frames: Vec<NodeFrame>,
    /// `Q^T K Q + D` (unconstrained, rotated) when `frames` is not empty.
    k_rot: Vec<f64>,
    /// The frames the direct factorization was formed with.
    frames_factored: Vec<NodeFrame>,
    /// Capacitance mode with frames: the frames, the LU factor (row-major) and pivots of
    /// the small system, and its unknowns' count.
    cap_frames: Option<Vec<NodeFrame>>,
    cap_lu: Vec<f64>,
    cap_piv: Vec<usize>,
    /// Friction's Woodbury correction for the factor in `chol` (direct mode): the slipping
    /// frames' indices, the columns `z_l = S^-1 e_t,l`, and the LU factor of
    /// `I + [w_k . z_l]`.
    slip_idx: Vec<usize>,
    slip_z: Vec<Vec<f64>>,
    slip_lu: Vec<f64>,
    slip_piv: Vec<usize>,
    /// The work space of this system's own solves.
    scratch: SolveScratch,
    /// Load control's multipliers `S^-1 1` of the capacitance depth column (work space).
    depth_mu: Vec<f64>,
    /// The bordered transposed solve's multipliers `S^-1 y_C` (work space).
    bordered_nu: Vec<f64>,
}

/// The local frame of an active node under normal contact: its equations, the unit
/// tangent `t` and upward normal `m` of the punch surface at its closest point (physical
/// `(r, z)` components), and the curvature stiffness `d` on its tangential dof (N/mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeFrame {
    /// Equation of `u_r` (`None` on the axis, where the frame is vertical).
    pub er: Option<usize>,
    /// Equation of `u_z` (the slot of the prescribed normal dof).
    pub ez: usize,
    /// Unit tangent `(t_r, t_z)`.
    pub t: [f64; 2],
    /// Unit normal `(m_r, m_z)`, `m = (-t_z, t_r)`.
    pub m: [f64; 2],
    /// Stiffness added on the tangential dof (`-lambda kappa / (1 + g kappa)`; with a
    /// slipping node under friction `kappa (-lambda + mu sigma tau) / (1 + g kappa)`).
    pub d: f64,
    /// Coulomb friction, sticking: the tangential dof is prescribed as well (`xbar` at the
    /// `u_r` equation is the prescribed `t . x`).
    pub stick: bool,
    /// Coulomb friction, slipping: the coefficient `c = -mu sigma` of the tangential
    /// equation `(t + c m) . (K x - b) + d t . x = 0` (`sigma` = +-1 the slip direction
    /// along `t`); 0 without friction. It makes the matrix unsymmetric: solved by the
    /// symmetric factor and a Woodbury correction of rank the number of slipping nodes.
    pub slip: f64,
}

impl ConstrainedSystem {
    /// Symbolic analysis of the model's pattern (once).
    ///
    /// # Errors
    /// [`FeError`] if the analysis fails.
    pub(crate) fn new(model: &Model) -> Result<ConstrainedSystem, FeError> {
        Ok(ConstrainedSystem {
            chol: SparseCholesky::analyse(&model.pattern)?,
            k_values: vec![0.0; model.pattern.nnz()],
            k_constrained: vec![0.0; model.pattern.nnz()],
            elements: ElementCache::default(),
            constrained: vec![false; model.dofs.n_eq],
            k_key: None,
            k_tangent: None,
            exact_next: false,
            factor_for: None,
            base: false,
            columns: HashMap::new(),
            schur_set: Vec::new(),
            schur: Vec::new(),
            capacitance: false,
            factor_ok: false,
            pcg: false,
            refresh: Refresh::default(),
            work: std::array::from_fn(|_| vec![0.0; model.dofs.n_eq]),
            cg_residual: false,
            pcg_iterations: 0,
            pcg_solves: 0,
            pcg_fallbacks: 0,
            seconds: [0.0; 3],
            frames: Vec::new(),
            k_rot: Vec::new(),
            frames_factored: Vec::new(),
            cap_frames: None,
            cap_lu: Vec::new(),
            cap_piv: Vec::new(),
            slip_idx: Vec::new(),
            slip_z: Vec::new(),
            slip_lu: Vec::new(),
            slip_piv: Vec::new(),
            scratch: SolveScratch::default(),
            depth_mu: Vec::new(),
            bordered_nu: Vec::new(),
        })
    }

    /// The rule that decides when the inexact solves refresh their factor (`refresh.rs`).
    pub fn refresh_rule(&self) -> RefreshRule {
        self.refresh.rule
    }

    /// Sets the refresh rule of the inexact solves (from the next run on).
    pub fn set_refresh_rule(&mut self, rule: RefreshRule) {
        self.refresh.rule = rule;
    }

    /// Keeps (or stops keeping) a log of every preconditioned CG solve, for the counts of
    /// docs/performance.md; the log starts empty.
    pub fn keep_pcg_log(&mut self, keep: bool) {
        self.refresh.log = keep.then(Vec::new);
    }

    /// The log of the preconditioned CG solves since [`ConstrainedSystem::keep_pcg_log`]
    /// (empty when not kept).
    pub fn pcg_log(&self) -> &[PcgEvent] {
        self.refresh.log.as_deref().unwrap_or(&[])
    }

    /// A run begins: resolves [`RefreshRule::Auto`] for a stress-only law (`law`) or
    /// another material.
    pub(crate) fn begin_run(&mut self, law: bool) {
        self.refresh.begin_run(law);
    }

    /// A time step begins: its first Newton solve comes next; `load`: the step
    /// prescribes the force (or the depth through the frame's spring).
    pub(crate) fn begin_step(&mut self, load: bool) {
        self.refresh.begin_step(load);
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
    /// assembled matrix and its factorizations. Otherwise only the elements whose tangents
    /// changed are re-formed and their differences added (`fe::Pattern::assemble_b_c_b_delta`;
    /// [`ConstrainedSystem::forget_preconditioner`] restarts from a full sum). Returns `true`
    /// if it assembled.
    pub(crate) fn set_tangent(
        &mut self,
        model: &Model,
        tangents: &[Mat4],
        reuse: Option<(&[f64], f64)>,
    ) -> bool {
        let t0 = std::time::Instant::now();
        let fresh = self.new_key(reuse, None);
        if fresh && reuse.is_some() {
            // a new key changes every element: a full sum, which the next delta restarts from
            model.pattern.assemble_b_c_b_cached(
                &model.disc,
                tangents,
                &mut self.elements,
                &mut self.k_values,
            );
        } else if fresh {
            model.pattern.assemble_b_c_b_delta(
                &model.disc,
                tangents,
                &mut self.elements,
                &mut self.k_values,
            );
        }
        self.seconds[0] += t0.elapsed().as_secs_f64();
        fresh
    }

    /// Sets the tangent from element matrices (lower triangles; finite strain, where the
    /// element matrices are not `sum w B^T C B`): never reused, always a full sum.
    pub(crate) fn set_tangent_elements(&mut self, model: &Model, ke: &[[[f64; 16]; 16]]) -> bool {
        let t0 = std::time::Instant::now();
        self.new_key(None, None);
        model.pattern.assemble_elements(ke, &mut self.k_values);
        self.elements.forget_sum();
        self.seconds[0] += t0.elapsed().as_secs_f64();
        true
    }

    /// As [`ConstrainedSystem::set_tangent`] with the same tangent `c_mat` at every Gauss
    /// point (an affine law), always reusable under `key = (c, dt)`.
    pub(crate) fn set_tangent_uniform(
        &mut self,
        model: &Model,
        c_mat: &Mat4,
        key: (&[f64], f64),
    ) -> bool {
        let t0 = std::time::Instant::now();
        let fresh = self.new_key(Some(key), Some(c_mat));
        if fresh {
            model
                .pattern
                .assemble_b_c_b_uniform(&model.disc, c_mat, &mut self.k_values);
            self.elements.forget_sum();
        }
        self.seconds[0] += t0.elapsed().as_secs_f64();
        fresh
    }

    /// Whether the tangent keyed `reuse` must be assembled (always for `None`; for a key,
    /// unless it is the current one: parameters bit for bit, dt to 1e-12 relative, since
    /// schedule times carry round-off, and a uniform tangent `uniform` to 1e-12 of its
    /// largest entry, or neither uniform); a new tangent drops the cached factorizations.
    ///
    /// Right after a factorization was handed over to a direct solver (`exact_next`),
    /// only a uniform tangent equal bit for bit keeps it: the same `K` the solver would
    /// assemble, so a forward run's bits do not depend on the handover. (An adjoint keeps
    /// a handed factor under the usual tolerance: the forward's own `K` for the steps
    /// under its key.)
    fn new_key(&mut self, reuse: Option<(&[f64], f64)>, uniform: Option<&Mat4>) -> bool {
        let exact = std::mem::take(&mut self.exact_next);
        let same_tangent = match (uniform, &self.k_tangent) {
            (None, None) => !exact,
            (Some(a), Some(b)) if exact => (a.0.iter().flatten())
                .zip(b.0.iter().flatten())
                .all(|(x, y)| x.to_bits() == y.to_bits()),
            (Some(a), Some(b)) => {
                let scale = a.0.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
                (a.0.iter().flatten())
                    .zip(b.0.iter().flatten())
                    .all(|(x, y)| (x - y).abs() <= 1e-12 * scale)
            }
            _ => false,
        };
        let same = same_tangent
            && match (reuse, &self.k_key) {
                (Some((p, dt)), Some((q, d))) => {
                    p.len() == q.len()
                        && p.iter().zip(q).all(|(a, b)| a.to_bits() == *b)
                        && (dt - d).abs() <= 1e-12 * dt.abs()
                }
                _ => false,
            };
        if !same {
            self.k_key = reuse.map(|(c, dt)| (c.iter().map(|v| v.to_bits()).collect(), dt));
            self.k_tangent = uniform.copied();
            self.factor_for = None;
            self.base = false;
            self.columns.clear();
            self.schur_set.clear();
            self.cap_frames = None;
        }
        !same
    }

    /// Marks the z-dofs of the active candidates as constrained.
    pub(crate) fn set_active(&mut self, model: &Model, active: &[bool]) {
        self.constrained.fill(false);
        for (k, _) in active.iter().enumerate().filter(|(_, a)| **a) {
            if let Some(e) = model.dofs.equation(2 * model.candidates[k] + 1) {
                self.constrained[e] = true;
            }
        }
    }

    /// Sets the frames of the active nodes for normal contact (call after
    /// [`ConstrainedSystem::set_active`]; every frame's `ez` must be constrained). An empty
    /// slice is vertical contact.
    pub(crate) fn set_frames(&mut self, frames: &[NodeFrame]) {
        if self.frames != frames {
            self.frames.clear();
            self.frames.extend_from_slice(frames);
        }
        for f in frames.iter().filter(|f| f.stick) {
            if let Some(er) = f.er {
                self.constrained[er] = true;
            }
        }
    }

    /// Whether a frame carries friction (sticking or slipping): such systems use the
    /// direct mode (sticking dofs are prescribed, slipping ones unsymmetric).
    fn friction(&self) -> bool {
        self.frames.iter().any(|f| f.stick || f.slip != 0.0)
    }

    /// The current tangent with its constraints, as assembled for the last Newton iteration
    /// (the matrix the direct solver factorizes: with normal contact, the active nodes' dofs
    /// rotated into the punch surface's frame with the curvature stiffness; constrained rows
    /// and columns replaced by their diagonal), as a full symmetric `sprs` matrix over the
    /// equations, and which equations are constrained (active contact dofs).
    pub fn matrix(&self, model: &Model) -> (sprs::CsMat<f64>, Vec<bool>) {
        let mut rotated = self.k_values.clone();
        for f in &self.frames {
            rotate_matrix(&model.pattern, &mut rotated, f);
        }
        let mut values = vec![0.0; self.k_values.len()];
        model
            .pattern
            .constrain(&rotated, &self.constrained, &mut values);
        (model.pattern.to_csmat(&values), self.constrained.clone())
    }

    /// Whether the active nodes have frames (normal contact) rather than vertical
    /// constraints.
    pub(crate) fn has_frames(&self) -> bool {
        !self.frames.is_empty()
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
    pub(crate) fn factorize(&mut self, model: &Model) -> Result<(), FeError> {
        let n = self.constrained.len();
        let m = self.constrained.iter().filter(|&&c| c).count();
        // capacitance: reusable tangent, and the columns stay a small multiple of K's factor
        let capacitance =
            self.k_key.is_some() && m <= MAX_CAPACITANCE && m * n <= 20_000_000 && !self.friction();
        self.pcg = false;
        if capacitance {
            if !self.frames.is_empty() {
                return self.factorize_capacitance_frames();
            }
            return self.factorize_capacitance(m);
        }
        self.capacitance = false;
        if self.k_key.is_some()
            && self.factor_for.as_ref() == Some(&self.constrained)
            && self.frames_factored == self.frames
        {
            return Ok(());
        }
        let t0 = std::time::Instant::now();
        self.form_constrained(model);
        self.factor_ok = false;
        self.chol.factorize(&self.k_constrained)?;
        self.factor_ok = true;
        if self.k_key.is_some() {
            self.factor_for = Some(self.constrained.clone());
            self.frames_factored.clone_from(&self.frames);
        }
        self.prepare_slip(model)?;
        self.seconds[1] += t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// `coef_k (K~ v)_{m_k}` over the equations `i` with `constrained[i] == prescribed`
    /// (`K~ = Q^T K Q` without the curvature stiffness: the normal row of slipping frame
    /// `k`).
    fn slip_row(&self, model: &Model, f: &NodeFrame, v: &[f64], prescribed: bool) -> f64 {
        let mut acc = 0.0;
        if self.constrained[f.ez] == prescribed {
            acc += self.k_rot[model.pattern.diag[f.ez]] * v[f.ez];
        }
        model.pattern.for_each_off_diagonal(f.ez, |i, p| {
            if self.constrained[i] == prescribed {
                acc += self.k_rot[p] * v[i];
            }
        });
        f.slip * acc
    }

    /// Friction's Woodbury data for the factor just formed (direct mode): with `S` the
    /// symmetric constrained matrix and `E` the unit vectors of the slipping nodes'
    /// tangential equations, the system is `S + E W^T` on the free equations (row `k` of
    /// `W^T` is the slipping node's `coef_k (K~ .)_{m_k}` over free equations); keep
    /// `Z = S^-1 E` and the LU factor of `I + W^T Z`.
    fn prepare_slip(&mut self, model: &Model) -> Result<(), FeError> {
        self.slip_idx.clear();
        self.slip_idx.extend(
            self.frames
                .iter()
                .enumerate()
                .filter(|(_, f)| f.slip != 0.0 && f.er.is_some())
                .map(|(i, _)| i),
        );
        let ns = self.slip_idx.len();
        if ns == 0 {
            return Ok(());
        }
        let n = self.constrained.len();
        self.slip_z.resize_with(ns, Vec::new);
        for (l, &i) in self.slip_idx.iter().enumerate() {
            let z = &mut self.slip_z[l];
            z.clear();
            z.resize(n, 0.0);
            if let Some(er) = self.frames[i].er {
                z[er] = 1.0;
            }
            self.chol.solve_in_place(z);
        }
        let mut a = vec![0.0; ns * ns];
        for (k, &i) in self.slip_idx.iter().enumerate() {
            let f = self.frames[i];
            for l in 0..ns {
                a[k * ns + l] = self.slip_row(model, &f, &self.slip_z[l], false)
                    + if k == l { 1.0 } else { 0.0 };
            }
        }
        let mut piv = vec![0usize; ns];
        dense_lu(&mut a, ns, &mut piv).map_err(|k| {
            FeError::NotPositiveDefinite(format!(
                "the friction (slip) correction is singular at slipping node {k}"
            ))
        })?;
        self.slip_lu = a;
        self.slip_piv = piv;
        Ok(())
    }

    /// Forms the constrained matrix of the current tangent and active set (direct mode):
    /// the cached direct factor and the capacitance columns no longer belong to it.
    fn form_constrained(&mut self, model: &Model) {
        if self.frames.is_empty() {
            model
                .pattern
                .constrain(&self.k_values, &self.constrained, &mut self.k_constrained);
        } else {
            self.k_rot.clear();
            self.k_rot.extend_from_slice(&self.k_values);
            for f in &self.frames {
                rotate_matrix(&model.pattern, &mut self.k_rot, f);
            }
            model
                .pattern
                .constrain(&self.k_rot, &self.constrained, &mut self.k_constrained);
        }
        self.cap_frames = None;
        self.factor_for = None;
        self.base = false;
        self.columns.clear();
        self.schur_set.clear();
        self.slip_idx.clear();
    }

    /// Makes the next assembly sum every element afresh instead of adding differences to
    /// the last matrix: what follows then depends on the tangents alone (call it at the
    /// start of any computation that must not depend on earlier ones, and after a failure
    /// that may have left non-finite values behind).
    pub(crate) fn forget_assembly(&mut self) {
        self.elements.forget_sum();
    }

    /// Drops every cached factorization, capacitance column and assembly sum, as a new
    /// system would have none (the symbolic analysis stays): what follows depends on its
    /// inputs alone, not on the tangents, active sets and order of an earlier computation
    /// on this workspace. (A reusable tangent's factor and capacitance columns otherwise
    /// carry over to the next computation with the same key, and the Schur factor grown in
    /// one order rounds differently from one grown in another.) The adjoint sweep and the
    /// forward sensitivities start with it, so that their bits do not depend on which of
    /// them ran first at a point.
    pub(crate) fn forget_factorizations(&mut self) {
        self.forget_assembly();
        self.k_key = None;
        self.k_tangent = None;
        self.exact_next = false;
        self.factor_for = None;
        self.base = false;
        self.columns.clear();
        self.schur_set.clear();
        self.schur.clear();
        self.capacitance = false;
        self.factor_ok = false;
        self.pcg = false;
        self.refresh.forget();
        self.frames.clear();
        self.frames_factored.clear();
        self.cap_frames = None;
        self.cap_lu.clear();
        self.cap_piv.clear();
        self.slip_idx.clear();
        self.slip_z.clear();
        self.slip_lu.clear();
        self.slip_piv.clear();
    }

    /// As [`ConstrainedSystem::forget_factorizations`], but keeps the factorization of a
    /// reusable tangent's unconstrained `K` (the capacitance mode's base: its key, values,
    /// factor, the columns `K^-1 e_c` and the Schur factor of the last prescribed set),
    /// which a computation with the same key then uses without factorizing or solving for
    /// the columns again. Those depend on the key alone (the columns are solves with the
    /// factor, the Schur factor is formed afresh from them for each prescribed set), so
    /// what follows is what a fresh system would compute from the same `K`. Without such
    /// a base everything is forgotten.
    pub(crate) fn forget_all_but_the_factor(&mut self) {
        if !(self.base && self.factor_ok && self.k_key.is_some()) {
            self.forget_factorizations();
            return;
        }
        let key = self.k_key.take();
        let tangent = self.k_tangent.take();
        let columns = std::mem::take(&mut self.columns);
        let set = std::mem::take(&mut self.schur_set);
        let schur = std::mem::take(&mut self.schur);
        self.forget_factorizations();
        self.k_key = key;
        self.k_tangent = tangent;
        self.columns = columns;
        self.schur_set = set;
        self.schur = schur;
        self.base = true;
        self.factor_ok = true;
    }

    /// Exchanges the factorization state of this system with `other`'s (a system of the
    /// same model: the same symbolic analysis): the tangent values and their key, the
    /// numeric factor, the capacitance columns and small factors, the direct mode's
    /// factor record. The counters, timings, refresh rule and work space stay with each
    /// system, and each forgets its assembly sum (the next per-point assembly sums every
    /// element). Each system afterwards holds a consistent state: a factor of the values
    /// under its key, or none.
    pub(crate) fn exchange_factor(&mut self, other: &mut ConstrainedSystem) {
        use std::mem::swap;
        swap(&mut self.chol, &mut other.chol);
        // the counters stay with their system
        swap(
            &mut self.chol.n_factorizations,
            &mut other.chol.n_factorizations,
        );
        swap(&mut self.chol.n_solves, &mut other.chol.n_solves);
        swap(&mut self.k_values, &mut other.k_values);
        swap(&mut self.k_constrained, &mut other.k_constrained);
        swap(&mut self.k_key, &mut other.k_key);
        swap(&mut self.k_tangent, &mut other.k_tangent);
        swap(&mut self.factor_for, &mut other.factor_for);
        swap(&mut self.frames_factored, &mut other.frames_factored);
        swap(&mut self.base, &mut other.base);
        swap(&mut self.columns, &mut other.columns);
        swap(&mut self.schur_set, &mut other.schur_set);
        swap(&mut self.schur, &mut other.schur);
        swap(&mut self.capacitance, &mut other.capacitance);
        swap(&mut self.factor_ok, &mut other.factor_ok);
        swap(&mut self.k_rot, &mut other.k_rot);
        swap(&mut self.cap_frames, &mut other.cap_frames);
        swap(&mut self.cap_lu, &mut other.cap_lu);
        swap(&mut self.cap_piv, &mut other.cap_piv);
        swap(&mut self.slip_idx, &mut other.slip_idx);
        swap(&mut self.slip_z, &mut other.slip_z);
        swap(&mut self.slip_lu, &mut other.slip_lu);
        swap(&mut self.slip_piv, &mut other.slip_piv);
        for s in [&mut *self, other] {
            s.forget_assembly();
            s.pcg = false;
            s.exact_next = s.k_key.is_some();
        }
    }

    /// Makes the next [`ConstrainedSystem::prepare_inexact`] factorize and the next
    /// assembly sum every element afresh: a time step that starts with this depends on its
    /// initial state alone, not on the factor or the assembly updates an earlier step left
    /// behind, so that replaying it from a checkpoint repeats it bit for bit.
    pub(crate) fn forget_preconditioner(&mut self) {
        self.forget_assembly();
        self.factor_ok = self.factor_ok && self.k_key.is_some();
        self.refresh.forget();
    }

    /// Prepares the next [`ConstrainedSystem::solve_inexact`]. A reusable tangent (linear
    /// law) is factorized as by [`ConstrainedSystem::factorize`] and solved exactly; for
    /// another tangent (a nonlinear law), with a factorization at hand, this only forms the
    /// constrained matrix: the solve then runs CG preconditioned by that earlier factor
    /// (Newton iterates change the tangent little), factorizing only if CG does not
    /// converge in a few iterations, or if the previous solve needed many.
    ///
    /// # Errors
    /// As [`ConstrainedSystem::factorize`].
    pub(crate) fn prepare_inexact(&mut self, model: &Model) -> Result<(), FeError> {
        let refresh = self.refresh.factorize_next();
        if self.k_key.is_some() || !self.factor_ok || refresh || self.friction() {
            self.refresh.factorized();
            return self.factorize(model);
        }
        let t0 = std::time::Instant::now();
        self.form_constrained(model);
        self.capacitance = false;
        self.pcg = true;
        self.seconds[1] += t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// Solves as [`ConstrainedSystem::solve_dirichlet`] to a relative residual `eta`
    /// (2-norm over the unconstrained equations; the constrained ones are exact) after
    /// [`ConstrainedSystem::prepare_inexact`]; exact after [`ConstrainedSystem::factorize`].
    /// Returns the CG iterations (0 for a direct solve).
    ///
    /// # Errors
    /// [`FeError::NotPositiveDefinite`] if CG fails and the fallback factorization too.
    pub(crate) fn solve_inexact(
        &mut self,
        model: &Model,
        b: &mut [f64],
        xbar: &[f64],
        eta: f64,
    ) -> Result<usize, FeError> {
        self.cg_residual = false;
        if !self.pcg {
            self.solve_dirichlet(model, b, xbar);
            return Ok(0);
        }
        rotate_in(&self.frames, b);
        let its = self.solve_pcg(model, b, xbar, eta, None);
        rotate_out(&self.frames, b);
        its
    }

    /// As [`ConstrainedSystem::solve_inexact`], CG starting from `guess` (on the free
    /// equations) instead of the preconditioner's solution: a solution of a nearby system
    /// (load control's depth column of the last Newton iterate). Vertical contact only
    /// (with node frames the guess would need their rotation: it is then not used).
    ///
    /// # Errors
    /// As [`ConstrainedSystem::solve_inexact`].
    pub(crate) fn solve_inexact_from(
        &mut self,
        model: &Model,
        b: &mut [f64],
        xbar: &[f64],
        eta: f64,
        guess: &[f64],
    ) -> Result<usize, FeError> {
        if !self.pcg || !self.frames.is_empty() {
            return self.solve_inexact(model, b, xbar, eta);
        }
        self.solve_pcg(model, b, xbar, eta, Some(guess))
    }

    /// `x . r` with `r = b - A x` the residual CG left on the free equations of the last
    /// inexact solve (vertical contact: no frames), or 0 where that solve was direct (its
    /// residual is round-off). Load control's depth column reads its energy from it
    /// without a product over the whole matrix (`newton.rs`, `Newton::border`).
    pub(crate) fn last_residual_dot(&self, x: &[f64]) -> f64 {
        if self.cg_residual && self.frames.is_empty() {
            dot(x, &self.work[0])
        } else {
            0.0
        }
    }

    /// Preconditioned CG on the constrained (rotated) matrix, `b` rotated.
    fn solve_pcg(
        &mut self,
        model: &Model,
        b: &mut [f64],
        xbar: &[f64],
        eta: f64,
        guess: Option<&[f64]>,
    ) -> Result<usize, FeError> {
        let t0 = std::time::Instant::now();
        self.dirichlet_rhs(model, b, xbar);
        let [r, z, p, q, rhs] = &mut self.work;
        rhs.copy_from_slice(b);
        let constrained = &self.constrained;
        let free_dot = |a: &[f64], b: &[f64]| -> f64 {
            a.iter()
                .zip(b)
                .zip(constrained)
                .filter(|(_, c)| !**c)
                .map(|((x, y), _)| x * y)
                .sum()
        };
        // x0 = M^-1 rhs (or the guess) on the free equations, exact on the constrained ones
        let bnorm = free_dot(rhs, rhs).sqrt();
        match guess {
            Some(g) => b.copy_from_slice(g),
            None => self.chol.solve_in_place(b),
        }
        impose(b, constrained, |e| xbar[e]);
        // r = rhs - A x (zero on constrained rows: A is diagonal there and x exact)
        q.fill(0.0);
        model.pattern.sym_mul_add(&self.k_constrained, b, q);
        for e in 0..r.len() {
            r[e] = if constrained[e] { 0.0 } else { rhs[e] - q[e] };
        }
        let tol = eta * bnorm;
        let mut iterations = 0;
        // r, z, p and q = A p vanish on the constrained equations (A is diagonal there):
        // plain dot products and updates over all equations are the free ones
        let mut converged = dot(r, r).sqrt() <= tol;
        let mut rz = 0.0;
        let cap = self.refresh.cap();
        while !converged && iterations < cap {
            // z = M^-1 r restricted to the free equations; p = z + beta p
            z.copy_from_slice(r);
            self.chol.solve_in_place(z);
            impose(z, constrained, |_| 0.0);
            let rz_new = dot(r, z);
            if iterations == 0 {
                p.copy_from_slice(z);
            } else {
                let beta = rz_new / rz;
                for (pi, zi) in p.iter_mut().zip(z.iter()) {
                    *pi = zi + beta * *pi;
                }
            }
            rz = rz_new;
            iterations += 1;
            q.fill(0.0);
            model.pattern.sym_mul_add(&self.k_constrained, p, q);
            let pq = dot(p, q);
            if !(pq > 0.0) {
                break;
            }
            let alpha = rz / pq;
            for (bi, pi) in b.iter_mut().zip(p.iter()) {
                *bi += alpha * pi;
            }
            for (ri, qi) in r.iter_mut().zip(q.iter()) {
                *ri -= alpha * qi;
            }
            converged = dot(r, r).sqrt() <= tol;
        }
        self.pcg_iterations += iterations;
        self.pcg_solves += 1;
        self.refresh.solved(iterations, converged);
        self.seconds[2] += t0.elapsed().as_secs_f64();
        self.cg_residual = converged;
        if converged {
            return Ok(iterations);
        }
        // the old factor is too far from this tangent: factorize it and solve directly
        self.pcg_fallbacks += 1;
        let t1 = std::time::Instant::now();
        self.pcg = false;
        self.factor_ok = false;
        self.chol.factorize(&self.k_constrained)?;
        self.factor_ok = true;
        // the new factor is this Newton iterate's own: the next solves precondition with it
        self.seconds[1] += t1.elapsed().as_secs_f64();
        let t2 = std::time::Instant::now();
        b.copy_from_slice(&self.work[4]);
        self.chol.solve_in_place(b);
        impose(b, &self.constrained, |e| xbar[e]);
        self.seconds[2] += t2.elapsed().as_secs_f64();
        Ok(iterations)
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
            self.factor_ok = false;
            self.chol.factorize(&self.k_values)?;
            self.factor_ok = true;
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
    pub(crate) fn solve_dirichlet(&mut self, model: &Model, b: &mut [f64], xbar: &[f64]) {
        let t0 = std::time::Instant::now();
        self.solve_own(model, b, xbar);
        self.seconds[2] += t0.elapsed().as_secs_f64();
    }

    /// [`ConstrainedSystem::solve_dirichlet_with`] with the system's own work space,
    /// counted.
    fn solve_own(&mut self, model: &Model, b: &mut [f64], xbar: &[f64]) {
        let mut scratch = std::mem::take(&mut self.scratch);
        self.solve_dirichlet_with(model, b, xbar, &mut scratch);
        self.scratch = scratch;
        self.chol.n_solves += 1;
    }

    /// The work space of [`ConstrainedSystem::solve_dirichlet_with`].
    pub(crate) fn solve_scratch(&self) -> SolveScratch {
        self.chol.scratch()
    }

    /// [`ConstrainedSystem::solve_dirichlet`] with the system shared and the solve's work
    /// space given (from [`ConstrainedSystem::solve_scratch`]): several threads may solve
    /// with one factorized system at once, with the same arithmetic, so the same bits
    /// (slipping frames included: their Woodbury correction reads the system only).
    /// These solves are neither timed nor counted.
    ///
    /// # Panics
    /// If [`ConstrainedSystem::factorize`] has not succeeded for the current tangent.
    pub(crate) fn solve_dirichlet_with(
        &self,
        model: &Model,
        b: &mut [f64],
        xbar: &[f64],
        scratch: &mut SolveScratch,
    ) {
        self.dirichlet_before(model, b, xbar);
        self.chol.solve_with(b, scratch);
        self.dirichlet_after(model, b, xbar);
    }

    /// [`ConstrainedSystem::solve_dirichlet_with`] for the `k` columns of the
    /// column-major block `b` (`n_eq x k`), column `c` with the prescribed values
    /// `xbar[c * n_eq..]`: what precedes and follows the factor's solve column by column
    /// as there, the factor's solves in one pass over the factor
    /// ([`SparseCholesky::solve_multi_with`]): each column the bits of its own solve.
    ///
    /// # Panics
    /// As [`ConstrainedSystem::solve_dirichlet_with`]; if `b` or `xbar` is not `n_eq * k`
    /// long.
    pub(crate) fn solve_dirichlet_multi(
        &self,
        model: &Model,
        b: &mut [f64],
        xbar: &[f64],
        k: usize,
        scratch: &mut SolveScratch,
    ) {
        let n = model.dofs.n_eq;
        assert_eq!(b.len(), n * k, "right-hand sides' length");
        assert_eq!(xbar.len(), n * k, "prescribed values' length");
        for (bc, xc) in b.chunks_exact_mut(n).zip(xbar.chunks_exact(n)) {
            self.dirichlet_before(model, bc, xc);
        }
        self.chol.solve_multi_with(b, k, scratch);
        for (bc, xc) in b.chunks_exact_mut(n).zip(xbar.chunks_exact(n)) {
            self.dirichlet_after(model, bc, xc);
        }
    }

    /// What [`ConstrainedSystem::solve_dirichlet_with`] does to `b` before the factor's
    /// solve, in each of the system's modes.
    fn dirichlet_before(&self, model: &Model, b: &mut [f64], xbar: &[f64]) {
        if self.capacitance {
            if self.frames.is_empty() {
                for &c in &self.schur_set {
                    b[c] = 0.0;
                }
            } else {
                self.capacitance_frames_before(b);
            }
            return;
        }
        rotate_in(&self.frames, b);
        if !self.slip_idx.is_empty() {
            for &i in &self.slip_idx {
                let f = self.frames[i];
                if let Some(er) = f.er {
                    b[er] += f.slip * b[f.ez] - self.slip_row(model, &f, xbar, true);
                }
            }
        }
        self.dirichlet_rhs(model, b, xbar);
    }

    /// What [`ConstrainedSystem::solve_dirichlet_with`] does to `b` after the factor's
    /// solve.
    fn dirichlet_after(&self, model: &Model, b: &mut [f64], xbar: &[f64]) {
        if self.capacitance {
            if self.frames.is_empty() {
                self.capacitance_after(b, xbar);
            } else {
                self.capacitance_frames_after(b, xbar);
            }
            return;
        }
        if !self.slip_idx.is_empty() {
            self.slip_after(model, b);
        }
        rotate_out(&self.frames, b);
    }

    /// The direct solve's Woodbury correction with slipping frames (`b` rotated, the
    /// slipping rows' right-hand side `b_t + coef b_m` less their prescribed columns, and
    /// solved): `y = y0 - Z (I + W^T Z)^-1 W^T y0`.
    fn slip_after(&self, model: &Model, b: &mut [f64]) {
        let ns = self.slip_idx.len();
        let mut h: Vec<f64> = self
            .slip_idx
            .iter()
            .map(|&i| self.slip_row(model, &self.frames[i], b, false))
            .collect();
        dense_lu_solve(&self.slip_lu, ns, &self.slip_piv, &mut h);
        for (l, g) in h.iter().enumerate() {
            for (x, z) in b.iter_mut().zip(&self.slip_z[l]) {
                *x -= g * z;
            }
        }
    }

    /// The transposed solve of the adjoint (docs/validation-contact.md §7): the transpose
    /// of [`ConstrainedSystem::solve_dirichlet`]'s map `(b, xbar) -> x` applied to a
    /// cotangent `g` of `x`. On entry `b` holds `g` (physical equation vector); on exit it
    /// holds the cotangent of the right-hand side `b` (physical), and `stick` holds, per
    /// frame (same order as [`ConstrainedSystem::set_frames`]), the cotangent of the
    /// prescribed tangential value `xbar` of a sticking node (0 for other frames).
    /// `v_p` gives the result's values on the prescribed equations `P` (the data of a
    /// cotangent that enters there, as a prescribed value enters the forward solve): read
    /// only without friction frames, where the system is symmetric and this is
    /// [`ConstrainedSystem::solve_dirichlet`] itself; with friction frames it must be zero
    /// on `P` (the Coulomb adjoint shifts its data instead, `constraint::coulomb`).
    ///
    /// With the rotated `K^ = Q^T K Q + D`, `F` the free and `P` the prescribed equations,
    /// `A = S + E W^T` the forward's matrix on `F` (slipping rows `(t + c m) . K~ + d t`):
    /// `w = A^-T g~_F` by the same Cholesky factor of `S` and the Woodbury correction with
    /// the roles of `E` and `W` swapped, `A^-T r = S^-1 (r - W (I + W^T Z)^-T Z^T r)`
    /// (one more triangular solve; `Z = S^-1 E` as in the forward); the cotangent of `b` is
    /// `Q w^` with `w^ = w` on `F` and `c_k w_t,k` in slipping node `k`'s normal slot, and
    /// that of `xbar` is `(g~ - K^ w^)_P`. Without slipping frames `A` is symmetric and
    /// this is the symmetric solve with zero prescribed values.
    ///
    /// # Panics
    /// If [`ConstrainedSystem::factorize`] has not succeeded for the current tangent.
    pub(crate) fn solve_transposed(
        &mut self,
        model: &Model,
        b: &mut [f64],
        v_p: &[f64],
        stick: &mut Vec<f64>,
    ) {
        let t0 = std::time::Instant::now();
        stick.clear();
        stick.resize(self.frames.len(), 0.0);
        if self.capacitance || !self.friction() {
            // symmetric, no sticking dof: the cotangent of b is the solve itself
            self.solve_own(model, b, v_p);
            self.seconds[2] += t0.elapsed().as_secs_f64();
            return;
        }
        debug_assert!(
            self.constrained
                .iter()
                .zip(v_p)
                .all(|(&c, &v)| !c || v == 0.0),
            "a transposed solve with friction frames takes no prescribed cotangent"
        );
        rotate_in(&self.frames, b);
        let g = b.to_vec();
        for (x, &c) in b.iter_mut().zip(&self.constrained) {
            if c {
                *x = 0.0;
            }
        }
        let ns = self.slip_idx.len();
        if ns > 0 {
            // h = Z^T r, (I + W^T Z)^T v = h, r <- r - W v
            let mut h: Vec<f64> = self.slip_z.iter().map(|z| dot(z, b)).collect();
            dense_lu_solve_transposed(&self.slip_lu, ns, &self.slip_piv, &mut h);
            for (l, &i) in self.slip_idx.iter().enumerate() {
                let f = self.frames[i];
                let v = h[l] * f.slip;
                if v == 0.0 {
                    continue;
                }
                if !self.constrained[f.ez] {
                    b[f.ez] -= v * self.k_rot[model.pattern.diag[f.ez]];
                }
                let (k_rot, constrained) = (&self.k_rot, &self.constrained);
                model.pattern.for_each_off_diagonal(f.ez, |i, p| {
                    if !constrained[i] {
                        b[i] -= v * k_rot[p];
                    }
                });
            }
        }
        self.chol.solve_in_place(b);
        for &i in &self.slip_idx {
            let f = self.frames[i];
            if let Some(er) = f.er {
                b[f.ez] = f.slip * b[er];
            }
        }
        // the cotangents of the sticking nodes' prescribed tangential values
        for (s, f) in stick.iter_mut().zip(&self.frames) {
            if let (true, Some(er)) = (f.stick, f.er) {
                *s = g[er] - model.pattern.row_dot(&self.k_rot, er, b);
            }
        }
        rotate_out(&self.frames, b);
        self.seconds[2] += t0.elapsed().as_secs_f64();
    }

    /// The capacitance mode with frames: the unconstrained factorization (once per
    /// tangent), the columns `z = K^-1 e` of both dofs of every active node, and the LU
    /// factor of the small system of [`ConstrainedSystem::capacitance_frames_after`].
    fn factorize_capacitance_frames(&mut self) -> Result<(), FeError> {
        let t0 = std::time::Instant::now();
        self.capacitance = true;
        if !self.base {
            self.factor_for = None;
            self.columns.clear();
            self.schur_set.clear();
            self.cap_frames = None;
            self.factor_ok = false;
            self.chol.factorize(&self.k_values)?;
            self.factor_ok = true;
            self.base = true;
        }
        if self.cap_frames.as_ref() == Some(&self.frames) {
            self.seconds[1] += t0.elapsed().as_secs_f64();
            return Ok(());
        }
        let n = self.constrained.len();
        for f in &self.frames {
            for e in f.er.into_iter().chain(Some(f.ez)) {
                if !self.columns.contains_key(&e) {
                    let mut z = vec![0.0; n];
                    z[e] = 1.0;
                    self.chol.solve_in_place(&mut z);
                    self.columns.insert(e, z);
                }
            }
        }
        // unknowns: the normal multiplier beta_k of every node, then alpha_k (tangential)
        let nf = self.frames.len();
        let nu = nf + self.frames.iter().filter(|f| f.er.is_some()).count();
        let alpha_idx = alpha_indices(&self.frames);
        let mut a = vec![0.0; nu * nu];
        // W(a_k, b_l) = a_k . (K^-1 E_l b_l)_k
        let w = |ak: [f64; 2], fk: &NodeFrame, bl: [f64; 2], fl: &NodeFrame| -> f64 {
            let col = |e: Option<usize>| e.and_then(|e| self.columns.get(&e));
            let at = |v: Option<&Vec<f64>>, k: &NodeFrame| -> [f64; 2] {
                v.map_or([0.0; 2], |v| [k.er.map_or(0.0, |e| v[e]), v[k.ez]])
            };
            let (zr, zz) = (at(col(fl.er), fk), at(col(Some(fl.ez)), fk));
            let u = [bl[0] * zr[0] + bl[1] * zz[0], bl[0] * zr[1] + bl[1] * zz[1]];
            ak[0] * u[0] + ak[1] * u[1]
        };
        for (k, fk) in self.frames.iter().enumerate() {
            for (l, fl) in self.frames.iter().enumerate() {
                a[k * nu + l] = w(fk.m, fk, fl.m, fl);
                if let Some(al) = alpha_idx[l] {
                    a[k * nu + al] = w(fk.m, fk, fl.t, fl);
                }
                if let Some(ak) = alpha_idx[k] {
                    a[ak * nu + l] = fk.d * w(fk.t, fk, fl.m, fl);
                    if let Some(al) = alpha_idx[l] {
                        a[ak * nu + al] =
                            fk.d * w(fk.t, fk, fl.t, fl) + if k == l { 1.0 } else { 0.0 };
                    }
                }
            }
        }
        let mut piv = vec![0usize; nu];
        dense_lu(&mut a, nu, &mut piv).map_err(|k| {
            FeError::NotPositiveDefinite(format!(
                "the normal-contact capacitance system is singular at unknown {k}"
            ))
        })?;
        self.cap_lu = a;
        self.cap_piv = piv;
        self.cap_frames = Some(self.frames.clone());
        self.seconds[1] += t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// `x = y + sum_l (alpha_l K^-1 E_l t_l + beta_l K^-1 E_l m_l)` with `y = K^-1 b'` (`b'`
    /// is `b` without its normal components at the active nodes, which are reactions), and
    /// `(alpha, beta)` such that `m_k . x_k = xbar_k` and the tangential equation
    /// `alpha_k + d_k t_k . x_k = 0` hold at every active node: here `b'`, before the
    /// factor's solve.
    fn capacitance_frames_before(&self, b: &mut [f64]) {
        for f in &self.frames {
            match f.er {
                Some(er) => {
                    let bm = f.m[0] * b[er] + f.m[1] * b[f.ez];
                    b[er] -= bm * f.m[0];
                    b[f.ez] -= bm * f.m[1];
                }
                None => b[f.ez] = 0.0,
            }
        }
    }

    /// The capacitance mode's correction with frames, after the factor's solve.
    fn capacitance_frames_after(&self, b: &mut [f64], xbar: &[f64]) {
        let nf = self.frames.len();
        let alpha_idx = alpha_indices(&self.frames);
        let nu = self.cap_piv.len();
        let mut rhs = vec![0.0; nu];
        for (k, f) in self.frames.iter().enumerate() {
            let y = [f.er.map_or(0.0, |e| b[e]), b[f.ez]];
            rhs[k] = xbar[f.ez] - (f.m[0] * y[0] + f.m[1] * y[1]);
            if let Some(ak) = alpha_idx[k] {
                rhs[ak] = -f.d * (f.t[0] * y[0] + f.t[1] * y[1]);
            }
        }
        dense_lu_solve(&self.cap_lu, nu, &self.cap_piv, &mut rhs);
        for (k, f) in self.frames.iter().enumerate().take(nf) {
            let beta = rhs[k];
            let alpha = alpha_idx[k].map_or(0.0, |a| rhs[a]);
            let coef = [
                alpha * f.t[0] + beta * f.m[0],
                alpha * f.t[1] + beta * f.m[1],
            ];
            for (e, c) in [(f.er, coef[0]), (Some(f.ez), coef[1])] {
                if let Some(z) = e.and_then(|e| self.columns.get(&e)) {
                    if c != 0.0 {
                        for (x, zi) in b.iter_mut().zip(z) {
                            *x += c * zi;
                        }
                    }
                }
            }
        }
    }

    /// `b - K xbar` on the unconstrained equations, `K_cc xbar_c` on the constrained ones:
    /// the right-hand side of the constrained matrix for the prescribed values `xbar`.
    fn dirichlet_rhs(&self, model: &Model, b: &mut [f64], xbar: &[f64]) {
        // K xbar has the columns of the few constrained equations only
        let k = if self.frames.is_empty() {
            &self.k_values
        } else {
            &self.k_rot
        };
        let constrained = &self.constrained;
        for (c, _) in constrained.iter().enumerate().filter(|(_, c)| **c) {
            let xc = xbar[c];
            if xc != 0.0 {
                model.pattern.for_each_off_diagonal(c, |i, p| {
                    if !constrained[i] {
                        b[i] -= k[p] * xc;
                    }
                });
            }
        }
        for (c, _) in constrained.iter().enumerate().filter(|(_, c)| **c) {
            b[c] = self.k_constrained[model.pattern.diag[c]] * xbar[c];
        }
    }

    /// The capacitance mode without frames, after the factor's solve of `b` (with
    /// `b_C = 0`): `x = K^-1 b - sum_c mu_c z_c` with `S mu = (K^-1 b)_C - xbar_C`.
    fn capacitance_after(&self, b: &mut [f64], xbar: &[f64]) {
        let set = &self.schur_set;
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

impl ConstrainedSystem {
    /// The capacitance mode's solve shared by the bordered steps: `b` (zero on the
    /// prescribed equations) becomes `K^-1 b` with the one factorization, and `depth_mu`
    /// the multipliers of a unit settlement, `S mu1 = 1`.
    fn solve_with_unit_multipliers(&mut self, b: &mut [f64]) {
        let mut scratch = std::mem::take(&mut self.scratch);
        self.chol.solve_with(b, &mut scratch);
        self.scratch = scratch;
        self.chol.n_solves += 1;
        let m = self.schur_set.len();
        self.depth_mu.clear();
        self.depth_mu.resize(m, 1.0);
        dense_cholesky_solve(&self.schur, m, &mut self.depth_mu);
    }

    /// Whether the current system is in the capacitance mode (a reusable tangent factorized
    /// exactly, no frames, the base set) and its prescribed equations are exactly those of
    /// the depth's unit settlement `v` (1 on each, 0 elsewhere): the condition of every
    /// bordered solve done with the stored columns.
    fn bordered_by_capacitance(&self, v: &[f64]) -> bool {
        if !self.capacitance || self.pcg || !self.frames.is_empty() || !self.base {
            return false;
        }
        let m = self.schur_set.len();
        let marked = v.iter().filter(|&&x| x != 0.0).count();
        m > 0
            && marked == m
            && (self.schur_set.iter())
                .all(|&e| v[e] == 1.0 && self.constrained[e] && self.columns.contains_key(&e))
    }

    /// Load control's depth column without a solve, where the capacitance mode holds the
    /// current system (a reusable tangent, vertical contact, no friction): the solution
    /// `du_U` of `K du_U = 0` on the free equations with `du_U = -1` on the prescribed
    /// ones `C` (the active candidates' vertical equations, marked 1 in `v`) is
    /// `-sum_c mu_c z_c` with `S mu = 1` on the stored columns `z_c = K^-1 e_c`, and the
    /// contact stiffness is `s = -(K v) . du_U = 1 . mu` (the reactions of a unit
    /// settlement, the Schur complement `[K^-1]_CC^-1` summed): `m` vector updates instead
    /// of a triangular solve pair. `col` receives `du_U`; returns `s`, or `None` (nothing
    /// written) when the current system is not in that mode or its prescribed equations
    /// are not exactly those of `v`.
    pub(crate) fn depth_column_capacitance(&mut self, v: &[f64], col: &mut [f64]) -> Option<f64> {
        if !self.bordered_by_capacitance(v) {
            return None;
        }
        let set = &self.schur_set;
        let m = set.len();
        let mu = &mut self.depth_mu;
        mu.clear();
        mu.resize(m, 1.0);
        dense_cholesky_solve(&self.schur, m, mu);
        col.fill(0.0);
        for (&c, &f) in set.iter().zip(mu.iter()) {
            let Some(z) = self.columns.get(&c) else {
                continue;
            };
            for (x, zi) in col.iter_mut().zip(z) {
                *x -= f * zi;
            }
        }
        for &c in set {
            col[c] = -1.0;
        }
        Some(mu.iter().sum())
    }
}

impl ConstrainedSystem {
    /// Load control's bordered forward step in the capacitance mode (a reusable tangent
    /// factorized exactly, vertical contact, no friction; the prescribed equations exactly
    /// those marked 1 in `v`) with one solve and one set of column updates serving the
    /// step and the depth column. With `y = K^-1 b~` (`b~` = `b` with the prescribed
    /// equations zeroed), `S mu = y_C - xbar_C` and `S mu1 = 1`, the step's solve is
    /// `du_1 = y - sum_c mu_c z_c` (`xbar` on `C`) and the depth column `du_2 = -sum_c
    /// mu1_c z_c` (`-1` on `C`), as [`ConstrainedSystem::depth_column_capacitance`].
    /// Since `K du_1 = b~ - sum_c mu_c e_c`, the linearized force row's product
    /// `g . du_1 = -(K v) . du_1 = -sum_C (K du_1)_c = sum_c mu_c`, and the contact
    /// stiffness is `s = 1 . mu1`: neither the product `K v` nor the depth column itself
    /// is formed. `du_of(g . du_1, s, v . K v)` (`v . K v` from the rows of `C` alone)
    /// returns the depth increment `dU`, and `b` receives `du_1 + dU du_2 = y - sum_c
    /// (mu_c + dU mu1_c) z_c`, `xbar_C - dU` on `C`. Returns `Some(du_of's result)`, or
    /// `None` (nothing changed) when the current system is not in that mode.
    pub(crate) fn solve_bordered<E>(
        &mut self,
        model: &Model,
        v: &[f64],
        b: &mut [f64],
        xbar: &[f64],
        du_of: impl FnOnce(f64, f64, f64) -> Result<f64, E>,
    ) -> Option<Result<f64, E>> {
        if !self.bordered_by_capacitance(v) {
            return None;
        }
        let m = self.schur_set.len();
        let t0 = std::time::Instant::now();
        for &c in &self.schur_set {
            b[c] = 0.0;
        }
        self.solve_with_unit_multipliers(b);
        let (mu1, mu) = (&self.depth_mu, &mut self.bordered_nu);
        mu.clear();
        mu.extend(self.schur_set.iter().map(|&c| b[c] - xbar[c]));
        dense_cholesky_solve(&self.schur, m, mu);
        let g_du1: f64 = mu.iter().sum();
        let s: f64 = mu1.iter().sum();
        // `v . K v`: the entries of `K` in the rows and columns of `C`
        let k = &self.k_values;
        let mut vkv = 0.0;
        for &c in &self.schur_set {
            vkv += k[model.pattern.diag[c]];
            model.pattern.for_each_off_diagonal(c, |i, p| {
                if v[i] != 0.0 {
                    vkv += k[p];
                }
            });
        }
        let du = match du_of(g_du1, s, vkv) {
            Ok(du) => du,
            Err(e) => {
                self.seconds[2] += t0.elapsed().as_secs_f64();
                return Some(Err(e));
            }
        };
        for ((c, n), u) in self.schur_set.iter().zip(mu.iter()).zip(mu1.iter()) {
            let f = n + du * u;
            if let Some(z) = self.columns.get(c) {
                for (x, zi) in b.iter_mut().zip(z) {
                    *x -= f * zi;
                }
            }
        }
        for &c in &self.schur_set {
            b[c] = xbar[c] - du;
        }
        self.seconds[2] += t0.elapsed().as_secs_f64();
        Some(Ok(du))
    }
}

impl ConstrainedSystem {
    /// The adjoint's bordered step in the capacitance mode (a reusable tangent, vertical
    /// contact, no friction; the prescribed equations exactly those marked 1 in `v`),
    /// with one solve and one set of column updates: with `y = K^-1 g~` (`g~` = `b` with
    /// the prescribed equations zeroed) and `S mu1 = 1`, the depth column `du_U =
    /// -sum_c mu1_c z_c` (`-1` on the prescribed equations) meets the right-hand side in
    /// `a = b . du_U = -mu1 . y_C - sum_C b`, and the Schur complement is `s = 1 . mu1`
    /// (as [`ConstrainedSystem::depth_column_capacitance`]); `rho = rho_of(a, s)`, and the
    /// transposed solve with the values `rho` on the prescribed equations is
    /// `x = y - sum_c (nu_c - rho mu1_c) z_c` with `S nu = y_C`. `b` (equations) holds the
    /// right-hand side on entry and the solution on exit. Returns `(rho, s)`, or `None`
    /// (nothing changed) when the current system is not in that mode.
    pub(crate) fn solve_transposed_bordered(
        &mut self,
        v: &[f64],
        b: &mut [f64],
        rho_of: &mut dyn FnMut(f64, f64) -> f64,
    ) -> Option<(f64, f64)> {
        if !self.bordered_by_capacitance(v) {
            return None;
        }
        let m = self.schur_set.len();
        let t0 = std::time::Instant::now();
        let mut g_c = 0.0;
        for &c in &self.schur_set {
            g_c += b[c];
            b[c] = 0.0;
        }
        self.solve_with_unit_multipliers(b);
        let (mu1, nu) = (&self.depth_mu, &mut self.bordered_nu);
        nu.clear();
        nu.extend(self.schur_set.iter().map(|&c| b[c]));
        let a = -nu.iter().zip(mu1.iter()).map(|(y, u)| y * u).sum::<f64>() - g_c;
        dense_cholesky_solve(&self.schur, m, nu);
        let s: f64 = mu1.iter().sum();
        let rho = rho_of(a, s);
        for ((c, n), u) in self.schur_set.iter().zip(nu.iter()).zip(mu1.iter()) {
            let f = n - rho * u;
            if let Some(z) = self.columns.get(c) {
                for (x, zi) in b.iter_mut().zip(z) {
                    *x -= f * zi;
                }
            }
        }
        for &c in &self.schur_set {
            b[c] = rho;
        }
        self.seconds[2] += t0.elapsed().as_secs_f64();
        Some((rho, s))
    }
}

/// Index of each frame's tangential unknown in the capacitance system (after the `nf`
/// normal ones), `None` on the axis.
fn alpha_indices(frames: &[NodeFrame]) -> Vec<Option<usize>> {
    let mut next = frames.len();
    frames
        .iter()
        .map(|f| {
            f.er.map(|_| {
                next += 1;
                next - 1
            })
        })
        .collect()
}

/// `values <- Q^T values Q` for the rotation `Q = [t m]` of one node's two equations, and
/// the curvature stiffness `d` on its tangential (first) equation. Both dofs of a node
/// share their structure, so the pattern does not change.
fn rotate_matrix(pattern: &Pattern, values: &mut [f64], f: &NodeFrame) {
    let Some(er) = f.er else {
        return;
    };
    let ez = f.ez;
    let (t, m) = (f.t, f.m);
    let mut a: Vec<(usize, usize)> = Vec::new();
    let mut b: Vec<(usize, usize)> = Vec::new();
    pattern.for_each_off_diagonal(er, |i, p| {
        if i != ez {
            a.push((i, p));
        }
    });
    pattern.for_each_off_diagonal(ez, |i, p| {
        if i != er {
            b.push((i, p));
        }
    });
    a.sort_unstable();
    b.sort_unstable();
    debug_assert!(a.len() == b.len() && a.iter().zip(&b).all(|(x, y)| x.0 == y.0));
    for (&(_, pa), &(_, pb)) in a.iter().zip(&b) {
        let (x, y) = (values[pa], values[pb]);
        values[pa] = t[0] * x + t[1] * y;
        values[pb] = m[0] * x + m[1] * y;
    }
    // the node's own block (column er holds row ez: paired dofs, ez = er + 1)
    let (dr, dz) = (pattern.diag[er], pattern.diag[ez]);
    let prz = Some(dr + 1).filter(|&p| p < pattern.col_ptr[er + 1] && pattern.row_idx[p] == ez);
    let krz = prz.map_or(0.0, |p| values[p]);
    let (krr, kzz) = (values[dr], values[dz]);
    let quad = |u: [f64; 2], v: [f64; 2]| {
        u[0] * (krr * v[0] + krz * v[1]) + u[1] * (krz * v[0] + kzz * v[1])
    };
    values[dr] = quad(t, t) + f.d;
    values[dz] = quad(m, m);
    if let Some(p) = prz {
        values[p] = quad(t, m);
    }
}

/// Physical to frame components at the rotated nodes: `(x_r, x_z) -> (t . x, m . x)`.
fn rotate_in(frames: &[NodeFrame], x: &mut [f64]) {
    for f in frames {
        if let Some(er) = f.er {
            let (a, b) = (x[er], x[f.ez]);
            x[er] = f.t[0] * a + f.t[1] * b;
            x[f.ez] = f.m[0] * a + f.m[1] * b;
        }
    }
}

/// Frame to physical components: `x = x_t t + x_m m`.
fn rotate_out(frames: &[NodeFrame], x: &mut [f64]) {
    for f in frames {
        if let Some(er) = f.er {
            let (a, b) = (x[er], x[f.ez]);
            x[er] = f.t[0] * a + f.m[0] * b;
            x[f.ez] = f.t[1] * a + f.m[1] * b;
        }
    }
}

/// In-place LU factorization with partial pivoting of the row-major `n x n` matrix `a`;
/// `Err(k)` at a zero pivot.
fn dense_lu(a: &mut [f64], n: usize, piv: &mut [usize]) -> Result<(), usize> {
    for k in 0..n {
        let p = (k..n)
            .max_by(|&i, &j| a[i * n + k].abs().total_cmp(&a[j * n + k].abs()))
            .unwrap_or(k);
        piv[k] = p;
        if !(a[p * n + k].abs() > 0.0) {
            return Err(k);
        }
        if p != k {
            for j in 0..n {
                a.swap(k * n + j, p * n + j);
            }
        }
        let d = a[k * n + k];
        for i in k + 1..n {
            let l = a[i * n + k] / d;
            a[i * n + k] = l;
            if l != 0.0 {
                for j in k + 1..n {
                    a[i * n + j] -= l * a[k * n + j];
                }
            }
        }
    }
    Ok(())
}

/// Solves with the factor of [`dense_lu`] in place.
fn dense_lu_solve(lu: &[f64], n: usize, piv: &[usize], b: &mut [f64]) {
    for k in 0..n {
        b.swap(k, piv[k]);
    }
    for i in 0..n {
        let mut v = b[i];
        for k in 0..i {
            v -= lu[i * n + k] * b[k];
        }
        b[i] = v;
    }
    for i in (0..n).rev() {
        let mut v = b[i];
        for k in i + 1..n {
            v -= lu[i * n + k] * b[k];
        }
        b[i] = v / lu[i * n + i];
    }
}

/// Solves `A^T x = b` with the factor `P A = L U` of [`dense_lu`] in place.
fn dense_lu_solve_transposed(lu: &[f64], n: usize, piv: &[usize], b: &mut [f64]) {
    // U^T y = b
    for i in 0..n {
        let mut v = b[i];
        for k in 0..i {
            v -= lu[k * n + i] * b[k];
        }
        b[i] = v / lu[i * n + i];
    }
    // L^T v = y (unit diagonal)
    for i in (0..n).rev() {
        let mut v = b[i];
        for k in i + 1..n {
            v -= lu[k * n + i] * b[k];
        }
        b[i] = v;
    }
    // x = P^T v
    for k in (0..n).rev() {
        b.swap(k, piv[k]);
    }
}

/// `x_c = v(c)` on the constrained equations `c`.
fn impose(x: &mut [f64], constrained: &[bool], v: impl Fn(usize) -> f64) {
    for (e, (xi, &c)) in x.iter_mut().zip(constrained).enumerate() {
        if c {
            *xi = v(e);
        }
    }
}

/// `sum a_i b_i` with four partial sums (vectorizable).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = a4
        .remainder()
        .iter()
        .zip(b4.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in a4.zip(b4) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
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
    use indentify_laws::{Elastic, Law, Mat4, Vec4};
    use indentify_mesh::CylinderMesher;

    /// The capacitance solve equals the direct one to round-off, for growing and shrinking
    /// sets of prescribed dofs, and needs one factorization for all of them.
    /// A graded unit cylinder under R0's cone.
    /// `x1` equals the reference `x2` to `tol` of its largest entry, and holds the
    /// prescribed values `xbar` exactly on the equations `sys` constrains.
    fn assert_same_solution(
        x1: &[f64],
        x2: &[f64],
        xbar: &[f64],
        sys: &ConstrainedSystem,
        tol: f64,
        what: &str,
    ) {
        let scale = x2.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for e in 0..x2.len() {
            assert!(
                (x1[e] - x2[e]).abs() <= tol * scale,
                "{what}: x[{e}] {} vs {}",
                x1[e],
                x2[e]
            );
            if sys.is_constrained(e) {
                assert_eq!(x1[e], xbar[e], "{what}: prescribed x[{e}]");
            }
        }
    }

    fn small_model(nr: usize, nz: usize) -> Model {
        let mesh = CylinderMesher {
            radius: 1.0,
            height: 1.0,
            nr,
            nz,
            grading_r: 1.2,
            grading_z: 1.2,
        }
        .build()
        .unwrap();
        Model::new(
            mesh,
            Punch::Cone {
                half_angle_deg: 68.0,
            },
        )
        .unwrap()
    }

    #[test]
    fn capacitance_and_direct_solves_agree() {
        let model = small_model(6, 5);
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
            assert_same_solution(
                &x1,
                &x2,
                &xbar,
                &direct,
                1e-10,
                &format!("{k_active} active"),
            );
        }
        assert!(reusable.capacitance);
        assert_eq!(reusable.factorizations(), 1);
        assert_eq!(direct.factorizations(), 6);
    }

    /// Load control's depth column from the capacitance mode's stored columns (no solve)
    /// equals the column solved by the direct factorization (`K du = 0` on the free
    /// equations, `du = -1` on the prescribed ones) to 1e-10, and its contact stiffness
    /// `1 . S^-1 1` the reactions' sum `-(K v) . du` of the solved column to 1e-10, for
    /// growing and shrinking contact sets; other modes decline.
    #[test]
    fn capacitance_depth_column_equals_the_solved_one() {
        let model = small_model(6, 5);
        let c = [20000.0, 0.3];
        let t = Elastic.tangent(&c, &Vec4::default(), 1.0).unwrap();
        let tangents = vec![t; model.disc.qp.len()];
        let n = model.dofs.n_eq;
        let nc = model.candidates.len();
        let mut reusable = ConstrainedSystem::new(&model).unwrap();
        let mut direct = ConstrainedSystem::new(&model).unwrap();
        for k_active in [1, 3, 4, 2, nc] {
            let active: Vec<bool> = (0..nc).map(|k| k < k_active).collect();
            reusable.set_tangent(&model, &tangents, Some((&c, 1.0)));
            reusable.set_active(&model, &active);
            reusable.factorize(&model).unwrap();
            direct.set_tangent(&model, &tangents, None);
            direct.set_active(&model, &active);
            direct.factorize(&model).unwrap();
            let mut v = vec![0.0; n];
            for k in (0..nc).filter(|&k| active[k]) {
                v[model.dofs.equation(2 * model.candidates[k] + 1).unwrap()] = 1.0;
            }
            let mut col = vec![0.0; n];
            let s1 = reusable.depth_column_capacitance(&v, &mut col).unwrap();
            assert!(
                direct
                    .depth_column_capacitance(&v, &mut col.clone())
                    .is_none()
            );
            let xbar: Vec<f64> = v.iter().map(|x| -x).collect();
            let mut x2 = vec![0.0; n];
            direct.solve_dirichlet(&model, &mut x2, &xbar);
            let mut kv = vec![0.0; n];
            model.pattern.sym_mul_add(direct.k_values(), &v, &mut kv);
            let s2 = -kv.iter().zip(&x2).map(|(a, b)| a * b).sum::<f64>();
            let what = format!("{k_active} active");
            assert_same_solution(&col, &x2, &xbar, &direct, 1e-10, &what);
            assert!(
                s1 > 0.0 && (s1 - s2).abs() <= 1e-10 * s2,
                "{what}: s {s1} vs {s2}"
            );
            // a `v` that is not the prescribed set: declined
            let mut w = v.clone();
            w[(0..n).find(|&e| v[e] == 0.0).unwrap()] = 1.0;
            assert!(reusable.depth_column_capacitance(&w, &mut col).is_none());
        }
        assert_eq!(reusable.factorizations(), 1);
    }

    /// Load control's fused bordered step in the capacitance mode: the arguments it hands
    /// `du_of` equal the products formed from direct solves (`g . du_1 = -(K v) . du_1`
    /// with the step's `du_1`, the stiffness `s = -(K v) . du_2` of the depth column
    /// `du_2`, and `v . K v`) to 1e-10, and its result equals `du_1 + dU du_2` from those
    /// solves to 1e-10 of its largest entry, `xbar - dU` exactly on the prescribed
    /// equations, for growing and shrinking contact sets, with one factorization; the
    /// direct mode and a `v` that is not the prescribed set decline, and an error from
    /// `du_of` is handed back.
    #[test]
    fn fused_bordered_step_equals_the_two_solves() {
        let model = small_model(6, 5);
        let c = [20000.0, 0.3];
        let t = Elastic.tangent(&c, &Vec4::default(), 1.0).unwrap();
        let tangents = vec![t; model.disc.qp.len()];
        let n = model.dofs.n_eq;
        let nc = model.candidates.len();
        let b0: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0)
            .collect();
        let mut reusable = ConstrainedSystem::new(&model).unwrap();
        let mut direct = ConstrainedSystem::new(&model).unwrap();
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        for (round, k_active) in [1, 3, 4, 2, nc].into_iter().enumerate() {
            let active: Vec<bool> = (0..nc).map(|k| k < k_active).collect();
            reusable.set_tangent(&model, &tangents, Some((&c, 1.0)));
            reusable.set_active(&model, &active);
            reusable.factorize(&model).unwrap();
            direct.set_tangent(&model, &tangents, None);
            direct.set_active(&model, &active);
            direct.factorize(&model).unwrap();
            let mut v = vec![0.0; n];
            for k in (0..nc).filter(|&k| active[k]) {
                v[model.dofs.equation(2 * model.candidates[k] + 1).unwrap()] = 1.0;
            }
            // prescribed increments on the active equations (zero elsewhere)
            let xbar: Vec<f64> = (0..n)
                .map(|i| v[i] * 1e-3 * ((i * 31) % 17) as f64)
                .collect();
            // the references: the two direct solves and the products
            let mut du1 = b0.clone();
            direct.solve_dirichlet(&model, &mut du1, &xbar);
            let minus_v: Vec<f64> = v.iter().map(|x| -x).collect();
            let mut du2 = vec![0.0; n];
            direct.solve_dirichlet(&model, &mut du2, &minus_v);
            let mut kv = vec![0.0; n];
            model.pattern.sym_mul_add(direct.k_values(), &v, &mut kv);
            let g_ref = -dot(&kv, &du1);
            let g_scale: f64 = kv.iter().zip(&du1).map(|(a, b)| (a * b).abs()).sum();
            let s_ref = -dot(&kv, &du2);
            let vkv_ref = dot(&v, &kv);
            let du = 0.37 - 0.1 * round as f64;
            let mut x = b0.clone();
            let mut args = (0.0, 0.0, 0.0);
            let got = reusable.solve_bordered(&model, &v, &mut x, &xbar, |g, s, vkv| {
                args = (g, s, vkv);
                Ok::<f64, ()>(du)
            });
            assert_eq!(got, Some(Ok(du)));
            let what = format!("{k_active} active");
            let (g, s, vkv) = args;
            assert!(
                (g - g_ref).abs() <= 1e-10 * g_scale,
                "{what}: g.du1 {g} vs {g_ref}"
            );
            assert!(
                (s - s_ref).abs() <= 1e-10 * s_ref,
                "{what}: s {s} vs {s_ref}"
            );
            assert!(
                (vkv - vkv_ref).abs() <= 1e-12 * vkv_ref.abs(),
                "{what}: v.Kv {vkv} vs {vkv_ref}"
            );
            let expect: Vec<f64> = du1.iter().zip(&du2).map(|(a, b)| a + du * b).collect();
            let xbar_du: Vec<f64> = (0..n)
                .map(|i| if v[i] != 0.0 { xbar[i] - du } else { xbar[i] })
                .collect();
            assert_same_solution(&x, &expect, &xbar_du, &direct, 1e-10, &what);
            // declined: the direct mode, and a `v` that is not the prescribed set
            let mut y = b0.clone();
            assert!(
                direct
                    .solve_bordered(&model, &v, &mut y, &xbar, |_, _, _| Ok::<f64, ()>(0.0))
                    .is_none()
            );
            let mut w = v.clone();
            w[(0..n).find(|&e| v[e] == 0.0).unwrap()] = 1.0;
            assert!(
                reusable
                    .solve_bordered(&model, &w, &mut y, &xbar, |_, _, _| Ok::<f64, ()>(0.0))
                    .is_none()
            );
            assert_eq!(y, b0, "{what}: a declined call leaves b as it was");
            // an error of `du_of` is handed back
            let err = reusable.solve_bordered(&model, &v, &mut y, &xbar, |_, _, _| Err("no"));
            assert_eq!(err, Some(Err("no")));
        }
        assert_eq!(reusable.factorizations(), 1);
    }

    /// With normal-contact frames (rotated dofs, curvature stiffness), the direct, the
    /// capacitance and the preconditioned-CG solves all equal a dense solve of the
    /// physical equations (`t . (K x - b) + d t . x = 0`, `m . x = xbar` at the active
    /// nodes, `K x = b` elsewhere) to 1e-10, and the capacitance mode still factorizes once.
    #[test]
    fn frame_solves_agree_with_a_dense_reference() {
        let model = small_model(6, 5);
        let c = [20000.0, 0.3];
        let t = Elastic.tangent(&c, &Vec4::default(), 1.0).unwrap();
        let tangents = vec![t; model.disc.qp.len()];
        let n = model.dofs.n_eq;
        let b0: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0)
            .collect();
        let nc = model.candidates.len();
        let active: Vec<bool> = (0..nc).map(|k| k < 4).collect();
        let frames: Vec<NodeFrame> = (0..4)
            .map(|k| {
                let node = model.candidates[k];
                let er = model.dofs.equation(2 * node);
                let th = if er.is_some() {
                    0.2 + 0.15 * k as f64
                } else {
                    0.0
                };
                NodeFrame {
                    er,
                    ez: model.dofs.equation(2 * node + 1).unwrap(),
                    t: [th.cos(), th.sin()],
                    m: [-th.sin(), th.cos()],
                    d: if er.is_some() { -300.0 * k as f64 } else { 0.0 },
                    stick: false,
                    slip: 0.0,
                }
            })
            .collect();
        assert!(frames[0].er.is_none() && frames[3].er.is_some());
        let mut xbar = vec![0.0; n];
        for (k, f) in frames.iter().enumerate() {
            xbar[f.ez] = 1e-3 * (k as f64 + 1.0);
        }
        // dense reference
        let mut reference = ConstrainedSystem::new(&model).unwrap();
        reference.set_tangent(&model, &tangents, None);
        let mut k = vec![0.0; n * n];
        for j in 0..n {
            for p in model.pattern.col_ptr[j]..model.pattern.col_ptr[j + 1] {
                let i = model.pattern.row_idx[p];
                k[i * n + j] = reference.k_values()[p];
                k[j * n + i] = reference.k_values()[p];
            }
        }
        let mut a = k.clone();
        let mut rhs = b0.clone();
        for f in &frames {
            match f.er {
                Some(er) => {
                    // t-row: t . (K x - b) + d t . x = 0 in the u_r slot
                    for j in 0..n {
                        a[er * n + j] = f.t[0] * k[er * n + j] + f.t[1] * k[f.ez * n + j];
                    }
                    a[er * n + er] += f.d * f.t[0];
                    a[er * n + f.ez] += f.d * f.t[1];
                    rhs[er] = f.t[0] * b0[er] + f.t[1] * b0[f.ez];
                    // m-row: m . x = xbar in the u_z slot
                    a[f.ez * n..(f.ez + 1) * n].fill(0.0);
                    a[f.ez * n + er] = f.m[0];
                    a[f.ez * n + f.ez] = f.m[1];
                }
                None => {
                    a[f.ez * n..(f.ez + 1) * n].fill(0.0);
                    a[f.ez * n + f.ez] = 1.0;
                }
            }
            rhs[f.ez] = xbar[f.ez];
        }
        let mut piv = vec![0; n];
        dense_lu(&mut a, n, &mut piv).unwrap();
        dense_lu_solve(&a, n, &piv, &mut rhs);
        let check = |x: &[f64], what: &str| {
            let scale = rhs.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for e in 0..n {
                assert!(
                    (x[e] - rhs[e]).abs() <= 1e-10 * scale,
                    "{what}: x[{e}] {} vs {}",
                    x[e],
                    rhs[e]
                );
            }
        };
        let mut capacitance = ConstrainedSystem::new(&model).unwrap();
        let mut direct = ConstrainedSystem::new(&model).unwrap();
        for round in 0..2 {
            capacitance.set_tangent(&model, &tangents, Some((&c, 1.0)));
            capacitance.set_active(&model, &active);
            capacitance.set_frames(&frames);
            capacitance.factorize(&model).unwrap();
            let mut x = b0.clone();
            capacitance.solve_dirichlet(&model, &mut x, &xbar);
            assert!(capacitance.capacitance);
            check(&x, &format!("capacitance, round {round}"));
            direct.set_tangent(&model, &tangents, None);
            direct.set_active(&model, &active);
            direct.set_frames(&frames);
            direct.factorize(&model).unwrap();
            let mut x = b0.clone();
            direct.solve_dirichlet(&model, &mut x, &xbar);
            check(&x, &format!("direct, round {round}"));
        }
        assert_eq!(capacitance.factorizations(), 1);
        // CG preconditioned by the factor of the vertical (unrotated) system
        let mut inexact = ConstrainedSystem::new(&model).unwrap();
        inexact.set_tangent(&model, &tangents, None);
        inexact.set_active(&model, &active);
        inexact.prepare_inexact(&model).unwrap();
        inexact.set_frames(&frames);
        inexact.set_tangent(&model, &tangents, None);
        inexact.prepare_inexact(&model).unwrap();
        let mut x = b0.clone();
        let its = inexact.solve_inexact(&model, &mut x, &xbar, 1e-13).unwrap();
        assert!(its > 0);
        check(&x, "inexact");
    }

    /// The transposed solve of the adjoint with friction is the transpose of the solve:
    /// `g . x(b, xbar) = V . b + pi . xbar` for any `g`, `b` and sticking values `xbar`
    /// (`(V, pi)` from [`ConstrainedSystem::solve_transposed`] of `g`), with sticking and
    /// slipping (both directions, on a curved frame with `d != 0`) nodes and the axis
    /// node; and it differs from the symmetric solve (the slipping rows matter).
    #[test]
    fn transposed_solve_is_the_adjoint_of_the_solve() {
        let model = small_model(6, 5);
        let c = [20000.0, 0.3];
        let t = Elastic.tangent(&c, &Vec4::default(), 1.0).unwrap();
        let tangents = vec![t; model.disc.qp.len()];
        let n = model.dofs.n_eq;
        let nc = model.candidates.len();
        let active: Vec<bool> = (0..nc).map(|k| k < 5).collect();
        // axis, stick, slip +, slip -, stick
        let frames: Vec<NodeFrame> = (0..5)
            .map(|k| {
                let node = model.candidates[k];
                let er = model.dofs.equation(2 * node);
                let th = if er.is_some() {
                    0.2 + 0.1 * k as f64
                } else {
                    0.0
                };
                let slip = match k {
                    2 => -0.2,
                    3 => 0.1,
                    _ => 0.0,
                };
                NodeFrame {
                    er,
                    ez: model.dofs.equation(2 * node + 1).unwrap(),
                    t: [th.cos(), th.sin()],
                    m: [-th.sin(), th.cos()],
                    d: if slip != 0.0 { -200.0 * k as f64 } else { 0.0 },
                    stick: er.is_some() && slip == 0.0,
                    slip,
                }
            })
            .collect();
        assert!(frames[0].er.is_none() && frames[1].stick && frames[4].stick);
        let mut sys = ConstrainedSystem::new(&model).unwrap();
        sys.set_tangent(&model, &tangents, None);
        sys.set_active(&model, &active);
        sys.set_frames(&frames);
        sys.factorize(&model).unwrap();
        let vec_of = |seed: usize| -> Vec<f64> {
            (0..n)
                .map(|i| (((i + seed) * 7919) % 101) as f64 / 50.0 - 1.0)
                .collect()
        };
        let g = vec_of(3);
        let mut v = g.clone();
        let mut pi = Vec::new();
        sys.solve_transposed(&model, &mut v, &vec![0.0; n], &mut pi);
        let mut plain = g.clone();
        sys.solve_dirichlet(&model, &mut plain, &vec![0.0; n]);
        let diff = v
            .iter()
            .zip(&plain)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(
            diff > 1e-6,
            "the slipping rows change the transposed solve: {diff}"
        );
        for seed in [11, 29] {
            let b = vec_of(seed);
            let mut xbar = vec![0.0; n];
            for (k, f) in frames.iter().enumerate() {
                if let (true, Some(er)) = (f.stick, f.er) {
                    xbar[er] = 1e-3 * (k as f64 + 1.0);
                }
            }
            let mut x = b.clone();
            sys.solve_dirichlet(&model, &mut x, &xbar);
            let lhs: f64 = g.iter().zip(&x).map(|(a, b)| a * b).sum();
            let mut rhs: f64 = v.iter().zip(&b).map(|(a, b)| a * b).sum();
            for (f, p) in frames.iter().zip(&pi) {
                if let (true, Some(er)) = (f.stick, f.er) {
                    rhs += p * xbar[er];
                } else {
                    assert_eq!(*p, 0.0);
                }
            }
            let scale: f64 = g.iter().zip(&x).map(|(a, b)| (a * b).abs()).sum();
            assert!(
                (lhs - rhs).abs() <= 1e-12 * scale,
                "g . x = {lhs} vs V . b + pi . xbar = {rhs}"
            );
        }
    }

    /// Inexact solves preconditioned by an earlier tangent's factor reach the requested
    /// residual with the prescribed values exact, and factorize when CG cannot converge
    /// in time; the result is the direct solve's to the tolerance.
    #[test]
    fn inexact_solves_match_direct_ones() {
        let model = small_model(8, 6);
        let c = [20000.0, 0.3];
        let stiff = Elastic.tangent(&c, &Vec4::default(), 1.0).unwrap();
        let nq = model.disc.qp.len();
        // a "plastic zone": softened tangents in the first elements, by `soft`
        let tangents = |soft: f64| -> Vec<Mat4> {
            (0..nq)
                .map(|q| if q < 9 * 6 { stiff * soft } else { stiff })
                .collect()
        };
        let n = model.dofs.n_eq;
        let b0: Vec<f64> = (0..n)
            .map(|i| ((i * 131) % 61) as f64 / 30.0 - 1.0)
            .collect();
        let xbar: Vec<f64> = (0..n).map(|i| 1e-4 * ((i * 7) % 5) as f64).collect();
        let nc = model.candidates.len();
        let active: Vec<bool> = (0..nc).map(|k| k < 3).collect();
        let mut inexact = ConstrainedSystem::new(&model).unwrap();
        let mut direct = ConstrainedSystem::new(&model).unwrap();
        // the first inexact preparation has no factor yet: it factorizes
        inexact.set_tangent(&model, &tangents(1.0), None);
        inexact.set_active(&model, &active);
        inexact.prepare_inexact(&model).unwrap();
        assert_eq!(inexact.factorizations(), 1);
        let mut x = b0.clone();
        assert_eq!(
            inexact.solve_inexact(&model, &mut x, &xbar, 1e-10).unwrap(),
            0
        );
        for (soft, fallback) in [(0.99, false), (1e-3, true)] {
            let k = tangents(soft);
            inexact.set_tangent(&model, &k, None);
            inexact.set_active(&model, &active);
            inexact.prepare_inexact(&model).unwrap();
            direct.set_tangent(&model, &k, None);
            direct.set_active(&model, &active);
            direct.factorize(&model).unwrap();
            let (mut x1, mut x2) = (b0.clone(), b0.clone());
            let fallbacks = inexact.pcg_fallbacks;
            let its = inexact
                .solve_inexact(&model, &mut x1, &xbar, 1e-10)
                .unwrap();
            direct.solve_dirichlet(&model, &mut x2, &xbar);
            assert_eq!(
                inexact.pcg_fallbacks > fallbacks,
                fallback,
                "soft {soft}: {its} its"
            );
            assert_same_solution(&x1, &x2, &xbar, &direct, 1e-7, &format!("soft {soft}"));
        }
        assert_eq!(inexact.factorizations(), 2);
        assert!(inexact.pcg_iterations > 0);
    }
}
