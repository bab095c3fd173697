//! Exact discrete adjoint and forward sensitivities of the indentation direct problem.
//!
//! From a [`Trajectory`] recorded by [`indentify_contact::DirectSolver`], [`Adjoint::gradient`]
//! sweeps the steps in reversed time (docs/theory.md §3, paper §3) and returns `dJ/dc` for any
//! `dJ/dF_i`; [`Adjoint::sensitivities`] differentiates the scheme forward and returns
//! the Jacobian `dF_i/dc`. Both are exact for the discrete scheme (active sets held at their
//! converged values) and use the same constrained tangents as the forward run.
//!
//! Derivation (docs/theory.md): linearizing step i with the active set fixed gives, per
//! Gauss point, `dsigma_i = C_i (B du_i + q_i)` with `q_i = y_{i-1} - R_i dc`,
//! `y_i = S dsigma_i - B du_i` (minus the viscoplastic-strain sensitivity),
//! `R_i = dr_i/dc = dS/dc (sigma_i - sigma_{i-1}) + dt_i dg/dc(sigma_i)`, and
//! `K_i du_i = -sum_g w B^T C_i q_i` on the free dofs with `du_i = 0` on the active contact
//! dofs; `dF_i = -sum_{k in A_i} (sum_g w B^T dsigma_i)_k`. Transposing, with `mu_{I+1} = 0`:
//! `K_i V_i = sum_g w B^T (C_i S - I) mu_{i+1}` with `V_i = dJ/dF_i` on `A_i`;
//! `mu_i = C_i (S mu_{i+1} - B V_i)`; `dJ/dc = -sum_i sum_g w mu_i . R_i`.
//!
//! The contact enters each step through the model's constraint, the direct solver's own
//! piece, as [`RecordedContact`] shows it: the step's constrained system (frames of the
//! active nodes under normal contact), the constraint's part of the adjoint's
//! right-hand side and its values on the constrained dofs (vertical: `V = rho` on the
//! active dofs; normal: `m . V = rho m_z` and the curvature source; Coulomb friction: the
//! `rho e_A` shift and the sticking ties between steps), the transposed solve, and the
//! prescribed values of the sensitivities. One sweep and one sensitivity loop serve every
//! contact kind: a new constraint brings its adjoint in its own file in
//! `crates/contact/src/constraint/` (docs/solver.md).
//!
//! Finite strain ([`indentify_contact::Kinematics::Finite`]): the same recursion with the
//! Gauss-point law in log-strain space and `B` replaced by the step's
//! `G_i = P(C(u_i)) B_L(u_i)`, the stiffness by the forward's consistent tangent
//! (material and geometric parts), and `dF_i` by the variation of the internal force
//! `K_i du_i + sum_g w0 G_i^T C_i q_i` (`finite.rs`, docs/validation-finite-strain.md).

mod affine;
pub mod check;
mod compliant;
mod finite;
mod load;
mod material;
mod nodal;
mod nodal_sens;
mod reuse;

pub use compliant::{FrameGradient, FrameIndex};
pub use load::{LoadReplay, LoadSensitivities};

use indentify_contact::{
    DirectSolver, ForceCotangent, Model, RecordedContact, Schedule, SolverOptions, StepFields,
    StepRecord, StepTangent, Trajectory,
};
use indentify_fe::dofs::NO_EQ;
use indentify_laws::{Law, LawError, Mat4, Material, Vec4};

/// Errors of the adjoint and sensitivity computations.
#[derive(Debug, thiserror::Error)]
pub enum AdjointError {
    /// The trajectory was run without recording fields.
    #[error(
        "the trajectory has no recorded fields ({fields} for {steps} steps): run the direct problem with record_fields = true"
    )]
    NotRecorded {
        /// Recorded field sets.
        fields: usize,
        /// Steps.
        steps: usize,
    },
    /// `dJ/dF` has the wrong length.
    #[error("dJ/dF has {got} entries but the trajectory has {expected} steps")]
    Length {
        /// Expected length.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// The law is not differentiable at these parameters.
    #[error(transparent)]
    NotDifferentiable(#[from] LawError),
    /// A tangent could not be formed or factorized at a step.
    #[error("step {step} (t = {t} s): {reason}")]
    Step {
        /// Step index in the trajectory.
        step: usize,
        /// Time (s).
        t: f64,
        /// What failed.
        reason: String,
    },
    /// Replaying a checkpointed segment failed or did not reproduce the run.
    #[error("checkpoint replay: {0}")]
    Replay(String),
    /// Setting up the linear system failed.
    #[error(transparent)]
    Fe(#[from] indentify_fe::FeError),
}

/// Result of an adjoint sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Gradient {
    /// `dJ/dc_k` in the law's parameter order.
    pub dj_dc: Vec<f64>,
    /// Wall time of the sweep (s).
    pub seconds: f64,
    /// Numeric factorizations the sweep needed.
    pub factorizations: usize,
}

/// Result of the forward sensitivity computation.
#[derive(Clone, Debug, PartialEq)]
pub struct Sensitivities {
    /// `dF_i/dc_k`: one row per trajectory step, one column per parameter.
    pub df_dc: Vec<Vec<f64>>,
    /// Wall time (s).
    pub seconds: f64,
}

impl Sensitivities {
    /// `J^T rho`: the gradient of a cost with `dJ/dF_i = rho_i`.
    pub fn transpose_mul(&self, rho: &[f64]) -> Vec<f64> {
        let np = self.df_dc.first().map_or(0, |r| r.len());
        let mut g = vec![0.0; np];
        for (row, r) in self.df_dc.iter().zip(rho) {
            for (gk, d) in g.iter_mut().zip(row) {
                *gk += r * d;
            }
        }
        g
    }
}

/// The forward run with which [`Adjoint::gradient_replayed`] replays a checkpointed
/// trajectory: the solver (built on the adjoint's model), and the schedule and options of
/// the recorded run.
#[derive(Debug)]
pub struct Replay<'a, 'm> {
    /// The direct solver on the adjoint's model.
    pub solver: &'a mut DirectSolver<'m>,
    /// The schedule of the recorded run.
    pub schedule: &'a Schedule,
    /// The options of the recorded run (with its `checkpoint_every`).
    pub opts: &'a SolverOptions,
}

/// Workspace for adjoint sweeps and sensitivities on one model (borrowed once, at
/// construction; symbolic analysis once).
#[derive(Debug)]
pub struct Adjoint<'m> {
    model: &'m Model,
    /// The model's contact constraint with the system of each recorded step.
    contact: RecordedContact<'m>,
    tangents: Vec<Mat4>,
    field_a: Vec<Vec4>,
    field_b: Vec<Vec4>,
    strain: Vec<[f64; 4]>,
    full: Vec<f64>,
    eq: Vec<f64>,
    /// Scratch of all dofs (finite strain, [`ForceCotangent::Shifted`]: `-rho e_A`).
    e_a: Vec<f64>,
    /// The step's finite-strain operators (`Kinematics::Finite` only).
    finite: Option<finite::FiniteStep>,
    /// The parameters a sensitivity pass skips (`true`: its column is never formed and
    /// stays zero); empty outside [`Adjoint::sensitivities_of`].
    skip: Vec<bool>,
    /// The one-pass sweep step of a law with one tangent ([`affine`]).
    fused: affine::Fused,
    /// Whether sweeps use it ([`Adjoint::set_fused`]), and the all-nodal sweeps.
    fuse: bool,
    /// The all-nodal sweep of a linear material with isotropic blocks (`material/nodal.rs`).
    nodal_mat: material::NodalMat,
    /// Whether a bordered step's scalar takes the later sticking ties' depth term
    /// ([`Adjoint::set_friction_depth_term`]; always, outside tests).
    depth_ties: bool,
    /// Whether the last forward sensitivity pass ran all-nodal (`nodal_sens.rs`).
    nodal_sens: bool,
    /// Whether the last Gauss-point sensitivity pass read `dF_i/dc_k` from the force
    /// dofs' rows of the step's tangent ([`ParamStep::solve`]).
    reaction_rows: bool,
    /// Whether a Gauss-point sensitivity pass that reads `dF_i/dc_k` from the tangent's
    /// rows forms the compact finite-strain operators ([`Adjoint::set_compact_finite`]).
    compact_finite: bool,
    /// Whether the last sensitivity pass did.
    compact_used: bool,
    /// Whether a Gauss-point sensitivity pass solves a step's parameters together
    /// ([`Adjoint::set_multi_solve`]).
    multi_solve: bool,
    /// Whether the last one did.
    multi_used: bool,
}

impl<'m> Adjoint<'m> {
    /// Prepares the workspace for `model`, which it keeps for every sweep.
    ///
    /// # Errors
    /// [`AdjointError::Fe`] if the symbolic analysis fails.
    pub fn new(model: &'m Model) -> Result<Adjoint<'m>, AdjointError> {
        let finite = (model.kinematics == indentify_contact::Kinematics::Finite)
            .then(|| finite::FiniteStep::new(model));
        let nq = model.disc.n_qp();
        Ok(Adjoint {
            model,
            contact: RecordedContact::new(model)?,
            tangents: vec![Mat4::ZERO; nq],
            field_a: vec![Vec4::ZERO; nq],
            field_b: vec![Vec4::ZERO; nq],
            strain: vec![[0.0; 4]; nq],
            full: vec![0.0; model.disc.n_dofs()],
            eq: vec![0.0; model.dofs.n_eq],
            e_a: Vec::new(),
            finite,
            skip: Vec::new(),
            fused: affine::Fused::default(),
            fuse: true,
            nodal_mat: material::NodalMat::default(),
            depth_ties: true,
            nodal_sens: false,
            reaction_rows: false,
            compact_finite: true,
            compact_used: false,
            multi_solve: true,
            multi_used: false,
        })
    }

    /// Whether the sweeps of a law with one tangent at every Gauss point (elasticity,
    /// Maxwell) under small strain visit the points once per step (`true`, the default)
    /// or twice, in the general form every law takes, and whether a linear material with
    /// isotropic blocks (`Prony`) sweeps all-nodal where it may (`material/nodal.rs`) or
    /// visits the points (for comparisons and measurements: the gradients agree to
    /// round-off). The forward sensitivities of a law with one isotropic tangent run
    /// all-nodal under the same switch (`nodal_sens.rs`; the columns agree to round-off).
    pub fn set_fused(&mut self, on: bool) {
        self.fuse = on;
    }

    /// Drops (`false`) the later sticking ties' depth term from the bordered steps' scalar
    /// (Coulomb friction under load control or through the frame; docs/theory.md §13):
    /// only so that a test can show the gradient is wrong without it.
    #[doc(hidden)]
    pub fn set_friction_depth_term(&mut self, on: bool) {
        self.depth_ties = on;
    }

    /// Whether a Gauss-point sensitivity pass under finite strain that reads `dF_i/dc_k`
    /// from the tangent's rows forms per point the compact `G = P L(F)` (`true`, the
    /// default: `finite.rs`) or `B_L` and `P` as the sweeps do (for comparisons and
    /// measurements: the columns agree to round-off).
    #[doc(hidden)]
    pub fn set_compact_finite(&mut self, on: bool) {
        self.compact_finite = on;
    }

    /// Whether a Gauss-point sensitivity pass solves the parameters' systems of a step in
    /// one pass over the factor (`true`, the default: each parameter's column the same
    /// bits) or one parameter after the other (for comparisons and measurements).
    #[doc(hidden)]
    pub fn set_multi_solve(&mut self, on: bool) {
        self.multi_solve = on;
    }

    /// Whether the last sensitivity pass solved the parameters of its steps together
    /// (for tests and measurements).
    #[doc(hidden)]
    pub fn last_pass_multi_solve(&self) -> bool {
        self.multi_used
    }

    /// Whether the last sensitivity pass formed the compact finite-strain operators (for
    /// tests and measurements).
    #[doc(hidden)]
    pub fn last_pass_compact_finite(&self) -> bool {
        self.compact_used
    }

    /// Starts a reversed-time sweep: `mu = 0`, nothing kept from an earlier one.
    fn begin_sweep(&mut self) {
        self.field_a.fill(Vec4::ZERO);
        self.fused.begin();
    }

    /// Forms `C_i` at every Gauss point and sets the system of step `i` (tangent, active
    /// set, the constraint's frames from the step's displacement `u1`), factorized. With
    /// `one` and a law with one tangent, only `self.tangents[0]` is set (the fused pass
    /// reads no other).
    fn prepare_step(
        &mut self,
        law: &dyn Law,
        c: &[f64],
        rec: &StepRecord,
        (sigma1, u1): (&[Vec4], &[f64]),
        i: usize,
        one: bool,
    ) -> Result<(), AdjointError> {
        let model = self.model;
        let fail = |reason: String| AdjointError::Step {
            step: i,
            t: rec.t,
            reason,
        };
        // the law's tangent (one for every point when it does not depend on the state)
        let uniform = self.finite.is_none() && law.is_linear();
        if uniform {
            let ct = law
                .tangent(c, &Vec4::ZERO, rec.dt)
                .map_err(|f| fail(f.reason))?;
            if one {
                self.tangents[0] = ct;
            } else {
                self.tangents.fill(ct);
            }
        } else {
            for (t, s) in self.tangents.iter_mut().zip(sigma1) {
                *t = law
                    .tangent(c, s, rec.dt)
                    .map_err(|f| fail(f.reason.clone()))?;
            }
        }
        if let Some(fs) = self.finite.as_mut() {
            // finite strain: the element tangents at u1 from the law's in log space
            fs.prepare(model, u1, sigma1, &self.tangents)
                .map_err(fail)?;
        }
        // with friction the frames' reactions come from the converged stresses
        let f_int = if self.contact.needs_internal_force() {
            force_into(model, self.finite.as_ref(), sigma1, &mut self.full);
            Some(self.full.as_slice())
        } else {
            None
        };
        let tangent = match &self.finite {
            Some(fs) => StepTangent::Elements(&fs.ke),
            None if uniform => StepTangent::Uniform {
                tangent: &self.tangents[0],
                params: c,
                dt: rec.dt,
            },
            None => StepTangent::Points(&self.tangents),
        };
        self.contact.prepare(rec, u1, f_int, tangent).map_err(fail)
    }

    /// Scatters `self.eq` into the full dof vector `self.full` ([`expand_into`]).
    fn expand(&mut self) {
        let model = self.model;
        expand_into(model, &self.eq, &mut self.full);
    }

    /// `self.full = sum_g w B^T field_b` ([`force_into`]).
    fn force_of_field_b(&mut self) {
        let model = self.model;
        force_into(model, self.finite.as_ref(), &self.field_b, &mut self.full);
    }

    /// `self.strain = B self.full` ([`strains_into`]).
    fn strains_of_full(&mut self) {
        let model = self.model;
        strains_into(model, self.finite.as_ref(), &self.full, &mut self.strain);
    }

    /// Restricts `self.full` to equations into `self.eq`.
    fn restrict(&mut self) {
        let model = self.model;
        model.dofs.restrict(&self.full, &mut self.eq);
    }

    /// The adjoint gradient `dJ/dc` for a cost with `dJ/dF_i = dj_df[i]` at each step of
    /// `traj` (0 for sub-steps the cost does not see).
    ///
    /// # Errors
    /// [`AdjointError::NotRecorded`], [`AdjointError::Length`],
    /// [`AdjointError::NotDifferentiable`] (e.g. Norton-Hoff with m <= 1), or a step failure.
    pub fn gradient(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        dj_df: &[f64],
    ) -> Result<Gradient, AdjointError> {
        let Some(law) = mat.as_law() else {
            return self.gradient_material(mat, c, traj, dj_df);
        };
        let start = std::time::Instant::now();
        let f0 = self.contact.factorizations();
        check_inputs(law, c, traj, dj_df.len())?;
        // every sweep from a new system's state (no factorization, no assembly sum kept):
        // the gradient depends on its inputs alone, not on what ran before on this workspace
        self.contact.begin();
        let mut sweep = Sweep::new(law, c);
        self.begin_sweep();
        self.begin_nodal(law, c, traj);
        for i in (0..traj.steps.len()).rev() {
            let (rec, s0, s1) = (&traj.steps[i], &traj.fields[i], &traj.fields[i + 1]);
            let step = Recorded {
                i,
                rec,
                f0: s0,
                f1: s1,
                rho: dj_df[i],
                prev_dt: i.checked_sub(1).map(|p| traj.steps[p].dt),
            };
            self.sweep_step(law, c, &mut sweep, &step)?;
        }
        Ok(Gradient {
            dj_dc: sweep.finish(law, c),
            seconds: start.elapsed().as_secs_f64(),
            factorizations: self.contact.factorizations() - f0,
        })
    }

    /// The adjoint gradient of a run recorded with checkpoints instead of fields
    /// ([`SolverOptions::checkpoint_every`]): each segment between checkpoints is replayed
    /// by `solver` (the same deterministic computation), swept backward, and dropped, so
    /// memory holds one segment's fields instead of the whole history.
    ///
    /// # Errors
    /// As [`Adjoint::gradient`]; [`AdjointError::Replay`] if a replay fails or does not
    /// reproduce the recorded steps, or if the replaying solver runs another model than
    /// this adjoint's.
    pub fn gradient_replayed(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        dj_df: &[f64],
        replay: Replay<'_, '_>,
    ) -> Result<Gradient, AdjointError> {
        if traj.fields.len() == traj.steps.len() + 1 {
            return self.gradient(mat, c, traj, dj_df);
        }
        if !std::ptr::eq(replay.solver.model(), self.model) {
            return Err(AdjointError::Replay(
                "the replaying solver runs another model than this adjoint's: build both \
                 from the same Model"
                    .into(),
            ));
        }
        let Some(law) = mat.as_law() else {
            return self.gradient_replayed_material(mat, c, traj, dj_df, replay);
        };
        let Replay {
            solver,
            schedule,
            opts,
        } = replay;
        let start = std::time::Instant::now();
        let f0 = self.contact.factorizations();
        self.contact.begin();
        let n = traj.steps.len();
        if dj_df.len() != n {
            return Err(AdjointError::Length {
                expected: n,
                got: dj_df.len(),
            });
        }
        law.check_params(c)?;
        law.check_differentiable(c)?;
        if traj.checkpoints.first().is_none_or(|cp| cp.steps_done != 0) {
            return Err(AdjointError::NotRecorded {
                fields: traj.fields.len(),
                steps: n,
            });
        }
        let mut sweep = Sweep::new(law, c);
        self.begin_sweep();
        replayed_steps_rev(solver, mat, c, schedule, opts, traj, |g, rec, s0, s1| {
            let step = Recorded {
                i: g,
                rec,
                f0: s0,
                f1: s1,
                rho: dj_df[g],
                prev_dt: g.checked_sub(1).map(|p| traj.steps[p].dt),
            };
            self.sweep_step(law, c, &mut sweep, &step)
        })?;
        Ok(Gradient {
            dj_dc: sweep.finish(law, c),
            seconds: start.elapsed().as_secs_f64(),
            factorizations: self.contact.factorizations() - f0,
        })
    }

    /// One step of the reversed-time sweep: `self.field_a` holds `mu_{i+1}` on entry and
    /// `mu_i` on exit (the contact keeps what the step passes to the one before it).
    fn sweep_step(
        &mut self,
        law: &dyn Law,
        c: &[f64],
        sweep: &mut Sweep,
        step: &Recorded<'_>,
    ) -> Result<(), AdjointError> {
        let Recorded {
            i,
            rec,
            f0,
            f1,
            rho,
            prev_dt,
        } = *step;
        let (sig0, sig1) = (&f0.sigma, &f1.sigma);
        // with mu_{i+1} = 0, no data, no contact and nothing carried, mu_i = 0
        if sweep.mu_zero && rho == 0.0 && rec.active.is_empty() && !self.contact.adjoint_pending() {
            return Ok(());
        }
        sweep.mu_zero = false;
        let shifted = self.contact.force_cotangent() == ForceCotangent::Shifted;
        let fuse = !shifted && self.fuse && self.fusable(law);
        self.prepare_step(law, c, rec, (sig1, &f1.u), i, fuse)?;
        if !(fuse
            && (self.nodal_source(i, rec) || self.fused.take_source(i, rec.dt, &mut self.full)))
        {
            if fuse {
                let t0 = self.tangents[0];
                self.tangents.fill(t0);
            }
            self.adjoint_source(sweep.s, rec, shifted.then_some(rho));
        }
        self.restrict();
        // the constraint's part and the transposed solve: V in self.eq
        let mut eq = std::mem::take(&mut self.eq);
        self.contact.adjoint_solve(rec, &f1.u, rho, &mut eq);
        self.eq = eq;
        self.expand();
        if shifted {
            // V' = V + rho e_A
            for d in force_dofs(self.model, rec) {
                self.full[d] += rho;
            }
        }
        if fuse {
            if !self.nodal_back_substitute(sweep, rec.dt) {
                let next = Self::next_of(law, c, i, prev_dt);
                self.back_substitute_fused(law, c, sweep, (rec.dt, sig0, sig1), next);
            }
        } else {
            self.back_substitute(law, c, sweep, rec.dt, sig0, sig1);
        }
        Ok(())
    }

    /// The body's part of a sweep step's right-hand side into `self.full` (all dofs), from
    /// `mu_{i+1}` in `self.field_a`: `g = sum_g w B^T (C S - I) mu_{i+1}`, and with a
    /// shifted force cotangent `shift = Some(rho)` ([`ForceCotangent::Shifted`]) less
    /// `rho K e_A` (small strain folded into the Gauss-point field,
    /// `B^T [C (S mu - rho B e_A) - mu]`; finite strain `G^T (C S - I) mu - rho K e_A` with
    /// the consistent tangent).
    fn adjoint_source(&mut self, s: Mat4, rec: &StepRecord, shift: Option<f64>) {
        let model = self.model;
        match (shift, self.finite.is_some()) {
            (Some(rho), false) => {
                self.full.fill(0.0);
                for d in force_dofs(model, rec) {
                    self.full[d] = 1.0;
                }
                model.disc.strains(&self.full, &mut self.strain);
                for q in 0..self.field_b.len() {
                    let sm = s.mul_vec(&self.field_a[q]) - Vec4(self.strain[q]) * rho;
                    self.field_b[q] = self.tangents[q].mul_vec(&sm) - self.field_a[q];
                }
                model.disc.internal_force(&self.field_b, &mut self.full);
            }
            (shift, _) => {
                for q in 0..self.field_b.len() {
                    let sm = s.mul_vec(&self.field_a[q]);
                    self.field_b[q] = self.tangents[q].mul_vec(&sm) - self.field_a[q];
                }
                self.force_of_field_b();
                if let (Some(rho), Some(fs)) = (shift, &self.finite) {
                    self.e_a.clear();
                    self.e_a.resize(self.full.len(), 0.0);
                    for d in force_dofs(model, rec) {
                        self.e_a[d] = -rho;
                    }
                    fs.add_k_times(model, &self.e_a, &mut self.full);
                }
            }
        }
    }

    /// The Gauss-point half of a sweep step, from the adjoint displacement `V` in
    /// `self.full`: `mu_i = C (S mu_{i+1} - B V)` into `field_a` (swapped), and
    /// `gradient -= sum w mu_i . R_i` with `R_i = dS/dc (s1 - s0) + dt dg/dc(s1)`; the
    /// `dS/dc` part is accumulated as `M = sum w mu (x) (s1 - s0)` and contracted with
    /// `dS/dc` once at the end.
    fn back_substitute(
        &mut self,
        law: &dyn Law,
        c: &[f64],
        sweep: &mut Sweep,
        dt: f64,
        sig0: &[Vec4],
        sig1: &[Vec4],
    ) {
        let model = self.model;
        self.strains_of_full();
        let s = sweep.s;
        for q in 0..self.field_b.len() {
            let sm = s.mul_vec(&self.field_a[q]);
            let mu = self.tangents[q].mul_vec(&(sm - Vec4(self.strain[q])));
            self.field_b[q] = mu;
            let wmu = mu * model.disc.qp[q].w;
            let ds = sig1[q] - sig0[q];
            for a in 0..4 {
                for b in 0..4 {
                    sweep.m_acc.0[a][b] += wmu[a] * ds[b];
                }
            }
            if sig1[q].max_abs() > 0.0 {
                law.flow_param_derivatives(c, &sig1[q], &mut sweep.dflow);
                for (g, d) in sweep.grad.iter_mut().zip(&sweep.dflow) {
                    *g -= dt * wmu.dot(d);
                }
            }
        }
        std::mem::swap(&mut self.field_a, &mut self.field_b);
    }

    /// Forward sensitivities `dF_i/dc_k` of every step force by direct differentiation.
    ///
    /// # Errors
    /// As [`Adjoint::gradient`].
    pub fn sensitivities(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
    ) -> Result<Sensitivities, AdjointError> {
        self.skip.clear();
        self.sensitivities_masked(mat, c, traj)
    }

    /// [`Adjoint::sensitivities`] of the parameters `columns` only (indices into `c`, in
    /// any order): the other parameters' systems are never solved and their columns of
    /// [`Sensitivities::df_dc`] stay zero. Each parameter's sensitivity is its own
    /// recursion on the step's factorized system, so the columns computed are the same
    /// bits as those of [`Adjoint::sensitivities`] (an identification differentiates its
    /// free parameters only: 4 of R2's 5).
    ///
    /// # Errors
    /// As [`Adjoint::gradient`]; [`AdjointError::Length`] for an index beyond `c`.
    pub fn sensitivities_of(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        columns: &[usize],
    ) -> Result<Sensitivities, AdjointError> {
        if let Some(&k) = columns.iter().find(|&&k| k >= c.len()) {
            return Err(AdjointError::Length {
                expected: c.len(),
                got: k + 1,
            });
        }
        self.skip = (0..c.len()).map(|k| !columns.contains(&k)).collect();
        let out = self.sensitivities_masked(mat, c, traj);
        self.skip.clear();
        out
    }

    /// Whether a Gauss-point sensitivity pass reads the force variations from the force
    /// dofs' rows of the step's tangent ([`ParamStep::solve`]): `Adjoint::set_fused` on
    /// and every candidate's vertical dof with an equation (`set_fused(false)` keeps the
    /// third pass over the Gauss points: `pinned.rs`).
    fn reactions_from_rows(&self) -> bool {
        let model = self.model;
        self.fuse && (model.candidates.iter()).all(|&n| model.dofs.equation(2 * n + 1).is_some())
    }

    /// Whether the running sensitivity pass skips parameter `k`.
    fn skips(&self, k: usize) -> bool {
        self.skip.get(k).copied().unwrap_or(false)
    }

    fn sensitivities_masked(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
    ) -> Result<Sensitivities, AdjointError> {
        let Some(law) = mat.as_law() else {
            return self.sensitivities_material(mat, c, traj);
        };
        let start = std::time::Instant::now();
        let n = traj.steps.len();
        check_inputs(law, c, traj, n)?;
        self.contact.begin();
        // a law with one isotropic tangent under vertical contact: no Gauss-point pass
        self.nodal_sens = false;
        self.reaction_rows = false;
        self.compact_used = false;
        self.multi_used = false;
        if let Some((df_dc, _)) =
            self.sensitivities_nodal(law, c, traj, material::SensDrive::Depth)?
        {
            self.nodal_sens = true;
            return Ok(Sensitivities {
                df_dc,
                seconds: start.elapsed().as_secs_f64(),
            });
        }
        let s = law.compliance(c);
        let np = c.len();
        let mut bufs = self.sens_buffers(np);
        let mut df = vec![vec![0.0; np]; n];
        // `dF_i/dc_k` from the force dofs' rows of the step's tangent where every one has
        // an equation (`set_fused(false)` keeps the Gauss-point pass: `pinned.rs`)
        let reactions = self.reactions_from_rows();
        self.reaction_rows = reactions;
        // the compact finite-strain operators where the tangent's rows give `dF_i/dc_k`
        // (`finite.rs`); every other pass keeps `B_L` and `P`
        let compact = reactions && self.compact_finite;
        if let Some(fs) = self.finite.as_mut() {
            fs.set_compact(compact);
        }
        let done = self.sensitivity_steps(law, c, traj, (&s, reactions), &mut bufs, &mut df);
        if let Some(fs) = self.finite.as_mut() {
            fs.set_compact(false);
        }
        done?;
        self.compact_used = compact && self.finite.is_some();
        Ok(Sensitivities {
            df_dc: df,
            seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// The steps of a Gauss-point sensitivity pass (`sensitivities_masked`): `s` the
    /// compliance, `reactions` whether `dF_i/dc_k` come from the tangent's rows.
    fn sensitivity_steps(
        &mut self,
        law: &dyn Law,
        c: &[f64],
        traj: &Trajectory,
        (s, reactions): (&Mat4, bool),
        bufs: &mut SensBuffers,
        df: &mut [Vec<f64>],
    ) -> Result<(), AdjointError> {
        let model = self.model;
        let np = c.len();
        let SensBuffers {
            y,
            r_field,
            work,
            multi,
        } = bufs;
        multi.cols.clear();
        if self.multi_solve {
            multi.cols.extend((0..np).filter(|&k| !self.skips(k)));
        }
        self.multi_used = multi.cols.len() > 1;
        let ne = model.dofs.n_eq;
        multi.block.resize(ne * multi.cols.len(), 0.0);
        multi.xbar.clear();
        multi.xbar.resize(ne * multi.cols.len(), 0.0);
        let mut cons = Vec::new();
        for i in 0..traj.steps.len() {
            let rec = &traj.steps[i];
            let f1 = &traj.fields[i + 1];
            self.prepare_step(law, c, rec, (&f1.sigma, &f1.u), i, false)?;
            // the prescribed values tied to the previous step (friction's sticking nodes)
            let prev = i
                .checked_sub(1)
                .map(|p| (&traj.steps[p], traj.fields[i].u.as_slice()));
            self.contact.prepare_sensitivities(rec, &f1.u, prev);
            let (sig0, sig1) = (&traj.fields[i].sigma, &f1.sigma);
            residual_param_field(law, c, sig0, sig1, rec.dt, r_field);
            if reactions {
                nodal_sens::active_equations(model, rec, &mut cons);
            }
            let step = ParamStep {
                model,
                tangents: &self.tangents,
                contact: &self.contact,
                finite: self.finite.as_ref(),
                s,
                r_field: r_field.as_slice(),
                np,
                rec,
                border: None,
                reactions: reactions.then_some(cons.as_slice()),
            };
            let skip = &self.skip;
            let active = |k: usize| !skip.get(k).copied().unwrap_or(false);
            // in parallel on a pool's worker (an identification's tasks, or a caller's
            // `ThreadPool::install`); from any other thread the parameters' work is too
            // short to gain from being handed to the pool (measured: no gain on 2 threads)
            let on_pool = rayon::current_thread_index().is_some();
            let par = np > 1 && on_pool && rayon::current_num_threads() > 1;
            let each = |f: &ParamFn<'_>,
                        y: &mut [Vec<Vec4>],
                        dfi: &mut [f64],
                        work: &mut [ParamWork]| {
                let one =
                    |(k, ((yk, dfk), w)): (usize, ((&mut Vec<Vec4>, &mut f64), &mut ParamWork))| {
                        if active(k) {
                            f(k, yk, dfk, w);
                        }
                    };
                if par {
                    use rayon::prelude::*;
                    y.par_iter_mut()
                        .zip(dfi.par_iter_mut())
                        .zip(work.par_iter_mut())
                        .enumerate()
                        .with_max_len(1)
                        .for_each(one);
                } else {
                    y.iter_mut()
                        .zip(dfi.iter_mut())
                        .zip(work.iter_mut())
                        .enumerate()
                        .for_each(one);
                }
            };
            if multi.cols.len() < 2 {
                each(
                    &|k, yk, dfk, w| step.solve(k, yk, dfk, w),
                    y,
                    &mut df[i],
                    work,
                );
                continue;
            }
            // the parameters' right-hand sides, their solves in one pass over the factor
            // (each column the bits of its own solve), then each parameter's remainder
            each(&|k, yk, _, w| step.rhs(k, yk, w), y, &mut df[i], work);
            let ne = model.dofs.n_eq;
            for (col, &k) in multi.block.chunks_exact_mut(ne).zip(&multi.cols) {
                col.copy_from_slice(&work[k].eq);
            }
            let works = &*work;
            let cols = &multi.cols;
            self.contact.sensitivity_solve_multi(
                &mut multi.block,
                |c| works[cols[c]].du_prev.as_slice(),
                &mut multi.xbar,
                &mut multi.solve,
            );
            for (col, &k) in multi.block.chunks_exact(ne).zip(&multi.cols) {
                work[k].eq.copy_from_slice(col);
            }
            each(
                &|k, yk, dfk, w| step.finish(k, yk, dfk, w),
                y,
                &mut df[i],
                work,
            );
        }
        Ok(())
    }
}

/// One parameter's part of a step of the sensitivity pass: `(k, y_k, dF_i/dc_k, work)`.
type ParamFn<'a> = dyn Fn(usize, &mut Vec<Vec4>, &mut f64, &mut ParamWork) + Sync + 'a;

/// The work space of one parameter's forward sensitivity in a step.
struct ParamWork {
    q: Vec<Vec4>,
    field_b: Vec<Vec4>,
    full: Vec<f64>,
    eq: Vec<f64>,
    strain: Vec<[f64; 4]>,
    /// Finite strain: the displacement variation (all dofs).
    du: Vec<f64>,
    /// The previous step's displacement variation (all dofs), kept when the contact ties
    /// a step to the previous one ([`RecordedContact::ties_steps`]; empty otherwise).
    du_prev: Vec<f64>,
    /// The prescribed values of the solve (equations; zero between solves).
    xbar: Vec<f64>,
    /// Load control: the step's depth variation `dU_i/dc_k` (mm per unit parameter).
    du_depth: f64,
    /// The force dofs' sum of the step's right-hand side ([`ParamStep::rhs`]).
    rhs_a: Option<f64>,
    solve: indentify_fe::SolveScratch,
}

/// A sensitivity pass's buffers for `np` parameters ([`Adjoint::sens_buffers`]).
pub(crate) struct SensBuffers {
    /// Each parameter's stress sensitivity at every Gauss point.
    pub y: Vec<Vec<Vec4>>,
    /// The local residual's parameter derivatives, `nq x np`.
    pub r_field: Vec<Vec4>,
    /// One work space per parameter: given a step's factorized system, the parameters'
    /// solves are independent (the same arithmetic on any thread, so the same bits).
    pub work: Vec<ParamWork>,
    /// The parameters' solves of a step together ([`RecordedContact::sensitivity_solve_multi`]).
    pub multi: MultiCols,
}

/// The block of a step's sensitivity solves, one column per parameter computed.
#[derive(Default)]
pub(crate) struct MultiCols {
    /// The parameters computed (not skipped), in order: column `c` is parameter `cols[c]`.
    cols: Vec<usize>,
    /// The right-hand sides, then the displacement variations (`n_eq x cols.len()`).
    block: Vec<f64>,
    /// The prescribed values (zero between solves).
    xbar: Vec<f64>,
    solve: indentify_fe::SolveScratch,
}

impl Adjoint<'_> {
    /// The buffers of a sensitivity pass for `np` parameters.
    pub(crate) fn sens_buffers(&self, np: usize) -> SensBuffers {
        let nq = self.model.disc.n_qp();
        SensBuffers {
            y: vec![vec![Vec4::ZERO; nq]; np],
            r_field: vec![Vec4::ZERO; nq * np],
            work: (0..np)
                .map(|_| ParamWork::new(self.model, &self.contact))
                .collect(),
            multi: MultiCols::default(),
        }
    }
}

impl ParamWork {
    fn new(model: &Model, contact: &RecordedContact<'_>) -> ParamWork {
        let nq = model.disc.n_qp();
        let nd = model.disc.n_dofs();
        ParamWork {
            q: vec![Vec4::ZERO; nq],
            field_b: vec![Vec4::ZERO; nq],
            full: vec![0.0; nd],
            eq: vec![0.0; model.dofs.n_eq],
            strain: vec![[0.0; 4]; nq],
            du: Vec::new(),
            du_prev: if contact.ties_steps() {
                vec![0.0; nd]
            } else {
                Vec::new()
            },
            xbar: vec![0.0; model.dofs.n_eq],
            du_depth: 0.0,
            rhs_a: None,
            solve: contact.solve_scratch(),
        }
    }
}

/// What a step's forward sensitivities share between the parameters (read only).
struct ParamStep<'a> {
    model: &'a Model,
    tangents: &'a [Mat4],
    /// The step's contact and its factorized system.
    contact: &'a RecordedContact<'a>,
    finite: Option<&'a finite::FiniteStep>,
    s: &'a Mat4,
    /// `R_i e_k` at every point, point-major ([`residual_param_field`]).
    r_field: &'a [Vec4],
    /// Number of parameters.
    np: usize,
    rec: &'a StepRecord,
    /// Load control: the step's depth column and what sets its depth variation
    /// (`load.rs`).
    border: Option<load::Border<'a>>,
    /// The equations of the step's force dofs (the active candidates' vertical dofs),
    /// when `dF_i/dc_k` is read from their rows of the step's tangent (`K du` there less
    /// the right-hand side: [`ParamStep::solve`]) instead of from a third pass over the
    /// Gauss points; under load control and through the frame also the force variation
    /// at the depth held, which sets the depth's ([`load::Border::shift`]). `None` keeps
    /// the passes over the points (`Adjoint::set_fused(false)`, an active dof without an
    /// equation).
    reactions: Option<&'a [usize]>,
}

impl ParamStep<'_> {
    /// Parameter `k`'s step: from `y_{i-1}` in `yk`, `K du = -sum w B^T C q` with
    /// `q = y_{i-1} - R_i e_k` (`du` on the constrained dofs as the contact prescribes:
    /// zero, or tied to the previous step's), `y_i` into `yk` and `dF_i/dc_k` into `dfk`.
    fn solve(&self, k: usize, yk: &mut [Vec4], dfk: &mut f64, w: &mut ParamWork) {
        self.rhs(k, yk, w);
        self.contact
            .sensitivity_solve(&mut w.eq, &w.du_prev, &mut w.xbar, &mut w.solve);
        self.finish(k, yk, dfk, w);
    }

    /// The first part of [`ParamStep::solve`]: the right-hand side
    /// `-sum w B^T C q` (equations) into `w.eq`, and `q`, and the right-hand side's force
    /// dofs' sum into `w.rhs_a` when the tangent's rows give `dF_i/dc_k`.
    fn rhs(&self, k: usize, yk: &[Vec4], w: &mut ParamWork) {
        let (model, np) = (self.model, self.np);
        for (qp, ((q, b), t)) in
            w.q.iter_mut()
                .zip(w.field_b.iter_mut())
                .zip(self.tangents)
                .enumerate()
        {
            *q = yk[qp] - self.r_field[qp * np + k];
            *b = t.mul_vec(q) * -1.0;
        }
        force_into(model, self.finite, &w.field_b, &mut w.full);
        // the right-hand side's force dofs: `delta f = K du - rhs` on every row
        let rhs_a = self
            .reactions
            .map(|_| force_dofs(model, self.rec).map(|d| w.full[d]).sum::<f64>());
        model.dofs.restrict(&w.full, &mut w.eq);
        w.rhs_a = rhs_a;
    }

    /// The rest of [`ParamStep::solve`], from the displacement variation in `w.eq`.
    fn finish(&self, k: usize, yk: &mut [Vec4], dfk: &mut f64, w: &mut ParamWork) {
        let model = self.model;
        let rhs_a = w.rhs_a;
        let shift = self.border.as_ref().map(|b| b.shift(self, k, rhs_a, w));
        expand_into(model, &w.eq, &mut w.full);
        if !w.du_prev.is_empty() {
            w.du_prev.copy_from_slice(&w.full);
            if let Some(du) = shift {
                load::relative_to_punch(model, &mut w.du_prev, du);
            }
        }
        strains_into(model, self.finite, &w.full, &mut w.strain);
        for (qp, y) in yk.iter_mut().enumerate() {
            let bv = Vec4(w.strain[qp]);
            let dsig = self.tangents[qp].mul_vec(&(bv + w.q[qp]));
            w.field_b[qp] = dsig;
            *y = self.s.mul_vec(&dsig) - bv;
        }
        if let (Some(cons), Some(rhs_a)) = (self.reactions, rhs_a) {
            *dfk = match &self.border {
                // a prescribed force varies as prescribed (`dF_i = dP_i`): nothing to form
                Some(b) if b.force_prescribed => b.given[k],
                _ => rhs_a - self.force_rows(cons, &w.eq),
            };
            if let Some(du) = shift {
                w.du_depth = du;
            }
            return;
        }
        delta_force_into(
            model,
            self.finite,
            self.tangents,
            &w.q,
            &mut w.field_b,
            &mut w.full,
            &mut w.du,
        );
        *dfk = -force_dofs(model, self.rec).map(|d| w.full[d]).sum::<f64>();
        if let Some(du) = shift {
            w.du_depth = du;
        }
    }
}

impl ParamStep<'_> {
    /// `(K du)_A`: the rows `cons` of the step's tangent against the displacement
    /// variation `du` (equations). With the right-hand side `rhs` of the step's solve,
    /// `delta f = sum w B^T C (B du + q) = K du + sum w B^T C q = K du - rhs` on every
    /// row (the geometric part in `K` under finite strain), so `dF_i/dc_k = rhs_A -
    /// (K du)_A`: the rows of the force dofs only, instead of a pass over the Gauss
    /// points.
    fn force_rows(&self, cons: &[usize], du: &[f64]) -> f64 {
        let (pat, k) = (&self.model.pattern, self.contact.tangent_values());
        let mut kdu = 0.0;
        for &c in cons {
            kdu += pat.row_dot(k, c, du);
        }
        kdu
    }
}

/// One recorded step as the sweep reads it: its index in the trajectory, its record, the
/// fields before (`f0`) and after (`f1`) it, and the cost's `dJ/dF_i` there.
#[derive(Clone, Copy)]
struct Recorded<'a> {
    i: usize,
    rec: &'a StepRecord,
    f0: &'a StepFields,
    f1: &'a StepFields,
    rho: f64,
    /// The length (s) of the step swept after this one (step `i - 1`), when known.
    prev_dt: Option<f64>,
}

/// Accumulators of one reversed-time sweep.
struct Sweep {
    s: Mat4,
    grad: Vec<f64>,
    /// Scratch: `dg/dc_k` at one Gauss point, every `k`.
    dflow: Vec<Vec4>,
    m_acc: Mat4,
    mu_zero: bool,
}

impl Sweep {
    fn new(law: &dyn Law, c: &[f64]) -> Sweep {
        Sweep {
            s: law.compliance(c),
            grad: vec![0.0; c.len()],
            dflow: vec![Vec4::ZERO; c.len()],
            m_acc: Mat4::ZERO,
            mu_zero: true,
        }
    }

    /// Adds the `dS/dc` contraction and returns `dJ/dc`.
    fn finish(mut self, law: &dyn Law, c: &[f64]) -> Vec<f64> {
        for (k, g) in self.grad.iter_mut().enumerate() {
            let dsk = law.compliance_derivative(c, k);
            let mut acc = 0.0;
            for a in 0..4 {
                for b in 0..4 {
                    acc += dsk.0[a][b] * self.m_acc.0[a][b];
                }
            }
            *g -= acc;
        }
        self.grad
    }
}

/// The dofs whose internal force sums to `-F_i` at step `rec`: the vertical dofs of its
/// active candidates (`e_A`).
fn force_dofs<'a>(model: &'a Model, rec: &'a StepRecord) -> impl Iterator<Item = usize> + 'a {
    rec.active
        .iter()
        .map(|&k| 2 * model.candidates[k as usize] + 1)
}

/// Scatters an equation vector `eq` into the full dof vector `full` (0 on fixed dofs).
fn expand_into(model: &Model, eq: &[f64], full: &mut [f64]) {
    for (d, &e) in model.dofs.eq.iter().enumerate() {
        full[d] = if e == NO_EQ { 0.0 } else { eq[e as usize] };
    }
}

/// `full = sum_g w B^T v` (`G_i` in place of `B` under finite strain).
fn force_into(model: &Model, finite: Option<&finite::FiniteStep>, v: &[Vec4], full: &mut [f64]) {
    match finite {
        None => model.disc.internal_force(v, full),
        Some(fs) => fs.force(model, v, full),
    }
}

/// `strain = B full` (`G_i` in place of `B` under finite strain).
fn strains_into(
    model: &Model,
    finite: Option<&finite::FiniteStep>,
    full: &[f64],
    strain: &mut [[f64; 4]],
) {
    match finite {
        None => model.disc.strains(full, strain),
        Some(fs) => fs.strains(model, full, strain),
    }
}

/// The variation of the internal force into `full`, which holds the displacement
/// variation `du` on entry, with `field_b` holding `dsigma = C (B du + q)`:
/// `sum_g w B^T dsigma` (small strain), `K du + sum_g w0 G^T C q` under finite strain
/// (geometric part included; `field_b` is overwritten with `C q`, `du` is scratch).
fn delta_force_into(
    model: &Model,
    finite: Option<&finite::FiniteStep>,
    tangents: &[Mat4],
    q: &[Vec4],
    field_b: &mut [Vec4],
    full: &mut [f64],
    du: &mut Vec<f64>,
) {
    match finite {
        None => model.disc.internal_force(field_b, full),
        Some(fs) => {
            for (b, (t, q)) in field_b.iter_mut().zip(tangents.iter().zip(q)) {
                *b = t.mul_vec(q);
            }
            fs.delta_force(model, field_b, full, du);
        }
    }
}

/// `R_i e_k = dr/dc_k` at every Gauss point of a step, every `k`, into `out` (point-major:
/// `out[q * np + k]`), as [`Law::residual_param_derivative`] gives them.
fn residual_param_field(
    law: &dyn Law,
    c: &[f64],
    sig0: &[Vec4],
    sig1: &[Vec4],
    dt: f64,
    out: &mut [Vec4],
) {
    let np = c.len();
    for ((r, s0), s1) in out.chunks_exact_mut(np).zip(sig0).zip(sig1) {
        law.residual_param_derivatives(c, s0, s1, dt, r);
    }
}

fn check_inputs(
    law: &dyn Law,
    c: &[f64],
    traj: &Trajectory,
    n_rho: usize,
) -> Result<(), AdjointError> {
    let n = traj.steps.len();
    if traj.fields.len() != n + 1 {
        return Err(AdjointError::NotRecorded {
            fields: traj.fields.len(),
            steps: n,
        });
    }
    if n_rho != n {
        return Err(AdjointError::Length {
            expected: n,
            got: n_rho,
        });
    }
    law.check_params(c)?;
    law.check_differentiable(c)?;
    Ok(())
}

/// Replays a checkpointed run segment by segment, the last first, and visits its steps in
/// reverse order: `visit(g, step, fields before, fields after)` with `g` the step's index
/// in the whole run. A segment that replays another number of steps than the run had is
/// an error.
fn replayed_steps_rev(
    solver: &mut DirectSolver<'_>,
    mat: &dyn Material,
    c: &[f64],
    schedule: &Schedule,
    opts: &SolverOptions,
    traj: &Trajectory,
    mut visit: impl FnMut(usize, &StepRecord, &StepFields, &StepFields) -> Result<(), AdjointError>,
) -> Result<(), AdjointError> {
    let (last, n) = (schedule.t.len() - 1, traj.steps.len());
    for (s_idx, cp) in traj.checkpoints.iter().enumerate().rev() {
        let (j_end, steps_end) = match traj.checkpoints.get(s_idx + 1) {
            Some(next) => (next.schedule_index, next.steps_done),
            None => (last, n),
        };
        let seg = solver
            .replay(mat, c, schedule, opts, cp, j_end)
            .map_err(|e| AdjointError::Replay(e.to_string()))?;
        if seg.steps.len() != steps_end - cp.steps_done {
            return Err(AdjointError::Replay(format!(
                "segment from schedule index {} replayed {} steps, the run had {}",
                cp.schedule_index,
                seg.steps.len(),
                steps_end - cp.steps_done
            )));
        }
        for i in (0..seg.steps.len()).rev() {
            visit(
                cp.steps_done + i,
                &seg.steps[i],
                &seg.fields[i],
                &seg.fields[i + 1],
            )?;
        }
    }
    Ok(())
}
