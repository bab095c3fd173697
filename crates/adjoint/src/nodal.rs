//! The all-nodal sweep of a law with one isotropic tangent (elasticity, Maxwell) under
//! small strain and vertical contact, from a run recorded from rest
//! (docs/validation-load-control.md §6, "All-nodal sweep"): no pass over the Gauss
//! points per step.
//!
//! Every operator of the fused pass (`affine.rs`) is `p I + q J` (`J = 1 (x) 1 / 3`), and
//! such operators form a commutative algebra (`J J = J`). So the Gauss-point fields the
//! sweep pairs are held by nodal vectors (equations):
//! - the stresses of a run from rest, `sigma_j = B a_j + J B b_j`: with `S`, `C_j` the
//!   compliance and the step's tangent, `sigma_{j+1} = C_j (S sigma_j + B du_j)` gives
//!   `a_{j+1} = c_p A`, `b_{j+1} = c_q A + (c_p + c_q) D`, `A = s_p a_j + du_j`,
//!   `D = s_q a_j + (s_p + s_q) b_j`;
//! - the adjoint stresses through `P_i = sum w B^T mu_i` and `Q_i = sum w B^T J mu_i`:
//!   `mu_i = C_i (S mu_{i+1} - B V_i)` gives
//!   `P_i = P_{i+1} + g_i - K_i V_i` (zero but on the constrained rows, where `K_i V_i`
//!   is the reaction: the free rows are the step's own equations) and
//!   `Q_i = (cs_p + cs_q) Q_{i+1} - (c_p + c_q) K_J V_i`, `K_J = sum w B^T J B` (formed
//!   once per model), `cs = C_i S`;
//! - the right-hand side of step `i`, `g_i = sum w B^T (C_i S - I) mu_{i+1} =
//!   t_p P_{i+1} + t_q Q_{i+1}`;
//! - the gradient's four sums, `sum w mu_i . sigma_j = a_j . P_i + b_j . Q_i` and
//!   `sum w tr(mu_i) tr(sigma_j) = 3 (a_j + b_j) . Q_i`.
//!
//! Per step: one sparse product with `K_J`, a few vector updates and the reactions of the
//! constrained rows, instead of `B V` and `B^T` at every Gauss point. The stresses' nodal
//! form is checked against the recorded last stress field once per sweep (else the sweep
//! keeps the Gauss-point pass). The sums are the fused pass's to round-off
//! (`tests/fused_sweep.rs`), sequential: the same bits on any number of threads.

use indentify_contact::{ContactKind, ForceCotangent, StepRecord, Trajectory};
use indentify_fe::dofs::NO_EQ;
use indentify_laws::{Law, Mat4, Vec4};

use crate::affine::{Iso, IsoParams};
use crate::{Adjoint, Sweep};

/// The all-nodal sweep's state.
#[derive(Debug, Default)]
pub(crate) struct Nodal {
    /// Whether the current sweep runs all-nodal.
    pub(crate) on: bool,
    /// `K_J = sum w B^T J B` on the model's pattern (geometry alone: formed once).
    pub(crate) kj: Vec<f64>,
    /// `a_j`, `b_j` of every recorded state `j = 0..=n`, flat (`n_eq` each).
    pub(crate) a: Vec<f64>,
    pub(crate) b: Vec<f64>,
    /// `P`, `Q` of the last step swept (equations).
    p: Vec<f64>,
    q: Vec<f64>,
    /// The right-hand side of the step being swept (equations), kept across its solve.
    g: Vec<f64>,
    /// Scratch: `K_J V`.
    kjv: Vec<f64>,
    /// The dofs without an equation (formed once).
    fixed: Vec<usize>,
    /// The step being swept and its constrained equations.
    step: usize,
    cons: Vec<usize>,
    /// The compliance and the law's parameter derivatives, isotropic.
    pub(crate) s: Option<Iso>,
    pub(crate) params: Option<IsoParams>,
}

impl Adjoint<'_> {
    /// Whether the last sweep of a stress-only law ran all-nodal (for tests that compare
    /// it with the Gauss-point pass, and measurements).
    #[doc(hidden)]
    pub fn last_sweep_was_nodal(&self) -> bool {
        self.fused.nodal.on
    }

    /// Starts the all-nodal sweep of `traj` when it applies (the fused sweep of `law`,
    /// vertical contact without friction's shift, every step's fields recorded from
    /// rest, isotropic operators, and the stresses' nodal form matching the recorded
    /// last field and the field of largest stress, to 1e-9 of that stress); otherwise
    /// leaves it off (the Gauss-point pass sweeps).
    pub(crate) fn begin_nodal(&mut self, law: &dyn Law, c: &[f64], traj: &Trajectory) {
        self.fused.nodal.on = false;
        let model = self.model;
        let n = traj.steps.len();
        let ok = self.fuse
            && self.fusable(law)
            && model.contact == ContactKind::Vertical
            && self.contact.force_cotangent() == ForceCotangent::Prescribed
            && n > 0
            && traj.fields.len() == n + 1
            && traj.fields[0].sigma.iter().all(|s| s.max_abs() == 0.0);
        #[cfg(test)]
        let ok = ok && !self.fused.general_form && !self.fused.per_point;
        if !ok {
            return;
        }
        let Some(params) = IsoParams::of(law, c) else {
            return;
        };
        let Some(s) = Iso::of(&law.compliance(c)) else {
            return;
        };
        // the fixed dofs do not move (the nodal form lives on the equations)
        let nd = &mut self.fused.nodal;
        if nd.fixed.is_empty() {
            nd.fixed = (model.dofs.eq.iter().enumerate())
                .filter(|(_, e)| **e == NO_EQ)
                .map(|(d, _)| d)
                .collect();
        }
        if !(traj.fields.iter()).all(|f| nd.fixed.iter().all(|&d| f.u[d] == 0.0)) {
            return;
        }
        let n_eq = model.dofs.n_eq;
        let nd = &mut self.fused.nodal;
        nd.a.clear();
        nd.a.resize((n + 1) * n_eq, 0.0);
        nd.b.clear();
        nd.b.resize((n + 1) * n_eq, 0.0);
        let mut du = std::mem::take(&mut nd.g);
        du.resize(n_eq, 0.0);
        for (j, rec) in traj.steps.iter().enumerate() {
            let Some(ct) = law
                .tangent(c, &Vec4::ZERO, rec.dt)
                .ok()
                .and_then(|t| Iso::of(&t))
            else {
                nd.g = du;
                return;
            };
            let (u0, u1) = (&traj.fields[j].u, &traj.fields[j + 1].u);
            for (d, &e) in model.dofs.eq.iter().enumerate() {
                if e != NO_EQ {
                    du[e as usize] = u1[d] - u0[d];
                }
            }
            let (done, next) = nd.a.split_at_mut((j + 1) * n_eq);
            let (bdone, bnext) = nd.b.split_at_mut((j + 1) * n_eq);
            let (a0, b0) = (&done[j * n_eq..], &bdone[j * n_eq..]);
            for k in 0..n_eq {
                let big_a = s.p * a0[k] + du[k];
                let big_d = s.q * a0[k] + (s.p + s.q) * b0[k];
                next[k] = ct.p * big_a;
                bnext[k] = ct.q * big_a + (ct.p + ct.q) * big_d;
            }
        }
        nd.g = du;
        // the nodal form against the recorded stresses at every point, of the last state
        // and of the state of largest stress, each to 1e-9 of the run's largest stress (a
        // run unloaded to rest ends with stresses of round-off, which alone would measure
        // nothing: an elastic body back at rest matches any isotropic law)
        let max_of = |j: usize| {
            (traj.fields[j].sigma)
                .iter()
                .fold(0.0f64, |m, x| m.max(x.max_abs()))
        };
        let (peak, scale) = (0..=n).fold((n, max_of(n)), |(pj, pm), j| {
            let m = max_of(j);
            if m > pm { (j, m) } else { (pj, pm) }
        });
        for j in std::iter::once(n).chain((peak != n).then_some(peak)) {
            if !(self.nodal_stresses_off(traj, j) <= 1e-9 * scale) {
                return;
            }
        }
        let nd = &mut self.fused.nodal;
        if nd.kj.len() != model.pattern.row_idx.len() {
            let mut j = Mat4::ZERO;
            for r in 0..3 {
                for col in 0..3 {
                    j.0[r][col] = 1.0 / 3.0;
                }
            }
            nd.kj.resize(model.pattern.row_idx.len(), 0.0);
            model
                .pattern
                .assemble_b_c_b_uniform(&model.disc, &j, &mut nd.kj);
        }
        for v in [&mut nd.p, &mut nd.q, &mut nd.kjv] {
            v.clear();
            v.resize(n_eq, 0.0);
        }
        nd.s = Some(s);
        nd.params = Some(params);
        nd.on = true;
    }

    /// The largest difference (MPa) at any point between the nodal form of the stresses
    /// of the recorded state `j` (`a_j`, `b_j`, formed by `begin_nodal`) and the recorded
    /// ones.
    fn nodal_stresses_off(&mut self, traj: &Trajectory, j: usize) -> f64 {
        let model = self.model;
        let n_eq = model.dofs.n_eq;
        let at = j * n_eq;
        let mut eq = std::mem::take(&mut self.eq);
        eq.copy_from_slice(&self.fused.nodal.a[at..at + n_eq]);
        crate::expand_into(model, &eq, &mut self.full);
        model.disc.strains(&self.full, &mut self.strain);
        let ea = std::mem::take(&mut self.strain);
        eq.copy_from_slice(&self.fused.nodal.b[at..at + n_eq]);
        crate::expand_into(model, &eq, &mut self.full);
        let mut eb = vec![[0.0; 4]; ea.len()];
        model.disc.strains(&self.full, &mut eb);
        self.eq = eq;
        let sig = &traj.fields[j].sigma;
        let worst = ea.iter().zip(&eb).zip(sig).fold(0.0f64, |m, ((x, y), s)| {
            let t = (y[0] + y[1] + y[2]) / 3.0;
            let r = Vec4([x[0] + t, x[1] + t, x[2] + t, x[3]]);
            m.max((r - *s).max_abs())
        });
        self.strain = ea;
        worst
    }

    /// The right-hand side of step `i` (tangent `self.tangents[0]`) from `P`, `Q`, into
    /// `self.full` (all dofs, as `Adjoint::adjoint_source` leaves it), kept for the
    /// back-substitution with the step's constrained equations; `false` (nothing written)
    /// when the sweep is not all-nodal.
    pub(crate) fn nodal_source(&mut self, i: usize, rec: &StepRecord) -> bool {
        let model = self.model;
        let nd = &mut self.fused.nodal;
        let (true, Some(s), Some(ct)) = (nd.on, nd.s, Iso::of(&self.tangents[0])) else {
            return false;
        };
        let t = ct.then(s).minus_identity();
        for ((g, p), q) in nd.g.iter_mut().zip(&nd.p).zip(&nd.q) {
            *g = t.p * p + t.q * q;
        }
        nd.step = i;
        nd.cons.clear();
        for &k in &rec.active {
            if let Some(e) = model.dofs.equation(2 * model.candidates[k as usize] + 1) {
                nd.cons.push(e);
            }
        }
        crate::expand_into(model, &nd.g, &mut self.full);
        true
    }

    /// The back-substitution of the step `nodal_source` began, from its adjoint
    /// displacement `V` in `self.eq`: `P`, `Q` of `mu_i` and the gradient's sums into
    /// `sweep`. `false` (nothing done) when the sweep is not all-nodal.
    pub(crate) fn nodal_back_substitute(&mut self, sweep: &mut Sweep, dt: f64) -> bool {
        let model = self.model;
        let nd = &mut self.fused.nodal;
        let (true, Some(s), Some(ct), Some(ip)) =
            (nd.on, nd.s, Iso::of(&self.tangents[0]), nd.params.as_ref())
        else {
            return false;
        };
        let v = &self.eq;
        let cs = ct.then(s);
        // P: the constrained rows' reactions (the free rows solve K V = g)
        let k = self.contact.tangent_values();
        let pat = &model.pattern;
        for &c in &nd.cons {
            nd.p[c] += nd.g[c] - pat.row_dot(k, c, v);
        }
        // Q = (cs_p + cs_q) Q - (c_p + c_q) K_J V, and the sums against the step's
        // stresses at its start (a0, b0) and end (a1, b1), in one pass
        nd.kjv.fill(0.0);
        pat.sym_mul_add(&nd.kj, v, &mut nd.kjv);
        let (fq, fv) = (cs.p + cs.q, ct.p + ct.q);
        let n_eq = v.len();
        let i = nd.step;
        let Nodal {
            a, b, p, q, kjv, ..
        } = nd;
        let (a0, a1) = (
            &a[i * n_eq..(i + 1) * n_eq],
            &a[(i + 1) * n_eq..(i + 2) * n_eq],
        );
        let (b0, b1) = (
            &b[i * n_eq..(i + 1) * n_eq],
            &b[(i + 1) * n_eq..(i + 2) * n_eq],
        );
        let mut t = [0.0; 6];
        for k in 0..n_eq {
            let qk = fq * q[k] - fv * kjv[k];
            q[k] = qk;
            t[0] += a1[k] * qk;
            t[1] += b1[k] * qk;
            t[2] += a0[k] * qk;
            t[3] += b0[k] * qk;
            t[4] += a1[k] * p[k];
            t[5] += a0[k] * p[k];
        }
        let [qa1, qb1, qa0, qb0, pa1, pa0] = t;
        let d1 = pa1 + qb1;
        let d0 = pa0 + qb0;
        let e1 = 3.0 * (qa1 + qb1);
        let e0 = 3.0 * (qa0 + qb0);
        ip.subtract(sweep, dt, [d1, d0, e1, e0]);
        true
    }
}
