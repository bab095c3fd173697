//! The adjoint sweep of a material with internal variables, written once against its
//! Jacobian blocks (docs/theory.md §12), the regime of every Gauss point held as
//! recorded. Per Gauss point and step, with `y = [sigma, alpha]` (`m` numbers), the
//! blocks `A = dR/dy_i`, `D = dR/dy_{i-1}`, `E = dR/d deps`, `P = dR/dc` of the recorded
//! step and the carries `z = D_{i+1}^T mu_{i+1}`, `e = E_{i+1}^T mu_{i+1}`:
//!
//! 1. `K_i^T V_i = B* (e + E_i^T A_i^-T z)` (the contact's constraints as for every law);
//! 2. `mu_i = -A_i^-T (z + Pi^T B V_i)`;
//! 3. `dJ/dc -= sum_g w <mu_i, P_i>`; `z <- D_i^T mu_i`, `e <- E_i^T mu_i`.
//!
//! The tangent of the step's system is `C_i = -Pi A_i^-1 E_i` from the same blocks.
//! A nonlinear material is asked for a point's four blocks in one
//! [`Material::jac_blocks`] call in the first pass (before the step's solve); `D`, `E`
//! and `P` are kept per point for the second (after it). A linear material's blocks are
//! formed once per step and the later step's folded in (`MatSweep::d_next`).
//! Every model: small and finite strain (`B` becomes the step's `G_i`, the stiffness the
//! forward's consistent tangent with its geometric part, `finite.rs`), vertical,
//! frictionless normal and Coulomb contact (whose `dJ/dF` enters as the shift
//! `V' = V + rho e_A`: under small strain `rho B e_A` joins `z`'s stress rows in the
//! source, under finite strain the source gains `K (-rho e_A)` as the laws' sweep does).

use indentify_contact::{
    ForceCotangent, LoadHistory, StepFields, StepRecord, StepTangent, Trajectory,
};
use indentify_fe::{Deformation, QP_PER_ELEMENT};
use indentify_laws::material::{Step, dense_solve_many};
use indentify_laws::{LogStrain, Mat4, Material, Vec4};

use crate::{Adjoint, AdjointError, Gradient, Replay, Sensitivities};

mod nodal;
pub(crate) use nodal::NodalMat;

/// Per-step rows of per-parameter variations (`[step][parameter]`).
type Rows = Vec<Vec<f64>>;

/// The accumulators and per-point work of one sweep (allocated once per sweep).
pub(crate) struct MatSweep {
    m: usize,
    /// `z = D_{i+1}^T mu_{i+1}` per point (`m` each).
    z: Vec<f64>,
    /// `e = E_{i+1}^T mu_{i+1}` per point.
    e: Vec<Vec4>,
    /// `G = A_i^-T Pi^T` per point (`m x 4`, row-major).
    g: Vec<f64>,
    /// `A_i^-T z` per point (`m` each).
    az: Vec<f64>,
    pub(crate) grad: Vec<f64>,
    /// `mu_{i+1} = 0` everywhere (nothing swept yet).
    pub(crate) zero: bool,
    /// The step's strain increment at every point (small strain `B (u_1 - u_0)`, finite
    /// strain the Hencky strains' difference).
    deps: Vec<Vec4>,
    /// Point scratch: `y0, y1` (m each), `A`, `A^T`, `D` (m^2), `E` (4m), `P` (m np)
    /// and an m-vector.
    y0: Vec<f64>,
    y1: Vec<f64>,
    a: Vec<f64>,
    at: Vec<f64>,
    d: Vec<f64>,
    ej: Vec<f64>,
    p: Vec<f64>,
    x: Vec<f64>,
    /// `P^T mu` of a point (`n_c`, scratch of the second pass).
    pacc: Vec<f64>,
    /// The material's blocks depend on `(c, dt)` only ([`Material::is_linear`]): `A^-T`,
    /// `G`, `D`, `E` and the tangent are formed once per step (in `ainvt`, `glin`, `d`,
    /// `ej`, `ct`) and every point reuses them.
    linear: bool,
    /// `A^-T` (`m x m`, row-major) of a linear material's step.
    ainvt: Vec<f64>,
    /// The right-hand sides `[Pi^T | z]` (`m x 5`, row-major) of a point's one
    /// elimination with `A^T`, and its solution `[G | A^-T z]`.
    rhs5: Vec<f64>,
    /// `G = A^-T Pi^T` (`m x 4`) of a linear material's step.
    glin: Vec<f64>,
    /// The tangent `-G^T E` of a linear material's step.
    ct: Mat4,
    /// A linear material's sweep carries `mu_{i+1}` itself (in `z`) and folds the later
    /// step's blocks into the earlier one's, once per step: `D_{i+1}` (`m x m`) and
    /// `E_{i+1}` (`m x 4`) of the step swept last (zero before the first);
    /// `Q = A_i^-T D_{i+1}^T` (`m x m`, so `A_i^-T z = Q mu_{i+1}`) and
    /// `S = E_{i+1}^T + E_i^T Q` (stored `m x 4`: the source `e + E_i^T A_i^-T z` is
    /// `S^T mu_{i+1}`); `E_i^T G_i` (4 x 4, a shifted source's part).
    d_next: Vec<f64>,
    e_next: Vec<f64>,
    qm: Vec<f64>,
    sm: Vec<f64>,
    eg: Mat4,
    /// A nonlinear material's blocks `D`, `E`, `P` of every point, from the one
    /// [`Material::jac_blocks`] call of the first pass, read by the second
    /// (`m x m`, `m x 4`, `m x n_c` per point; empty for a linear material).
    dblk: Vec<f64>,
    eblk: Vec<f64>,
    pblk: Vec<f64>,
    /// `Q`'s 4 x 4 blocks are isotropic (`a P + b J`): their `a` and `b - a`
    /// (`nb x nb`, `nb = m / 4`), used instead of the dense `Q` ([`MatSweep::isotropic_q`]).
    iso: bool,
    qa: Vec<f64>,
    qc: Vec<f64>,
}

impl MatSweep {
    pub(crate) fn new(mat: &dyn Material, np: usize, nq: usize) -> MatSweep {
        let m = mat.state_len();
        let per_point = if mat.is_linear() { 0 } else { nq };
        MatSweep {
            m,
            z: vec![0.0; nq * m],
            e: vec![Vec4::ZERO; nq],
            g: vec![0.0; nq * m * 4],
            az: vec![0.0; nq * m],
            grad: vec![0.0; np],
            zero: true,
            deps: vec![Vec4::ZERO; nq],
            y0: vec![0.0; m],
            y1: vec![0.0; m],
            a: vec![0.0; m * m],
            at: vec![0.0; m * m],
            d: vec![0.0; m * m],
            ej: vec![0.0; m * 4],
            p: vec![0.0; m * np],
            x: vec![0.0; m],
            pacc: vec![0.0; np],
            linear: mat.is_linear(),
            ainvt: vec![0.0; m * m],
            rhs5: vec![0.0; m * 5],
            glin: vec![0.0; m * 4],
            ct: Mat4::ZERO,
            d_next: vec![0.0; m * m],
            e_next: vec![0.0; m * 4],
            qm: vec![0.0; m * m],
            sm: vec![0.0; m * 4],
            eg: Mat4::ZERO,
            dblk: vec![0.0; per_point * m * m],
            eblk: vec![0.0; per_point * m * 4],
            pblk: vec![0.0; per_point * m * np],
            iso: false,
            qa: vec![0.0; (m / 4) * (m / 4)],
            qc: vec![0.0; (m / 4) * (m / 4)],
        }
    }

    /// A linear material's step blocks from the state of point `q` (any point: they do not
    /// depend on it): `A^-T`, `G = A^-T Pi^T`, `D`, `E` and the tangent `-G^T E`.
    /// `false` when `A` is singular.
    fn linear_blocks(&mut self, mat: &dyn Material, c: &[f64], deps: &Vec4, dt: f64) -> bool {
        let m = self.m;
        let step = Step {
            y0: &self.y0,
            y1: &self.y1,
            deps,
            dt,
            regime: indentify_laws::material::Regime::Smooth,
        };
        mat.jac_state(c, &step, &mut self.a);
        mat.jac_previous(c, &step, &mut self.d);
        mat.jac_strain(c, &step, &mut self.ej);
        for r in 0..m {
            for k in 0..m {
                self.at[k * m + r] = self.a[r * m + k];
            }
        }
        self.ainvt.fill(0.0);
        for j in 0..m {
            self.ainvt[j * m + j] = 1.0;
        }
        if !dense_solve_many(&mut self.at, m, &mut self.ainvt, m) {
            return false;
        }
        for k in 0..m {
            for j in 0..4 {
                self.glin[k * 4 + j] = self.ainvt[k * m + j];
            }
        }
        for a in 0..4 {
            for b in 0..4 {
                self.ct.0[a][b] = -(0..m)
                    .map(|k| self.glin[k * 4 + a] * self.ej[k * 4 + b])
                    .sum::<f64>();
                self.eg.0[b][a] = -self.ct.0[a][b];
            }
        }
        // the later step's blocks folded in (see `d_next`)
        for k in 0..m {
            let row = &self.ainvt[k * m..(k + 1) * m];
            for r in 0..m {
                let dr = &self.d_next[r * m..(r + 1) * m];
                self.qm[k * m + r] = row.iter().zip(dr).map(|(a, b)| a * b).sum();
            }
        }
        for r in 0..m {
            for b in 0..4 {
                self.sm[r * 4 + b] = self.e_next[r * 4 + b]
                    + (0..m)
                        .map(|k| self.ej[k * 4 + b] * self.qm[k * m + r])
                        .sum::<f64>();
            }
        }
        self.iso = self.isotropic_q();
        true
    }

    /// Whether every 4 x 4 block `Q_IJ` of `Q` is an isotropic operator
    /// `a P + b J` (`P`, `J` the deviatoric and spherical projectors in Mandel
    /// components) to 1e-10 of `Q`'s largest entry, as for an isotropic linear material
    /// whose internal variables are tensors (`Prony`); if so, `qa[I nb + J] = a` and
    /// `qc[I nb + J] = b - a` are set for [`q_mu_isotropic`].
    fn isotropic_q(&mut self) -> bool {
        let m = self.m;
        if m % 4 != 0 {
            return false;
        }
        let nb = m / 4;
        if nb > 16 {
            return false;
        }
        // (the elimination leaves structural zeros at 1e-13 of the largest entry when the
        // relaxation times and the compliance differ by 1e9, R2's three-term series)
        let big = self.qm.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        let tol = 1e-10 * big;
        for bi in 0..nb {
            for bj in 0..nb {
                let e = |i: usize, j: usize| self.qm[(4 * bi + i) * m + 4 * bj + j];
                let a = e(3, 3);
                let b = e(0, 0) + 2.0 * e(0, 1);
                let (diag, off) = ((2.0 * a + b) / 3.0, (b - a) / 3.0);
                for i in 0..4 {
                    for j in 0..4 {
                        let want = match (i, j) {
                            (3, 3) => a,
                            (3, _) | (_, 3) => 0.0,
                            _ if i == j => diag,
                            _ => off,
                        };
                        if (e(i, j) - want).abs() > tol {
                            return false;
                        }
                    }
                }
                self.qa[bi * nb + bj] = a;
                self.qc[bi * nb + bj] = b - a;
            }
        }
        true
    }

    /// Loads `y0, y1` of point `q` from the recorded fields (plain loops: a few numbers,
    /// which `copy_from_slice` makes four `memmove` calls per point).
    #[allow(clippy::manual_memcpy)]
    fn load(&mut self, f0: &StepFields, f1: &StepFields, q: usize) {
        let n = self.m - 4;
        let (s0, s1) = (&f0.sigma[q].0, &f1.sigma[q].0);
        for k in 0..4 {
            self.y0[k] = s0[k];
            self.y1[k] = s1[k];
        }
        let (a0, a1) = (&f0.alpha[q * n..(q + 1) * n], &f1.alpha[q * n..(q + 1) * n]);
        for k in 0..n {
            self.y0[4 + k] = a0[k];
            self.y1[4 + k] = a1[k];
        }
    }
}

/// `out = Q mu` from the isotropic blocks of `Q` ([`MatSweep::isotropic_q`], `nb <= 16`
/// blocks): `(Q mu)_I = sum_J a_IJ mu_J + 1 sum_J (b_IJ - a_IJ) tr(mu_J) / 3`, about
/// `5 nb^2` products instead of `m^2 = 16 nb^2`.
#[allow(clippy::needless_range_loop)]
fn q_mu_isotropic(nb: usize, qa: &[f64], qc: &[f64], mu: &[f64], out: &mut [f64]) {
    let mut t = [0.0; 16];
    for j in 0..nb {
        t[j] = (mu[4 * j] + mu[4 * j + 1] + mu[4 * j + 2]) / 3.0;
    }
    for i in 0..nb {
        let (mut o, mut sph) = ([0.0; 4], 0.0);
        for j in 0..nb {
            let a = qa[i * nb + j];
            for c in 0..4 {
                o[c] += a * mu[4 * j + c];
            }
            sph += qc[i * nb + j] * t[j];
        }
        out[4 * i] = o[0] + sph;
        out[4 * i + 1] = o[1] + sph;
        out[4 * i + 2] = o[2] + sph;
        out[4 * i + 3] = o[3];
    }
}

/// `sum_j a[j] b[j]` in index order, as a plain loop: the bits of
/// `a.iter().zip(b).map(|(x, y)| x * y).sum()` (a sum starts from `-0.0`), without the
/// iterator adapters the `dev` profile leaves as calls in the sweep's per-point products.
#[inline(always)]
#[allow(clippy::needless_range_loop)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut s = -0.0;
    for j in 0..a.len() {
        s += a[j] * b[j];
    }
    s
}

/// `out[k] = sum_r blk[r * cols + k] x[r]` for every column `k < cols = out.len()` of a
/// row-major block against `x` (`x.len()` rows): each column's sum in row order from
/// `-0.0` (the bits of the strided dot product per column it replaces, and of the
/// iterator sum before that), taken row by row over contiguous rows, as plain loops
/// without the adapters the `dev` profile leaves as calls.
#[inline(always)]
fn column_dots(blk: &[f64], x: &[f64], out: &mut [f64]) {
    let cols = out.len();
    out.fill(-0.0);
    if cols == 0 {
        return;
    }
    for (row, &xr) in blk.chunks_exact(cols).zip(x) {
        for (o, b) in out.iter_mut().zip(row) {
            *o += b * xr;
        }
    }
}

/// [`column_dots`] of an `m x 4` block (`m = x.len()`), on the stack.
#[inline(always)]
fn column_dots4(blk: &[f64], x: &[f64]) -> [f64; 4] {
    let mut out = [-0.0; 4];
    for (row, &xr) in blk.chunks_exact(4).zip(x) {
        for (o, b) in out.iter_mut().zip(row) {
            *o += b * xr;
        }
    }
    out
}

/// The point's tangent `-G^T E` from its `m x 4` blocks `G` and `E` (row-major, `m` rows
/// each): entry `(a, b)` is `-sum_k G[k][a] E[k][b]`, summed over `k` in order from
/// `-0.0` (the bits of one strided dot product per entry), row by row.
#[inline(always)]
fn tangent_of(g: &[f64], e: &[f64]) -> Mat4 {
    let mut acc = [[-0.0; 4]; 4];
    for (gk, ek) in g.chunks_exact(4).zip(e.chunks_exact(4)) {
        for (row, &ga) in acc.iter_mut().zip(gk) {
            for (o, &eb) in row.iter_mut().zip(ek) {
                *o += ga * eb;
            }
        }
    }
    let mut ct = Mat4::ZERO;
    for (c, a) in ct.0.iter_mut().zip(&acc) {
        for (x, y) in c.iter_mut().zip(a) {
            *x = -y;
        }
    }
    ct
}

impl Adjoint<'_> {
    /// [`Adjoint::gradient`] for a material without [`Material::as_law`].
    pub(crate) fn gradient_material(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        dj_df: &[f64],
    ) -> Result<Gradient, AdjointError> {
        let start = std::time::Instant::now();
        let f0 = self.contact.factorizations();
        self.check_material(mat, c, traj, dj_df.len(), true)?;
        self.contact.begin();
        // the all-nodal sweep where it applies (`material/nodal.rs`; its `MatSweep` holds
        // the step's blocks and one point)
        let nodal = self.begin_nodal_material(mat, c, traj);
        let nq = if nodal { 1 } else { self.model.disc.n_qp() };
        let mut sw = MatSweep::new(mat, c.len(), nq);
        for i in (0..traj.steps.len()).rev() {
            let fields = (&traj.fields[i], &traj.fields[i + 1]);
            if nodal {
                self.nodal_material_step(mat, c, &mut sw, i, &traj.steps[i], fields, dj_df[i])?;
                continue;
            }
            self.material_step(mat, c, &mut sw, i, &traj.steps[i], fields, dj_df[i], None)?;
        }
        Ok(Gradient {
            dj_dc: sw.grad,
            seconds: start.elapsed().as_secs_f64(),
            factorizations: self.contact.factorizations() - f0,
        })
    }

    /// [`Adjoint::gradient_replayed`] for a material without [`Material::as_law`]: each
    /// stretch between checkpoints replayed, swept backward and dropped.
    /// (The caller, [`Adjoint::gradient_replayed`], has checked that `replay` runs this
    /// adjoint's model.)
    pub(crate) fn gradient_replayed_material(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        dj_df: &[f64],
        replay: Replay<'_, '_>,
    ) -> Result<Gradient, AdjointError> {
        let Replay {
            solver,
            schedule,
            opts,
        } = replay;
        let start = std::time::Instant::now();
        let f0 = self.contact.factorizations();
        let n = traj.steps.len();
        self.check_material(mat, c, traj, dj_df.len(), false)?;
        if traj.checkpoints.first().is_none_or(|cp| cp.steps_done != 0) {
            return Err(AdjointError::NotRecorded {
                fields: traj.fields.len(),
                steps: n,
            });
        }
        self.contact.begin();
        let mut sw = MatSweep::new(mat, c.len(), self.model.disc.n_qp());
        crate::replayed_steps_rev(solver, mat, c, schedule, opts, traj, |g, rec, s0, s1| {
            self.material_step(mat, c, &mut sw, g, rec, (s0, s1), dj_df[g], None)
                .map(|_| ())
        })?;
        Ok(Gradient {
            dj_dc: sw.grad,
            seconds: start.elapsed().as_secs_f64(),
            factorizations: self.contact.factorizations() - f0,
        })
    }

    /// [`Adjoint::sensitivities`] for a material without [`Material::as_law`]: per step
    /// and Gauss point the blocks of the recorded step (`A^-1` formed once), then per
    /// parameter `k`, with the carries `dy_{i-1}` and `B du_{i-1}` (docs/theory.md §12):
    /// `q = -D dy_{i-1} + E B du_{i-1} - P e_k`, `K du = -B* Pi A^-1 q` (the contact's
    /// prescribed values as for every law), `dsigma = C B du + Pi A^-1 q`,
    /// `dy_i = A^-1 (q - E B du)`, `dF_i = -e_A . B* dsigma`.
    pub(crate) fn sensitivities_material(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
    ) -> Result<Sensitivities, AdjointError> {
        let start = std::time::Instant::now();
        let (df_dc, _) = self.material_sensitivities(mat, c, traj, SensDrive::Depth)?;
        Ok(Sensitivities {
            df_dc,
            seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// The forward sensitivities of [`Adjoint::sensitivities_material`], under load
    /// control or through the instrument's frame (`drive`) with the bordered step of
    /// `load.rs`: `dF_i/dc` and `dU_i/dc` per step (the latter zero under depth control).
    pub(crate) fn material_sensitivities(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        drive: SensDrive<'_>,
    ) -> Result<(Rows, Rows), AdjointError> {
        let model = self.model;
        let n = traj.steps.len();
        self.check_material(mat, c, traj, n, true)?;
        self.contact.begin();
        // a linear material with isotropic blocks under vertical contact: the all-nodal
        // pass (`material/nodal/sens.rs`), which reads the tangent's rows
        self.nodal_sens = false;
        if let Some(out) = self.material_sensitivities_nodal(mat, c, traj, drive)? {
            self.nodal_sens = true;
            self.reaction_rows = !matches!(drive, SensDrive::Depth);
            return Ok(out);
        }
        let (m, np, nq) = (mat.state_len(), c.len(), model.disc.n_qp());
        let mut sw = MatSweep::new(mat, np, nq);
        // per point of the step: A^-1, D, E, P
        let mut ainv = vec![0.0; nq * m * m];
        let mut dblk = vec![0.0; nq * m * m];
        let mut eblk = vec![0.0; nq * m * 4];
        let mut pblk = vec![0.0; nq * m * np];
        // per parameter: dy (m per point) and B du (4 per point) of the previous step
        let mut dy = vec![vec![0.0; nq * m]; np];
        let mut bdu = vec![vec![[0.0; 4]; nq]; np];
        let mut qv = vec![0.0; nq * m];
        let mut h = vec![Vec4::ZERO; nq];
        let mut df = vec![vec![0.0; np]; n];
        let mut dh = vec![vec![0.0; np]; n];
        let mut carry = crate::load::SegmentCarry::new(np, model.dofs.n_eq);
        // (one work space per parameter: friction ties each one's solve to its own
        // previous displacement variation)
        let mut works: Vec<crate::ParamWork> = (0..np)
            .map(|_| crate::ParamWork::new(model, &self.contact))
            .collect();
        if let SensDrive::Frame(f) = drive {
            for (k, w) in works.iter_mut().enumerate() {
                f.seed(model, k, &mut w.du_prev);
            }
        }
        // a bordered drive's force variations (at the depth held, and the step's) from
        // the force dofs' rows of the step's tangent: `rhs_A - (K du)_A` with the
        // right-hand side `rhs = -sum w B^T Pi A^-1 q` (`lib.rs`, `ParamStep::solve`);
        // a load-controlled step's force is prescribed. (Depth control keeps its pass.)
        let rows = !matches!(drive, SensDrive::Depth) && self.reactions_from_rows();
        self.reaction_rows = rows;
        let mut cons = Vec::new();
        // the last point's `A` before its elimination: a linear material's repeats at
        // every point of a step, whose inverse is then copied (the same bits)
        let mut a_last: Vec<f64> = Vec::with_capacity(m * m);
        for i in 0..n {
            let rec = &traj.steps[i];
            let (f0, f1) = (&traj.fields[i], &traj.fields[i + 1]);
            let fail = |reason: String| AdjointError::Step {
                step: i,
                t: rec.t,
                reason,
            };
            self.step_strains(f0, f1, &mut sw.deps).map_err(fail)?;
            a_last.clear();
            for q in 0..nq {
                sw.load(f0, f1, q);
                let deps = sw.deps[q];
                let step = Step {
                    y0: &sw.y0,
                    y1: &sw.y1,
                    deps: &deps,
                    dt: rec.dt,
                    regime: f1.regime[q],
                };
                mat.jac_blocks(
                    c,
                    &step,
                    &mut sw.a,
                    &mut dblk[q * m * m..(q + 1) * m * m],
                    &mut eblk[q * m * 4..(q + 1) * m * 4],
                    &mut pblk[q * m * np..(q + 1) * m * np],
                );
                // A^-1 in one elimination with m right-hand sides, or the previous
                // point's where its `A` has the same bits (a linear material's)
                let same = q > 0
                    && a_last.len() == m * m
                    && (sw.a[..m * m].iter().zip(&a_last)).all(|(x, y)| x.to_bits() == y.to_bits());
                if same {
                    ainv.copy_within((q - 1) * m * m..q * m * m, q * m * m);
                } else {
                    a_last.clear();
                    a_last.extend_from_slice(&sw.a[..m * m]);
                }
                let inv = &mut ainv[q * m * m..(q + 1) * m * m];
                if !same {
                    inv.fill(0.0);
                    for j in 0..m {
                        inv[j * m + j] = 1.0;
                    }
                }
                if !same && !dense_solve_many(&mut sw.a, m, inv, m) {
                    return Err(AdjointError::Step {
                        step: i,
                        t: rec.t,
                        reason: format!(
                            "{}: singular local Jacobian A at Gauss point {q}",
                            mat.name()
                        ),
                    });
                }
                let e = &eblk[q * m * 4..(q + 1) * m * 4];
                let mut ct = Mat4::ZERO;
                for a in 0..4 {
                    for b in 0..4 {
                        ct.0[a][b] = -(0..m).map(|k| inv[a * m + k] * e[k * 4 + b]).sum::<f64>();
                    }
                }
                self.tangents[q] = ct;
            }
            self.prepare_material_step(rec, f1, None).map_err(fail)?;
            let border = match drive {
                SensDrive::Depth => None,
                SensDrive::Load(h) => carry.step(&mut self.contact, h, traj, i, (&df, &dh))?,
                SensDrive::Frame(f) => Some(f.step(&mut self.contact, rec, &mut carry)),
            };
            let finite = self.finite.as_ref();
            let prev = match (i.checked_sub(1), drive) {
                (Some(p), _) => Some((&traj.steps[p], traj.fields[i].u.as_slice())),
                // the first step's ties read the initial depth, a parameter's through h0
                (None, SensDrive::Frame(f)) => Some((f.initial(), traj.fields[0].u.as_slice())),
                (None, _) => None,
            };
            self.contact.prepare_sensitivities(rec, &f1.u, prev);
            if rows {
                crate::nodal_sens::active_equations(model, rec, &mut cons);
            }
            // whether the step's force is prescribed (load control)
            let prescribed = matches!((drive, border), (SensDrive::Load(_), Some(true)));
            let kvals = self.contact.tangent_values();
            let force_rows = |du: &[f64]| {
                let mut kdu = 0.0;
                for &e in &cons {
                    kdu += model.pattern.row_dot(kvals, e, du);
                }
                kdu
            };
            for k in 0..np {
                if self.skips(k) {
                    continue;
                }
                let (dyk, bduk) = (&mut dy[k], &mut bdu[k]);
                for q in 0..nq {
                    let (d, e) = (&dblk[q * m * m..], &eblk[q * m * 4..]);
                    let p = &pblk[q * m * np..];
                    for r in 0..m {
                        let mut v = -p[r * np + k];
                        for j in 0..m {
                            v -= d[r * m + j] * dyk[q * m + j];
                        }
                        for j in 0..4 {
                            v += e[r * 4 + j] * bduk[q][j];
                        }
                        qv[q * m + r] = v;
                    }
                    let inv = &ainv[q * m * m..];
                    let hq = Vec4(std::array::from_fn(|a| {
                        (0..m).map(|j| inv[a * m + j] * qv[q * m + j]).sum::<f64>()
                    }));
                    h[q] = hq;
                    self.field_b[q] = hq * -1.0;
                }
                let w = &mut works[k];
                crate::force_into(model, finite, &self.field_b, &mut w.full);
                let rhs_a = rows.then(|| {
                    crate::force_dofs(model, rec)
                        .map(|d| w.full[d])
                        .sum::<f64>()
                });
                model.dofs.restrict(&w.full, &mut w.eq);
                self.contact
                    .sensitivity_solve(&mut w.eq, &w.du_prev, &mut w.xbar, &mut w.solve);
                if let Some(load) = border {
                    // the depth's variation: from the force's at the depth held
                    // (`dF^U = -e_A . (K du + B* Pi A^-1 q)`) under load control
                    let du_u = if let (true, Some(rhs_a)) = (load, rhs_a) {
                        (carry.given[k] - (rhs_a - force_rows(&w.eq))) / carry.s
                    } else if load {
                        crate::expand_into(model, &w.eq, &mut w.full);
                        crate::strains_into(model, finite, &w.full, &mut w.strain);
                        for q in 0..nq {
                            let b = Vec4(w.strain[q]);
                            w.field_b[q] = self.tangents[q].mul_vec(&b) + h[q];
                        }
                        match finite {
                            None => model.disc.internal_force(&w.field_b, &mut w.full),
                            Some(fs) => fs.delta_force(model, &h, &mut w.full, &mut w.du),
                        }
                        let df_held: f64 = -crate::force_dofs(model, rec)
                            .map(|d| w.full[d])
                            .sum::<f64>();
                        (carry.given[k] - df_held) / carry.s
                    } else {
                        carry.given[k]
                    };
                    for (e, col) in w.eq.iter_mut().zip(&carry.col.col) {
                        *e += du_u * col;
                    }
                    dh[i][k] = du_u;
                }
                crate::expand_into(model, &w.eq, &mut w.full);
                if !w.du_prev.is_empty() {
                    w.du_prev.copy_from_slice(&w.full);
                    crate::load::relative_to_punch(model, &mut w.du_prev, dh[i][k]);
                }
                crate::strains_into(model, finite, &w.full, &mut w.strain);
                for q in 0..nq {
                    let b = Vec4(w.strain[q]);
                    self.field_b[q] = self.tangents[q].mul_vec(&b) + h[q];
                    let (inv, e) = (&ainv[q * m * m..], &eblk[q * m * 4..]);
                    for r in 0..m {
                        sw.x[r] = qv[q * m + r] - (0..4).map(|j| e[r * 4 + j] * b[j]).sum::<f64>();
                    }
                    for r in 0..m {
                        dyk[q * m + r] = (0..m).map(|j| inv[r * m + j] * sw.x[j]).sum();
                    }
                    bduk[q] = b.0;
                }
                if let Some(rhs_a) = rhs_a {
                    df[i][k] = if prescribed {
                        carry.given[k]
                    } else {
                        rhs_a - force_rows(&w.eq)
                    };
                    continue;
                }
                match finite {
                    None => model.disc.internal_force(&self.field_b, &mut w.full),
                    // K du + sum w0 G^T Pi A^-1 q (geometric part included)
                    Some(fs) => fs.delta_force(model, &h, &mut w.full, &mut w.du),
                }
                df[i][k] = -crate::force_dofs(model, rec)
                    .map(|d| w.full[d])
                    .sum::<f64>();
            }
        }
        Ok((df, dh))
    }

    /// The inputs' checks: recorded fields (unless replayed), lengths, the parameters'
    /// ranges and the law's differentiability there (every model, small and finite strain,
    /// with or without friction, is one this sweep takes).
    pub(crate) fn check_material(
        &self,
        mat: &dyn Material,
        c: &[f64],
        traj: &Trajectory,
        n_rho: usize,
        need_fields: bool,
    ) -> Result<(), AdjointError> {
        let n = traj.steps.len();
        if need_fields && traj.fields.len() != n + 1 {
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
        mat.check_params(c)?;
        mat.check_differentiable(c)?;
        Ok(())
    }

    /// One step of the reversed-time sweep (steps 1-3 of the module's recursion) with
    /// `dJ/dF_i = rho`, or under load control (`border`) with the `rho` the step's depth
    /// column sets (`load.rs`). Returns the `rho` used.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn material_step(
        &mut self,
        mat: &dyn Material,
        c: &[f64],
        sw: &mut MatSweep,
        i: usize,
        rec: &StepRecord,
        (f0, f1): (&StepFields, &StepFields),
        rho: f64,
        border: Option<crate::load::BorderedRho<'_>>,
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
        let model = self.model;
        let m = sw.m;
        let nq = model.disc.n_qp();
        let fail = |q: usize, what: &str| AdjointError::Step {
            step: i,
            t: rec.t,
            reason: format!(
                "{}: singular local Jacobian A at Gauss point {q} ({what})",
                mat.name()
            ),
        };
        self.step_strains(f0, f1, &mut sw.deps)
            .map_err(|reason| AdjointError::Step {
                step: i,
                t: rec.t,
                reason,
            })?;
        let finite = self.finite.is_some();
        // Coulomb friction: dJ/dF enters as the shift `V' = V + rho e_A` (lib.rs), whose
        // part `rho B e_A` joins `z`'s stress rows in the source; under load control
        // (`border`) `rho` is not known yet and `bordered_rho` adds that part, `-rho K e_A`
        let shifted = self.contact.force_cotangent() == ForceCotangent::Shifted;
        let shift_source = shifted && border.is_none();
        if shift_source && !finite {
            self.full.fill(0.0);
            for d in crate::force_dofs(model, rec) {
                self.full[d] = 1.0;
            }
            self.strains_of_full();
        }
        // a linear material: its blocks once for the step
        let linear = sw.linear;
        if linear {
            sw.load(f0, f1, 0);
            let deps = sw.deps[0];
            if !sw.linear_blocks(mat, c, &deps, rec.dt) {
                return Err(fail(0, "tangent"));
            }
            self.tangents.fill(sw.ct);
        }
        // per point: G = A^-T Pi^T, C = -G^T E, A^-T z, and the source e + E^T A^-T z
        for q in 0..nq {
            if linear {
                // `z` holds `mu_{i+1}`: `A^-T z = Q mu_{i+1}`, the source `S^T mu_{i+1}`
                let mu1 = &sw.z[q * m..(q + 1) * m];
                let az = &mut sw.az[q * m..(q + 1) * m];
                if sw.iso {
                    q_mu_isotropic(m / 4, &sw.qa, &sw.qc, mu1, az);
                } else {
                    for (k, a) in az.iter_mut().enumerate() {
                        *a = dot(&sw.qm[k * m..(k + 1) * m], mu1);
                    }
                }
                let mut src = Vec4::ZERO;
                for (r, mu) in mu1.iter().enumerate() {
                    for b in 0..4 {
                        src.0[b] += sw.sm[r * 4 + b] * mu;
                    }
                }
                if shift_source && !finite {
                    src += sw.eg.mul_vec(&Vec4(self.strain[q])) * rho;
                }
                self.field_b[q] = src;
                continue;
            }
            sw.load(f0, f1, q);
            let deps = sw.deps[q];
            let step = Step {
                y0: &sw.y0,
                y1: &sw.y1,
                deps: &deps,
                dt: rec.dt,
                regime: f1.regime[q],
            };
            // every block of the point in one call; `D`, `E`, `P` kept for the second pass
            let np = sw.grad.len();
            let ej = &mut sw.eblk[q * m * 4..(q + 1) * m * 4];
            mat.jac_blocks(
                c,
                &step,
                &mut sw.a,
                &mut sw.dblk[q * m * m..(q + 1) * m * m],
                ej,
                &mut sw.pblk[q * m * np..(q + 1) * m * np],
            );
            let ej = &sw.eblk[q * m * 4..(q + 1) * m * 4];
            // one solve with A^T for [Pi^T | z]: G and A^-T z (the material's closed
            // form, or an elimination)
            sw.rhs5.fill(0.0);
            for k in 0..m {
                if k < 4 {
                    sw.rhs5[k * 5 + k] = 1.0;
                }
                sw.rhs5[k * 5 + 4] = sw.z[q * m + k];
            }
            if !mat.solve_state_transpose(c, &step, &sw.a, &mut sw.rhs5, 5, &mut sw.at) {
                return Err(fail(q, "tangent and adjoint"));
            }
            for k in 0..m {
                sw.g[(q * m + k) * 4..(q * m + k + 1) * 4]
                    .copy_from_slice(&sw.rhs5[k * 5..k * 5 + 4]);
                sw.x[k] = sw.rhs5[k * 5 + 4];
            }
            let gq = &sw.g[q * m * 4..(q + 1) * m * 4];
            self.tangents[q] = tangent_of(gq, ej);
            sw.az[q * m..(q + 1) * m].copy_from_slice(&sw.x);
            if shift_source && !finite {
                let bea = self.strain[q];
                let gq = &sw.g[q * m * 4..(q + 1) * m * 4];
                for k in 0..m {
                    sw.x[k] += rho * (0..4).map(|j| gq[k * 4 + j] * bea[j]).sum::<f64>();
                }
            }
            let mut src = sw.e[q];
            let ex = column_dots4(ej, &sw.x);
            for b in 0..4 {
                src.0[b] += ex[b];
            }
            self.field_b[q] = src;
        }
        let reason = |r: String| AdjointError::Step {
            step: i,
            t: rec.t,
            reason: r,
        };
        let uniform = (linear && !finite).then_some(c);
        self.prepare_material_step(rec, f1, uniform)
            .map_err(reason)?;
        // K^T V = B* source, V = rho on the active dofs
        self.force_of_field_b();
        if let (true, Some(fs)) = (shift_source, &self.finite) {
            // (finite strain: the shift's part of the source is K (-rho e_A))
            self.e_a.clear();
            self.e_a.resize(self.full.len(), 0.0);
            for d in crate::force_dofs(model, rec) {
                self.e_a[d] = -rho;
            }
            fs.add_k_times(model, &self.e_a, &mut self.full);
        }
        self.restrict();
        let rho = match border {
            Some(b) => self.bordered_rho(i, rec, &f1.u, b)?,
            None => rho,
        };
        let mut eq = std::mem::take(&mut self.eq);
        self.contact.adjoint_solve(rec, &f1.u, rho, &mut eq);
        self.eq = eq;
        self.expand();
        if shifted {
            for d in crate::force_dofs(model, rec) {
                self.full[d] += rho;
            }
        }
        self.strains_of_full();
        // mu = -(A^-T z + G B V); gradient; carries for the step before
        for q in 0..nq {
            let bv = self.strain[q];
            let gq = if linear {
                &sw.glin[..]
            } else {
                &sw.g[q * m * 4..(q + 1) * m * 4]
            };
            for k in 0..m {
                sw.x[k] = -(sw.az[q * m + k] + dot(&gq[k * 4..k * 4 + 4], &bv));
            }
            let w = model.disc.qp[q].w;
            if linear {
                sw.load(f0, f1, q);
                let deps = sw.deps[q];
                let step = Step {
                    y0: &sw.y0,
                    y1: &sw.y1,
                    deps: &deps,
                    dt: rec.dt,
                    regime: f1.regime[q],
                };
                // dJ/dc -= w mu^T P (the material's contraction: a closed form, or its block)
                mat.jac_params_transpose(c, &step, &sw.x, -w, &mut sw.p, &mut sw.grad);
                // the carry is `mu_i` itself (folded into the step before)
                #[allow(clippy::manual_memcpy)] // (no `memmove` call per point)
                for k in 0..m {
                    sw.z[q * m + k] = sw.x[k];
                }
                continue;
            }
            // the blocks of the first pass: dJ/dc -= w mu^T P (the trait default's sums),
            // the carries D^T mu and E^T mu
            let np = sw.grad.len();
            let (d, ej) = (
                &sw.dblk[q * m * m..(q + 1) * m * m],
                &sw.eblk[q * m * 4..(q + 1) * m * 4],
            );
            let p = &sw.pblk[q * m * np..(q + 1) * m * np];
            column_dots(p, &sw.x, &mut sw.pacc);
            for (g, s) in sw.grad.iter_mut().zip(&sw.pacc) {
                *g += -w * s;
            }
            column_dots(d, &sw.x, &mut sw.z[q * m..(q + 1) * m]);
            sw.e[q] = Vec4(column_dots4(ej, &sw.x));
        }
        if linear {
            sw.d_next.copy_from_slice(&sw.d);
            sw.e_next.copy_from_slice(&sw.ej);
        }
        Ok(rho)
    }

    /// The step's strain increment at every Gauss point into `out`: `B (u_1 - u_0)`
    /// under small strain, `E(u_1) - E(u_0)` (Hencky strains, with the forward's own
    /// routines) under finite strain.
    ///
    /// # Errors
    /// A message naming the Gauss point where a recorded state is inverted.
    fn step_strains(
        &self,
        f0: &StepFields,
        f1: &StepFields,
        out: &mut [Vec4],
    ) -> Result<(), String> {
        let disc = &self.model.disc;
        for e in 0..disc.elements.len() {
            let (u0, u1) = (disc.gather(e, &f0.u), disc.gather(e, &f1.u));
            // (small strain: the element's increment once, not once per Gauss point)
            let mut due = [0.0; 16];
            for ((d, a), b) in due.iter_mut().zip(&u1).zip(&u0) {
                *d = a - b;
            }
            for g in 0..QP_PER_ELEMENT {
                let q = QP_PER_ELEMENT * e + g;
                let qp = &disc.qp[q];
                out[q] = if self.finite.is_some() {
                    let hencky = |ue: &[f64; 16]| {
                        let def = Deformation::new(qp, ue);
                        (def.det() > 0.0)
                            .then(|| LogStrain::from_difference(&def.c_minus_one()))
                            .flatten()
                            .map(|ls| ls.e)
                            .ok_or_else(|| format!("inverted recorded state at Gauss point {q}"))
                    };
                    hencky(&u1)? - hencky(&u0)?
                } else {
                    Vec4(qp.strain(&due))
                };
            }
        }
        Ok(())
    }

    /// Sets the step's system from the tangents in `self.tangents`: under finite strain
    /// the element tangents at `u_1` (material and geometric parts); with friction the
    /// frames' reactions from the recorded stresses.
    ///
    /// # Errors
    /// A message from the finite-strain operators or the contact.
    /// `uniform`: the parameters of a linear material under small strain, whose one
    /// tangent (in `self.tangents[0]`) keys the reuse of the factorization as a linear
    /// law's does.
    fn prepare_material_step(
        &mut self,
        rec: &StepRecord,
        f1: &StepFields,
        uniform: Option<&[f64]>,
    ) -> Result<(), String> {
        let model = self.model;
        if let Some(fs) = self.finite.as_mut() {
            fs.prepare(model, &f1.u, &f1.sigma, &self.tangents)?;
        }
        let f_int = if self.contact.needs_internal_force() {
            crate::force_into(model, self.finite.as_ref(), &f1.sigma, &mut self.full);
            Some(self.full.as_slice())
        } else {
            None
        };
        let tangent = match (&self.finite, uniform) {
            (Some(fs), _) => StepTangent::Elements(&fs.ke),
            (None, Some(params)) => StepTangent::Uniform {
                tangent: &self.tangents[0],
                params,
                dt: rec.dt,
            },
            (None, None) => StepTangent::Points(&self.tangents),
        };
        self.contact.prepare(rec, &f1.u, f_int, tangent)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use indentify_laws::Prony;

    /// A Prony solid's folded block `Q = A_i^-T D_{i+1}^T` has isotropic 4 x 4 blocks,
    /// and the product from their two coefficients equals the dense `Q mu` to 1e-12 of
    /// `max|Q| |mu|_1` (one to three terms, the validation's and R2's bench parameters;
    /// measured: a few 1e-14, the dense `Q`'s departures from isotropy, which are the
    /// elimination's round-off).
    #[test]
    fn prony_q_is_isotropic_and_its_product_is_the_dense_one() {
        let mut worst = 0.0f64;
        for (e, nu, terms) in [
            (3000.0, 0.35, [(0.3, 0.2), (0.2, 2.0), (0.1, 0.05)]),
            (1e5, 0.3, [(0.3, 0.2), (0.2, 2.0), (0.1, 20.0)]),
        ]
        .into_iter()
        .flat_map(|(e, nu, t)| (1..=3).map(move |n| (e, nu, t[..n].to_vec())))
        {
            let n = terms.len();
            let prony = Prony::new(n).unwrap();
            let mut c = vec![e, nu];
            for &(g, tau) in &terms {
                c.extend([g, tau]);
            }
            let m = prony.state_len();
            let mut sw = MatSweep::new(&prony, c.len(), 1);
            let deps = Vec4::ZERO;
            assert!(sw.linear_blocks(&prony, &c, &deps, 1.0 / 30.0));
            sw.d_next.copy_from_slice(&sw.d);
            sw.e_next.copy_from_slice(&sw.ej);
            assert!(sw.linear_blocks(&prony, &c, &deps, 1.0 / 30.0));
            assert!(sw.iso, "{n} terms");
            assert!(sw.qm.iter().any(|v| *v != 0.0));
            let mu: Vec<f64> = (0..m).map(|r| (0.3 + 1.7 * r as f64).sin()).collect();
            let mut fast = vec![0.0; m];
            q_mu_isotropic(m / 4, &sw.qa, &sw.qc, &mu, &mut fast);
            for k in 0..m {
                let row = &sw.qm[k * m..(k + 1) * m];
                let want = dot(row, &mu);
                let big = sw.qm.iter().fold(0.0f64, |s, v| s.max(v.abs()));
                let size = big * mu.iter().map(|v| v.abs()).sum::<f64>();
                worst = worst.max((fast[k] - want).abs() / size);
                assert!(
                    (fast[k] - want).abs() <= 1e-12 * size,
                    "{n} terms, row {k}: {} vs {want}",
                    fast[k]
                );
            }
        }
        eprintln!("isotropic Q mu against the dense product: {worst:e}");
    }
}

/// How a sensitivity pass of a material drives its steps: by depth, under load control
/// (`load.rs`), or by depth through the instrument's frame (`compliant.rs`).
#[derive(Clone, Copy)]
pub(crate) enum SensDrive<'a> {
    Depth,
    Load(&'a LoadHistory),
    Frame(&'a crate::compliant::FrameDrive),
}
