//! The all-nodal forward sensitivities of a linear material whose blocks are isotropic
//! (`Prony`), under small strain and vertical contact, from a run recorded from rest,
//! driven by depth, under load control or through the frame (docs/performance.md,
//! "Prony's and load control's sensitivity pass all-nodal"): the forward counterpart of
//! the all-nodal sweep (`material/nodal.rs`), under the same conditions and from its
//! nodal states and checks, with no pass over the Gauss points per step.
//!
//! The Gauss-point pass (`Adjoint::material_sensitivities`) carries per point and
//! parameter `k` the state's variation `dy_{i-1}` and `B du_{i-1}`, and per step forms
//! `q = -P e_k - D dy_{i-1} + E B du_{i-1}`, solves `K du = -sum w B^T Pi A^-1 q`, and
//! sets `dy_i = A^-1 (q - E B du)`, `dF_i = -e_A . sum w B^T Pi dy_i`. Every block of
//! `A`, `D`, `E` and of the parameter derivative `P` (linear in `y_i`, `y_{i-1}` and
//! `deps`: `P e_k = Da_k y_i + Dd_k y_{i-1} + De_k deps`) is `d P + s J` (`P`, `J` the
//! deviatoric and spherical projectors), and such blocks multiply channel by channel. So
//! each block `I` of `dy` is a pair of nodal vectors (equations), `P B a_I + J B h_I`, as
//! the recorded states `y_j` of the sweep (`nd.a`, `nd.h`) and `deps = B du` (`a = h =
//! du`). With `M = -A^-1 D`, `N = -A^-1 E` and `G*_k = -A^-1 D*_k` (blocks, per step
//! length), in each channel:
//! - `z = A^-1 q`: `z_I = sum_J (Ga_k,IJ y_{i,J} + Gd_k,IJ y_{i-1,J} + M_IJ dy_J) +
//!   Ge_k,I du_rec,i - N_I du_{i-1}`: vector updates;
//! - the right-hand side `-sum w B^T Pi z = -(K_P z_a,0 + K_J z_h,0)`, `K_P = sum w B^T P
//!   B`, `K_J = sum w B^T J B` formed once per model: two sparse products;
//! - the solve gives `du` (zero on the active dofs, as the contact prescribes), bordered
//!   under load control and through the frame as the Gauss-point pass is (`load.rs`):
//!   the force variation at the depth held `rhs_A - (K_i du)_A` sets `dU_i/dc_k`, whose
//!   depth column joins `du`;
//! - `dF_i = rhs_A - (K_i du)_A` (the rows of the active dofs of the step's tangent,
//!   `K_i = c_d K_P + c_s K_J`; prescribed on a load-controlled step);
//! - `dy_{i,I} = z_I + N_I du`, `du_{i-1} <- du`.
//!
//! Per parameter and step: two sparse products, the solve, the active rows and
//! `O(nb^2)` vector updates (`nb` the state's blocks), instead of the blocks' products at
//! every Gauss point and three passes over them. The columns are the Gauss-point pass's
//! to round-off (`tests/nodal_material_sens.rs`); each parameter's recursion is the same
//! arithmetic on any thread, so the same bits on any number of threads.

use indentify_contact::Trajectory;
use indentify_fe::dofs::NO_EQ;
use indentify_laws::material::dense_solve_many;
use indentify_laws::{Mat4, Material, Vec4};

use super::{IsoBlocks, StepOps, smooth_step};
use crate::affine::Iso;
use crate::load::Border;
use crate::material::{MatSweep, SensDrive};
use crate::nodal_sens::{EqWork, MultiBlock, ParamSteps, Rows, active_equations};
use crate::{Adjoint, AdjointError};

/// A step length's blocks of the forward recursion: `G*_k = -A^-1 D*_k` per parameter
/// (`D*_k` the parameter derivative's blocks against `y_i`, `y_{i-1}`, `deps`).
struct SensOps {
    dt_bits: u64,
    ga: Vec<IsoBlocks>,
    gd: Vec<IsoBlocks>,
    ge: Vec<IsoBlocks>,
}

/// `-(l r)` channel by channel (`l`: `nb x nb` blocks, `r`: `nb x cols`).
fn neg_product(l: &IsoBlocks, r: &IsoBlocks) -> IsoBlocks {
    let nb = l.cols;
    let cols = r.cols;
    let mut out = IsoBlocks {
        cols,
        d: vec![0.0; nb * cols],
        s: vec![0.0; nb * cols],
    };
    for i in 0..nb {
        for j in 0..cols {
            let (mut d, mut s) = (0.0, 0.0);
            for k in 0..nb {
                d += l.d(i, k) * r.d(k, j);
                s += l.s(i, k) * r.s(k, j);
            }
            out.d[i * cols + j] = -d;
            out.s[i * cols + j] = -s;
        }
    }
    out
}

impl SensOps {
    /// The blocks at `(c, dt)` from the step's operators `ops`, or `None` when `A^-1` is
    /// not of isotropic blocks.
    fn of(mat: &dyn Material, c: &[f64], ops: &StepOps) -> Option<SensOps> {
        let m = mat.state_len();
        let nb = m / 4;
        let dt = f64::from_bits(ops.dt_bits);
        let zero = vec![0.0; m];
        let mut a = vec![0.0; m * m];
        mat.jac_state(c, &smooth_step(&zero, &zero, &Vec4::ZERO, dt), &mut a);
        let mut inv = vec![0.0; m * m];
        for j in 0..m {
            inv[j * m + j] = 1.0;
        }
        if !dense_solve_many(&mut a, m, &mut inv, m) {
            return None;
        }
        let ainv = IsoBlocks::of(&inv, nb, nb, 1e-10)?;
        let map = |v: &[IsoBlocks]| v.iter().map(|b| neg_product(&ainv, b)).collect();
        Some(SensOps {
            dt_bits: ops.dt_bits,
            ga: map(&ops.da),
            gd: map(&ops.dd),
            ge: map(&ops.de),
        })
    }
}

/// One parameter's state and work space (equations; `nb` blocks of `n_eq` where
/// blocked).
struct MatParam {
    /// `dy_{i-1}`'s channels `a`, `h`, and `z`'s.
    ya: Vec<f64>,
    yh: Vec<f64>,
    za: Vec<f64>,
    zh: Vec<f64>,
    /// `du_{i-1}`.
    bdu: Vec<f64>,
    /// The right-hand side, then `du`.
    eq: Vec<f64>,
    /// The right-hand side's sum over the active rows.
    rhs_a: f64,
    xbar: Vec<f64>,
    solve: indentify_fe::SolveScratch,
}

impl EqWork for MatParam {
    fn eq(&mut self) -> &mut [f64] {
        &mut self.eq
    }
}

/// What a step shares between its parameters (read only).
struct MatStep<'a> {
    pattern: &'a indentify_fe::Pattern,
    /// The step's tangent `K_i`, and `K_P`, `K_J`.
    k: &'a [f64],
    kp: &'a [f64],
    kj: &'a [f64],
    nb: usize,
    n_eq: usize,
    /// The recorded states before and after the step (`nb` blocks each) and the step's
    /// displacement increment.
    a0: &'a [f64],
    a1: &'a [f64],
    h0: &'a [f64],
    h1: &'a [f64],
    du_rec: &'a [f64],
    ops: &'a StepOps,
    sens: &'a SensOps,
    cons: &'a [usize],
    contact: &'a indentify_contact::RecordedContact<'a>,
    border: Option<Border<'a>>,
}

/// `out = sum f x` over the terms whose factor is not zero (`out` zero when none).
fn combine<'x>(out: &mut [f64], terms: impl Iterator<Item = (f64, &'x [f64])>) {
    let mut first = true;
    for (f, x) in terms.filter(|(f, _)| *f != 0.0) {
        if first {
            for (o, x) in out.iter_mut().zip(x) {
                *o = f * x;
            }
            first = false;
        } else {
            for (o, x) in out.iter_mut().zip(x) {
                *o += f * x;
            }
        }
    }
    if first {
        out.fill(0.0);
    }
}

impl ParamSteps<MatParam> for MatStep<'_> {
    /// Parameter `k`'s step (the module's recursion): `dy_i` into `w.ya`, `w.yh`, `du`
    /// into `w.bdu`; returns `dF_i/dc_k` and `dU_i/dc_k` (zero without a border).
    fn solve(&self, k: usize, w: &mut MatParam) -> (f64, f64) {
        self.rhs(k, w);
        self.contact
            .sensitivity_solve(&mut w.eq, &[], &mut w.xbar, &mut w.solve);
        self.finish(k, w)
    }

    /// The first part of [`MatStep::solve`]: `z` into `w.za`, `w.zh`, the right-hand
    /// side into `w.eq` and its sum over the active rows into `w.rhs_a`.
    fn rhs(&self, k: usize, w: &mut MatParam) {
        let (nb, ne) = (self.nb, self.n_eq);
        let (ops, so) = (self.ops, self.sens);
        fn blk(v: &[f64], j: usize, ne: usize) -> &[f64] {
            &v[j * ne..(j + 1) * ne]
        }
        // z = A^-1 q, channel by channel
        for chan_s in [false, true] {
            let pick =
                |b: &IsoBlocks, i: usize, j: usize| if chan_s { b.s(i, j) } else { b.d(i, j) };
            let (y, x1, x0) = if chan_s {
                (&w.yh, self.h1, self.h0)
            } else {
                (&w.ya, self.a1, self.a0)
            };
            let z = if chan_s { &mut w.zh } else { &mut w.za };
            for bi in 0..nb {
                let terms = (0..nb)
                    .flat_map(|bj| {
                        [
                            (pick(&so.ga[k], bi, bj), blk(x1, bj, ne)),
                            (pick(&so.gd[k], bi, bj), blk(x0, bj, ne)),
                            (pick(&ops.m, bi, bj), blk(y, bj, ne)),
                        ]
                    })
                    .chain([
                        (pick(&so.ge[k], bi, 0), self.du_rec),
                        (-pick(&ops.n, bi, 0), w.bdu.as_slice()),
                    ]);
                combine(&mut z[bi * ne..(bi + 1) * ne], terms);
            }
        }
        // the right-hand side -(K_P z_a,0 + K_J z_h,0)
        w.eq.fill(0.0);
        (self.pattern).sym_mul_add_pair((self.kp, &w.za[..ne]), (self.kj, &w.zh[..ne]), &mut w.eq);
        for b in w.eq.iter_mut() {
            *b = -*b;
        }
        w.rhs_a = self.cons.iter().map(|&c| w.eq[c]).sum();
    }

    /// The rest of [`MatStep::solve`], from the displacement variation at the depth held
    /// in `w.eq`.
    fn finish(&self, k: usize, w: &mut MatParam) -> (f64, f64) {
        let (nb, ne, ops) = (self.nb, self.n_eq, self.ops);
        let rhs_a = w.rhs_a;
        let (pat, kv) = (self.pattern, self.k);
        let rows = |du: &[f64]| {
            self.cons
                .iter()
                .map(|&c| pat.row_dot(kv, c, du))
                .sum::<f64>()
        };
        let (df, du_u) = match &self.border {
            None => (rhs_a - rows(&w.eq), 0.0),
            Some(b) => {
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
        // dy_i = z + N du
        for bi in 0..nb {
            let (nd, ns) = (ops.n.d(bi, 0), ops.n.s(bi, 0));
            let r = bi * ne..(bi + 1) * ne;
            for ((za, zh), du) in w.za[r.clone()].iter_mut().zip(&mut w.zh[r]).zip(&w.eq) {
                *za += nd * du;
                *zh += ns * du;
            }
        }
        std::mem::swap(&mut w.ya, &mut w.za);
        std::mem::swap(&mut w.yh, &mut w.zh);
        w.bdu.copy_from_slice(&w.eq);
        (df, du_u)
    }
}

impl Adjoint<'_> {
    /// The forward sensitivities `dF_i/dc_k`, `dU_i/dc_k` of `traj` all-nodal (the
    /// module's recursion; the parameters [`Adjoint::skips`] leaves out stay zero), or
    /// `None` when the pass does not apply: the all-nodal sweep's conditions
    /// (`Adjoint::begin_nodal_material`: `set_fused` on, small strain, vertical contact,
    /// a run from rest, the fixed dofs at zero, the nodal states matching the recorded
    /// ones), a constraint that ties steps or an active dof without an equation; the
    /// Gauss-point pass then runs. Call it after `self.contact.begin()`.
    pub(crate) fn material_sensitivities_nodal(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        drive: SensDrive<'_>,
    ) -> Result<Option<(Rows, Rows)>, AdjointError> {
        if !self.nodal_sens_applies() {
            return Ok(None);
        }
        // (the sweep's flag reports sweeps: kept as it was)
        let swept = self.nodal_mat.on;
        let on = self.begin_nodal_material(mat, c, traj);
        let mut nd = std::mem::take(&mut self.nodal_mat);
        nd.on = swept;
        let out = if on {
            self.material_sens_steps(&mut nd, mat, c, traj, drive)
                .map(Some)
        } else {
            Ok(None)
        };
        self.nodal_mat = nd;
        out
    }

    fn material_sens_steps(
        &mut self,
        nd: &mut super::NodalMat,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        drive: SensDrive<'_>,
    ) -> Result<(Rows, Rows), AdjointError> {
        let model = self.model;
        let (n, np, n_eq, nb) = (traj.steps.len(), c.len(), model.dofs.n_eq, nd.nb);
        if nd.kp.len() != model.pattern.row_idx.len() {
            // K_P = sum w B^T P B (P = I - J)
            let mut p = Mat4::ZERO;
            for r in 0..4 {
                for col in 0..4 {
                    let j = if r < 3 && col < 3 { 1.0 / 3.0 } else { 0.0 };
                    p.0[r][col] = if r == col { 1.0 - j } else { -j };
                }
            }
            nd.kp.resize(model.pattern.row_idx.len(), 0.0);
            model
                .pattern
                .assemble_b_c_b_uniform(&model.disc, &p, &mut nd.kp);
        }
        let vec = |len: usize| vec![0.0; len];
        let mut work: Vec<MatParam> = (0..np)
            .map(|_| MatParam {
                ya: vec(nb * n_eq),
                yh: vec(nb * n_eq),
                za: vec(nb * n_eq),
                zh: vec(nb * n_eq),
                bdu: vec(n_eq),
                eq: vec(n_eq),
                rhs_a: 0.0,
                xbar: vec(n_eq),
                solve: self.contact.solve_scratch(),
            })
            .collect();
        let mut df = vec![vec![0.0; np]; n];
        let mut dh = vec![vec![0.0; np]; n];
        let mut carry = crate::load::SegmentCarry::new(np, n_eq);
        let mut sw = MatSweep::new(mat, np, 1);
        let mut sens: Option<SensOps> = None;
        let mut du_rec = vec![0.0; n_eq];
        let mut cons = Vec::new();
        let mut multi = MultiBlock::new(self, np);
        for i in 0..n {
            let rec = &traj.steps[i];
            let (f0, f1) = (&traj.fields[i], &traj.fields[i + 1]);
            let fail = |reason: &str| AdjointError::Step {
                step: i,
                t: rec.t,
                reason: format!("{}: {reason}", mat.name()),
            };
            // the step's tangent as the sweep forms it, and its operators
            sw.load(f0, f1, 0);
            if !sw.linear_blocks(mat, c, &Vec4::ZERO, rec.dt) {
                return Err(fail("singular local Jacobian A (tangent)"));
            }
            if Iso::of(&sw.ct).is_none() || !nd.ops_for(mat, c, rec.dt) {
                return Err(fail("the all-nodal pass's blocks are not isotropic"));
            }
            let ops = nd.ops.as_ref().expect("set");
            if sens.as_ref().is_none_or(|s| s.dt_bits != ops.dt_bits) {
                sens = SensOps::of(mat, c, ops);
            }
            let Some(so) = sens.as_ref() else {
                return Err(fail("the all-nodal pass's A^-1 is not of isotropic blocks"));
            };
            self.tangents[0] = sw.ct;
            self.prepare_material_step(rec, f1, Some(c))
                .map_err(|r| fail(&r))?;
            let border = self.nodal_border(drive, traj, i, &mut carry, (&df, &dh))?;
            active_equations(model, rec, &mut cons);
            for (d, &e) in model.dofs.eq.iter().enumerate() {
                if e != NO_EQ {
                    du_rec[e as usize] = f1.u[d] - f0.u[d];
                }
            }
            let blk = nb * n_eq;
            let step = MatStep {
                pattern: &model.pattern,
                k: self.contact.tangent_values(),
                kp: &nd.kp,
                kj: &nd.kj,
                nb,
                n_eq,
                a0: &nd.a[i * blk..(i + 1) * blk],
                a1: &nd.a[(i + 1) * blk..(i + 2) * blk],
                h0: &nd.h[i * blk..(i + 1) * blk],
                h1: &nd.h[(i + 1) * blk..(i + 2) * blk],
                du_rec: &du_rec,
                ops,
                sens: so,
                cons: &cons,
                contact: &self.contact,
                border: border.map(|load| carry.border(load, drive)),
            };
            let rows = (&mut df[i][..], &mut dh[i][..]);
            multi.step(&self.contact, &mut work, rows, &self.skip, &step);
        }
        self.multi_used = multi.cols.len() > 1;
        Ok((df, dh))
    }
}
