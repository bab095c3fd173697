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
}

impl Border<'_> {
    /// Adds `dU_i/dc_k du_U` to the displacement variation `w.eq` (on entry: at the
    /// depth held) and returns `dU_i/dc_k`.
    pub(crate) fn shift(
        &self,
        step: &crate::ParamStep<'_>,
        k: usize,
        _yk: &[Vec4],
        w: &mut crate::ParamWork,
    ) -> f64 {
        let du = if self.load {
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
            (self.given[k] - df) / self.s
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
    /// the parameters.
    ///
    /// # Errors
    /// As [`Adjoint::gradient_load`].
    pub fn sensitivities_load(
        &mut self,
        law: &dyn Law,
        c: &[f64],
        traj: &Trajectory,
        history: &LoadHistory,
    ) -> Result<LoadSensitivities, AdjointError> {
        let model = self.model;
        let start = std::time::Instant::now();
        let n = traj.steps.len();
        check_inputs(law, c, traj, n)?;
        self.contact.begin();
        let s_mat = law.compliance(c);
        let np = c.len();
        let nq = model.disc.n_qp();
        let n_eq = model.dofs.n_eq;
        let mut y = vec![vec![Vec4::ZERO; nq]; np];
        let mut df = vec![vec![0.0; np]; n];
        let mut dh = vec![vec![0.0; np]; n];
        let mut r_field = vec![Vec4::ZERO; nq * np];
        let mut work: Vec<crate::ParamWork> = (0..np)
            .map(|_| crate::ParamWork::new(model, &self.contact))
            .collect();
        let mut col = Column {
            col: vec![0.0; n_eq],
            kv: vec![0.0; n_eq],
        };
        // the state a segment starts from: its force's and depth's variations
        let mut start_f = vec![0.0; np];
        let mut start_u = vec![0.0; np];
        let mut given = vec![0.0; np];
        for i in 0..n {
            let rec = &traj.steps[i];
            let f1 = &traj.fields[i + 1];
            self.prepare_step(law, c, rec, &f1.sigma, &f1.u, i)?;
            let prev = i
                .checked_sub(1)
                .map(|p| (&traj.steps[p], traj.fields[i].u.as_slice()));
            self.contact.prepare_sensitivities(rec, &f1.u, prev);
            let (sig0, sig1) = (&traj.fields[i].sigma, &f1.sigma);
            crate::residual_param_field(law, c, sig0, sig1, rec.dt, &mut r_field);
            let j = segment_index(history, rec.t);
            let load = load_controlled(history, rec.t);
            if i > 0 && segment_index(history, traj.steps[i - 1].t) != j {
                start_f.clone_from(&df[i - 1]);
                start_u.clone_from(&dh[i - 1]);
            }
            let t_s = if j == 0 { 0.0 } else { history.ends[j - 1].0 };
            let theta = ((rec.t - t_s) / (history.ends[j].0 - t_s)).min(1.0);
            let mixed = j > 0 && matches!(history.ends[j - 1].1, Target::Force(_)) != load;
            for (g, (f, u)) in given.iter_mut().zip(start_f.iter().zip(&start_u)) {
                *g = match (mixed, load) {
                    (false, _) => 0.0,
                    (true, true) => (1.0 - theta) * f,
                    (true, false) => (1.0 - theta) * u,
                };
            }
            let bordered = load || mixed;
            let s = if bordered {
                if self.contact.force_cotangent() == ForceCotangent::Shifted {
                    return Err(AdjointError::Step {
                        step: i,
                        t: rec.t,
                        reason: "load control: the exact sensitivities with Coulomb \
                                 friction are not available (its sticking ties read the \
                                 punch depth)"
                            .into(),
                    });
                }
                self.contact.depth_column(rec, &mut col.col, &mut col.kv)
            } else {
                0.0
            };
            if load && !(s.is_finite() && s > 0.0) {
                return Err(AdjointError::Step {
                    step: i,
                    t: rec.t,
                    reason: format!(
                        "load control: the contact stiffness dF/dU = {s:.3e} N/mm of the \
                         recorded step is not positive"
                    ),
                });
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
                border: bordered.then_some(Border {
                    col: &col.col,
                    s,
                    load,
                    given: &given,
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
