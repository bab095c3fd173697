//! The contact side of the adjoint sweep and the forward sensitivities: a model's
//! constraint ([`super::Constraint`], the direct solver's piece) with the constrained
//! system of a converged recorded step ([`RecordedContact`]). This is the one interface
//! `crates/adjoint` uses; the system's solve modes stay private to this crate.
//!
//! One step of the reversed-time sweep, as `crates/adjoint` drives it (docs/solver.md):
//!
//! 1. [`RecordedContact::prepare`]: the step's tangent, its active set, the constraint's
//!    frames ([`super::Constraint::recorded_frames`]), the factorization;
//! 2. the body's right-hand side `g = sum_g w B^T (C S - I) mu_{i+1}` (the adjoint crate;
//!    with [`ForceCotangent::Shifted`] less `rho K e_A`);
//! 3. [`RecordedContact::adjoint_solve`]: the constraint's terms of `g` and its values on
//!    the constrained equations ([`super::Constraint::adjoint_rhs`]), the transposed
//!    solve, what the step passes to the one before ([`super::Constraint::adjoint_carry`]);
//! 4. the Gauss-point back-substitution (the adjoint crate; with
//!    [`ForceCotangent::Shifted`] from `V + rho e_A`).
//!
//! A drive that makes the depth an unknown (a prescribed force) borders step 3 with its
//! own row and column: the hook is [`RecordedContact::adjoint_solve`] (docs/solver.md).

use indentify_fe::{FeError, SolveScratch};
use indentify_laws::Mat4;

use super::{Constraint, Step, for_model};
use crate::StepRecord;
use crate::model::Model;
use crate::system::{ConstrainedSystem, NodeFrame};

/// How a constraint takes the cost's `rho = dJ/dF_i` into the adjoint of a step
/// (`F_i = -e_A . f_int`, `e_A` the vertical dofs of the active nodes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ForceCotangent {
    /// As the adjoint's values on the constrained equations (`m . V = rho m_z`), the data
    /// of the transposed solve: vertical and frictionless normal contact.
    Prescribed,
    /// As a shift of the adjoint displacement, `V' = V + rho e_A`, with `rho K e_A` taken
    /// from the right-hand side and zero values on the constrained equations: Coulomb
    /// friction, whose sticking rows tie a step to the previous one.
    Shifted,
}

/// The tangent of a recorded step.
#[derive(Clone, Copy, Debug)]
pub enum StepTangent<'a> {
    /// One tangent at every Gauss point (an affine law), reusable while the parameters
    /// `params` and the step length `dt` (s) stay the same.
    Uniform {
        /// The tangent `C`.
        tangent: &'a Mat4,
        /// The law's parameters.
        params: &'a [f64],
        /// The step length (s).
        dt: f64,
    },
    /// The tangent of every Gauss point (small strain).
    Points(&'a [Mat4]),
    /// The element matrices (lower triangles; finite strain).
    Elements(&'a [[[f64; 16]; 16]]),
}

/// A prescribed value of the forward sensitivities tied to the previous step's
/// displacement variation `du`: `xbar[eq] = coef (t . du_node)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tie {
    /// The prescribed equation.
    pub eq: usize,
    /// The node whose previous variation it reads.
    pub node: usize,
    /// The factor.
    pub coef: f64,
    /// The direction `(r, z)`.
    pub t: [f64; 2],
}

/// The contact constraint of a model with the constrained system of its recorded steps:
/// what the adjoint sweep and the forward sensitivities need of the contact (the same
/// piece as the direct solver's).
#[derive(Debug)]
pub struct RecordedContact<'m> {
    model: &'m Model,
    constraint: Box<dyn Constraint + 'm>,
    system: ConstrainedSystem,
    /// The frames of the prepared step.
    frames: Vec<NodeFrame>,
    /// Scratch: the active set as flags.
    active: Vec<bool>,
    /// The adjoint's values on the constrained equations (zero between solves).
    v_p: Vec<f64>,
    /// The cotangents of the sticking nodes' prescribed values (per frame).
    stick: Vec<f64>,
    /// The prepared step's sensitivity ties.
    ties: Vec<Tie>,
    /// Load control: scratch of the depth column's solve (equations).
    w: Vec<f64>,
    /// The next [`RecordedContact::begin`] keeps a reusable tangent's factorization
    /// (set by [`RecordedContact::exchange_factor`]).
    keep_factor: bool,
}

impl<'m> RecordedContact<'m> {
    /// The constraint of `model`'s contact kind and its system (symbolic analysis once).
    ///
    /// # Errors
    /// [`FeError`] if the symbolic analysis fails.
    pub fn new(model: &'m Model) -> Result<RecordedContact<'m>, FeError> {
        Ok(RecordedContact {
            model,
            constraint: for_model(model),
            system: ConstrainedSystem::new(model)?,
            frames: Vec::new(),
            active: vec![false; model.candidates.len()],
            v_p: vec![0.0; model.dofs.n_eq],
            stick: Vec::new(),
            ties: Vec::new(),
            w: vec![0.0; model.dofs.n_eq],
            keep_factor: false,
        })
    }

    /// Starts a computation from a new system's state (no factorization, no assembly sum,
    /// nothing carried from an earlier sweep): its bits depend on its inputs alone.
    ///
    /// After [`RecordedContact::exchange_factor`], the next `begin` keeps the
    /// factorization of a reusable tangent (a linear law's unconstrained `K`, its
    /// capacitance columns) and forgets everything else: a step under the same key
    /// (parameters, step length, tangent) then needs no factorization and no column
    /// solve, and computes what a fresh system would from the same `K`.
    pub fn begin(&mut self) {
        if std::mem::take(&mut self.keep_factor) {
            self.system.forget_all_but_the_factor();
        } else {
            self.system.forget_factorizations();
        }
        self.constraint.adjoint_reset();
    }

    /// Exchanges this contact's factorization with the one `solver` kept of its last run
    /// (built on the same model; `false`, nothing exchanged, otherwise): a linear law's
    /// factor of the unconstrained tangent and the capacitance columns of every dof its
    /// run prescribed, keyed by the parameters, the step length and the tangent. The next
    /// [`RecordedContact::begin`] keeps it, so that the adjoint sweep or sensitivity pass
    /// of that run's trajectory reuses the forward's factor and columns for the steps
    /// under its key (the last ones: a sweep runs backward) and factorizes the others as
    /// before. The solver receives this contact's last factorization in exchange, which
    /// its next run uses only for a tangent equal bit for bit (so its runs keep their
    /// bits); a factor of another tangent is never used.
    pub fn exchange_factor(&mut self, solver: &mut crate::DirectSolver<'_>) -> bool {
        if !std::ptr::eq(solver.model(), self.model) {
            return false;
        }
        self.system.exchange_factor(solver.system_mut());
        self.keep_factor = true;
        true
    }

    /// Numeric factorizations done so far.
    pub fn factorizations(&self) -> usize {
        self.system.factorizations()
    }

    /// The prepared step's tangent `K = sum w B^T C B` without its constraints (the
    /// values of the model's pattern): the adjoint's all-nodal sweep of an affine law
    /// reads the reactions `(K V)_c` of its constrained rows from it.
    pub fn tangent_values(&self) -> &[f64] {
        self.system.k_values()
    }

    /// Whether [`RecordedContact::prepare`] needs the step's internal force (Coulomb
    /// friction: the reactions and the slipping nodes' curvature stiffness come from it).
    pub fn needs_internal_force(&self) -> bool {
        self.constraint.frames_need_force()
    }

    /// How the cost's `dJ/dF_i` enters the adjoint ([`ForceCotangent`]).
    pub fn force_cotangent(&self) -> ForceCotangent {
        self.constraint.force_cotangent()
    }

    /// Whether the sweep carries a load into the step before the last one swept (it may
    /// then not be skipped).
    pub fn adjoint_pending(&self) -> bool {
        self.constraint.adjoint_pending()
    }

    /// Whether the forward sensitivities of a step read the previous step's displacement
    /// variation ([`RecordedContact::sensitivity_solve`]'s `du_prev`).
    pub fn ties_steps(&self) -> bool {
        self.constraint.ties_steps()
    }

    /// Sets the system of the converged step `rec` at its displacement `u` (all dofs):
    /// the tangent, the active set, the constraint's frames (from the internal force
    /// `f_int`, all dofs, when [`RecordedContact::needs_internal_force`]), and factorizes.
    ///
    /// # Errors
    /// A message if the record does not fit the constraint or the factorization fails.
    pub fn prepare(
        &mut self,
        rec: &StepRecord,
        u: &[f64],
        f_int: Option<&[f64]>,
        tangent: StepTangent<'_>,
    ) -> Result<(), String> {
        let model = self.model;
        match tangent {
            StepTangent::Uniform {
                tangent,
                params,
                dt,
            } => {
                self.system
                    .set_tangent_uniform(model, tangent, (params, dt));
            }
            StepTangent::Points(t) => {
                self.system.set_tangent(model, t, None);
            }
            StepTangent::Elements(ke) => {
                self.system.set_tangent_elements(model, ke);
            }
        }
        self.active.fill(false);
        for &k in &rec.active {
            self.active[k as usize] = true;
        }
        self.system.set_active(model, &self.active);
        (self.constraint).recorded_frames(rec, u, f_int, &mut self.frames)?;
        self.system.set_frames(&self.frames);
        self.system.factorize(model).map_err(|e| e.to_string())
    }

    /// The contact part of one step of the adjoint sweep, on the prepared step `rec`
    /// (displacement `u`) with the cost's `rho = dJ/dF_i`: `g` (equations) holds the
    /// body's right-hand side on entry and the adjoint displacement `V` on exit (the
    /// constraint's terms added, its values on the constrained equations, the transposed
    /// solve); what the step passes to the one before is kept for the next call.
    pub fn adjoint_solve(&mut self, rec: &StepRecord, u: &[f64], rho: f64, g: &mut [f64]) {
        let step = Step {
            rec,
            u,
            frames: &self.frames,
        };
        self.constraint.adjoint_rhs(&step, rho, g, &mut self.v_p);
        // a drive with the depth as an unknown sets `rho` from the step's depth column
        // before this solve (`depth_column`; docs/theory.md §13)
        self.system
            .solve_transposed(self.model, g, &self.v_p, &mut self.stick);
        self.v_p.fill(0.0);
        self.constraint.adjoint_carry(&step, &self.stick);
    }

    /// [`RecordedContact::depth_column`], the cotangent and
    /// [`RecordedContact::adjoint_solve`] of a prepared step under vertical contact in one
    /// solve, where its system is in the capacitance mode (an affine law): `g` (equations)
    /// holds the body's right-hand side on entry and the adjoint displacement on exit,
    /// `rho = rho_of(a, s)` with `a = g . du_U` and `s` the step's Schur complement.
    /// Returns `(rho, s)`, or `None` (nothing changed) elsewhere: the caller then takes
    /// the three steps.
    pub fn adjoint_solve_bordered(
        &mut self,
        rec: &StepRecord,
        u: &[f64],
        g: &mut [f64],
        rho_of: &mut dyn FnMut(f64, f64) -> f64,
    ) -> Option<(f64, f64)> {
        let model = self.model;
        if model.contact != crate::ContactKind::Vertical
            || self.force_cotangent() != ForceCotangent::Prescribed
        {
            return None;
        }
        self.w.fill(0.0);
        for &k in &rec.active {
            if let Some(e) = model.dofs.equation(2 * model.candidates[k as usize] + 1) {
                self.w[e] = 1.0;
            }
        }
        let out = self.system.solve_transposed_bordered(&self.w, g, rho_of)?;
        let step = Step {
            rec,
            u,
            frames: &self.frames,
        };
        self.stick.clear();
        self.constraint.adjoint_carry(&step, &self.stick);
        Some(out)
    }

    /// Load control's depth column of the prepared step `rec` (docs/theory.md §13): the
    /// variation `du_U = w - v` (equations) of the step's displacement per unit depth
    /// increment with everything before the step held, the forward's own bordered column
    /// (`v`: 1 on the active candidates' vertical equations, `K w = K v` with the
    /// constrained equations held at zero), into `col`; `kv` (equations) is scratch.
    /// Returns the Schur complement `s = dF/dU = -(K v) . du_U` (N/mm), the step's
    /// contact stiffness.
    pub fn depth_column(&mut self, rec: &StepRecord, col: &mut [f64], kv: &mut [f64]) -> f64 {
        let model = self.model;
        // `v` in `col`
        col.fill(0.0);
        for &k in &rec.active {
            if let Some(e) = model.dofs.equation(2 * model.candidates[k as usize] + 1) {
                col[e] = 1.0;
            }
        }
        // an affine law's capacitance system gives the column without a solve (and
        // without `K v`)
        self.w.copy_from_slice(col);
        if let Some(s) = self.system.depth_column_capacitance(&self.w, col) {
            return s;
        }
        kv.fill(0.0);
        model.pattern.sym_mul_add(self.system.k_values(), col, kv);
        self.w.copy_from_slice(kv);
        // `v_p` is zero between solves: the constrained equations held at zero
        self.system.solve_dirichlet(model, &mut self.w, &self.v_p);
        for (c, w) in col.iter_mut().zip(&self.w) {
            *c = w - *c;
        }
        -kv.iter().zip(col.iter()).map(|(a, b)| a * b).sum::<f64>()
    }

    /// Load control with a constraint that ties steps (Coulomb friction; docs/theory.md
    /// §13): on the prepared step `rec` (displacement `u`, all dofs), before
    /// [`RecordedContact::adjoint_solve`], what the load the later steps carry into it
    /// makes of a unit depth increment, its depth column `col` (equations, from
    /// [`RecordedContact::depth_column`]) held: the part of the bordered scalar `a_i`
    /// beside the body's `g . du_U` (0 for other constraints).
    pub fn adjoint_depth(&self, rec: &StepRecord, u: &[f64], col: &[f64]) -> f64 {
        let step = Step {
            rec,
            u,
            frames: &self.frames,
        };
        self.constraint.adjoint_depth(&step, col)
    }

    /// Forms the prescribed values of the prepared step `rec` (displacement `u`) that
    /// depend on the previous step `prev` (its record and displacement; `None` for the
    /// first step), for [`RecordedContact::sensitivity_solve`].
    pub fn prepare_sensitivities(
        &mut self,
        rec: &StepRecord,
        u: &[f64],
        prev: Option<(&StepRecord, &[f64])>,
    ) {
        self.ties.clear();
        let step = Step {
            rec,
            u,
            frames: &self.frames,
        };
        self.constraint
            .sensitivity_ties(&step, prev, &mut self.ties);
    }

    /// The work space of one [`RecordedContact::sensitivity_solve`] (one per thread).
    pub fn solve_scratch(&self) -> SolveScratch {
        self.system.solve_scratch()
    }

    /// One parameter's solve of the forward sensitivities on the prepared step: `b`
    /// (equations) holds the right-hand side on entry and the displacement variation on
    /// exit, with the constrained equations prescribed (zero, or tied to the previous
    /// step's variation `du_prev`, all dofs; read only when
    /// [`RecordedContact::ties_steps`]). `xbar` (equations) is the caller's scratch, zero
    /// on entry and exit. Several threads may solve at once, each with its own `xbar`
    /// and `scratch` (from [`RecordedContact::solve_scratch`]): the same bits.
    pub fn sensitivity_solve(
        &self,
        b: &mut [f64],
        du_prev: &[f64],
        xbar: &mut [f64],
        scratch: &mut SolveScratch,
    ) {
        for t in &self.ties {
            let (n, d) = (t.node, du_prev);
            xbar[t.eq] = t.coef * (t.t[0] * d[2 * n] + t.t[1] * d[2 * n + 1]);
        }
        self.system
            .solve_dirichlet_with(self.model, b, xbar, scratch);
        for t in &self.ties {
            xbar[t.eq] = 0.0;
        }
    }

    /// [`RecordedContact::sensitivity_solve`] of `k` parameters at once: `b` holds their
    /// right-hand sides as the columns of a column-major `n_eq x k` block on entry and
    /// their displacement variations on exit, column `c`'s constrained equations tied to
    /// `du_prev(c)` (read only when [`RecordedContact::ties_steps`]); `xbar` (`n_eq x k`)
    /// is the caller's scratch, zero on entry and exit. The factor is read once for the
    /// `k` solves; each column gets the bits [`RecordedContact::sensitivity_solve`] gives
    /// it.
    ///
    /// # Panics
    /// If `b` or `xbar` is not a whole number of columns of `n_eq`, or they differ in
    /// length.
    pub fn sensitivity_solve_multi<'a>(
        &self,
        b: &mut [f64],
        du_prev: impl Fn(usize) -> &'a [f64],
        xbar: &mut [f64],
        scratch: &mut SolveScratch,
    ) {
        let n = self.model.dofs.n_eq;
        assert!(n > 0 && b.len() % n == 0, "whole columns of the equations");
        let k = b.len() / n;
        for (c, xc) in xbar.chunks_exact_mut(n).enumerate().take(k) {
            if self.ties.is_empty() {
                break;
            }
            let d = du_prev(c);
            for t in &self.ties {
                let nd = t.node;
                xc[t.eq] = t.coef * (t.t[0] * d[2 * nd] + t.t[1] * d[2 * nd + 1]);
            }
        }
        self.system
            .solve_dirichlet_multi(self.model, b, xbar, k, scratch);
        for xc in xbar.chunks_exact_mut(n) {
            for t in &self.ties {
                xc[t.eq] = 0.0;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ContactKind, DirectSolver, Punch, Schedule, SolverOptions, trapezoid};
    use indentify_laws::{Elastic, Law, LawMaterial, Vec4};
    use indentify_mesh::CylinderMesher;

    /// A recorded step's frames go into the workspace's own buffer
    /// ([`Constraint::recorded_frames`]): preparing the steps of a run a second time, the
    /// buffer holds every step's frames at the same address (no allocation per step),
    /// and the same frames as the first time; frictionless normal contact and Coulomb
    /// friction (vertical contact has none).
    #[test]
    fn recorded_frames_fill_the_workspace_buffer() {
        for kind in [
            ContactKind::Normal,
            ContactKind::normal_with_friction(0.2).unwrap(),
        ] {
            let mesh = CylinderMesher {
                radius: 4.0,
                height: 4.0,
                nr: 6,
                nz: 6,
                grading_r: 1.45,
                grading_z: 1.45,
            }
            .build()
            .unwrap();
            let model = Model::with_contact(mesh, Punch::Sphere { radius: 1.0 }, kind).unwrap();
            let c = [1e5, 0.3];
            let schedule = Schedule::from_segments(&trapezoid(0.05, 1.0, 1.0, 1.0, 3)).unwrap();
            let opts = SolverOptions {
                record_fields: true,
                ..SolverOptions::default()
            };
            let traj = DirectSolver::new(&model)
                .unwrap()
                .run(&LawMaterial(&Elastic), &c, &schedule, &opts)
                .unwrap();
            let mut rc = RecordedContact::new(&model).unwrap();
            let mut f_int = vec![0.0; model.disc.n_dofs()];
            let mut pass = |rc: &mut RecordedContact<'_>| {
                let mut out = Vec::new();
                for (i, rec) in traj.steps.iter().enumerate() {
                    let f = &traj.fields[i + 1];
                    let ct = Elastic.tangent(&c, &Vec4::ZERO, rec.dt).unwrap();
                    model.disc.internal_force(&f.sigma, &mut f_int);
                    let tangent = StepTangent::Uniform {
                        tangent: &ct,
                        params: &c,
                        dt: rec.dt,
                    };
                    rc.prepare(rec, &f.u, Some(&f_int), tangent).unwrap();
                    out.push((rc.frames.as_ptr(), rc.frames.clone()));
                }
                out
            };
            let first = pass(&mut rc);
            let again = pass(&mut rc);
            let most = again.iter().map(|(_, f)| f.len()).max().unwrap_or(0);
            assert!(most > 1, "{kind:?}: no step with frames");
            let at = again[0].0;
            for (i, ((p, f), (_, f0))) in again.iter().zip(&first).enumerate() {
                assert_eq!(*p, at, "{kind:?}: step {i}'s frames in a new buffer");
                assert!(f == f0, "{kind:?}: step {i}'s frames differ");
            }
        }
    }
}
