//! The all-nodal sweep of a linear material whose blocks are isotropic (`Prony`), under
//! small strain and vertical contact, from a run recorded from rest
//! (docs/validation-load-control.md §6, "All-nodal sweep"): no pass over the Gauss
//! points per step.
//!
//! Every 4 x 4 block of the material's blocks `A`, `D`, `E` and of their parameter
//! derivatives is `p I + q J`, which is `d P + s J` with `P = I - J` the deviatoric and
//! `J = 1 (x) 1 / 3` the spherical projector (`d = p`, `s = p + q`): two independent
//! channels. So the Gauss-point fields the sweep pairs are nodal vectors (equations), each
//! block `I` of a state or adjoint state:
//! - the states of a run from rest, `y_{j,I} = P B a_{j,I} + J B h_{j,I}`: the step
//!   `y_{j+1} = M y_j + N B du_j` (`M = -A^-1 D`, `N = -A^-1 E`, blocks `(d, s)`) gives
//!   `a_{j+1,I} = sum_J M^d_IJ a_{j,J} + N^d_I du_j`, `h` the same with `s`;
//! - the adjoint states through `R_I = sum w B^T P mu_I` and `Q_I = sum w B^T J mu_I`:
//!   `mu_i = -(Qf mu_{i+1} + G B V_i)` (`Qf = A_i^-T D_{i+1}^T`, `G = A_i^-T Pi^T`,
//!   `material.rs`) gives `R_I = -sum_J Qf^d_IJ R_J - G^d_I K_P V`,
//!   `Q_I = -sum_J Qf^s_IJ Q_J - G^s_I K_J V`, with `K_J = sum w B^T J B` (formed once
//!   per model) and `K_P V = (K_i V - c_s K_J V) / c_d` from the step's own equations
//!   (`K_i V` is the right-hand side on the free rows, read from the step's tangent on the
//!   constrained ones; `K_i = c_d K_P + c_s K_J`);
//! - the right-hand side `sum w B^T S^T mu_{i+1} = sum_I (S^d_I R_I + S^s_I Q_I)`;
//! - the gradient `-sum w mu^T P(c)`: the residual's parameter derivative is linear in the
//!   state and strain increment (probed block by block from [`Material::jac_params`] once
//!   per step length), and `sum w mu_I . (d P + s J) y_J = d a_J . R_I + s h_J . Q_I`.
//!
//! Per step: one sparse product with `K_J`, the reactions of the constrained rows and
//! vector operations on `nb = m / 4` blocks, instead of `B du`, `B V`, `B^T` and the
//! material's products at every Gauss point. The nodal states are checked against the
//! recorded last state and the state of largest stress at every point once per sweep,
//! each to 1e-9 of each block's largest over the run (else the Gauss-point pass sweeps):
//! a run held until relaxed ends with states of round-off, which alone measure nothing.
//! Sequential: the same bits on any number of threads.
//!
//! Under load control (`load.rs`) and through the frame (`compliant.rs`) the step is
//! bordered: its cotangent comes from the
//! nodal right-hand side `g` against the step's depth column and its Schur complement,
//! as the Gauss-point sweep forms it from its own `g` (the same vector), and the
//! transposed solve takes it (one solve with the capacitance system of the material's
//! uniform tangent). The free rows still solve `K_i V = g`, so `K_i V` and the
//! recursion of `R`, `Q` are unchanged.

use indentify_contact::{ContactKind, ForceCotangent, StepFields, StepRecord, Trajectory};
use indentify_fe::dofs::NO_EQ;
use indentify_laws::material::{Regime, Step, dense_solve_many};
use indentify_laws::{Mat4, Material, Vec4};

mod sens;

use super::MatSweep;
use crate::affine::Iso;
use crate::load::{BorderedRho, not_positive};
use crate::{Adjoint, AdjointError};

/// The most blocks a state may have (`Prony`'s eight terms and the stress).
const MAX_BLOCKS: usize = 9;

/// A matrix of isotropic 4 x 4 blocks by each block's deviatoric and spherical
/// eigenvalues (`rows x cols` blocks, row-major).
#[derive(Clone, Debug, Default, PartialEq)]
struct IsoBlocks {
    cols: usize,
    d: Vec<f64>,
    s: Vec<f64>,
}

impl IsoBlocks {
    /// The blocks of the dense row-major `dense` (`4 rows x 4 cols`) when each is
    /// `p I + q J` to `tol` of the largest entry.
    fn of(dense: &[f64], rows: usize, cols: usize, tol: f64) -> Option<IsoBlocks> {
        let w = 4 * cols;
        let big = dense[..4 * rows * w]
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        if !big.is_finite() {
            return None;
        }
        let mut out = IsoBlocks {
            cols,
            d: vec![0.0; rows * cols],
            s: vec![0.0; rows * cols],
        };
        for bi in 0..rows {
            for bj in 0..cols {
                let e = |i: usize, j: usize| dense[(4 * bi + i) * w + 4 * bj + j];
                let iso = Iso {
                    p: e(3, 3),
                    q: 3.0 * e(0, 1),
                };
                for i in 0..4 {
                    for j in 0..4 {
                        let sph = if i < 3 && j < 3 { iso.q / 3.0 } else { 0.0 };
                        let want = if i == j { iso.p + sph } else { sph };
                        if (e(i, j) - want).abs() > tol * big {
                            return None;
                        }
                    }
                }
                out.d[bi * cols + bj] = iso.p;
                out.s[bi * cols + bj] = iso.p + iso.q;
            }
        }
        Some(out)
    }

    fn d(&self, i: usize, j: usize) -> f64 {
        self.d[i * self.cols + j]
    }

    fn s(&self, i: usize, j: usize) -> f64 {
        self.s[i * self.cols + j]
    }
}

/// A step length's operators: the state's step `M`, `N` and, per parameter, the blocks
/// of the residual's derivative with respect to `y1`, `y0` and `deps`.
#[derive(Clone, Debug, Default)]
struct StepOps {
    dt_bits: u64,
    m: IsoBlocks,
    n: IsoBlocks,
    da: Vec<IsoBlocks>,
    dd: Vec<IsoBlocks>,
    de: Vec<IsoBlocks>,
    /// Per block pair `(I, J)`: whether some parameter's `y1` (first) or `y0` (second)
    /// block is not zero; per block `I`, whether some `deps` block is not zero.
    pairs: Vec<(bool, bool)>,
    strain_blocks: Vec<bool>,
}

impl StepOps {
    /// The operators of `mat` at `(c, dt)`, or `None` when the material's residual is not
    /// linear without offset in the state, or a block is not isotropic.
    fn of(mat: &dyn Material, c: &[f64], dt: f64) -> Option<StepOps> {
        let m = mat.state_len();
        let (nb, np) = (m / 4, c.len());
        let zero = vec![0.0; m];
        let mut unit = vec![0.0; m];
        // the residual and its parameter derivative vanish at rest
        let mut r = vec![0.0; m];
        mat.residual(c, &smooth_step(&zero, &zero, &Vec4::ZERO, dt), &mut r);
        let mut p = vec![0.0; m * np];
        mat.jac_params(c, &smooth_step(&zero, &zero, &Vec4::ZERO, dt), &mut p);
        if r.iter().chain(&p).any(|v| *v != 0.0) {
            return None;
        }
        // A X = [D | E]: M = -X[:, ..m], N = -X[:, m..]
        let st = smooth_step(&zero, &zero, &Vec4::ZERO, dt);
        let (mut a, mut d, mut e) = (vec![0.0; m * m], vec![0.0; m * m], vec![0.0; m * 4]);
        mat.jac_state(c, &st, &mut a);
        mat.jac_previous(c, &st, &mut d);
        mat.jac_strain(c, &st, &mut e);
        let w = m + 4;
        let mut x = vec![0.0; m * w];
        for r in 0..m {
            for k in 0..m {
                x[r * w + k] = -d[r * m + k];
            }
            for k in 0..4 {
                x[r * w + m + k] = -e[r * 4 + k];
            }
        }
        if !dense_solve_many(&mut a, m, &mut x, w) {
            return None;
        }
        let mut mm = vec![0.0; m * m];
        let mut nn = vec![0.0; m * 4];
        for r in 0..m {
            mm[r * m..(r + 1) * m].copy_from_slice(&x[r * w..r * w + m]);
            nn[r * 4..(r + 1) * 4].copy_from_slice(&x[r * w + m..(r + 1) * w]);
        }
        let tol = 1e-10;
        let (m_ops, n_ops) = (
            IsoBlocks::of(&mm, nb, nb, tol)?,
            IsoBlocks::of(&nn, nb, 1, tol)?,
        );
        // the parameter derivative's blocks, probed one unit state entry at a time
        let mut da = vec![vec![0.0; m * m]; np];
        let mut dd = vec![vec![0.0; m * m]; np];
        let mut de = vec![vec![0.0; m * 4]; np];
        for col in 0..m + m + 4 {
            unit.fill(0.0);
            let mut du = Vec4::ZERO;
            let st = if col < m {
                unit[col] = 1.0;
                smooth_step(&zero, &unit, &du, dt)
            } else if col < 2 * m {
                unit[col - m] = 1.0;
                smooth_step(&unit, &zero, &du, dt)
            } else {
                du.0[col - 2 * m] = 1.0;
                smooth_step(&zero, &zero, &du, dt)
            };
            mat.jac_params(c, &st, &mut p);
            for row in 0..m {
                for k in 0..np {
                    let v = p[row * np + k];
                    match col {
                        j if j < m => da[k][row * m + j] = v,
                        j if j < 2 * m => dd[k][row * m + j - m] = v,
                        j => de[k][row * 4 + j - 2 * m] = v,
                    }
                }
            }
        }
        let tol = 1e-12;
        let blocks = |v: &[Vec<f64>], cols: usize| {
            v.iter()
                .map(|x| IsoBlocks::of(x, nb, cols, tol))
                .collect::<Option<Vec<_>>>()
        };
        let (da, dd, de) = (blocks(&da, nb)?, blocks(&dd, nb)?, blocks(&de, 1)?);
        let any = |v: &[IsoBlocks], at: usize| v.iter().any(|b| b.d[at] != 0.0 || b.s[at] != 0.0);
        let pairs = (0..nb * nb)
            .map(|at| (any(&da, at), any(&dd, at)))
            .collect();
        let strain_blocks = (0..nb).map(|at| any(&de, at)).collect();
        Some(StepOps {
            dt_bits: dt.to_bits(),
            m: m_ops,
            n: n_ops,
            da,
            dd,
            de,
            pairs,
            strain_blocks,
        })
    }

    /// The check of linearity: the probed linear form of `jac_params` at a recorded point
    /// equals the material's own there (to 1e-10 of the larger).
    fn linear_at(&self, mat: &dyn Material, c: &[f64], step: &Step<'_>) -> bool {
        let (m, np) = (step.y1.len(), c.len());
        let mut p = vec![0.0; m * np];
        mat.jac_params(c, step, &mut p);
        let apply = |b: &IsoBlocks, x: &[f64], row_block: usize, comp: usize| {
            let mut v = 0.0;
            for bj in 0..b.cols {
                let xs = &x[4 * bj..4 * bj + 4];
                let tr = (xs[0] + xs[1] + xs[2]) / 3.0;
                let dev = xs[comp] - if comp < 3 { tr } else { 0.0 };
                let sph = if comp < 3 { tr } else { 0.0 };
                v += b.d(row_block, bj) * dev + b.s(row_block, bj) * sph;
            }
            v
        };
        let big = p.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        (0..m).all(|row| {
            (0..np).all(|k| {
                let (bi, comp) = (row / 4, row % 4);
                let want = apply(&self.da[k], step.y1, bi, comp)
                    + apply(&self.dd[k], step.y0, bi, comp)
                    + apply(&self.de[k], &step.deps.0, bi, comp);
                (want - p[row * np + k]).abs() <= 1e-10 * big
            })
        })
    }
}

/// `[x . r, y . q]` in four lanes each (a fixed order: the same bits on any number of
/// threads; the lanes let the compiler use vector registers).
#[inline]
fn dot_pair(x: &[f64], r: &[f64], y: &[f64], q: &[f64]) -> [f64; 2] {
    let (mut s, mut t) = ([0.0; 4], [0.0; 4]);
    let n4 = x.len() / 4 * 4;
    for (((x, r), y), q) in (x[..n4].chunks_exact(4))
        .zip(r[..n4].chunks_exact(4))
        .zip(y[..n4].chunks_exact(4))
        .zip(q[..n4].chunks_exact(4))
    {
        for l in 0..4 {
            s[l] += x[l] * r[l];
            t[l] += y[l] * q[l];
        }
    }
    for e in n4..x.len() {
        s[0] += x[e] * r[e];
        t[0] += y[e] * q[e];
    }
    [(s[0] + s[1]) + (s[2] + s[3]), (t[0] + t[1]) + (t[2] + t[3])]
}

/// A step in the smooth regime (a linear material has no other).
fn smooth_step<'a>(y0: &'a [f64], y1: &'a [f64], deps: &'a Vec4, dt: f64) -> Step<'a> {
    Step {
        y0,
        y1,
        deps,
        dt,
        regime: Regime::Smooth,
    }
}

/// The all-nodal material sweep's state (kept by the workspace across sweeps).
#[derive(Debug, Default)]
pub(crate) struct NodalMat {
    /// Whether the last sweep ran all-nodal.
    pub(crate) on: bool,
    nb: usize,
    /// `K_J = sum w B^T J B` on the model's pattern (formed once).
    kj: Vec<f64>,
    /// `K_P = sum w B^T P B` (formed once, by the first forward sensitivity pass:
    /// `nodal/sens.rs`).
    kp: Vec<f64>,
    /// The dofs without an equation (formed once).
    fixed: Vec<usize>,
    /// `a_{j,I}`, `h_{j,I}` of every recorded state: `[(j nb + I) n_eq + e]`.
    a: Vec<f64>,
    h: Vec<f64>,
    /// `R_I`, `Q_I` of the adjoint state of the last step swept, and their next values.
    r: Vec<f64>,
    q: Vec<f64>,
    r_new: Vec<f64>,
    q_new: Vec<f64>,
    /// Scratch (equations): the right-hand side, `K_i V`, `K_J V`, `K_P V`, `du`.
    g: Vec<f64>,
    kv: Vec<f64>,
    kjv: Vec<f64>,
    kpv: Vec<f64>,
    du: Vec<f64>,
    /// The operators of the step length last used.
    ops: Option<StepOps>,
}

impl NodalMat {
    /// Sets `self.ops` to the operators of step length `dt` (kept while it repeats);
    /// `false` when they are not of the module's form.
    fn ops_for(&mut self, mat: &dyn Material, c: &[f64], dt: f64) -> bool {
        if self.ops.as_ref().is_some_and(|o| o.dt_bits == dt.to_bits()) {
            return true;
        }
        self.ops = StepOps::of(mat, c, dt);
        self.ops.is_some()
    }
}

impl Adjoint<'_> {
    /// Whether the last depth- or load-controlled sweep of a material with internal
    /// variables ran all-nodal (for tests that compare it with the Gauss-point pass).
    #[doc(hidden)]
    pub fn last_material_sweep_was_nodal(&self) -> bool {
        self.nodal_mat.on
    }

    /// Starts the all-nodal sweep of `traj` when it applies: `Adjoint::set_fused` on, a
    /// linear material with isotropic blocks under small strain and vertical contact
    /// without friction's shift, every step's fields recorded from rest, the fixed dofs
    /// at zero, and the nodal states matching the recorded last state and the state of
    /// largest stress at every point; otherwise `false` (the Gauss-point pass sweeps).
    pub(crate) fn begin_nodal_material(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
    ) -> bool {
        let mut nd = std::mem::take(&mut self.nodal_mat);
        nd.on = self.nodal_material_setup(&mut nd, mat, c, traj);
        let on = nd.on;
        self.nodal_mat = nd;
        on
    }

    fn nodal_material_setup(
        &mut self,
        nd: &mut NodalMat,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
    ) -> bool {
        let model = self.model;
        let n = traj.steps.len();
        let m = mat.state_len();
        let ok = self.fuse
            && self.finite.is_none()
            && mat.is_linear()
            && m % 4 == 0
            && m / 4 <= MAX_BLOCKS
            && model.contact == ContactKind::Vertical
            && self.contact.force_cotangent() == ForceCotangent::Prescribed
            && n > 0
            && traj.fields.len() == n + 1
            && traj.fields[0].sigma.iter().all(|s| s.max_abs() == 0.0)
            && traj.fields[0].alpha.iter().all(|a| *a == 0.0);
        if !ok {
            return false;
        }
        if nd.fixed.is_empty() {
            nd.fixed = (model.dofs.eq.iter().enumerate())
                .filter(|(_, e)| **e == NO_EQ)
                .map(|(d, _)| d)
                .collect();
        }
        if !(traj.fields.iter()).all(|f| nd.fixed.iter().all(|&d| f.u[d] == 0.0)) {
            return false;
        }
        let (nb, n_eq) = (m / 4, model.dofs.n_eq);
        nd.nb = nb;
        nd.ops = None;
        // (the state at rest is zero; the loop below writes every later one whole)
        for v in [&mut nd.a, &mut nd.h] {
            v.resize((n + 1) * nb * n_eq, 0.0);
            v[..nb * n_eq].fill(0.0);
        }
        for v in [
            &mut nd.r,
            &mut nd.q,
            &mut nd.r_new,
            &mut nd.q_new,
            &mut nd.g,
            &mut nd.kv,
            &mut nd.kjv,
            &mut nd.kpv,
            &mut nd.du,
        ] {
            v.clear();
            v.resize(nb * n_eq, 0.0);
        }
        // the states step by step
        for (j, rec) in traj.steps.iter().enumerate() {
            if !nd.ops_for(mat, c, rec.dt) {
                return false;
            }
            let ops = nd.ops.as_ref().expect("set");
            let (u0, u1) = (&traj.fields[j].u, &traj.fields[j + 1].u);
            for (d, &e) in model.dofs.eq.iter().enumerate() {
                if e != NO_EQ {
                    nd.du[e as usize] = u1[d] - u0[d];
                }
            }
            let blk = nb * n_eq;
            for (x, chan_s) in [(&mut nd.a, false), (&mut nd.h, true)] {
                let (done, next) = x.split_at_mut((j + 1) * blk);
                let prev = &done[j * blk..];
                for bi in 0..nb {
                    let out = &mut next[bi * n_eq..(bi + 1) * n_eq];
                    let f = if chan_s {
                        ops.n.s(bi, 0)
                    } else {
                        ops.n.d(bi, 0)
                    };
                    for (o, d) in out.iter_mut().zip(&nd.du) {
                        *o = f * d;
                    }
                    for bj in 0..nb {
                        let f = if chan_s {
                            ops.m.s(bi, bj)
                        } else {
                            ops.m.d(bi, bj)
                        };
                        if f != 0.0 {
                            let src = &prev[bj * n_eq..(bj + 1) * n_eq];
                            for (o, s) in out.iter_mut().zip(src) {
                                *o += f * s;
                            }
                        }
                    }
                }
            }
        }
        if !self.nodal_states_match(nd, mat, c, traj) {
            return false;
        }
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
        true
    }

    /// The nodal form of the recorded states against the recorded ones at every point,
    /// block by block, of the last state and of the state of largest stress, each to
    /// 1e-9 of the block's largest over the run (a run unloaded and held until relaxed
    /// ends with states of round-off, which alone would measure nothing: a body back at
    /// rest matches any isotropic material), and the probed parameter derivative against
    /// the material's at the point of largest stress of the state of largest stress.
    fn nodal_states_match(
        &mut self,
        nd: &mut NodalMat,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
    ) -> bool {
        let model = self.model;
        let (nb, n_eq, n) = (nd.nb, model.dofs.n_eq, traj.steps.len());
        let nq = model.disc.n_qp();
        let na = nb * 4 - 4;
        // each block's largest entry over the run, and the state of largest stress
        let mut scale = vec![0.0f64; nb];
        let (mut peak, mut peak_sigma) = (n, 0.0f64);
        for (j, f) in traj.fields.iter().enumerate() {
            let sig = f.sigma.iter().fold(0.0f64, |m, x| m.max(x.max_abs()));
            scale[0] = scale[0].max(sig);
            if sig > peak_sigma {
                (peak, peak_sigma) = (j, sig);
            }
            if na > 0 {
                for a in f.alpha.chunks_exact(na) {
                    for (bi, blk) in a.chunks_exact(4).enumerate() {
                        let m = blk.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                        scale[bi + 1] = scale[bi + 1].max(m);
                    }
                }
            }
        }
        let mut full = vec![0.0; model.disc.n_dofs()];
        let (mut ea, mut eh) = (vec![[0.0; 4]; nq], vec![[0.0; 4]; nq]);
        for j in std::iter::once(n).chain((peak != n).then_some(peak)) {
            let state = &traj.fields[j];
            for (bi, &scale) in scale.iter().enumerate() {
                let at = (j * nb + bi) * n_eq;
                crate::expand_into(model, &nd.a[at..at + n_eq], &mut full);
                model.disc.strains(&full, &mut ea);
                crate::expand_into(model, &nd.h[at..at + n_eq], &mut full);
                model.disc.strains(&full, &mut eh);
                let rec = |q: usize, k: usize| {
                    if bi == 0 {
                        state.sigma[q].0[k]
                    } else {
                        state.alpha[q * na + 4 * (bi - 1) + k]
                    }
                };
                let mut worst = 0.0f64;
                for q in 0..nq {
                    let (x, y) = (&ea[q], &eh[q]);
                    let t = (y[0] + y[1] + y[2] - x[0] - x[1] - x[2]) / 3.0;
                    let v = [x[0] + t, x[1] + t, x[2] + t, x[3]];
                    for (k, vk) in v.iter().enumerate() {
                        worst = worst.max((vk - rec(q, k)).abs());
                    }
                }
                if !(worst <= 1e-9 * scale) {
                    return false;
                }
            }
        }
        // the parameter derivative is the probed linear form at a recorded point: the
        // point of largest stress of the state of largest stress, with the step into it
        // (the last state's, at rest, would measure round-off)
        self.linear_at_state(nd, mat, c, traj, peak)
    }

    /// Whether the material's parameter derivative at the point of largest stress of the
    /// recorded state `j >= 1`, with the step into it, is the probed linear form.
    fn linear_at_state(
        &self,
        nd: &mut NodalMat,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        j: usize,
    ) -> bool {
        let model = self.model;
        let na = nd.nb * 4 - 4;
        let Some(into) = j.checked_sub(1) else {
            return false;
        };
        let (f0, f1) = (&traj.fields[into], &traj.fields[j]);
        let Some(qbig) = (0..f1.sigma.len())
            .max_by(|&x, &y| f1.sigma[x].max_abs().total_cmp(&f1.sigma[y].max_abs()))
        else {
            return false;
        };
        let mut du = vec![0.0; model.disc.n_dofs()];
        for ((d, a), b) in du.iter_mut().zip(&f1.u).zip(&f0.u) {
            *d = a - b;
        }
        let mut eps = vec![[0.0; 4]; model.disc.n_qp()];
        model.disc.strains(&du, &mut eps);
        let state = |f: &StepFields| {
            let mut y = f.sigma[qbig].0.to_vec();
            y.extend_from_slice(&f.alpha[qbig * na..(qbig + 1) * na]);
            y
        };
        let (y0, y1) = (state(f0), state(f1));
        let deps = Vec4(eps[qbig]);
        let step = Step {
            y0: &y0,
            y1: &y1,
            deps: &deps,
            dt: traj.steps[into].dt,
            regime: Regime::Smooth,
        };
        // (the sweep sets each step's operators again: `ops_for` keeps them by length)
        if !nd.ops_for(mat, c, step.dt) {
            return false;
        }
        nd.ops
            .as_ref()
            .is_some_and(|ops| ops.linear_at(mat, c, &step))
    }

    /// One step of the all-nodal sweep (the module's recursion), in place of
    /// `Adjoint::material_step` (depth control, `dJ/dF_i = rho`).
    ///
    /// # Errors
    /// As `Adjoint::material_step`; a step whose folded blocks are not isotropic (the
    /// sweep's start checked every step length's) is refused rather than swept wrong.
    #[allow(clippy::too_many_arguments)] // (`material_step`'s own, less the border)
    pub(crate) fn nodal_material_step(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        sw: &mut MatSweep,
        i: usize,
        rec: &StepRecord,
        (f0, f1): (&StepFields, &StepFields),
        rho: f64,
    ) -> Result<(), AdjointError> {
        self.nodal_material_step_bordered(mat, c, sw, i, rec, (f0, f1), rho, None)
            .map(|_| ())
    }

    /// [`Adjoint::nodal_material_step`] with the cotangent of a load-controlled step (or
    /// of a depth-controlled step whose depth starts from a load-controlled one's) set by
    /// its depth column (`border`, `load.rs`): the bordered scalar from the nodal
    /// right-hand side, as `Adjoint::material_step` forms it from the Gauss-point one, and
    /// the step's transposed solve with it (one solve where the system is an affine law's
    /// capacitance system). Returns the cotangent used.
    ///
    /// # Errors
    /// As [`Adjoint::nodal_material_step`]; [`AdjointError::Step`] when a load-controlled
    /// step's contact stiffness is not positive.
    #[allow(clippy::too_many_arguments)] // (`material_step`'s own)
    pub(crate) fn nodal_material_step_bordered(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        sw: &mut MatSweep,
        i: usize,
        rec: &StepRecord,
        (f0, f1): (&StepFields, &StepFields),
        rho: f64,
        border: Option<BorderedRho<'_>>,
    ) -> Result<f64, AdjointError> {
        if border.is_none()
            && sw.zero
            && rho == 0.0
            && rec.active.is_empty()
            && !self.contact.adjoint_pending()
        {
            return Ok(rho);
        }
        sw.zero = false;
        let fail = |reason: String| AdjointError::Step {
            step: i,
            t: rec.t,
            reason: format!("{}: {reason}", mat.name()),
        };
        sw.load(f0, f1, 0);
        if !sw.linear_blocks(mat, c, &Vec4::ZERO, rec.dt) {
            return Err(fail("singular local Jacobian A (tangent)".into()));
        }
        let mut nd = std::mem::take(&mut self.nodal_mat);
        let out = self.nodal_step_inner(&mut nd, mat, c, sw, (i, rec), (f0, f1), (rho, border));
        self.nodal_mat = nd;
        sw.d_next.copy_from_slice(&sw.d);
        sw.e_next.copy_from_slice(&sw.ej);
        out.map_err(|e| match e {
            StepError::Nodal(reason) => fail(reason),
            StepError::Adjoint(e) => e,
        })
    }

    #[allow(clippy::too_many_arguments)]
    fn nodal_step_inner(
        &mut self,
        nd: &mut NodalMat,
        mat: &dyn Material,
        c: &[f64],
        sw: &mut MatSweep,
        (i, rec): (usize, &StepRecord),
        (f0, f1): (&StepFields, &StepFields),
        (rho, border): (f64, Option<BorderedRho<'_>>),
    ) -> Result<f64, StepError> {
        let model = self.model;
        let (nb, n_eq) = (nd.nb, model.dofs.n_eq);
        let m = 4 * nb;
        let not_iso =
            || StepError::Nodal("the all-nodal sweep's folded blocks are not isotropic".into());
        let qf = IsoBlocks::of(&sw.qm, nb, nb, 1e-10).ok_or_else(not_iso)?;
        let sm = IsoBlocks::of(&sw.sm, nb, 1, 1e-10).ok_or_else(not_iso)?;
        let gl = IsoBlocks::of(&sw.glin, nb, 1, 1e-10).ok_or_else(not_iso)?;
        let ct = Iso::of(&sw.ct).ok_or_else(not_iso)?;
        let (cd, cs) = (ct.p, ct.p + ct.q);
        if !nd.ops_for(mat, c, rec.dt) {
            return Err(StepError::Nodal(
                "the all-nodal sweep's parameter blocks are not isotropic".into(),
            ));
        }
        debug_assert_eq!(sw.m, m);
        // the step's system
        self.tangents[0] = sw.ct;
        self.prepare_material_step(rec, f1, Some(c))
            .map_err(StepError::Nodal)?;
        // the right-hand side sum_I S^d_I R_I + S^s_I Q_I
        nd.g.fill(0.0);
        let g = &mut nd.g[..n_eq];
        for bi in 0..nb {
            let (fd, fs) = (sm.d(bi, 0), sm.s(bi, 0));
            let (r, q) = (
                &nd.r[bi * n_eq..(bi + 1) * n_eq],
                &nd.q[bi * n_eq..(bi + 1) * n_eq],
            );
            for ((g, r), q) in g.iter_mut().zip(r).zip(q) {
                *g += fd * r + fs * q;
            }
        }
        let mut eq = std::mem::take(&mut self.eq);
        eq.copy_from_slice(g);
        let rho = match border {
            None => {
                self.contact.adjoint_solve(rec, &f1.u, rho, &mut eq);
                rho
            }
            // the depth column, the cotangent and the transposed solve in one solve (an
            // affine law's capacitance system), else the bordered scalar from the
            // right-hand side and the plain solve, as the Gauss-point sweep does
            Some(b) => {
                match (self.contact).adjoint_solve_bordered(rec, &f1.u, &mut eq, &mut *b.rho_of) {
                    Some((rho, _)) if rho.is_finite() => rho,
                    Some((_, s)) => {
                        self.eq = eq;
                        return Err(StepError::Adjoint(not_positive(i, rec, s)));
                    }
                    None => {
                        eq.copy_from_slice(g);
                        self.eq = eq;
                        let rho = self
                            .bordered_rho(i, rec, &f1.u, b)
                            .map_err(StepError::Adjoint)?;
                        eq = std::mem::take(&mut self.eq);
                        self.contact.adjoint_solve(rec, &f1.u, rho, &mut eq);
                        rho
                    }
                }
            }
        };
        // K_i V: the right-hand side on the free rows, the step's tangent on the
        // constrained ones
        let kv = &mut nd.kv[..n_eq];
        kv.copy_from_slice(g);
        let k = self.contact.tangent_values();
        let pat = &model.pattern;
        for &cand in &rec.active {
            if let Some(e) = model.dofs.equation(2 * model.candidates[cand as usize] + 1) {
                kv[e] = pat.row_dot(k, e, &eq);
            }
        }
        let kjv = &mut nd.kjv[..n_eq];
        kjv.fill(0.0);
        pat.sym_mul_add(&nd.kj, &eq, kjv);
        let kpv = &mut nd.kpv[..n_eq];
        for ((p, v), j) in kpv.iter_mut().zip(kv.iter()).zip(kjv.iter()) {
            *p = (v - cs * j) / cd;
        }
        self.eq = eq;
        // R, Q of mu_i
        for bi in 0..nb {
            let rn = &mut nd.r_new[bi * n_eq..(bi + 1) * n_eq];
            let qn = &mut nd.q_new[bi * n_eq..(bi + 1) * n_eq];
            let (gd, gs) = (gl.d(bi, 0), gl.s(bi, 0));
            for ((r, q), (p, j)) in rn
                .iter_mut()
                .zip(qn.iter_mut())
                .zip(kpv.iter().zip(kjv.iter()))
            {
                *r = -gd * p;
                *q = -gs * j;
            }
            for bj in 0..nb {
                let (fd, fs) = (qf.d(bi, bj), qf.s(bi, bj));
                let (r, q) = (
                    &nd.r[bj * n_eq..(bj + 1) * n_eq],
                    &nd.q[bj * n_eq..(bj + 1) * n_eq],
                );
                if fd != 0.0 {
                    for (o, x) in rn.iter_mut().zip(r) {
                        *o -= fd * x;
                    }
                }
                if fs != 0.0 {
                    for (o, x) in qn.iter_mut().zip(q) {
                        *o -= fs * x;
                    }
                }
            }
        }
        std::mem::swap(&mut nd.r, &mut nd.r_new);
        std::mem::swap(&mut nd.q, &mut nd.q_new);
        // the gradient: per block pair, a_J . R_I and h_J . Q_I at the step's end (t = 1)
        // and start (t = 0), and du . R_I, du . Q_I
        let blk = nb * n_eq;
        let (a1, a0) = (
            &nd.a[(i + 1) * blk..(i + 2) * blk],
            &nd.a[i * blk..(i + 1) * blk],
        );
        let (h1, h0) = (
            &nd.h[(i + 1) * blk..(i + 2) * blk],
            &nd.h[i * blk..(i + 1) * blk],
        );
        let du = &mut nd.du[..n_eq];
        for (d, &e) in model.dofs.eq.iter().enumerate() {
            if e != NO_EQ {
                du[e as usize] = f1.u[d] - f0.u[d];
            }
        }
        let ops = nd.ops.as_ref().expect("set");
        let np = c.len();
        let mut sums = [0.0; 4 * MAX_BLOCKS + 2];
        for bi in 0..nb {
            let (r, q) = (
                &nd.r[bi * n_eq..(bi + 1) * n_eq],
                &nd.q[bi * n_eq..(bi + 1) * n_eq],
            );
            // (a pair whose coefficients are all zero is skipped: its sums stay zero)
            sums.fill(0.0);
            for bj in 0..nb {
                let x = bj * n_eq..(bj + 1) * n_eq;
                if ops.pairs[bi * nb + bj].0 {
                    [sums[4 * bj], sums[4 * bj + 1]] =
                        dot_pair(&a1[x.clone()], r, &h1[x.clone()], q);
                }
                if ops.pairs[bi * nb + bj].1 {
                    [sums[4 * bj + 2], sums[4 * bj + 3]] = dot_pair(&a0[x.clone()], r, &h0[x], q);
                }
            }
            if ops.strain_blocks[bi] {
                [sums[4 * nb], sums[4 * nb + 1]] = dot_pair(du, r, du, q);
            }
            for k in 0..np {
                let mut acc = 0.0;
                for bj in 0..nb {
                    let (ak, dk) = (&ops.da[k], &ops.dd[k]);
                    acc += ak.d(bi, bj) * sums[4 * bj] + ak.s(bi, bj) * sums[4 * bj + 1];
                    acc += dk.d(bi, bj) * sums[4 * bj + 2] + dk.s(bi, bj) * sums[4 * bj + 3];
                }
                let ek = &ops.de[k];
                acc += ek.d(bi, 0) * sums[4 * nb] + ek.s(bi, 0) * sums[4 * nb + 1];
                sw.grad[k] -= acc;
            }
        }
        Ok(rho)
    }
}

/// How a step of the all-nodal sweep fails: a condition of the nodal form (a message,
/// named with the material by the caller) or the bordered step's own error.
enum StepError {
    Nodal(String),
    Adjoint(AdjointError),
}
