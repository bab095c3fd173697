//! The exact gradient of depth control through the instrument's frame (docs/theory.md
//! §13.7): a run of [`indentify_contact::DirectSolver::run_compliant`], whose steps solve
//! `h_i + Cf F_i(h_1..h_i, c) = H_i` with `H_i = h_meas(t_i) - vd (t_i - t0) - h0`
//! prescribed, and a cost on the forces, `dJ/dF_i = g_i`.
//!
//! With the multipliers `mu_i` of the step equations `F_i - (H_i - h_i) / Cf = 0` and
//! `rho_i = g_i + mu_i`, stationarity in `h_i` reads `rho_i s_i + a_i + mu_i / Cf = 0`,
//! `s_i = dF_i/dh_i` the step's Schur complement and `a_i = sum_{j > i} rho_j dF_j/dh_i`
//! what the later steps make of its depth (the sweep's right-hand side against the step's
//! depth column, as under load control, `load.rs`). Hence one scalar per step:
//!
//! ```text
//!   rho_i = (g_i - Cf a_i) / (1 + Cf s_i),    dJ/dH_i = (a_i + s_i g_i) / (1 + Cf s_i)
//! ```
//!
//! `dJ/dc = sum_i rho_i dF_i/dc|_h` is the depth-controlled sweep with the cotangents
//! `rho_i`; the frame's parameters move the prescribed `H_i` (`dH_i/dvd = -(t_i - t0)`,
//! `dH_i/dh0 = -1`) or the spring (`dJ/dCf = -sum_i F_i dJ/dH_i`). `Cf = 0` is plain depth
//! control (`rho_i = g_i`), where `dJ/dH_i = a_i + s_i g_i` is the force's sensitivity
//! to the prescribed depth history the frame's derivatives need.
//!
//! Coulomb friction: the punch depth `h_i` is an unknown here as under load control, and
//! the next step's sticking ties read it, so `a_i` gains their term
//! ([`indentify_contact::RecordedContact::adjoint_depth`]) and `rho_i` enters as friction's
//! shifted cotangent (`Adjoint::bordered_rho`, `load.rs`); the forward sensitivities keep
//! each step's motion relative to the punch for the next step's ties.

use crate::SensBuffers;
use indentify_contact::{
    DirectSolver, Frame, RecordedContact, Schedule, SolverOptions, StepFields, StepRecord,
    Trajectory,
};
use indentify_laws::{Law, Material};

use crate::LoadReplay;
use crate::load::{BorderedRho, Column, SegmentCarry};
use crate::material::MatSweep;
use crate::{Adjoint, AdjointError, Recorded, Sweep, check_inputs};

/// The gradient of a cost on the forces of a compliant depth-controlled run.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameGradient {
    /// `dJ/dc_k` in the material's parameter order.
    pub dj_dc: Vec<f64>,
    /// `dJ/dCf` (per mm/N), `dJ/dvd` (per mm/s), `dJ/dh0` (per mm).
    pub dj_dframe: [f64; 3],
    /// `dJ/dH_i`: the cost's sensitivity to each step's prescribed punch-side depth
    /// (per mm).
    pub dj_dh: Vec<f64>,
    /// Wall time of the sweep (s).
    pub seconds: f64,
    /// Numeric factorizations the sweep needed.
    pub factorizations: usize,
}

impl Adjoint<'_> {
    /// The adjoint gradient of a cost with `dJ/dF_i = dj_df[i]` at each step of `traj`,
    /// a run of [`indentify_contact::DirectSolver::run_compliant`] over the machine
    /// depths `schedule` through `frame` (recorded with fields): with respect to the
    /// material's parameters and the frame's `Cf`, `vd`, `h0`. A stress-only law sweeps
    /// as [`Adjoint::gradient`] does, a material with internal variables through its
    /// blocks (`material.rs`), each step bordered by its depth column; every contact
    /// kind, Coulomb friction included (the later ties' depth term, docs/theory.md §13.7).
    ///
    /// # Errors
    /// As [`Adjoint::gradient`]; [`AdjointError::Step`] for a step whose stiffness
    /// `1 + Cf s` is not positive.
    pub fn gradient_compliant(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        (schedule, frame): (&Schedule, &Frame),
        dj_df: &[f64],
    ) -> Result<FrameGradient, AdjointError> {
        self.gradient_compliant_from(mat, c, traj, (schedule, frame), dj_df, None)
    }

    /// [`Adjoint::gradient_compliant`] of a run recorded with checkpoints instead of
    /// fields ([`indentify_contact::SolverOptions::checkpoint_every`] in
    /// [`indentify_contact::DirectSolver::run_compliant`]): each stretch between
    /// checkpoints is replayed by `replay.solver` with
    /// [`indentify_contact::DirectSolver::replay_compliant`] (through the same frame, the
    /// same bits), swept backward and dropped, so the sweep holds one stretch's fields at a
    /// time. A trajectory with every step's fields is swept as by
    /// [`Adjoint::gradient_compliant`].
    ///
    /// # Errors
    /// As [`Adjoint::gradient_compliant`]; [`AdjointError::Replay`] when the replaying
    /// solver runs another model or a stretch replays other steps than the run took;
    /// [`AdjointError::NotRecorded`] for a run with neither fields nor a checkpoint at its
    /// start.
    #[allow(clippy::too_many_arguments)]
    pub fn gradient_compliant_replayed(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        (schedule, frame): (&Schedule, &Frame),
        dj_df: &[f64],
        replay: LoadReplay<'_, '_>,
    ) -> Result<FrameGradient, AdjointError> {
        if traj.fields.len() == traj.steps.len() + 1 {
            return self.gradient_compliant(mat, c, traj, (schedule, frame), dj_df);
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
        self.gradient_compliant_from(mat, c, traj, (schedule, frame), dj_df, Some(replay))
    }

    /// [`Adjoint::gradient_compliant`] from the recorded fields (`replay` `None`) or from
    /// the replayed stretches between checkpoints.
    fn gradient_compliant_from(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        (schedule, frame): (&Schedule, &Frame),
        dj_df: &[f64],
        replay: Option<LoadReplay<'_, '_>>,
    ) -> Result<FrameGradient, AdjointError> {
        let start = std::time::Instant::now();
        let f0 = self.contact.factorizations();
        self.check_drive_inputs(mat, c, traj, dj_df.len(), replay.is_some())?;
        let law = mat.as_law();
        let cf = frame.compliance;
        if !(cf.is_finite() && cf >= 0.0) {
            return Err(AdjointError::Step {
                step: 0,
                t: schedule.t[0],
                reason: format!("the frame compliance Cf = {cf} must be finite and >= 0"),
            });
        }
        self.contact.begin();
        let n = traj.steps.len();
        let n_eq = self.model.dofs.n_eq;
        let mut col = Column {
            col: vec![0.0; n_eq],
            kv: vec![0.0; n_eq],
        };
        let mut dj_dh = vec![0.0; n];
        // a linear material with isotropic blocks: the all-nodal sweep where it applies
        // (`material/nodal.rs`, its step bordered as the Gauss-point one)
        let nodal = law.is_none() && replay.is_none() && self.begin_nodal_material(mat, c, traj);
        if law.is_none() && !nodal {
            self.nodal_mat.on = false;
        }
        let mut which = match law {
            Some(law) => Which::Law(law, Box::new(Sweep::new(law, c))),
            None => Which::Material(Box::new(MatSweep::new(
                mat,
                c.len(),
                if nodal { 1 } else { self.model.disc.n_qp() },
            ))),
        };
        self.begin_sweep();
        if let (Some(law), None) = (law, &replay) {
            self.begin_nodal(law, c, traj);
        }
        // the initial displacement (the first step's fields before it), which friction's
        // h0 term reads after the sweep
        let mut u_initial: Option<Vec<f64>> = None;
        let mut visit = |adj: &mut Self,
                         i: usize,
                         f0: &StepFields,
                         f1: &StepFields|
         -> Result<(), AdjointError> {
            let rec = &traj.steps[i];
            let g = dj_df[i];
            if i == 0 && adj.depth_ties {
                u_initial = Some(f0.u.clone());
            }
            // the steps after the last contact (a run unloaded through the frame off its
            // impression): with nothing later swept (`mu_{i+1} = 0`), no contact and
            // nothing carried, the step's depth column is zero (`a_i = s_i = 0`, so
            // `dJ/dH_i = 0`) and its force has no dof to act on, whatever `g_i`: its
            // adjoint state is zero and so is its share of the gradient. Skipped, as the
            // depth-controlled sweep skips such steps without a cost (`Adjoint::sweep_step`)
            let untouched = match &which {
                Which::Law(_, sweep) => sweep.mu_zero,
                Which::Material(sw) => sw.zero,
            };
            if untouched && rec.active.is_empty() && !adj.contact.adjoint_pending() {
                dj_dh[i] = 0.0;
                return Ok(());
            }
            let mut d = 0.0;
            let mut rho_of = |a: f64, s: f64| {
                let q = 1.0 + cf * s;
                d = (a + s * g) / q;
                (g - cf * a) / q
            };
            let border = BorderedRho {
                col: &mut col,
                rho_of: &mut rho_of,
            };
            match &mut which {
                Which::Law(law, sweep) => {
                    let step = Recorded {
                        i,
                        rec,
                        f0,
                        f1,
                        rho: g,
                        prev_dt: i.checked_sub(1).map(|p| traj.steps[p].dt),
                    };
                    adj.bordered_step(*law, c, sweep, &step, border)?;
                }
                Which::Material(sw) if nodal => {
                    adj.nodal_material_step_bordered(
                        mat,
                        c,
                        sw,
                        i,
                        rec,
                        (f0, f1),
                        g,
                        Some(border),
                    )?;
                }
                Which::Material(sw) => {
                    adj.material_step(mat, c, sw, i, rec, (f0, f1), g, Some(border))?;
                }
            }
            if !d.is_finite() {
                return Err(AdjointError::Step {
                    step: i,
                    t: rec.t,
                    reason: "compliant depth control: the stiffness 1 + Cf dF/dh of the \
                             recorded step is not positive"
                        .into(),
                });
            }
            dj_dh[i] = d;
            Ok(())
        };
        match replay {
            None => {
                for i in (0..n).rev() {
                    visit(self, i, &traj.fields[i], &traj.fields[i + 1])?;
                }
            }
            Some(LoadReplay { solver, opts }) => {
                replayed_compliant_steps_rev(
                    solver,
                    (mat, c),
                    (schedule, frame),
                    opts,
                    traj,
                    |i, f0, f1| visit(self, i, f0, f1),
                )?;
            }
        }
        let dj_dc = match which {
            Which::Law(law, sweep) => sweep.finish(law, c),
            Which::Material(sw) => sw.grad,
        };
        let t0 = schedule.t[0];
        let mut dj_dframe = [0.0; 3];
        for (s, d) in traj.steps.iter().zip(&dj_dh) {
            dj_dframe[0] -= s.force * d;
            dj_dframe[1] -= (s.t - t0) * d;
            dj_dframe[2] -= d;
        }
        // Coulomb friction: the first step's sticking ties read the initial depth H(t0),
        // which moves with -h0 (the carry the sweep left is the first step's)
        if let Some(u0) = u_initial
            .as_deref()
            .filter(|_| self.contact.adjoint_pending())
        {
            col.col.fill(0.0);
            let init = initial_record(schedule, frame);
            dj_dframe[2] -= self.contact.adjoint_depth(&init, u0, &col.col);
        }
        Ok(FrameGradient {
            dj_dc,
            dj_dframe,
            dj_dh,
            seconds: start.elapsed().as_secs_f64(),
            factorizations: self.contact.factorizations() - f0,
        })
    }
}

/// Replays a checkpointed run of [`indentify_contact::DirectSolver::run_compliant`]
/// stretch by stretch, the last first, and visits its steps in reverse order:
/// `visit(i, fields before, fields after)` with `i` the step's index in the whole run.
/// A stretch that replays another number of steps than the run had, or other steps
/// (times, or depths beyond round-off), is an error.
fn replayed_compliant_steps_rev(
    solver: &mut DirectSolver<'_>,
    (mat, c): (&dyn Material, &[f64]),
    (schedule, frame): (&Schedule, &Frame),
    opts: &SolverOptions,
    traj: &Trajectory,
    mut visit: impl FnMut(usize, &StepFields, &StepFields) -> Result<(), AdjointError>,
) -> Result<(), AdjointError> {
    let (last, n) = (schedule.t.len() - 1, traj.steps.len());
    for (s_idx, cp) in traj.checkpoints.iter().enumerate().rev() {
        let (j_end, steps_end) = match traj.checkpoints.get(s_idx + 1) {
            Some(next) => (next.schedule_index, next.steps_done),
            None => (last, n),
        };
        let seg = solver
            .replay_compliant(mat, c, schedule, frame, opts, cp, j_end)
            .map_err(|e| AdjointError::Replay(e.to_string()))?;
        let recorded = traj.steps.get(cp.steps_done..steps_end).unwrap_or(&[]);
        let scale = recorded.iter().fold(0.0f64, |m, s| m.max(s.depth.abs()));
        if seg.steps.len() != recorded.len()
            || seg.steps.iter().zip(recorded).any(|(a, b)| {
                a.t.to_bits() != b.t.to_bits() || (a.depth - b.depth).abs() > 1e-9 * scale
            })
        {
            return Err(AdjointError::Replay(format!(
                "the compliant stretch from schedule index {} replayed {} steps, the run \
                 had {} (or other depths)",
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

/// The sweep of a stress-only law, or of a material with internal variables.
enum Which<'a> {
    Law(&'a dyn Law, Box<Sweep>),
    Material(Box<MatSweep>),
}

/// Where the frame's parameters sit in the parameter vector of
/// [`Adjoint::sensitivities_compliant`] (the material's derivatives with respect to them
/// are zero: an instrumented law, identify's `Instrumented`); `None`: not a parameter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameIndex {
    /// The index of `Cf`.
    pub compliance: Option<usize>,
    /// The index of `vd`.
    pub drift: Option<usize>,
    /// The index of `h0`.
    pub offset: Option<usize>,
}

impl Adjoint<'_> {
    /// Forward sensitivities `dF_i/dc_k` and `dh_i/dc_k` of a run of
    /// [`indentify_contact::DirectSolver::run_compliant`] (`traj` recorded with fields),
    /// for a material whose parameter vector `c` holds the frame's parameters at `at`
    /// (their law derivatives zero). Each step's depth variation solves the
    /// differentiated spring `dh_i (1 + Cf s_i) = dH_i - F_i dCf - Cf dF_i^h` (`dF_i^h` the
    /// force variation at the depth held; `dH_i = -(t_i - t0) dvd - dh0`), by the load
    /// control's bordered column (`load.rs`) with `s_i + 1 / Cf` for `s_i`; at `Cf = 0`
    /// the depth variation is `dH_i - F_i dCf`, prescribed (`FrameDrive::step`). A
    /// stress-only law steps as [`Adjoint::sensitivities`] does; a material with internal
    /// variables through its blocks (`material.rs`). With Coulomb friction each step keeps
    /// its motion relative to the punch, `du + dh e_z`, for the next step's sticking ties
    /// (docs/theory.md §13.7).
    ///
    /// # Errors
    /// As [`Adjoint::gradient_compliant`].
    pub fn sensitivities_compliant(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        (schedule, frame): (&Schedule, &Frame),
        at: FrameIndex,
    ) -> Result<crate::LoadSensitivities, AdjointError> {
        let model = self.model;
        let start = std::time::Instant::now();
        let drive = FrameDrive::new(schedule, frame, at);
        if !(drive.cf.is_finite() && drive.cf >= 0.0) {
            return Err(AdjointError::Step {
                step: 0,
                t: drive.t0,
                reason: format!(
                    "the frame compliance Cf = {} must be finite and >= 0",
                    drive.cf
                ),
            });
        }
        let Some(law) = mat.as_law() else {
            let (df, dh) = self.material_sensitivities(
                mat,
                c,
                traj,
                crate::material::SensDrive::Frame(&drive),
            )?;
            return Ok(crate::LoadSensitivities {
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
        let sd = crate::material::SensDrive::Frame(&drive);
        if let Some((df, dh)) = self.sensitivities_nodal(law, c, traj, sd)? {
            self.nodal_sens = true;
            self.reaction_rows = true;
            return Ok(crate::LoadSensitivities {
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
        for (k, w) in work.iter_mut().enumerate() {
            drive.seed(model, k, &mut w.du_prev);
        }
        // the force at the depth held (which sets the depth's variation through the
        // spring) and the step's force from the force dofs' rows of the step's tangent
        // (`ParamStep::solve`)
        let reactions = self.reactions_from_rows();
        self.nodal_sens = false;
        self.reaction_rows = reactions;
        let mut cons = Vec::new();
        for i in 0..n {
            let rec = &traj.steps[i];
            let f1 = &traj.fields[i + 1];
            self.prepare_step(law, c, rec, (&f1.sigma, &f1.u), i, false)?;
            let prev = match i.checked_sub(1) {
                Some(p) => (&traj.steps[p], traj.fields[i].u.as_slice()),
                None => (drive.initial(), traj.fields[0].u.as_slice()),
            };
            self.contact.prepare_sensitivities(rec, &f1.u, Some(prev));
            let (sig0, sig1) = (&traj.fields[i].sigma, &f1.sigma);
            crate::residual_param_field(law, c, sig0, sig1, rec.dt, &mut r_field);
            let load = drive.step(&mut self.contact, rec, &mut carry);
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
                border: Some(crate::load::Border {
                    col: &carry.col.col,
                    s: carry.s,
                    load,
                    given: &carry.given,
                    force_prescribed: false,
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
        Ok(crate::LoadSensitivities {
            dh_dc: dh,
            df_dc: df,
            seconds: start.elapsed().as_secs_f64(),
        })
    }
}

/// A compliant run's steps as its forward sensitivities see them: the frame's compliance,
/// the test's first time, where the frame's parameters sit in the parameter vector, and
/// the initial state's record (the punch at `H(t0) = h_meas(t0) - h0`, out of contact).
pub(crate) struct FrameDrive {
    cf: f64,
    t0: f64,
    at: FrameIndex,
    init: StepRecord,
}

impl FrameDrive {
    pub(crate) fn new(schedule: &Schedule, frame: &Frame, at: FrameIndex) -> FrameDrive {
        let t0 = schedule.t[0];
        FrameDrive {
            cf: frame.compliance,
            t0,
            at,
            init: initial_record(schedule, frame),
        }
    }

    /// The record of the initial state, the "previous step" of the first step's sticking
    /// ties (Coulomb friction: a node touching down in the first step sticks where it
    /// projected at the initial depth, which moves with `h0`).
    pub(crate) fn initial(&self) -> &StepRecord {
        &self.init
    }

    /// Parameter `k`'s displacement variation of the initial state relative to the punch
    /// into `du_prev` (all dofs, zero on entry; empty without ties): `-e_z` on every
    /// candidate for `h0` (the initial depth is `H(t0)`), zero for the others.
    pub(crate) fn seed(&self, model: &indentify_contact::Model, k: usize, du_prev: &mut [f64]) {
        if self.at.offset == Some(k) {
            crate::load::relative_to_punch(model, du_prev, -1.0);
        }
    }

    /// The bordered column of the prepared step `rec` into `carry` (its depth column, the
    /// pivot and each parameter's given value) and whether the depth variation solves the
    /// spring (`true`, `Cf > 0`: `dh (s + 1/Cf) = (dH - F dCf) / Cf - dF^h`, the load
    /// control's form) or is prescribed (`false`, `Cf = 0`: `dh = dH - F dCf`).
    pub(crate) fn step(
        &self,
        contact: &mut RecordedContact<'_>,
        rec: &StepRecord,
        carry: &mut SegmentCarry,
    ) -> bool {
        let s = contact.depth_column(rec, &mut carry.col.col, &mut carry.col.kv);
        // dH_i - F_i dCf per parameter
        let given = &mut carry.given;
        given.fill(0.0);
        if let Some(k) = self.at.compliance {
            given[k] = -rec.force;
        }
        if let Some(k) = self.at.drift {
            given[k] = -(rec.t - self.t0);
        }
        if let Some(k) = self.at.offset {
            given[k] = -1.0;
        }
        if self.cf > 0.0 {
            given.iter_mut().for_each(|g| *g /= self.cf);
            carry.s = s + 1.0 / self.cf;
            true
        } else {
            carry.s = s;
            false
        }
    }
}

/// The record of a compliant run's initial state: time `t0`, the punch at `H(t0)`
/// (`DirectSolver::run_compliant` starts there), no contact, no force.
fn initial_record(schedule: &Schedule, frame: &Frame) -> StepRecord {
    StepRecord {
        t: schedule.t[0],
        dt: 0.0,
        depth: frame.prescribed(schedule, schedule.t[0]),
        force: 0.0,
        contact_radius: 0.0,
        active: Vec::new(),
        lambda: Vec::new(),
        slip: Vec::new(),
        iterations: 0,
        active_set_changes: 0,
        on_schedule: true,
        schedule_index: 0,
    }
}
