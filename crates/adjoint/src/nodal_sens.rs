//! The all-nodal forward sensitivities of a law with one isotropic tangent (elasticity,
//! Maxwell) under small strain and vertical contact, from a run recorded from rest
//! (docs/performance.md, "A cheaper sensitivity pass"): the forward counterpart of the
//! all-nodal adjoint sweep (`nodal.rs`), under the same conditions, with no pass over
//! the Gauss points per step.
//!
//! Every operator of the recursion (`lib.rs`, `ParamStep::solve`) is `p I + q J`
//! (`J = 1 (x) 1 / 3`), and a Gauss-point field `B x + J B x'` of two nodal vectors
//! (equations) stays of that form under them: `(p I + q J)(B x + J B x') = B (p x) +
//! J B (q x + (p + q) x')`. With the stresses `sigma_j = B a_j + J B b_j` of `nodal.rs`,
//! parameter `k`'s step `i` (tangent `C = (c_p, c_q)`, compliance `S = (s_p, s_q)`):
//! - `R_i e_k = dS/dc_k (sigma_{i+1} - sigma_i) + dt D_k sigma_{i+1}` (the law's
//!   isotropic parameter derivatives) is `(r, r')`;
//! - `q = y_{i-1} - R_i e_k = (q_a, q_b)` from the previous step's `y = (y, y')`;
//! - the right-hand side `-sum w B^T C q = -(K_i q_a + (c_p + c_q) K_J q_b)`, with
//!   `K_i = c_p K_1 + c_q K_J` the step's own tangent (`K_1 = sum w B^T B`, `K_J = sum w
//!   B^T J B`, formed once per model): two sparse products instead of a Gauss-point pass;
//! - the solve gives `du` (zero on the active dofs, as the contact prescribes);
//! - `dsigma = C (B du + q) = (c_p w, c_q w + (c_p + c_q) q_b)` with `w = du + q_a`,
//!   `y_i = S dsigma - B du`: vector updates;
//! - `dF_i = -sum_A (sum w B^T dsigma)_A = -sum_A (K_i w + (c_p + c_q) K_J q_b)_A`: the
//!   rows of the active dofs only (on the free rows it is the step's equation, zero).
//!
//! Per parameter and step: two sparse products, the solve and a few vector updates,
//! instead of three passes over the Gauss points and the residual's parameter
//! derivatives at every point. The columns are the Gauss-point pass's to round-off
//! (`tests/nodal_sensitivities.rs`); each parameter's recursion is the same arithmetic on
//! any thread, so the same bits on any number of threads. The stresses' nodal form is
//! checked against the recorded last state and the state of largest stress (as the sweep
//! checks it), so an elastic run unloaded to rest, whose last stresses are round-off,
//! runs all-nodal too (`tests/compliant_unload.rs`).
//!
//! Under load control (`Adjoint::sensitivities_load`) and through the frame
//! (`Adjoint::sensitivities_compliant`) the step is bordered as the Gauss-point pass
//! borders it (`load.rs`, [`crate::load::Border`]): the solve gives `du` at the depth
//! held, the force variation there, `rhs_A - (K_i du)_A` from the same rows, sets
//! `dU_i/dc_k`, whose depth column joins `du`; `dF_i/dc_k` is then prescribed (a
//! load-controlled step) or read from the rows again. The same recursion serves a linear
//! material whose blocks are isotropic (`Prony`, `material/nodal/sens.rs`), whose states
//! carry one pair of nodal vectors per block; [`for_each_param`] and
//! `Adjoint::nodal_border` are shared by both (`tests/nodal_material_sens.rs`).

use indentify_contact::{StepRecord, Trajectory};
use indentify_laws::{Law, Vec4};

use crate::affine::Iso;
use crate::load::Border;
use crate::material::SensDrive;
use crate::{Adjoint, AdjointError};

/// Per-step rows of per-parameter variations (`[step][parameter]`).
pub(crate) type Rows = Vec<Vec<f64>>;

/// A parameter's work space whose right-hand side, then solution, is `eq()`.
pub(crate) trait EqWork: Send {
    fn eq(&mut self) -> &mut [f64];
}

impl EqWork for NodalParam {
    fn eq(&mut self) -> &mut [f64] {
        &mut self.eq
    }
}

/// A step's parameter functions for [`MultiBlock::step`]: a parameter's whole step, and
/// its parts before and after the solve (each returning `(dF_i/dc_k, dU_i/dc_k)`).
pub(crate) trait ParamSteps<W>: Sync {
    fn solve(&self, k: usize, w: &mut W) -> (f64, f64);
    fn rhs(&self, k: usize, w: &mut W);
    fn finish(&self, k: usize, w: &mut W) -> (f64, f64);
}

/// The computed parameters' solves of a step together (`Adjoint::set_multi_solve`, as
/// the Gauss-point pass): their right-hand sides, then solutions (`n_eq` per column),
/// the prescribed values and the solve's scratch.
pub(crate) struct MultiBlock {
    pub(crate) cols: Vec<usize>,
    block: Vec<f64>,
    xbar: Vec<f64>,
    scratch: indentify_fe::SolveScratch,
}

impl MultiBlock {
    pub(crate) fn new(adj: &Adjoint<'_>, np: usize) -> MultiBlock {
        let cols: Vec<usize> = (0..np)
            .filter(|&k| adj.multi_solve && !adj.skips(k))
            .collect();
        let n = cols.len() * adj.model.dofs.n_eq;
        MultiBlock {
            cols,
            block: vec![0.0; n],
            xbar: vec![0.0; n],
            scratch: adj.contact.solve_scratch(),
        }
    }

    /// Every computed parameter's step into `(df, dh)`: one after the other
    /// ([`for_each_param`]) with fewer than two columns, else the right-hand sides, one
    /// multi-column solve (each column the bits of its own solve) and the remainders.
    pub(crate) fn step<W: EqWork>(
        &mut self,
        contact: &indentify_contact::RecordedContact<'_>,
        work: &mut [W],
        (df, dh): (&mut [f64], &mut [f64]),
        skip: &[bool],
        f: &impl ParamSteps<W>,
    ) {
        let active = |k: usize| !skip.get(k).copied().unwrap_or(false);
        if self.cols.len() < 2 {
            for_each_param(work, df, dh, |k, w| active(k).then(|| f.solve(k, w)));
            return;
        }
        for_each_param(work, df, dh, |k, w| {
            if active(k) {
                f.rhs(k, w);
            }
            None
        });
        let n_eq = self.block.len() / self.cols.len();
        for (col, &k) in self.block.chunks_exact_mut(n_eq).zip(&self.cols) {
            col.copy_from_slice(work[k].eq());
        }
        contact.sensitivity_solve_multi(
            &mut self.block,
            |_| &[],
            &mut self.xbar,
            &mut self.scratch,
        );
        for (col, &k) in self.block.chunks_exact(n_eq).zip(&self.cols) {
            work[k].eq().copy_from_slice(col);
        }
        for_each_param(work, df, dh, |k, w| active(k).then(|| f.finish(k, w)));
    }
}

/// One parameter's state and work space in the all-nodal pass (equation vectors).
struct NodalParam {
    /// `y_{i-1} = (y, y')`: `B y + J B y'`.
    y: Vec<f64>,
    yb: Vec<f64>,
    qa: Vec<f64>,
    qb: Vec<f64>,
    /// `K_i q_a` and `K_J q_b`.
    kq: Vec<f64>,
    kjq: Vec<f64>,
    /// The right-hand side, then `du`.
    eq: Vec<f64>,
    xbar: Vec<f64>,
    solve: indentify_fe::SolveScratch,
}

/// What a step shares between its parameters (read only).
struct NodalStep<'a> {
    pattern: &'a indentify_fe::Pattern,
    /// `K_i` (the step's unconstrained tangent) and `K_J`.
    k: &'a [f64],
    kj: &'a [f64],
    /// The states `a`, `b` before and after the step.
    a0: &'a [f64],
    a1: &'a [f64],
    b0: &'a [f64],
    b1: &'a [f64],
    /// The tangent, the compliance, the step length (s).
    ct: Iso,
    s: Iso,
    dt: f64,
    /// The law's parameter derivatives: `dS/dc_k`, `D_k`.
    ds: &'a [Iso],
    dg: &'a [Iso],
    /// The active dofs' equations.
    cons: &'a [usize],
    contact: &'a indentify_contact::RecordedContact<'a>,
    /// Load control or the frame: the step's depth column and what sets its depth
    /// variation (`load.rs`).
    border: Option<Border<'a>>,
}

impl ParamSteps<NodalParam> for NodalStep<'_> {
    /// Parameter `k`'s step: `y_i` into `w.y`, `w.yb`, returns `dF_i/dc_k` and
    /// `dU_i/dc_k` (zero without a border).
    fn solve(&self, k: usize, w: &mut NodalParam) -> (f64, f64) {
        self.rhs(k, w);
        self.contact
            .sensitivity_solve(&mut w.eq, &[], &mut w.xbar, &mut w.solve);
        self.finish(k, w)
    }

    /// The first part of [`NodalStep::solve`]: `q`, its products and the right-hand side
    /// into `w.eq`.
    fn rhs(&self, k: usize, w: &mut NodalParam) {
        let (ds, dg, dt) = (self.ds[k], self.dg[k], self.dt);
        for e in 0..w.y.len() {
            let (a1, b1) = (self.a1[e], self.b1[e]);
            let (xa, xb) = (a1 - self.a0[e], b1 - self.b0[e]);
            let ra = ds.p * xa + dt * (dg.p * a1);
            let rb = ds.q * xa + (ds.p + ds.q) * xb + dt * (dg.q * a1 + (dg.p + dg.q) * b1);
            w.qa[e] = w.y[e] - ra;
            w.qb[e] = w.yb[e] - rb;
        }
        w.kq.fill(0.0);
        self.pattern.sym_mul_add(self.k, &w.qa, &mut w.kq);
        w.kjq.fill(0.0);
        self.pattern.sym_mul_add(self.kj, &w.qb, &mut w.kjq);
        let f = self.ct.p + self.ct.q;
        for ((b, kq), kjq) in w.eq.iter_mut().zip(&w.kq).zip(&w.kjq) {
            *b = -(kq + f * kjq);
        }
    }

    /// The rest of [`NodalStep::solve`], from `du` at the depth held in `w.eq`.
    fn finish(&self, k: usize, w: &mut NodalParam) -> (f64, f64) {
        let (ct, s) = (self.ct, self.s);
        let f = ct.p + ct.q;
        let pat = self.pattern;
        let (df, du_u) = match &self.border {
            None => {
                // dF: the active rows of K_i (q_a + du) + (c_p + c_q) K_J q_b
                let mut df = 0.0;
                for &c in self.cons {
                    df += w.kq[c] + pat.row_dot(self.k, c, &w.eq) + f * w.kjq[c];
                }
                (-df, 0.0)
            }
            // the bordered step (`load.rs`): the force variation at the depth held,
            // `rhs_A - (K du)_A`, sets the depth's, whose column joins `du`; the step's
            // force is then prescribed or read from the rows again
            Some(b) => {
                let rhs_a: f64 = self.cons.iter().map(|&c| -(w.kq[c] + f * w.kjq[c])).sum();
                let rows = |du: &[f64]| {
                    self.cons
                        .iter()
                        .map(|&c| pat.row_dot(self.k, c, du))
                        .sum::<f64>()
                };
                let du_u = b.depth_variation(k, rhs_a - rows(&w.eq));
                for (e, c) in w.eq.iter_mut().zip(b.col) {
                    *e += du_u * c;
                }
                let df = if b.force_prescribed {
                    b.given[k]
                } else {
                    rhs_a - rows(&w.eq)
                };
                (df, du_u)
            }
        };
        for e in 0..w.y.len() {
            let du = w.eq[e];
            let wv = du + w.qa[e];
            let (sa, sb) = (ct.p * wv, ct.q * wv + f * w.qb[e]);
            w.y[e] = s.p * sa - du;
            w.yb[e] = s.q * sa + (s.p + s.q) * sb;
        }
        (df, du_u)
    }
}

impl Adjoint<'_> {
    /// Numeric factorizations this workspace has made so far (its sweeps and sensitivity
    /// passes; a pass that took the forward's factor makes none for the steps under its
    /// key).
    pub fn factorizations(&self) -> usize {
        self.contact.factorizations()
    }

    /// Whether the last forward sensitivity pass ran all-nodal (for tests and
    /// measurements).
    #[doc(hidden)]
    pub fn last_pass_nodal(&self) -> bool {
        self.nodal_sens
    }

    /// Whether the last Gauss-point sensitivity pass read `dF_i/dc_k` from the force
    /// dofs' rows of each step's tangent instead of a third pass over the Gauss points
    /// (under load control and through the frame also the force at the depth held,
    /// instead of two more passes; for tests and measurements).
    #[doc(hidden)]
    pub fn last_pass_reaction_rows(&self) -> bool {
        self.reaction_rows
    }

    /// The forward sensitivities `dF_i/dc_k` and `dU_i/dc_k` of `traj` all-nodal, driven
    /// by depth, under load control or through the frame (`drive`, the bordered step of
    /// `load.rs`; `dU_i/dc_k` zero under depth control; the parameters
    /// [`Adjoint::skips`] leaves out stay zero), or `None` when the pass does not apply
    /// (the conditions of the all-nodal sweep, `Adjoint::begin_nodal`, a constraint that
    /// ties steps, an active dof without an equation, or a law whose residual's parameter
    /// derivatives are not the isotropic form's at the largest stress): the Gauss-point
    /// pass then runs. Call it after `self.contact.begin()`.
    pub(crate) fn sensitivities_nodal(
        &mut self,
        law: &dyn Law,
        c: &[f64],
        traj: &Trajectory,
        drive: SensDrive<'_>,
    ) -> Result<Option<(Rows, Rows)>, AdjointError> {
        let model = self.model;
        if !self.nodal_sens_applies() {
            return Ok(None);
        }
        self.begin_nodal(law, c, traj);
        let on = std::mem::take(&mut self.fused.nodal.on);
        if !on || !self.residual_is_isotropic(law, c, traj) {
            return Ok(None);
        }
        let (Some(s), Some(ip)) = (self.fused.nodal.s, self.fused.nodal.params.take()) else {
            return Ok(None);
        };
        let n = traj.steps.len();
        let n_eq = model.dofs.n_eq;
        let np = c.len();
        let vec = || vec![0.0; n_eq];
        let mut work: Vec<NodalParam> = (0..np)
            .map(|_| NodalParam {
                y: vec(),
                yb: vec(),
                qa: vec(),
                qb: vec(),
                kq: vec(),
                kjq: vec(),
                eq: vec(),
                xbar: vec(),
                solve: self.contact.solve_scratch(),
            })
            .collect();
        let mut df = vec![vec![0.0; np]; n];
        let mut dh = vec![vec![0.0; np]; n];
        let mut carry = crate::load::SegmentCarry::new(np, n_eq);
        let mut cons = Vec::new();
        let mut multi = MultiBlock::new(self, np);
        for i in 0..n {
            let rec = &traj.steps[i];
            let f1 = &traj.fields[i + 1];
            self.prepare_step(law, c, rec, (&f1.sigma, &f1.u), i, true)?;
            let border = self.nodal_border(drive, traj, i, &mut carry, (&df, &dh))?;
            let ct = Iso::of(&self.tangents[0]).ok_or_else(|| AdjointError::Step {
                step: i,
                t: rec.t,
                reason: "the tangent is no longer isotropic".into(),
            })?;
            active_equations(model, rec, &mut cons);
            let nd = &self.fused.nodal;
            let (r0, r1) = (i * n_eq..(i + 1) * n_eq, (i + 1) * n_eq..(i + 2) * n_eq);
            let step = NodalStep {
                pattern: &model.pattern,
                k: self.contact.tangent_values(),
                kj: &nd.kj,
                a0: &nd.a[r0.clone()],
                a1: &nd.a[r1.clone()],
                b0: &nd.b[r0],
                b1: &nd.b[r1],
                ct,
                s,
                dt: rec.dt,
                ds: &ip.ds,
                dg: &ip.dg,
                cons: &cons,
                contact: &self.contact,
                border: border.map(|load| carry.border(load, drive)),
            };
            let rows = (&mut df[i][..], &mut dh[i][..]);
            multi.step(&self.contact, &mut work, rows, &self.skip, &step);
        }
        self.multi_used = multi.cols.len() > 1;
        self.fused.nodal.params = Some(ip);
        Ok(Some((df, dh)))
    }

    /// Whether the all-nodal sensitivity pass may run on this workspace's model and
    /// contact: no constraint ties a step to the previous one (friction's sticking) and
    /// every candidate's vertical dof has an equation (its row gives `dF_i/dc_k`).
    pub(crate) fn nodal_sens_applies(&self) -> bool {
        let model = self.model;
        !self.contact.ties_steps()
            && (model.candidates.iter()).all(|&n| model.dofs.equation(2 * n + 1).is_some())
    }

    /// Prepares step `i`'s sensitivities in the contact (its system prepared) and, for a
    /// bordered drive, its depth column into `carry`: `Some(load)` when the step is
    /// bordered ([`crate::load::SegmentCarry::step`], `FrameDrive::step`).
    pub(crate) fn nodal_border(
        &mut self,
        drive: SensDrive<'_>,
        traj: &Trajectory,
        i: usize,
        carry: &mut crate::load::SegmentCarry,
        rows: (&[Vec<f64>], &[Vec<f64>]),
    ) -> Result<Option<bool>, AdjointError> {
        let rec = &traj.steps[i];
        let border = match drive {
            SensDrive::Depth => None,
            SensDrive::Load(h) => carry.step(&mut self.contact, h, traj, i, rows)?,
            SensDrive::Frame(f) => Some(f.step(&mut self.contact, rec, carry)),
        };
        let prev = match (i.checked_sub(1), drive) {
            (Some(p), _) => Some((&traj.steps[p], traj.fields[i].u.as_slice())),
            (None, SensDrive::Frame(f)) => Some((f.initial(), traj.fields[0].u.as_slice())),
            (None, _) => None,
        };
        self.contact
            .prepare_sensitivities(rec, &traj.fields[i + 1].u, prev);
        Ok(border)
    }

    /// Whether the law's own `R_i e_k` (`Law::residual_param_derivatives`) is the
    /// isotropic form's `dS/dc_k (s1 - s0) + dt D_k s1` at the point of largest stress of
    /// the last step and of the step into the state of largest stress, each to 1e-12 of
    /// its largest entry (a linear law that differentiates its residual otherwise keeps
    /// the Gauss-point pass; a run unloaded to rest ends with stresses of round-off,
    /// where a form that differs only at larger stresses would go unseen).
    fn residual_is_isotropic(&self, law: &dyn Law, c: &[f64], traj: &Trajectory) -> bool {
        let (Some(ip), n) = (&self.fused.nodal.params, traj.steps.len()) else {
            return false;
        };
        if n == 0 {
            return false;
        }
        let largest = |j: usize| {
            (traj.fields[j].sigma)
                .iter()
                .fold(0.0f64, |m, x| m.max(x.max_abs()))
        };
        let (peak, _) = (1..=n).fold((n, largest(n)), |(pj, pm), j| {
            let m = largest(j);
            if m > pm { (j, m) } else { (pj, pm) }
        });
        let mut out = vec![Vec4::ZERO; c.len()];
        let apply = |m: Iso, x: &Vec4| {
            let t = (x.0[0] + x.0[1] + x.0[2]) * (m.q / 3.0);
            Vec4([
                m.p * x.0[0] + t,
                m.p * x.0[1] + t,
                m.p * x.0[2] + t,
                m.p * x.0[3],
            ])
        };
        std::iter::once(n)
            .chain((peak != n).then_some(peak))
            .all(|j| {
                let (f0, f1, rec) = (&traj.fields[j - 1], &traj.fields[j], &traj.steps[j - 1]);
                let Some(q) = (0..f1.sigma.len())
                    .max_by(|&a, &b| f1.sigma[a].max_abs().total_cmp(&f1.sigma[b].max_abs()))
                else {
                    return false;
                };
                let (s0, s1) = (f0.sigma[q], f1.sigma[q]);
                law.residual_param_derivatives(c, &s0, &s1, rec.dt, &mut out);
                out.iter().enumerate().all(|(k, o)| {
                    let iso = apply(ip.ds[k], &(s1 - s0)) + apply(ip.dg[k], &s1) * rec.dt;
                    let scale = o.max_abs().max(iso.max_abs());
                    (iso - *o).max_abs() <= 1e-12 * scale
                })
            })
    }
}

/// The equations of the active candidates' vertical dofs of step `rec` into `out`.
pub(crate) fn active_equations(
    model: &indentify_contact::Model,
    rec: &StepRecord,
    out: &mut Vec<usize>,
) {
    out.clear();
    out.extend(
        rec.active
            .iter()
            .filter_map(|&k| model.dofs.equation(2 * model.candidates[k as usize] + 1)),
    );
}

/// Runs `one(k, work)` for every parameter `k` of a step, storing its `(dF_i/dc_k,
/// dU_i/dc_k)` (`None`: skipped, left zero): in parallel on a pool's worker with more
/// than one thread, as the Gauss-point pass (each parameter's recursion is the same
/// arithmetic on any thread: the same bits), else in order.
pub(crate) fn for_each_param<W: Send>(
    work: &mut [W],
    df: &mut [f64],
    dh: &mut [f64],
    one: impl Fn(usize, &mut W) -> Option<(f64, f64)> + Sync,
) {
    let each = |(k, ((w, f), h)): (usize, ((&mut W, &mut f64), &mut f64))| {
        if let Some((a, b)) = one(k, w) {
            (*f, *h) = (a, b);
        }
    };
    let on_pool = rayon::current_thread_index().is_some();
    if work.len() > 1 && on_pool && rayon::current_num_threads() > 1 {
        use rayon::prelude::*;
        work.par_iter_mut()
            .zip(df.par_iter_mut())
            .zip(dh.par_iter_mut())
            .enumerate()
            .with_max_len(1)
            .for_each(each);
    } else {
        work.iter_mut()
            .zip(df.iter_mut())
            .zip(dh.iter_mut())
            .enumerate()
            .for_each(each);
    }
}
