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

use indentify_contact::{ForceCotangent, LoadHistory, Target, Trajectory};
use indentify_laws::{Law, Vec4};

use crate::{Adjoint, AdjointError, Gradient, Recorded, Sweep, check_inputs};

/// Whether the step ending at time `t` (s) prescribes the force.
pub(crate) fn load_controlled(history: &LoadHistory, t: f64) -> bool {
    matches!(history.segment_at(t).1, Target::Force(_))
}

impl Adjoint<'_> {
    /// The adjoint gradient `dJ/dc` of a run of [`indentify_contact::DirectSolver::run_history`]
    /// (`traj`, recorded with fields) for a cost with `dJ/dU_i = dj_dh[i]` at its
    /// load-controlled steps (the depth is the observable there) and `dJ/dF_i = dj_df[i]`
    /// at its depth-controlled ones (entries of the other kind are ignored).
    ///
    /// # Errors
    /// As [`Adjoint::gradient`]; [`AdjointError::Step`] when a load-controlled step's
    /// contact stiffness is not positive or its contact kind is not supported
    /// (Coulomb friction: its sticking ties read the depth; refused with the reason).
    pub fn gradient_load(
        &mut self,
        law: &dyn Law,
        c: &[f64],
        traj: &Trajectory,
        history: &LoadHistory,
        dj_dh: &[f64],
        dj_df: &[f64],
    ) -> Result<Gradient, AdjointError> {
        let start = std::time::Instant::now();
        let f0 = self.contact.factorizations();
        check_inputs(law, c, traj, dj_df.len())?;
        if dj_dh.len() != traj.steps.len() {
            return Err(AdjointError::Length {
                expected: traj.steps.len(),
                got: dj_dh.len(),
            });
        }
        self.contact.begin();
        let mut sweep = Sweep::new(law, c);
        self.field_a.fill(Vec4::ZERO);
        let n_eq = self.model.dofs.n_eq;
        let mut col = Column {
            col: vec![0.0; n_eq],
            kv: vec![0.0; n_eq],
        };
        // what the steps of a segment carry to the step before it when their prescribed
        // values start from its state: the force (load after depth) or the depth (depth
        // after load)
        let mut pending = 0.0;
        for i in (0..traj.steps.len()).rev() {
            let (rec, s0, s1) = (&traj.steps[i], &traj.fields[i], &traj.fields[i + 1]);
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
            };
            // the segment's start (time) and whether its prescribed values start from the
            // state of a step of the other kind (whose value then varies with c)
            let t_s = if j == 0 { 0.0 } else { history.ends[j - 1].0 };
            let t_end = history.ends[j].0;
            let mixed = j > 0 && matches!(history.ends[j - 1].1, Target::Force(_)) != load;
            let theta = (rec.t - t_s) / (t_end - t_s);
            if load {
                let rho = self.bordered_step(law, c, &mut sweep, &step, &mut col, |a, s| {
                    -(dj_dh[i] + a + carried) / s
                })?;
                if mixed && theta < 1.0 {
                    // P_i = F_s + theta (P - F_s): the start's force takes
                    // -(1 - theta) rho_i (the multiplier of F_i = P_i is -rho_i)
                    pending -= (1.0 - theta) * rho;
                }
            } else if mixed && theta < 1.0 {
                // U_i = U_s + theta (U_end - U_s): dL/dU_i carried to the start's depth
                let rho = step.rho;
                let mut d = 0.0;
                self.bordered_step(law, c, &mut sweep, &step, &mut col, |a, s| {
                    d = dj_dh[i] + a + rho * s;
                    rho
                })?;
                pending += (1.0 - theta) * d;
            } else {
                self.sweep_step(law, c, &mut sweep, &step)?;
            }
        }
        Ok(Gradient {
            dj_dc: sweep.finish(law, c),
            seconds: start.elapsed().as_secs_f64(),
            factorizations: self.contact.factorizations() - f0,
        })
    }
}

/// The depth column of a step and `K v` (scratch of [`Adjoint::bordered_step`]).
struct Column {
    col: Vec<f64>,
    kv: Vec<f64>,
}

/// The index of the segment of `history` a step ending at `t` (s) belongs to.
fn segment_index(history: &LoadHistory, t: f64) -> usize {
    history
        .ends
        .partition_point(|e| e.0 < t)
        .min(history.ends.len() - 1)
}

impl Adjoint<'_> {
    /// One sweep step whose cotangent `rho = dJ/dF_i` depends on the step's depth
    /// column: `rho_of(a, s)` with `a = g . du_U` (the right-hand side `g` before the
    /// step's own cotangent) and the Schur complement `s = dF_i/dU_i`. Returns `rho`.
    ///
    /// # Errors
    /// As [`Adjoint::gradient_load`].
    fn bordered_step(
        &mut self,
        law: &dyn Law,
        c: &[f64],
        sweep: &mut Sweep,
        step: &Recorded<'_>,
        col: &mut Column,
        rho_of: impl FnOnce(f64, f64) -> f64,
    ) -> Result<f64, AdjointError> {
        let Recorded { i, rec, f0, f1, .. } = *step;
        let fail = |reason: String| AdjointError::Step {
            step: i,
            t: rec.t,
            reason,
        };
        if self.contact.force_cotangent() == ForceCotangent::Shifted {
            return Err(fail(
                "load control: the exact gradient with Coulomb friction is not available \
                 (its sticking ties read the punch depth); fit this record with \
                 `contact: Normal` or in depth control"
                    .into(),
            ));
        }
        self.prepare_step(law, c, rec, &f1.sigma, &f1.u, i)?;
        self.adjoint_source(sweep.s, rec, None);
        self.restrict();
        let s = self.contact.depth_column(rec, &mut col.col, &mut col.kv);
        let a: f64 = self.eq.iter().zip(&col.col).map(|(g, d)| g * d).sum();
        let rho = rho_of(a, s);
        if !rho.is_finite() {
            return Err(fail(format!(
                "load control: the contact stiffness dF/dU = {s:.3e} N/mm of the recorded \
                 step is not positive: its depth is not determined by its force"
            )));
        }
        sweep.mu_zero = false;
        let mut eq = std::mem::take(&mut self.eq);
        self.contact.adjoint_solve(rec, &f1.u, rho, &mut eq);
        self.eq = eq;
        self.expand();
        self.back_substitute(law, c, sweep, rec.dt, &f0.sigma, &f1.sigma);
        Ok(rho)
    }
}
