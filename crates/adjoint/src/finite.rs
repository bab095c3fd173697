//! The step operators of the exact adjoint and sensitivities under finite strain
//! (`Kinematics::Finite`, docs/validation-finite-strain.md §5 "Exact adjoint").
//!
//! At a converged step with displacement `u_i` and log-space stresses `T_i` (the recorded
//! Gauss-point state), the small-strain operator `B` becomes `G_i = P(C(u_i)) B_L(u_i)`
//! (`dE_log = G_i du`, `E_log = ln(C)/2`, `P = 2 dE/dC`) and the step's stiffness the
//! forward's consistent tangent `K_i = sum w0 (B_L^T (P A P + T:L) B_L + G_geo(S))`
//! (`S = P T`). Both are formed here from the recorded displacement with the forward's
//! element routines ([`Deformation`], [`LogStrain`]); nothing of the kinematics is
//! re-derived.

use indentify_contact::Model;
use indentify_fe::{Deformation, QP_PER_ELEMENT};
use indentify_laws::{LogStrain, Mat4, Vec4};

/// `B_L` of one Gauss point in the compact per-node form of [`Deformation::b_l`].
type CompactB = [[[f64; 2]; 4]; 8];

/// The finite-strain operators of one step: per Gauss point `B_L(u_i)` and `P(u_i)`, per
/// element the consistent tangent `K_e` (lower triangle, as the forward assembles it).
#[derive(Debug)]
pub(crate) struct FiniteStep {
    b: Vec<CompactB>,
    p: Vec<Mat4>,
    /// Element tangents `K_e` (lower triangles, row >= column).
    pub(crate) ke: Vec<[[f64; 16]; 16]>,
}

impl FiniteStep {
    /// Workspace for `model`.
    pub(crate) fn new(model: &Model) -> FiniteStep {
        let (nq, ne) = (model.disc.n_qp(), model.disc.elements.len());
        FiniteStep {
            b: vec![[[[0.0; 2]; 4]; 8]; nq],
            p: vec![Mat4::ZERO; nq],
            ke: vec![[[0.0; 16]; 16]; ne],
        }
    }

    /// Forms `B_L`, `P` and the element tangents at the step's displacement `u` (all
    /// dofs), stresses `t` and law tangents `a = dT/dE` (every Gauss point).
    ///
    /// # Errors
    /// A message naming the Gauss point if `det F <= 0` there (the recorded state of a
    /// converged step never has one; this guards a corrupted trajectory).
    pub(crate) fn prepare(
        &mut self,
        model: &Model,
        u: &[f64],
        t: &[Vec4],
        a: &[Mat4],
    ) -> Result<(), String> {
        let disc = &model.disc;
        for e in 0..disc.elements.len() {
            let ue = disc.gather(e, u);
            let ke = &mut self.ke[e];
            *ke = [[0.0; 16]; 16];
            for g in 0..QP_PER_ELEMENT {
                let q = QP_PER_ELEMENT * e + g;
                let qp = &disc.qp[q];
                let def = Deformation::new(qp, &ue);
                let det = def.det();
                let ls = (det > 0.0)
                    .then(|| LogStrain::from_difference(&def.c_minus_one()))
                    .flatten()
                    .ok_or_else(|| {
                        format!(
                            "finite strain: det F = {det} at Gauss point {q} of a recorded step"
                        )
                    })?;
                let b = def.b_l(qp);
                let dm = ls.material_tangent(&a[q], &t[q]);
                def.add_tangent(qp, &dm, &ls.pk2(&t[q]), qp.w, ke);
                self.b[q] = b;
                self.p[q] = ls.p;
            }
        }
        Ok(())
    }

    /// `f = sum_g w0 G_g^T v_g` over all dofs (overwrites `f`): the finite-strain
    /// counterpart of [`indentify_fe::Discretization::internal_force`].
    pub(crate) fn force(&self, model: &Model, v: &[Vec4], f: &mut [f64]) {
        let disc = &model.disc;
        f.fill(0.0);
        for e in 0..disc.elements.len() {
            let mut fe = [0.0; 16];
            for g in 0..QP_PER_ELEMENT {
                let q = QP_PER_ELEMENT * e + g;
                let pv = self.p[q].mul_vec(&v[q]);
                Deformation::add_bt(&self.b[q], &pv, disc.qp[q].w, &mut fe);
            }
            for (d, x) in disc.element_dofs(e).iter().zip(fe) {
                f[*d] += x;
            }
        }
    }

    /// `G_g du` at every Gauss point (the log-strain variation): the finite-strain
    /// counterpart of [`indentify_fe::Discretization::strains`].
    pub(crate) fn strains(&self, model: &Model, du: &[f64], out: &mut [[f64; 4]]) {
        let disc = &model.disc;
        for e in 0..disc.elements.len() {
            let ue = disc.gather(e, du);
            for g in 0..QP_PER_ELEMENT {
                let q = QP_PER_ELEMENT * e + g;
                let mut gl = [0.0; 4];
                for (a, ba) in self.b[q].iter().enumerate() {
                    for (row, v) in gl.iter_mut().enumerate() {
                        *v += ba[row][0] * ue[2 * a] + ba[row][1] * ue[2 * a + 1];
                    }
                }
                out[q] = self.p[q].mul_vec(&Vec4(gl)).0;
            }
        }
    }

    /// Adds `K du` (the assembled element tangents times `du`, all dofs) to `f`.
    pub(crate) fn add_k_times(&self, model: &Model, du: &[f64], f: &mut [f64]) {
        let disc = &model.disc;
        for (e, k) in self.ke.iter().enumerate() {
            let dofs = disc.element_dofs(e);
            let ue = dofs.map(|d| du[d]);
            for p in 0..16 {
                let mut s = 0.0;
                for (q, uq) in ue.iter().enumerate() {
                    s += if p >= q { k[p][q] } else { k[q][p] } * uq;
                }
                f[dofs[p]] += s;
            }
        }
    }

    /// The variation of the internal force `delta f = K du + sum_g w0 G_g^T cq_g` (all
    /// dofs) for `cq = C q` and the displacement variation `du`, which `f` holds on entry
    /// and receives on exit.
    /// `du` is the caller's scratch (all dofs), so that threads can share the step.
    pub(crate) fn delta_force(&self, model: &Model, cq: &[Vec4], f: &mut [f64], du: &mut Vec<f64>) {
        du.clear();
        du.extend_from_slice(f);
        self.force(model, cq, f);
        self.add_k_times(model, du, f);
    }
}
