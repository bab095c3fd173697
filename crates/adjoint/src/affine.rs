//! The sweep of a law with one tangent at every Gauss point (elasticity, Maxwell:
//! [`Law::is_linear`]) under small strain, in one pass over the Gauss points per step
//! (docs/validation-load-control.md §6, "One pass per step").
//!
//! A sweep step visits every point twice in its general form (`lib.rs`): the right-hand
//! side `g_i = sum_g w B^T (C_i S - I) mu_{i+1}` before the solve, and the
//! back-substitution `mu_i = C_i (S mu_{i+1} - B V_i)` with the gradient's sums after it.
//! The right-hand side of the step swept next, `g_{i-1}`, needs only `mu_i` and that
//! step's tangent, which for such a law is `C(c, dt_{i-1})` at every point: the
//! back-substitution of step `i` forms it in the same pass, element by element
//! (`B V_i`, `mu_i`, the sums, `B^T (C_{i-1} S - I) mu_i`), and step `i-1` starts from
//! it ([`Fused::take_source`]).
//!
//! When `S`, `C`, `dS/dc_k` and the flow's `dg/dc_k = D_k sigma` are isotropic (`p I + q J`,
//! [`Iso`]; checked numerically once per sweep, with the flow's linearity), each 4x4
//! product is two coefficients and the gradient's part of a step is four sums
//! (`w mu . s1`, `w mu . s0`, `w tr(mu) tr(s1)`, `w tr(mu) tr(s0)`) instead of an outer
//! product and the flow's derivatives at every point. Otherwise the general form's
//! per-point arithmetic is kept (the same `mu_i` and `g_{i-1}` bits). The sums are added
//! in fixed chunks of elements, the same chunks on any number of threads: the same bits
//! on any number of threads, and the general sweep's gradient to round-off
//! (`tests/fused_sweep.rs`).

use std::f64::consts::FRAC_1_SQRT_2;

use indentify_fe::QP_PER_ELEMENT;
use indentify_laws::{Law, Mat4, Vec4};
use rayon::prelude::*;

use crate::{Adjoint, Sweep};

/// Elements per chunk of the fused pass (fixed: the sums' order does not depend on the
/// thread count).
const CHUNK: usize = 8;

/// One chunk of the general fused pass: its index, its elements' forces, its points'
/// `mu_i`, and its sums (`mu (x) (s1 - s0)`, the flow's part, scratch).
type GeneralChunk<'a> = (
    usize,
    (
        (
            ((&'a mut [[f64; 16]], &'a mut [Vec4]), &'a mut Mat4),
            &'a mut [f64],
        ),
        &'a mut [Vec4],
    ),
);

/// One chunk of the isotropic fused pass: its index, its elements' forces, its points'
/// `mu_i` and its four sums.
type IsoChunk<'a> = (
    usize,
    ((&'a mut [[f64; 16]], &'a mut [Vec4]), &'a mut [f64; 4]),
);

/// The fused pass's work space and the right-hand side it leaves for the next step.
#[derive(Debug, Default)]
pub(crate) struct Fused {
    /// The body's right-hand side `g` (all dofs) of the step `next` names.
    g: Vec<f64>,
    /// The step whose right-hand side `g` holds (its index and step length's bits).
    next: Option<(usize, u64)>,
    /// Each element's part of `g`.
    forces: Vec<[f64; 16]>,
    /// Per chunk: `sum w mu (x) (s1 - s0)`.
    m_part: Vec<Mat4>,
    /// Per chunk and parameter: `-dt sum w mu . dg/dc_k(s1)`.
    g_part: Vec<f64>,
    /// Per chunk and parameter: scratch for `dg/dc_k`.
    dflow: Vec<Vec4>,
    /// Steps whose right-hand side came from the previous step's pass (a count).
    pub(crate) reused: usize,
    /// The isotropic form of the law's parameter derivatives, found at a sweep's first
    /// pass (`None` inside: not looked for yet; `Some(None)`: not isotropic).
    iso: Option<Option<IsoParams>>,
    /// Tests only: keep the general per-point form even for an isotropic law.
    #[cfg(test)]
    pub(crate) general_form: bool,
    /// Tests only: keep the Gauss-point pass where the all-nodal sweep applies.
    #[cfg(test)]
    pub(crate) per_point: bool,
    /// Per chunk: the isotropic sums `[w mu . s1, w mu . s0, w tr mu tr s1, w tr mu tr s0]`.
    sums: Vec<[f64; 4]>,
    /// The all-nodal sweep (`nodal.rs`).
    pub(crate) nodal: crate::nodal::Nodal,
}

/// `M = p I + q J` with `J = 1 (x) 1 / 3` (Mandel; `J x = tr(x) / 3 1`): an isotropic
/// fourth-order operator by its two coefficients.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Iso {
    pub(crate) p: f64,
    pub(crate) q: f64,
}

impl Iso {
    /// `M` as `p I + q J` when it is that to 1e-13 of its largest entry.
    pub(crate) fn of(m: &Mat4) -> Option<Iso> {
        let (p, q) = (m.0[3][3], 3.0 * m.0[0][1]);
        let scale = m.max_abs();
        let iso = Iso { p, q };
        let ok = (0..4).all(|a| {
            (0..4).all(|b| {
                let j = if a < 3 && b < 3 { q / 3.0 } else { 0.0 };
                let want = if a == b { p + j } else { j };
                (m.0[a][b] - want).abs() <= 1e-13 * scale
            })
        });
        (ok && scale.is_finite()).then_some(iso)
    }

    #[cfg(test)]
    fn apply(self, x: &Vec4) -> Vec4 {
        let t = (x.0[0] + x.0[1] + x.0[2]) * (self.q / 3.0);
        Vec4([
            self.p * x.0[0] + t,
            self.p * x.0[1] + t,
            self.p * x.0[2] + t,
            self.p * x.0[3],
        ])
    }
}

impl Iso {
    /// `self * o` (apply `o` first): `(p1 I + q1 J)(p2 I + q2 J) = p1 p2 I + (p1 q2 + q1 p2
    /// + q1 q2) J`, since `J J = J`.
    pub(crate) fn then(self, o: Iso) -> Iso {
        Iso {
            p: self.p * o.p,
            q: self.p * o.q + self.q * o.p + self.q * o.q,
        }
    }

    /// `self - I`.
    pub(crate) fn minus_identity(self) -> Iso {
        Iso {
            p: self.p - 1.0,
            q: self.q,
        }
    }
}

/// An [`Iso`] with `q / 3` at hand, for the fused pass's inner loop.
#[derive(Clone, Copy)]
struct Iso3 {
    p: f64,
    q3: f64,
}

impl Iso3 {
    fn of(m: Iso) -> Iso3 {
        Iso3 {
            p: m.p,
            q3: m.q / 3.0,
        }
    }

    #[inline]
    fn apply(self, x: &Vec4) -> Vec4 {
        let t = (x.0[0] + x.0[1] + x.0[2]) * self.q3;
        Vec4([
            self.p * x.0[0] + t,
            self.p * x.0[1] + t,
            self.p * x.0[2] + t,
            self.p * x.0[3],
        ])
    }
}

/// `B u_e` at a Gauss point from its compact B operator (`QuadPoint::dn`), as
/// `QuadPoint::strain` with the shear scaled by a product instead of a quotient.
#[inline]
fn strain(dn: &[[f64; 3]; 8], ue: &[f64; 16]) -> [f64; 4] {
    let (mut rr, mut zz, mut tt, mut rz) = (0.0, 0.0, 0.0, 0.0);
    for (a, [dr, dz, nr]) in dn.iter().enumerate() {
        let (ur, uz) = (ue[2 * a], ue[2 * a + 1]);
        rr += dr * ur;
        zz += dz * uz;
        tt += nr * ur;
        rz += dz * ur + dr * uz;
    }
    [rr, zz, tt, rz * FRAC_1_SQRT_2]
}

/// `fe += B^T s` at a Gauss point (the weight already in `s`), as `QuadPoint::add_bt`.
#[inline]
fn add_bt(dn: &[[f64; 3]; 8], s: &Vec4, fe: &mut [f64; 16]) {
    let (s0, s1, s2, s3) = (s.0[0], s.0[1], s.0[2], s.0[3] * FRAC_1_SQRT_2);
    for (a, [dr, dz, nr]) in dn.iter().enumerate() {
        fe[2 * a] += dr * s0 + nr * s2 + dz * s3;
        fe[2 * a + 1] += dz * s1 + dr * s3;
    }
}

/// The parameter derivatives of a law whose compliance derivatives `dS/dc_k` and flow
/// derivatives `dg/dc_k = D_k sigma` (the flow linear in the stress) are isotropic: then
/// `sum w mu . R_i` needs four sums per step instead of `mu (x) (s1 - s0)` and the flow's
/// derivatives at every point.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct IsoParams {
    pub(crate) ds: Vec<Iso>,
    pub(crate) dg: Vec<Iso>,
}

impl IsoParams {
    /// The isotropic forms of `law`'s `dS/dc_k` and `D_k`, or `None` when one is not
    /// isotropic or the flow's derivative is not linear in the stress (checked at a
    /// stress).
    pub(crate) fn of(law: &dyn Law, c: &[f64]) -> Option<IsoParams> {
        let np = c.len();
        let ds = (0..np)
            .map(|k| Iso::of(&law.compliance_derivative(c, k)))
            .collect::<Option<Vec<_>>>()?;
        // D_k column by column from unit stresses
        let mut d = vec![Mat4::ZERO; np];
        let mut out = vec![Vec4::ZERO; np];
        for j in 0..4 {
            let mut e = Vec4::ZERO;
            e.0[j] = 1.0;
            law.flow_param_derivatives(c, &e, &mut out);
            for (dk, o) in d.iter_mut().zip(&out) {
                for a in 0..4 {
                    dk.0[a][j] = o.0[a];
                }
            }
        }
        let dg = d.iter().map(Iso::of).collect::<Option<Vec<_>>>()?;
        // linear: D_k sigma is the law's own derivative at a stress
        let sigma = Vec4([1.0, -2.0, 0.5, 3.0]);
        law.flow_param_derivatives(c, &sigma, &mut out);
        for (dk, o) in d.iter().zip(&out) {
            let lin = dk.mul_vec(&sigma);
            let scale = o.max_abs().max(dk.max_abs());
            if (lin - *o).max_abs() > 1e-12 * scale {
                return None;
            }
        }
        Some(IsoParams { ds, dg })
    }
}

impl IsoParams {
    /// `gradient -= sum w mu . R_i` of a step of length `dt` (s) from its four sums
    /// `[w mu . s1, w mu . s0, w tr(mu) tr(s1), w tr(mu) tr(s0)]`: with `M = p I + q J`,
    /// `sum w mu . M x = p sum w mu . x + q/3 sum w tr(mu) tr(x)`.
    pub(crate) fn subtract(&self, sweep: &mut Sweep, dt: f64, [d1, d0, e1, e0]: [f64; 4]) {
        for ((g, a), b) in sweep.grad.iter_mut().zip(&self.ds).zip(&self.dg) {
            *g -= a.p * (d1 - d0) + a.q / 3.0 * (e1 - e0) + dt * (b.p * d1 + b.q / 3.0 * e1);
        }
    }
}

/// The step swept next, for the fused pass: its index, step length (s) and tangent.
#[derive(Clone, Copy)]
pub(crate) struct Next {
    pub(crate) i: usize,
    pub(crate) dt: f64,
    pub(crate) tangent: Mat4,
}

impl Fused {
    /// Forgets any right-hand side kept from an earlier sweep.
    pub(crate) fn begin(&mut self) {
        self.next = None;
        self.reused = 0;
        self.iso = None;
        self.nodal.on = false;
    }

    /// Moves the right-hand side formed for step `i` (step length `dt`) into `full` and
    /// returns `true`, or returns `false` (nothing written) when the last pass formed none
    /// for that step.
    pub(crate) fn take_source(&mut self, i: usize, dt: f64, full: &mut Vec<f64>) -> bool {
        if self.next != Some((i, dt.to_bits())) || self.g.len() != full.len() {
            self.next = None;
            return false;
        }
        self.next = None;
        self.reused += 1;
        std::mem::swap(&mut self.g, full);
        true
    }
}

impl Adjoint<'_> {
    /// Whether a sweep step of `law` may use the fused pass: small strain and one tangent
    /// at every point.
    pub(crate) fn fusable(&self, law: &dyn Law) -> bool {
        self.finite.is_none() && law.is_linear()
    }

    /// The tangent of the step swept after step `i`, whose length is `prev_dt`, or `None`
    /// (no such step, or its tangent fails: that step then forms its own right-hand side).
    pub(crate) fn next_of(
        law: &dyn Law,
        c: &[f64],
        i: usize,
        prev_dt: Option<f64>,
    ) -> Option<Next> {
        let (i, dt) = (i.checked_sub(1)?, prev_dt?);
        let tangent = law.tangent(c, &Vec4::ZERO, dt).ok()?;
        Some(Next { i, dt, tangent })
    }

    /// The back-substitution of a prepared step of a fusable law (`self.tangents` all
    /// `C_i`, the adjoint displacement `V` in `self.full`, `mu_{i+1}` in `self.field_a`):
    /// `mu_i` into `self.field_a`, the gradient's sums into `sweep`, and with `next` the
    /// right-hand side of that step, kept for [`Fused::take_source`].
    pub(crate) fn back_substitute_fused(
        &mut self,
        law: &dyn Law,
        c: &[f64],
        sweep: &mut Sweep,
        (dt, sig0, sig1): (f64, &[Vec4], &[Vec4]),
        next: Option<Next>,
    ) {
        let params = self
            .fused
            .iso
            .take()
            .unwrap_or_else(|| IsoParams::of(law, c));
        #[cfg(test)]
        let params = params.filter(|_| !self.fused.general_form);
        let forms = params.as_ref().and_then(|_| {
            let cn = match next {
                Some(n) => Some(Iso::of(&n.tangent)?),
                None => None,
            };
            Some((Iso::of(&sweep.s)?, Iso::of(&self.tangents[0])?, cn))
        });
        if let (Some(ip), Some(forms)) = (&params, forms) {
            self.back_substitute_iso(ip, sweep, (dt, sig0, sig1), forms, next);
            self.fused.iso = Some(params);
            return;
        }
        self.fused.iso = Some(params);
        let model = self.model;
        let disc = &model.disc;
        let np = c.len();
        let ne = disc.elements.len();
        let n_chunks = ne.div_ceil(CHUNK);
        let f = &mut self.fused;
        f.forces.resize(ne, [0.0; 16]);
        f.m_part.resize(n_chunks, Mat4::ZERO);
        // (every law has a parameter; `npc` keeps the chunks non-empty regardless)
        let npc = np.max(1);
        f.g_part.resize(n_chunks * npc, 0.0);
        f.dflow.resize(n_chunks * npc, Vec4::ZERO);
        let (s, ct) = (sweep.s, self.tangents[0]);
        let next_c = next.map(|n| n.tangent);
        let (v, mu_in) = (&self.full, &self.field_a);
        let chunk_qp = CHUNK * QP_PER_ELEMENT;
        let work = |(k, ((((fes, mu_out), m), gp), dflow)): GeneralChunk<'_>| {
            *m = Mat4::ZERO;
            gp.fill(0.0);
            for (j, fe) in fes.iter_mut().enumerate() {
                let e = k * CHUNK + j;
                let ve = disc.gather(e, v);
                *fe = [0.0; 16];
                for g in 0..QP_PER_ELEMENT {
                    let q = QP_PER_ELEMENT * e + g;
                    let qp = &disc.qp[q];
                    let bv = Vec4(qp.strain(&ve));
                    let sm = s.mul_vec(&mu_in[q]);
                    let mu = ct.mul_vec(&(sm - bv));
                    mu_out[QP_PER_ELEMENT * j + g] = mu;
                    let wmu = mu * qp.w;
                    let ds = sig1[q] - sig0[q];
                    for a in 0..4 {
                        for b in 0..4 {
                            m.0[a][b] += wmu[a] * ds[b];
                        }
                    }
                    if sig1[q].max_abs() > 0.0 {
                        law.flow_param_derivatives(c, &sig1[q], &mut dflow[..np]);
                        for (gk, d) in gp.iter_mut().zip(dflow.iter()) {
                            *gk -= dt * wmu.dot(d);
                        }
                    }
                    if let Some(cn) = &next_c {
                        // the next step's source, as `Adjoint::adjoint_source` forms it
                        let src = cn.mul_vec(&s.mul_vec(&mu)) - mu;
                        qp.add_bt(&src.0, qp.w, fe);
                    }
                }
            }
        };
        let nq = QP_PER_ELEMENT * ne;
        // on one thread in place (handing a pass to a pool of one costs more than it does)
        if rayon::current_num_threads() > 1 {
            f.forces
                .par_chunks_mut(CHUNK)
                .zip(self.field_b[..nq].par_chunks_mut(chunk_qp))
                .zip(f.m_part.par_iter_mut())
                .zip(f.g_part.par_chunks_mut(npc))
                .zip(f.dflow.par_chunks_mut(npc))
                .enumerate()
                .for_each(work);
        } else {
            f.forces
                .chunks_mut(CHUNK)
                .zip(self.field_b[..nq].chunks_mut(chunk_qp))
                .zip(f.m_part.iter_mut())
                .zip(f.g_part.chunks_mut(npc))
                .zip(f.dflow.chunks_mut(npc))
                .enumerate()
                .for_each(work);
        }
        // the chunks' sums in chunk order
        for (m, gp) in f.m_part.iter().zip(f.g_part.chunks(npc)) {
            for a in 0..4 {
                for b in 0..4 {
                    sweep.m_acc.0[a][b] += m.0[a][b];
                }
            }
            for (g, p) in sweep.grad.iter_mut().zip(gp) {
                *g += p;
            }
        }
        f.next = None;
        if let Some(n) = next {
            // the elements' parts summed in element order, as `internal_force` does
            f.g.resize(v.len(), 0.0);
            f.g.fill(0.0);
            for (e, fe) in f.forces.iter().enumerate() {
                for (d, x) in disc.element_dofs(e).iter().zip(fe) {
                    f.g[*d] += x;
                }
            }
            f.next = Some((n.i, n.dt.to_bits()));
        }
        std::mem::swap(&mut self.field_a, &mut self.field_b);
    }
}

impl Adjoint<'_> {
    /// [`Adjoint::back_substitute_fused`] of a law whose operators are isotropic
    /// (`S`, `C_i`, the next step's `C`, `dS/dc_k`, `D_k`: [`Iso`]): each 4x4 product is
    /// two coefficients, and the gradient's part of the step is, with `M = p I + q J`,
    /// `sum w mu . M x = p sum w mu . x + q/3 sum w tr(mu) tr(x)` for `x = s1, s0`.
    fn back_substitute_iso(
        &mut self,
        ip: &IsoParams,
        sweep: &mut Sweep,
        (dt, sig0, sig1): (f64, &[Vec4], &[Vec4]),
        (s, ct, cn): (Iso, Iso, Option<Iso>),
        next: Option<Next>,
    ) {
        let model = self.model;
        let disc = &model.disc;
        let ne = disc.elements.len();
        let n_chunks = ne.div_ceil(CHUNK);
        let f = &mut self.fused;
        f.forces.resize(ne, [0.0; 16]);
        f.sums.resize(n_chunks, [0.0; 4]);
        let (v, mu_in) = (&self.full, &self.field_a);
        let chunk_qp = CHUNK * QP_PER_ELEMENT;
        // the operators composed once: `mu = C S mu_{i+1} - C B V` and the next step's
        // source `(C' S - I) mu` (each a `p I + q J` applied with `q / 3` precomputed)
        let cs = Iso3::of(ct.then(s));
        let ct = Iso3::of(ct);
        let tn = cn.map(|cn| Iso3::of(cn.then(s).minus_identity()));
        let work = |(k, ((fes, mu_out), sums)): IsoChunk<'_>| {
            let mut acc = [0.0; 4];
            for (j, fe) in fes.iter_mut().enumerate() {
                let e = k * CHUNK + j;
                let ve = disc.gather(e, v);
                *fe = [0.0; 16];
                for g in 0..QP_PER_ELEMENT {
                    let q = QP_PER_ELEMENT * e + g;
                    let qp = &disc.qp[q];
                    let bv = strain(&qp.dn, &ve);
                    let m = &mu_in[q];
                    let t = (m.0[0] + m.0[1] + m.0[2]) * cs.q3 - (bv[0] + bv[1] + bv[2]) * ct.q3;
                    let mu = Vec4([
                        cs.p * m.0[0] - ct.p * bv[0] + t,
                        cs.p * m.0[1] - ct.p * bv[1] + t,
                        cs.p * m.0[2] - ct.p * bv[2] + t,
                        cs.p * m.0[3] - ct.p * bv[3],
                    ]);
                    mu_out[QP_PER_ELEMENT * j + g] = mu;
                    let wmu = mu * qp.w;
                    let tw = wmu.0[0] + wmu.0[1] + wmu.0[2];
                    let (s1, s0) = (&sig1[q], &sig0[q]);
                    acc[0] += wmu.dot(s1);
                    acc[1] += wmu.dot(s0);
                    acc[2] += tw * (s1.0[0] + s1.0[1] + s1.0[2]);
                    acc[3] += tw * (s0.0[0] + s0.0[1] + s0.0[2]);
                    if let Some(tn) = tn {
                        add_bt(&qp.dn, &tn.apply(&wmu), fe);
                    }
                }
            }
            *sums = acc;
        };
        let nq = QP_PER_ELEMENT * ne;
        if rayon::current_num_threads() > 1 {
            f.forces
                .par_chunks_mut(CHUNK)
                .zip(self.field_b[..nq].par_chunks_mut(chunk_qp))
                .zip(f.sums.par_iter_mut())
                .enumerate()
                .for_each(work);
        } else {
            f.forces
                .chunks_mut(CHUNK)
                .zip(self.field_b[..nq].chunks_mut(chunk_qp))
                .zip(f.sums.iter_mut())
                .enumerate()
                .for_each(work);
        }
        let mut t = [0.0; 4];
        for p in &f.sums {
            for (a, b) in t.iter_mut().zip(p) {
                *a += b;
            }
        }
        ip.subtract(sweep, dt, t);
        f.next = None;
        if let Some(n) = next {
            f.g.resize(v.len(), 0.0);
            f.g.fill(0.0);
            for (e, fe) in f.forces.iter().enumerate() {
                for (d, x) in disc.element_dofs(e).iter().zip(fe) {
                    f.g[*d] += x;
                }
            }
            f.next = Some((n.i, n.dt.to_bits()));
        }
        std::mem::swap(&mut self.field_a, &mut self.field_b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use indentify_contact::{
        ContactKind, DirectSolver, HistorySegment, LoadHistory, Model, Punch, SolverOptions,
    };
    use indentify_laws::{LawMaterial, Maxwell};
    use indentify_mesh::CylinderMesher;

    /// The fused pass in its general per-point form (for a linear law that is not
    /// isotropic; none exists yet, so Maxwell with the isotropic form switched off), in
    /// its isotropic per-point form, and the all-nodal sweep (`nodal.rs`) give the general
    /// two-pass sweep's gradient to 1e-12, under load control with depth and force costs.
    #[test]
    fn general_form_of_the_fused_pass_equals_the_two_pass_sweep() {
        let mesh = CylinderMesher {
            radius: 4.0,
            height: 4.0,
            nr: 6,
            nz: 6,
            grading_r: 1.45,
            grading_z: 1.45,
        }
        .build()
        .unwrap();
        let cone = Punch::Cone {
            half_angle_deg: 68.0,
        };
        let m = Model::with_contact(mesh, cone, ContactKind::Vertical).unwrap();
        let seg = |depth: Option<f64>, force: Option<f64>| HistorySegment {
            duration: 1.0,
            depth,
            force,
            steps: 5,
        };
        let h = LoadHistory::from_segments(&[
            seg(Some(0.02), None),
            seg(None, Some(40.0)),
            seg(None, Some(40.0)),
            seg(Some(0.01), None),
        ])
        .unwrap();
        let (mat, c) = (LawMaterial(&Maxwell), [21000.0, 0.3, 25000.0]);
        let opts = SolverOptions {
            record_fields: true,
            ..SolverOptions::default()
        };
        let traj = DirectSolver::new(&m)
            .unwrap()
            .run_history(&mat, &c, &h, &opts)
            .unwrap();
        let n = traj.steps.len();
        let dj_dh: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let dj_df: Vec<f64> = (0..n).map(|i| 1e-3 * (i % 3) as f64).collect();
        let mut adj = Adjoint::new(&m).unwrap();
        let grad = |adj: &mut Adjoint, fused: bool, general_form: bool, per_point: bool| {
            adj.set_fused(fused);
            adj.fused.general_form = general_form;
            adj.fused.per_point = per_point;
            adj.gradient_load(&mat, &c, &traj, &h, &dj_dh, &dj_df)
                .unwrap()
                .dj_dc
        };
        let two = grad(&mut adj, false, false, false);
        let general = grad(&mut adj, true, true, true);
        let iso = grad(&mut adj, true, false, true);
        assert!(adj.fused.reused > 0);
        let nodal = grad(&mut adj, true, false, false);
        assert!(adj.fused.nodal.on && adj.fused.reused == 0);
        let scale = two.iter().fold(0.0f64, |m, g| m.max(g.abs()));
        for (((a, b), d), e) in two.iter().zip(&general).zip(&iso).zip(&nodal) {
            assert!((a - b).abs() <= 1e-12 * scale, "{two:?} vs {general:?}");
            assert!((a - d).abs() <= 1e-12 * scale, "{two:?} vs {iso:?}");
            assert!((a - e).abs() <= 1e-12 * scale, "{two:?} vs {nodal:?}");
        }
    }

    #[test]
    fn isotropic_forms_are_recognized_and_others_refused() {
        let c = [20000.0, 0.3, 30000.0];
        let t = Maxwell.tangent(&c, &Vec4::ZERO, 0.1).unwrap();
        let iso = Iso::of(&t).unwrap();
        let x = Vec4([1.0, -2.0, 0.5, 3.0]);
        assert!((iso.apply(&x) - t.mul_vec(&x)).max_abs() <= 1e-12 * t.max_abs());
        let mut skew = t;
        skew.0[0][3] = 1.0;
        assert!(Iso::of(&skew).is_none());
        assert!(IsoParams::of(&Maxwell, &c).is_some());
    }
}
