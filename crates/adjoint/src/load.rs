//! The exact gradient under load control (docs/theory.md §13): the adjoint of the
//! bordered system, one scalar per load-controlled step.
//!
//! A load-controlled step `i` has the punch depth `U_i` as an unknown with the equation
//! `F_i(U_1..U_i, c) = P_i`. With `J` a function of the depths (and of the forces of
//! depth-controlled steps), `dJ/dc = rho . dF/dc|_U`, the depth-controlled adjoint's
//! gradient with `dJ/dF_i = rho_i`, where the `rho_i` solve the transposed (upper
//! triangular) system `-sum_{j >= i} dF_j/dU_i rho_j = dJ/dU_i`. In the reversed-time
//! sweep that is one scalar per step: `rho_i = -(dJ/dU_i + a_i) / s_i`, with
//! `s_i = dF_i/dU_i` the step's Schur complement (the contact stiffness of the forward's
//! bordered update) and `a_i = g_i . du_U,i` what the later steps' cotangents make of the
//! depth: the sweep's right-hand side `g_i` (before the step's own cotangent enters)
//! against the step's depth column `du_U,i` ([`RecordedContact::depth_column`]). The
//! depth-controlled steps of a mixed history keep `rho_i = dJ/dF_i`.
//!
//! Coulomb friction (docs/theory.md §13): the sticking ties read each node's position
//! relative to the punch, `x + U e_z`, so `a_i` gains what the later steps' ties make of
//! the depth ([`RecordedContact::adjoint_depth`]), the cotangent enters as friction's
//! shift (`-rho_i K e_A` on the right-hand side, `K e_A` the depth column's `K v`), and
//! the forward sensitivities keep each step's relative motion `du + dU e_z` for the
//! next step's ties ([`relative_to_punch`]).

use crate::SensBuffers;
use indentify_contact::{
    DirectSolver, ForceCotangent, LoadHistory, Model, RecordedContact, SolverOptions, StepFields,
    StepRecord, Target, Trajectory,
};
use indentify_laws::{Law, Material, Vec4};

use crate::material::MatSweep;
use crate::{Adjoint, AdjointError, Gradient, Recorded, Sweep, check_inputs};

/// Whether the step ending at time `t` (s) prescribes the force.
pub(crate) fn load_controlled(history: &LoadHistory, t: f64) -> bool {
    matches!(history.segment_at(t).1, Target::Force(_))
}

impl Adjoint<'_> {
    /// The adjoint gradient `dJ/dc` of a run of [`indentify_contact::DirectSolver::run_history`]
    /// (`traj`, recorded with fields) for a cost with `dJ/dU_i = dj_dh[i]` at its
    /// load-controlled steps (the depth is the observable there) and `dJ/dF_i = dj_df[i]`
    /// at its depth-controlled ones (entries of the other kind are ignored). A stress-only
    /// law ([`Material::as_law`]) sweeps as [`Adjoint::gradient`] does for it; a material
    /// with internal variables through its blocks (`material.rs`, regime held), the
    /// bordered scalar formed from the same step's system.
    ///
    /// # Errors
    /// As [`Adjoint::gradient`]; [`AdjointError::Step`] when a load-controlled step's
    /// contact stiffness is not positive.
    pub fn gradient_load(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        history: &LoadHistory,
        dj_dh: &[f64],
        dj_df: &[f64],
    ) -> Result<Gradient, AdjointError> {
        self.gradient_load_from(mat, c, (traj, history), (dj_dh, dj_df), None)
    }

    /// [`Adjoint::gradient_load`] of a run recorded with checkpoints instead of fields
    /// ([`SolverOptions::checkpoint_every`] in [`DirectSolver::run_history`]): each stretch
    /// between checkpoints is replayed by `replay.solver` with
    /// [`DirectSolver::replay_history`] (its load-controlled segments driven by their
    /// force again, the same bits), swept backward and dropped. A trajectory with every
    /// step's fields is swept as by [`Adjoint::gradient_load`].
    ///
    /// # Errors
    /// As [`Adjoint::gradient_load`]; [`AdjointError::Replay`] as for
    /// [`Adjoint::gradient_replayed`].
    #[allow(clippy::too_many_arguments)]
    pub fn gradient_load_replayed(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        history: &LoadHistory,
        dj_dh: &[f64],
        dj_df: &[f64],
        replay: LoadReplay<'_, '_>,
    ) -> Result<Gradient, AdjointError> {
        if traj.fields.len() == traj.steps.len() + 1 {
            return self.gradient_load(mat, c, traj, history, dj_dh, dj_df);
        }
        if !std::ptr::eq(replay.solver.model(), self.model) {
            return Err(AdjointError::Replay(
                "the replaying solver runs another model than this adjoint's: build both \
                 from the same Model"
                    .into(),
            ));
        }
        if traj.checkpoints.first().is_none_or(|cp| cp.steps_done != 0) {
            return Err(AdjointError::NotRecorded {
                fields: traj.fields.len(),
                steps: traj.steps.len(),
            });
        }
        self.gradient_load_from(mat, c, (traj, history), (dj_dh, dj_df), Some(replay))
    }

    /// [`Adjoint::gradient_load`] from the recorded fields (`replay` `None`) or from the
    /// replayed stretches between checkpoints.
    fn gradient_load_from(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        (traj, history): (&Trajectory, &LoadHistory),
        (dj_dh, dj_df): (&[f64], &[f64]),
        replay: Option<LoadReplay<'_, '_>>,
    ) -> Result<Gradient, AdjointError> {
        let start = std::time::Instant::now();
        let f0 = self.contact.factorizations();
        self.check_drive_inputs(mat, c, traj, dj_df.len(), replay.is_some())?;
        let law = mat.as_law();
        if dj_dh.len() != traj.steps.len() {
            return Err(AdjointError::Length {
                expected: traj.steps.len(),
                got: dj_dh.len(),
            });
        }
        self.contact.begin();
        let source = Source {
            mat,
            c,
            traj,
            history,
            replay,
        };
        let dj_dc = if let Some(law) = law {
            let mut sweep = Sweep::new(law, c);
            self.begin_sweep();
            if source.replay.is_none() {
                self.begin_nodal(law, c, traj);
            }
            self.load_sweep(source, (dj_dh, dj_df), |adj, step, border| match border {
                Some(b) => adj.bordered_step(law, c, &mut sweep, step, b),
                None => adj.sweep_step(law, c, &mut sweep, step).map(|()| step.rho),
            })?;
            sweep.finish(law, c)
        } else {
            // the all-nodal sweep of a linear material with isotropic blocks where it
            // applies (`material/nodal.rs`, its step bordered as the Gauss-point one)
            let nodal = if source.replay.is_none() {
                self.begin_nodal_material(mat, c, traj)
            } else {
                self.nodal_mat.on = false;
                false
            };
            let nq = if nodal { 1 } else { self.model.disc.n_qp() };
            let mut sw = MatSweep::new(mat, c.len(), nq);
            self.load_sweep(source, (dj_dh, dj_df), |adj, step, border| {
                let Recorded {
                    i,
                    rec,
                    f0,
                    f1,
                    rho,
                    ..
                } = *step;
                if nodal {
                    return adj.nodal_material_step_bordered(
                        mat,
                        c,
                        &mut sw,
                        i,
                        rec,
                        (f0, f1),
                        rho,
                        border,
                    );
                }
                adj.material_step(mat, c, &mut sw, i, rec, (f0, f1), rho, border)
            })?;
            sw.grad
        };
        Ok(Gradient {
            dj_dc,
            seconds: start.elapsed().as_secs_f64(),
            factorizations: self.contact.factorizations() - f0,
        })
    }

    /// The reversed-time sweep of a load-controlled run: `step(adjoint, step, border)`
    /// sweeps one step, with the cotangent `step.rho = dJ/dF_i` given (`border` `None`)
    /// or set by its depth column (`border`), and returns the cotangent it used. The
    /// steps' fields come from the trajectory or its replayed stretches (`source`).
    fn load_sweep(
        &mut self,
        source: Source<'_, '_, '_>,
        (dj_dh, dj_df): (&[f64], &[f64]),
        mut step_fn: impl FnMut(
            &mut Self,
            &Recorded<'_>,
            Option<BorderedRho<'_>>,
        ) -> Result<f64, AdjointError>,
    ) -> Result<(), AdjointError> {
        let (traj, history) = (source.traj, source.history);
        let n_eq = self.model.dofs.n_eq;
        let mut col = Column {
            col: vec![0.0; n_eq],
            kv: vec![0.0; n_eq],
        };
        // what the steps of a segment carry to the step before it when their prescribed
        // values start from its state: the force (load after depth) or the depth (depth
        // after load)
        let mut pending = 0.0;
        let mut visit = |adj: &mut Self,
                         i: usize,
                         s0: &StepFields,
                         s1: &StepFields|
         -> Result<(), AdjointError> {
            let rec = &traj.steps[i];
            let j = segment_index(history, rec.t);
            let load = load_controlled(history, rec.t);
            // this step starts the next step's segment: it takes that segment's carry
            let starts_next = traj
                .steps
                .get(i + 1)
                .is_some_and(|next| segment_index(history, next.t) != j);
            let carried = if starts_next {
                std::mem::take(&mut pending)
            } else {
                0.0
            };
            let step = Recorded {
                i,
                rec,
                f0: s0,
                f1: s1,
                rho: if load { 0.0 } else { dj_df[i] + carried },
                prev_dt: i.checked_sub(1).map(|p| traj.steps[p].dt),
            };
            // the segment's start (time) and whether its prescribed values start from the
            // state of a step of the other kind (whose value then varies with c)
            let t_s = if j == 0 { 0.0 } else { history.ends[j - 1].0 };
            let t_end = history.ends[j].0;
            let mixed = j > 0 && matches!(history.ends[j - 1].1, Target::Force(_)) != load;
            let theta = (rec.t - t_s) / (t_end - t_s);
            if load {
                let mut rho_of = |a: f64, s: f64| -(dj_dh[i] + a + carried) / s;
                let border = BorderedRho {
                    col: &mut col,
                    rho_of: &mut rho_of,
                };
                let rho = step_fn(adj, &step, Some(border))?;
                if mixed && theta < 1.0 {
                    // P_i = F_s + theta (P - F_s): the start's force takes
                    // -(1 - theta) rho_i (the multiplier of F_i = P_i is -rho_i)
                    pending -= (1.0 - theta) * rho;
                }
            } else if mixed && theta < 1.0 {
                // U_i = U_s + theta (U_end - U_s): dL/dU_i carried to the start's depth
                let rho = step.rho;
                let mut d = 0.0;
                let mut rho_of = |a: f64, s: f64| {
                    d = dj_dh[i] + a + rho * s;
                    rho
                };
                let border = BorderedRho {
                    col: &mut col,
                    rho_of: &mut rho_of,
                };
                step_fn(adj, &step, Some(border))?;
                pending += (1.0 - theta) * d;
            } else {
                step_fn(adj, &step, None)?;
            }
            Ok(())
        };
        match source.replay {
            None => {
                for i in (0..traj.steps.len()).rev() {
                    visit(self, i, &traj.fields[i], &traj.fields[i + 1])?;
                }
            }
            Some(LoadReplay { solver, opts }) => {
                replayed_load_steps_rev(
                    solver,
                    (source.mat, source.c),
                    history,
                    opts,
                    traj,
                    |i, s0, s1| visit(self, i, s0, s1),
                )?;
            }
        }
        Ok(())
    }
}

/// The forward run with which [`Adjoint::gradient_load_replayed`] replays a checkpointed
/// load-controlled trajectory: the solver (built on the adjoint's model) and the options
/// of the recorded run (with its `checkpoint_every`).
#[derive(Debug)]
pub struct LoadReplay<'a, 'm> {
    /// The direct solver on the adjoint's model.
    pub solver: &'a mut DirectSolver<'m>,
    /// The options of the recorded run.
    pub opts: &'a SolverOptions,
}

/// Where a load-controlled sweep reads its steps: the trajectory, its history, and the
/// replay of its stretches between checkpoints (`None`: its recorded fields).
struct Source<'a, 'r, 'm> {
    mat: &'a dyn Material,
    c: &'a [f64],
    traj: &'a Trajectory,
    history: &'a LoadHistory,
    replay: Option<LoadReplay<'r, 'm>>,
}

/// Replays a checkpointed run of [`DirectSolver::run_history`] stretch by stretch, the
/// last first, and visits its steps in reverse order: `visit(i, fields before, fields
/// after)` with `i` the step's index in the whole run. A stretch that replays another
/// number of steps than the run had, or other steps, is an error.
fn replayed_load_steps_rev(
    solver: &mut DirectSolver<'_>,
    (mat, c): (&dyn Material, &[f64]),
    history: &LoadHistory,
    opts: &SolverOptions,
    traj: &Trajectory,
    mut visit: impl FnMut(usize, &StepFields, &StepFields) -> Result<(), AdjointError>,
) -> Result<(), AdjointError> {
    let (last, n) = (history.schedule.t.len() - 1, traj.steps.len());
    for (s_idx, cp) in traj.checkpoints.iter().enumerate().rev() {
        let (j_end, steps_end) = match traj.checkpoints.get(s_idx + 1) {
            Some(next) => (next.schedule_index, next.steps_done),
            None => (last, n),
        };
        let seg = solver
            .replay_history(mat, c, history, opts, cp, j_end)
            .map_err(|e| AdjointError::Replay(e.to_string()))?;
        // the same steps: their times, and their depths to round-off (a capacitance
        // system with frames keeps factors grown in the run's order)
        let recorded = traj.steps.get(cp.steps_done..steps_end).unwrap_or(&[]);
        let scale = recorded.iter().fold(0.0f64, |m, s| m.max(s.depth.abs()));
        if seg.steps.len() != recorded.len()
            || seg.steps.iter().zip(recorded).any(|(a, b)| {
                a.t.to_bits() != b.t.to_bits() || (a.depth - b.depth).abs() > 1e-9 * scale
            })
        {
            return Err(AdjointError::Replay(format!(
                "the stretch from schedule index {} replayed {} steps, the run had {} (or \
                 other depths)",
                cp.schedule_index,
                seg.steps.len(),
                recorded.len()
            )));
        }
        for i in (0..seg.steps.len()).rev() {
            visit(cp.steps_done + i, &seg.fields[i], &seg.fields[i + 1])?;
        }
    }
    Ok(())
}

/// A sweep step's cotangent under load control: the step's depth column (scratch) and
/// `rho_of(a, s)`, the cotangent from `a = g . du_U` (the right-hand side `g` before the
/// step's own cotangent) and the Schur complement `s = dF_i/dU_i`.
pub(crate) struct BorderedRho<'a> {
    pub(crate) col: &'a mut Column,
    pub(crate) rho_of: &'a mut dyn FnMut(f64, f64) -> f64,
}

impl Adjoint<'_> {
    /// The cotangent of a prepared step `i` (displacement `u`, all dofs) whose sweep
    /// right-hand side is in `self.eq` ([`BorderedRho`]). With a shifted force cotangent
    /// ([`ForceCotangent::Shifted`], Coulomb friction) `self.eq` holds the right-hand side
    /// without the shift on entry and with it, `-rho K e_A`, on exit.
    ///
    /// # Errors
    /// As [`Adjoint::gradient_load`].
    pub(crate) fn bordered_rho(
        &mut self,
        i: usize,
        rec: &StepRecord,
        u: &[f64],
        b: BorderedRho<'_>,
    ) -> Result<f64, AdjointError> {
        let s = self
            .contact
            .depth_column(rec, &mut b.col.col, &mut b.col.kv);
        let a: f64 = self
            .eq
            .iter()
            .zip(&b.col.col)
            .map(|(g, d)| g * d)
            .sum::<f64>()
            + if self.depth_ties {
                self.contact.adjoint_depth(rec, u, &b.col.col)
            } else {
                0.0
            };
        let rho = (b.rho_of)(a, s);
        if !rho.is_finite() {
            return Err(not_positive(i, rec, s));
        }
        if self.contact.force_cotangent() == ForceCotangent::Shifted {
            // the shift's part of the right-hand side: `K e_A` is the depth column's `K v`
            for (g, kv) in self.eq.iter_mut().zip(&b.col.kv) {
                *g -= rho * kv;
            }
        }
        Ok(rho)
    }
}

/// The error of a load-controlled step `i` whose contact stiffness `s` (N/mm) gives no
/// finite cotangent.
pub(crate) fn not_positive(i: usize, rec: &StepRecord, s: f64) -> AdjointError {
    AdjointError::Step {
        step: i,
        t: rec.t,
        reason: format!(
            "load control: the contact stiffness dF/dU = {s:.3e} N/mm of the recorded step \
             is not positive: its depth is not determined by its force"
        ),
    }
}

/// The depth column of a step and `K v` (scratch of [`Adjoint::bordered_step`]).
pub(crate) struct Column {
    pub(crate) col: Vec<f64>,
    pub(crate) kv: Vec<f64>,
}

/// The index of the segment of `history` a step ending at `t` (s) belongs to.
fn segment_index(history: &LoadHistory, t: f64) -> usize {
    history
        .ends
        .partition_point(|e| e.0 < t)
        .min(history.ends.len() - 1)
}

impl Adjoint<'_> {
    /// The inputs of a load-controlled or compliant sweep of `mat` at `c` over `traj`
    /// with `n_rho` cotangents: a law's as [`Adjoint::gradient`] checks them (a replayed
    /// run, whose fields are not recorded, only its parameters and the cotangents'
    /// count), a material's through its own check.
    pub(crate) fn check_drive_inputs(
        &self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        n_rho: usize,
        replayed: bool,
    ) -> Result<(), AdjointError> {
        match mat.as_law() {
            Some(law) if !replayed => check_inputs(law, c, traj, n_rho),
            Some(law) => {
                if n_rho != traj.steps.len() {
                    return Err(AdjointError::Length {
                        expected: traj.steps.len(),
                        got: n_rho,
                    });
                }
                law.check_params(c)?;
                law.check_differentiable(c)?;
                Ok(())
            }
            None => self.check_material(mat, c, traj, n_rho, !replayed),
        }
    }
}

impl Adjoint<'_> {
    /// One sweep step of a stress-only law whose cotangent `rho = dJ/dF_i` depends on
    /// the step's depth column ([`BorderedRho`]). Returns `rho`.
    ///
    /// # Errors
    /// As [`Adjoint::gradient_load`].
    pub(crate) fn bordered_step(
        &mut self,
        law: &dyn Law,
        c: &[f64],
        sweep: &mut Sweep,
        step: &Recorded<'_>,
        border: BorderedRho<'_>,
    ) -> Result<f64, AdjointError> {
        let Recorded {
            i,
            rec,
            f0,
            f1,
            prev_dt,
            ..
        } = *step;
        // (a shifted cotangent's part of the source is added by `bordered_rho`; Coulomb
        // friction's shifted cotangent takes the two-pass sweep)
        let fuse = self.fuse
            && self.fusable(law)
            && self.contact.force_cotangent() != ForceCotangent::Shifted;
        self.prepare_step(law, c, rec, (&f1.sigma, &f1.u), i, fuse)?;
        if !(fuse
            && (self.nodal_source(i, rec) || self.fused.take_source(i, rec.dt, &mut self.full)))
        {
            if fuse {
                let t0 = self.tangents[0];
                self.tangents.fill(t0);
            }
            self.adjoint_source(sweep.s, rec, None);
        }
        self.restrict();
        // an affine law's capacitance system: the depth column, the cotangent and the
        // transposed solve in one solve (`RecordedContact::adjoint_solve_bordered`)
        let mut eq = std::mem::take(&mut self.eq);
        let one = if fuse {
            (self.contact).adjoint_solve_bordered(rec, &f1.u, &mut eq, &mut *border.rho_of)
        } else {
            None
        };
        self.eq = eq;
        let rho = match one {
            Some((rho, _)) if rho.is_finite() => rho,
            Some((_, s)) => return Err(not_positive(i, rec, s)),
            None => {
                let rho = self.bordered_rho(i, rec, &f1.u, border)?;
                let mut eq = std::mem::take(&mut self.eq);
                self.contact.adjoint_solve(rec, &f1.u, rho, &mut eq);
                self.eq = eq;
                rho
            }
        };
        sweep.mu_zero = false;
        self.expand();
        if self.contact.force_cotangent() == ForceCotangent::Shifted {
            // V' = V + rho e_A
            for d in crate::force_dofs(self.model, rec) {
                self.full[d] += rho;
            }
        }
        if fuse {
            if !self.nodal_back_substitute(sweep, rec.dt) {
                let next = Self::next_of(law, c, i, prev_dt);
                let fields = (rec.dt, f0.sigma.as_slice(), f1.sigma.as_slice());
                self.back_substitute_fused(law, c, sweep, fields, next);
            }
        } else {
            self.back_substitute(law, c, sweep, rec.dt, &f0.sigma, &f1.sigma);
        }
        Ok(rho)
    }
}

/// Load control in a step's forward sensitivities: the step's depth column and Schur
/// complement, and what sets each parameter's depth variation `dU_i/dc_k`: under load
/// control `(dP_i - dF_i^U) / s` (`dF_i^U` the force variation at the depth held, `dP_i`
/// the prescribed force's, nonzero where the segment starts from a depth-controlled
/// step's force), under depth control `dU_i` itself (nonzero where the segment starts
/// from a load-controlled step's depth).
pub(crate) struct Border<'a> {
    pub col: &'a [f64],
    pub s: f64,
    pub load: bool,
    /// `dP_i/dc_k` (load) or `dU_i/dc_k` (depth), one per parameter.
    pub given: &'a [f64],
    /// Whether the step's force is prescribed (load control: `dF_i/dc_k = dP_i/dc_k`,
    /// `given`, with nothing to form), or computed (a depth-controlled step, the frame's
    /// spring).
    pub force_prescribed: bool,
}

impl Border<'_> {
    /// Parameter `k`'s depth variation `dU_i/dc_k` from the force variation at the depth
    /// held, `df_held` (N per unit parameter): `(dP_i - dF_i^U) / s` under load control
    /// (the frame's spring in the same form), the given `dU_i` under depth control.
    pub(crate) fn depth_variation(&self, k: usize, df_held: f64) -> f64 {
        if self.load {
            (self.given[k] - df_held) / self.s
        } else {
            self.given[k]
        }
    }

    /// Adds `dU_i/dc_k du_U` to the displacement variation `w.eq` (on entry: at the
    /// depth held) and returns `dU_i/dc_k`. Under load control the force variation at
    /// the depth held comes from the force dofs' rows of the step's tangent, `rhs_A -
    /// (K du)_A` with `rhs_a` the right-hand side's sum over the force dofs (given where
    /// the step reads its rows, [`crate::ParamStep::solve`]), else from a pass over the
    /// Gauss points.
    pub(crate) fn shift(
        &self,
        step: &crate::ParamStep<'_>,
        k: usize,
        rhs_a: Option<f64>,
        w: &mut crate::ParamWork,
    ) -> f64 {
        let du = if let (true, Some(cons), Some(rhs_a)) = (self.load, step.reactions, rhs_a) {
            self.depth_variation(k, rhs_a - step.force_rows(cons, &w.eq))
        } else if self.load {
            let model = step.model;
            crate::expand_into(model, &w.eq, &mut w.full);
            crate::strains_into(model, step.finite, &w.full, &mut w.strain);
            for qp in 0..w.field_b.len() {
                let bv = Vec4(w.strain[qp]);
                w.field_b[qp] = step.tangents[qp].mul_vec(&(bv + w.q[qp]));
            }
            crate::delta_force_into(
                model,
                step.finite,
                step.tangents,
                &w.q,
                &mut w.field_b,
                &mut w.full,
                &mut w.du,
            );
            let df: f64 = -crate::force_dofs(model, step.rec)
                .map(|d| w.full[d])
                .sum::<f64>();
            self.depth_variation(k, df)
        } else {
            self.given[k]
        };
        for (e, c) in w.eq.iter_mut().zip(self.col) {
            *e += du * c;
        }
        du
    }
}

/// Forward sensitivities of a load-controlled run: `dU_i/dc` and `dF_i/dc` per step.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadSensitivities {
    /// `dU_i/dc_k` (mm per unit parameter): one row per trajectory step (0 where the
    /// depth is prescribed and does not depend on the parameters).
    pub dh_dc: Vec<Vec<f64>>,
    /// `dF_i/dc_k` (N per unit parameter; 0 where the force is prescribed and fixed).
    pub df_dc: Vec<Vec<f64>>,
    /// Wall time (s).
    pub seconds: f64,
}

impl Adjoint<'_> {
    /// Forward sensitivities of a run of
    /// [`indentify_contact::DirectSolver::run_history`] (`traj` recorded with fields):
    /// the forward's bordered system differentiated, one depth column per step shared by
    /// the parameters; a material with internal variables through its blocks
    /// (`material.rs`).
    ///
    /// # Errors
    /// As [`Adjoint::gradient_load`].
    pub fn sensitivities_load(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        history: &LoadHistory,
    ) -> Result<LoadSensitivities, AdjointError> {
        let model = self.model;
        let start = std::time::Instant::now();
        let Some(law) = mat.as_law() else {
            let (df, dh) = self.material_sensitivities(
                mat,
                c,
                traj,
                crate::material::SensDrive::Load(history),
            )?;
            return Ok(LoadSensitivities {
                dh_dc: dh,
                df_dc: df,
                seconds: start.elapsed().as_secs_f64(),
            });
        };
        let n = traj.steps.len();
        check_inputs(law, c, traj, n)?;
        self.contact.begin();
        // a law with one isotropic tangent under vertical contact: the bordered all-nodal
        // pass (`nodal_sens.rs`), which reads the tangent's rows
        let drive = crate::material::SensDrive::Load(history);
        if let Some((df, dh)) = self.sensitivities_nodal(law, c, traj, drive)? {
            self.nodal_sens = true;
            self.reaction_rows = true;
            return Ok(LoadSensitivities {
                dh_dc: dh,
                df_dc: df,
                seconds: start.elapsed().as_secs_f64(),
            });
        }
        let s_mat = law.compliance(c);
        let np = c.len();
        let SensBuffers {
            mut y,
            mut r_field,
            mut work,
            ..
        } = self.sens_buffers(np);
        let mut df = vec![vec![0.0; np]; n];
        let mut dh = vec![vec![0.0; np]; n];
        let mut carry = SegmentCarry::new(np, model.dofs.n_eq);
        // the force at the depth held (which sets the depth's variation) and a
        // depth-controlled step's force from the force dofs' rows of the step's tangent
        // (`ParamStep::solve`); a load-controlled step's force is prescribed
        let reactions = self.reactions_from_rows();
        self.nodal_sens = false;
        self.reaction_rows = reactions;
        let mut cons = Vec::new();
        for i in 0..n {
            let rec = &traj.steps[i];
            let f1 = &traj.fields[i + 1];
            self.prepare_step(law, c, rec, (&f1.sigma, &f1.u), i, false)?;
            let prev = i
                .checked_sub(1)
                .map(|p| (&traj.steps[p], traj.fields[i].u.as_slice()));
            self.contact.prepare_sensitivities(rec, &f1.u, prev);
            let (sig0, sig1) = (&traj.fields[i].sigma, &f1.sigma);
            crate::residual_param_field(law, c, sig0, sig1, rec.dt, &mut r_field);
            let border = carry.step(&mut self.contact, history, traj, i, (&df, &dh))?;
            if reactions {
                crate::nodal_sens::active_equations(model, rec, &mut cons);
            }
            let step = crate::ParamStep {
                model,
                tangents: &self.tangents,
                contact: &self.contact,
                finite: self.finite.as_ref(),
                s: &s_mat,
                r_field: &r_field,
                np,
                rec,
                reactions: reactions.then_some(cons.as_slice()),
                border: border.map(|load| Border {
                    col: &carry.col.col,
                    s: carry.s,
                    load,
                    given: &carry.given,
                    force_prescribed: load,
                }),
            };
            for (k, ((yk, dfk), w)) in y
                .iter_mut()
                .zip(df[i].iter_mut())
                .zip(work.iter_mut())
                .enumerate()
            {
                w.du_depth = 0.0;
                step.solve(k, yk, dfk, w);
                dh[i][k] = w.du_depth;
            }
        }
        Ok(LoadSensitivities {
            dh_dc: dh,
            df_dc: df,
            seconds: start.elapsed().as_secs_f64(),
        })
    }
}

/// What the forward sensitivities of a load-controlled run carry from step to step: the
/// variations of the force and depth a segment starts from, each step's prescribed
/// variations (`given`, [`Border::given`]), its depth column and Schur complement.
pub(crate) struct SegmentCarry {
    start_f: Vec<f64>,
    start_u: Vec<f64>,
    pub(crate) given: Vec<f64>,
    pub(crate) col: Column,
    pub(crate) s: f64,
}

impl SegmentCarry {
    pub(crate) fn new(np: usize, n_eq: usize) -> SegmentCarry {
        SegmentCarry {
            start_f: vec![0.0; np],
            start_u: vec![0.0; np],
            given: vec![0.0; np],
            col: Column {
                col: vec![0.0; n_eq],
                kv: vec![0.0; n_eq],
            },
            s: 0.0,
        }
    }

    /// The step's [`Border`] as [`SegmentCarry::step`] or `FrameDrive::step` set it
    /// (`load` their answer): the force is prescribed on a load-controlled step of a
    /// load history, computed through the frame.
    pub(crate) fn border(&self, load: bool, drive: crate::material::SensDrive<'_>) -> Border<'_> {
        Border {
            col: &self.col.col,
            s: self.s,
            load,
            given: &self.given,
            force_prescribed: load && matches!(drive, crate::material::SensDrive::Load(_)),
        }
    }

    /// Step `i` of `traj` (its system prepared in `contact`), with the variations
    /// `(df, dh)` of the steps before it: `Some(load)` when the step is bordered (under
    /// load control, or under depth control starting from a load-controlled step's
    /// depth), with `given`, `col` and `s` set; `None` for a plain depth-controlled step.
    ///
    /// # Errors
    /// [`AdjointError::Step`] for a load-controlled step whose contact stiffness is not
    /// positive.
    pub(crate) fn step(
        &mut self,
        contact: &mut RecordedContact<'_>,
        history: &LoadHistory,
        traj: &Trajectory,
        i: usize,
        (df, dh): (&[Vec<f64>], &[Vec<f64>]),
    ) -> Result<Option<bool>, AdjointError> {
        let rec = &traj.steps[i];
        let j = segment_index(history, rec.t);
        let load = load_controlled(history, rec.t);
        if i > 0 && segment_index(history, traj.steps[i - 1].t) != j {
            self.start_f.clone_from(&df[i - 1]);
            self.start_u.clone_from(&dh[i - 1]);
        }
        let t_s = if j == 0 { 0.0 } else { history.ends[j - 1].0 };
        let theta = ((rec.t - t_s) / (history.ends[j].0 - t_s)).min(1.0);
        let mixed = j > 0 && matches!(history.ends[j - 1].1, Target::Force(_)) != load;
        for (g, (f, u)) in self
            .given
            .iter_mut()
            .zip(self.start_f.iter().zip(&self.start_u))
        {
            *g = match (mixed, load) {
                (false, _) => 0.0,
                (true, true) => (1.0 - theta) * f,
                (true, false) => (1.0 - theta) * u,
            };
        }
        if !(load || mixed) {
            self.s = 0.0;
            return Ok(None);
        }
        self.s = contact.depth_column(rec, &mut self.col.col, &mut self.col.kv);
        if load && !(self.s.is_finite() && self.s > 0.0) {
            return Err(AdjointError::Step {
                step: i,
                t: rec.t,
                reason: format!(
                    "load control: the contact stiffness dF/dU = {:.3e} N/mm of the \
                     recorded step is not positive",
                    self.s
                ),
            });
        }
        Ok(Some(load))
    }
}

/// Friction's sticking ties read a node's motion relative to the punch, `du + dU e_z`
/// (docs/theory.md §13): adds a step's depth variation `du` (mm per unit parameter) to
/// the vertical dofs of every candidate in `du_prev` (all dofs), the displacement
/// variation the next step's ties read.
pub(crate) fn relative_to_punch(model: &Model, du_prev: &mut [f64], du: f64) {
    if du_prev.is_empty() || du == 0.0 {
        return;
    }
    for &n in &model.candidates {
        du_prev[2 * n + 1] += du;
    }
}
