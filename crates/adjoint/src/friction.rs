//! The exact adjoint and forward sensitivities with Coulomb friction
//! ([`indentify_contact::ContactKind::NormalFriction`]), the contact set and the
//! stick/slip partition held at their converged values (docs/validation-contact.md §7),
//! small or finite strain.
//!
//! Step `i` linearized, in the frames `(t, m)` of its active nodes (`z = Q^T du`):
//! `m . du = 0` on every active node; a sticking node ties its closest point to the
//! previous step's, `t_i . du_i = (1 + g_i kappa_i) t_{i-1} . du_{i-1} / (1 + g_{i-1}
//! kappa_{i-1})` (the prescribed value `p_i` of its tangential slot: the previous step's
//! displacement enters the step); a slipping node's row is `(t + c m) . (K du + B* C q) +
//! d t . du = 0` with `c = -mu sigma` (unsymmetric: `A = S + E W^T` on the free slots);
//! `dsigma = C (B du + q)`, `dF = -e_A . B* dsigma` as without friction. The **forward
//! sensitivities** solve this with the step's frames and the stick values from the
//! previous step's `du`. The **adjoint** transposes it: with the step's outgoing
//! functional `rho dF + <mu_{i+1}, y> + l_i . du` (`l_i` the load of step `i + 1`'s
//! sticking nodes on this step's tangential motion),
//!
//! ```text
//! g   = B* [(C S - I) mu_{i+1} - rho C B e_A] + l_i
//! V   = Q w^,  w = A^-T (Q^T g)_F,  w^ = w on F, c_k w_t,k on slipping normal slots
//! pi  = (Q^T g - K^ w^)_P   at the sticking tangential slots (cotangent of p_i)
//! mu_i = C (S mu_{i+1} - B (V + rho e_A)),  dJ/dc -= <mu_i, R_i>
//! l_{i-1} = sum_k pi_k (1 + g_i kappa_i) / (1 + g_{i-1} kappa_{i-1}) t_{i-1,k}
//! ```
//!
//! ([`ConstrainedSystem::solve_transposed`](indentify_contact::ConstrainedSystem::solve_transposed)
//! for `w` and `pi`).
//!
//! Finite strain ([`indentify_contact::Kinematics::Finite`], docs/validation-finite-strain.md
//! §7): the friction rows and the stick ties are the same (the closest point, its arc
//! coordinate and `1 + g kappa` are functions of the displaced node); the element part
//! becomes the step's `G_i = P B_L(u_i)` in place of `B`, `K` the consistent tangent
//! (geometric part included), the variation of the internal force `K du + G^T C q` (no
//! longer `B* dsigma`), hence `g = G^T (C S - I) mu_{i+1} - rho K e_A + l_i` and
//! `mu_i = C (S mu_{i+1} - G (V + rho e_A))`; the reactions that form the frames are the
//! finite internal force `sum w0 B_L^T P T`.

use indentify_contact::{Model, StepRecord, Trajectory};
use indentify_laws::{Law, Vec4};

use crate::{Adjoint, AdjointError, Recorded, Sensitivities, Sweep, check_inputs};

/// `1 + g kappa` of candidate `k`'s closest point at displacement `u` and depth `depth`
/// (`active`: measured as a node in contact), with its tangent: the closest point moves by
/// `t . du / (1 + g kappa)`.
fn arc_rate(model: &Model, k: usize, u: &[f64], depth: f64, active: bool) -> (f64, [f64; 2]) {
    let p = model.project(k, u, depth);
    let p = if active { p.in_contact() } else { p };
    (1.0 + p.gap * p.kappa, p.t)
}

impl Adjoint<'_> {
    /// The active candidates of `rec` paired with their frames in `self.frames` (index
    /// into `frames` per active candidate).
    fn frame_of_active(&self, rec: &StepRecord, i: usize) -> Result<Vec<usize>, AdjointError> {
        let model = self.model;
        let mut out = Vec::with_capacity(rec.active.len());
        for (j, &k) in rec.active.iter().enumerate() {
            let ez = model.dofs.equation(2 * model.candidates[k as usize] + 1);
            match self.frames.get(j) {
                Some(f) if Some(f.ez) == ez => out.push(j),
                _ => {
                    return Err(AdjointError::Step {
                        step: i,
                        t: rec.t,
                        reason: format!("active candidate {k} has no contact frame"),
                    });
                }
            }
        }
        if rec.slip.len() != rec.active.len() {
            return Err(AdjointError::Step {
                step: i,
                t: rec.t,
                reason: format!(
                    "the step records {} stick/slip statuses for {} active nodes",
                    rec.slip.len(),
                    rec.active.len()
                ),
            });
        }
        Ok(out)
    }

    /// One step of the reversed-time sweep with friction: `self.field_a` holds `mu_{i+1}`
    /// on entry and `mu_i` on exit; `sweep.stick` holds step `i + 1`'s sticking loads on
    /// entry and step `i`'s on exit.
    pub(crate) fn sweep_step_friction(
        &mut self,
        law: &dyn Law,
        c: &[f64],
        sweep: &mut Sweep,
        step: &Recorded<'_>,
    ) -> Result<(), AdjointError> {
        let model = self.model;
        let Recorded {
            i,
            rec,
            f0,
            f1,
            rho,
        } = *step;
        let (sig0, sig1) = (&f0.sigma, &f1.sigma);
        if sweep.mu_zero && rho == 0.0 && rec.active.is_empty() && sweep.stick.is_empty() {
            return Ok(());
        }
        sweep.mu_zero = false;
        self.prepare_step(law, c, rec, sig1, &f1.u, i)?;
        let pairs = self.frame_of_active(rec, i)?;
        let s = sweep.s;
        if self.finite.is_none() {
            // e_A: 1 on the vertical dof of every active node
            self.full.fill(0.0);
            for &k in &rec.active {
                self.full[2 * model.candidates[k as usize] + 1] = 1.0;
            }
            model.disc.strains(&self.full, &mut self.strain);
            // g = B* [(C S - I) mu_{i+1} - rho C B e_A]
            for q in 0..self.field_b.len() {
                let sm = s.mul_vec(&self.field_a[q]) - Vec4(self.strain[q]) * rho;
                self.field_b[q] = self.tangents[q].mul_vec(&sm) - self.field_a[q];
            }
            model.disc.internal_force(&self.field_b, &mut self.full);
        } else {
            // finite strain: g = G^T (C S - I) mu_{i+1} - rho K e_A (K the consistent
            // tangent, geometric part included: dF = -e_A . (K du + G^T C q))
            for q in 0..self.field_b.len() {
                let sm = s.mul_vec(&self.field_a[q]);
                self.field_b[q] = self.tangents[q].mul_vec(&sm) - self.field_a[q];
            }
            self.force_of_field_b();
            let mut e_a = std::mem::take(&mut self.xbar_full);
            e_a.clear();
            e_a.resize(self.full.len(), 0.0);
            for &k in &rec.active {
                e_a[2 * model.candidates[k as usize] + 1] = -rho;
            }
            if let Some(fs) = &self.finite {
                fs.add_k_times(model, &e_a, &mut self.full);
            }
            self.xbar_full = e_a;
        }
        // + l_i: the sticking loads of step i + 1 on this step's tangential motion
        let active_now = |k: usize| rec.active.binary_search(&(k as u32)).is_ok();
        for (k, pi) in std::mem::take(&mut sweep.stick) {
            let (rate, t) = arc_rate(model, k, &f1.u, rec.depth, active_now(k));
            let n = model.candidates[k];
            self.full[2 * n] += pi / rate * t[0];
            self.full[2 * n + 1] += pi / rate * t[1];
        }
        self.restrict();
        let mut eq = std::mem::take(&mut self.eq);
        let pi = self.system.solve_transposed(model, &mut eq);
        self.eq = eq;
        // this step's sticking nodes load the previous step
        for (j, &k) in rec.active.iter().enumerate() {
            let fj = pairs[j];
            if self.frames[fj].stick && pi[fj] != 0.0 {
                let (rate, _) = arc_rate(model, k as usize, &f1.u, rec.depth, true);
                sweep.stick.push((k as usize, pi[fj] * rate));
            }
        }
        // V' = V + rho e_A
        self.expand();
        for &k in &rec.active {
            self.full[2 * model.candidates[k as usize] + 1] += rho;
        }
        self.back_substitute(law, c, sweep, rec.dt, sig0, sig1);
        Ok(())
    }

    /// Forward sensitivities with friction (see the module's documentation).
    pub(crate) fn sensitivities_friction(
        &mut self,
        law: &dyn Law,
        c: &[f64],
        traj: &Trajectory,
    ) -> Result<Sensitivities, AdjointError> {
        let model = self.model;
        let start = std::time::Instant::now();
        let n = traj.steps.len();
        check_inputs(law, c, traj, n)?;
        self.system.forget_factorizations();
        let s = law.compliance(c);
        let np = c.len();
        let nq = model.disc.n_qp();
        let nd = model.disc.n_dofs();
        let mut y = vec![vec![Vec4::ZERO; nq]; np];
        // du of the previous step, per parameter (all dofs; 0 before the first step)
        let mut du_prev = vec![vec![0.0; nd]; np];
        let mut df = vec![vec![0.0; np]; n];
        let mut q_field = vec![Vec4::ZERO; nq];
        let mut r_field = vec![Vec4::ZERO; nq * np];
        for i in 0..n {
            let rec = &traj.steps[i];
            let f1 = &traj.fields[i + 1];
            self.prepare_step(law, c, rec, &f1.sigma, &f1.u, i)?;
            let pairs = self.frame_of_active(rec, i)?;
            // sticking nodes: t_i . du_i = coef t_{i-1} . du_{i-1}
            let mut stick: Vec<(usize, usize, f64, [f64; 2])> = Vec::new();
            if i > 0 {
                let prev = &traj.steps[i - 1];
                let u0 = &traj.fields[i].u;
                for (j, &k) in rec.active.iter().enumerate() {
                    let f = self.frames[pairs[j]];
                    if let (true, Some(er)) = (f.stick, f.er) {
                        let k = k as usize;
                        let was_active = prev.active.binary_search(&(k as u32)).is_ok();
                        let (rate0, t0) = arc_rate(model, k, u0, prev.depth, was_active);
                        let (rate1, _) = arc_rate(model, k, &f1.u, rec.depth, true);
                        stick.push((er, model.candidates[k], rate1 / rate0, t0));
                    }
                }
            }
            let (sig0, sig1) = (&traj.fields[i].sigma, &f1.sigma);
            crate::residual_param_field(law, c, sig0, sig1, rec.dt, &mut r_field);
            for k in 0..np {
                for qp in 0..nq {
                    q_field[qp] = y[k][qp] - r_field[qp * np + k];
                    self.field_b[qp] = self.tangents[qp].mul_vec(&q_field[qp]) * -1.0;
                }
                self.force_of_field_b();
                self.restrict();
                self.xbar.fill(0.0);
                for &(er, node, coef, t0) in &stick {
                    let d = &du_prev[k];
                    self.xbar[er] = coef * (t0[0] * d[2 * node] + t0[1] * d[2 * node + 1]);
                }
                let mut eq = std::mem::take(&mut self.eq);
                self.system.solve_dirichlet(model, &mut eq, &self.xbar);
                self.eq = eq;
                self.expand();
                du_prev[k].copy_from_slice(&self.full);
                self.strains_of_full();
                for qp in 0..nq {
                    let bv = Vec4(self.strain[qp]);
                    let dsig = self.tangents[qp].mul_vec(&(bv + q_field[qp]));
                    self.field_b[qp] = dsig;
                    y[k][qp] = s.mul_vec(&dsig) - bv;
                }
                self.delta_force(&q_field);
                df[i][k] = -rec
                    .active
                    .iter()
                    .map(|&a| self.full[2 * model.candidates[a as usize] + 1])
                    .sum::<f64>();
            }
            self.xbar.fill(0.0);
        }
        Ok(Sensitivities {
            df_dc: df,
            seconds: start.elapsed().as_secs_f64(),
        })
    }
}
