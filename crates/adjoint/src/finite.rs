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
use indentify_fe::{Deformation, QP_PER_ELEMENT, QuadPoint};
use indentify_laws::{LogStrain, Mat4, Vec4};

/// `B_L` of one Gauss point in the compact per-node form of [`Deformation::b_l`].
type CompactB = [[[f64; 2]; 4]; 8];

/// `G = P L(F)` of one Gauss point (the compact form, [`FiniteStep::set_compact`]): with
/// `gamma = [du_r,R, du_r,Z, du_z,R, du_z,Z, du_r/R]` the gradient of the displacement
/// variation, `B_L = L(F) gamma` ([`Deformation::add_tangent`]) and `G_i du = G gamma`.
/// `P` couples the in-plane components `[RR, ZZ, sqrt2*RZ]` among themselves and `L`'s
/// in-plane rows read `gamma`'s first four entries only, its hoop row the fifth only: so
/// `G` is an in-plane 3 x 4 block and one hoop scalar (13 numbers for the 80 of `B_L`
/// and `P`).
#[derive(Clone, Copy, Debug, Default)]
struct PointG {
    /// Rows `RR`, `ZZ`, `sqrt2*RZ` over `gamma[0..4]`.
    plane: [[f64; 4]; 3],
    /// `P_tt F_tt`, over `gamma[4]`.
    tt: f64,
}

impl PointG {
    /// `G = P L(F)`.
    fn new(def: &Deformation, p: &Mat4) -> PointG {
        let [[frr, frz], [fzr, fzz]] = def.f;
        let r2 = std::f64::consts::FRAC_1_SQRT_2;
        // the in-plane rows of L (RR, ZZ, sqrt2*RZ) over gamma[0..4]
        let l = [
            [frr, 0.0, fzr, 0.0],
            [0.0, frz, 0.0, fzz],
            [frz * r2, frr * r2, fzz * r2, fzr * r2],
        ];
        const PLANE: [usize; 3] = [0, 1, 3];
        let p = &p.0;
        let plane = PLANE.map(|i| {
            std::array::from_fn(|j| p[i][0] * l[0][j] + p[i][1] * l[1][j] + p[i][3] * l[2][j])
        });
        PointG {
            plane,
            tt: p[2][2] * def.ftt,
        }
    }
}

/// The finite-strain operators of one step: per Gauss point `B_L(u_i)` and `P(u_i)` (or,
/// in the compact form, `G = P L(F)`), per element the consistent tangent `K_e` (lower
/// triangle, as the forward assembles it).
#[derive(Debug)]
pub(crate) struct FiniteStep {
    b: Vec<CompactB>,
    p: Vec<Mat4>,
    g: Vec<PointG>,
    /// Whether [`FiniteStep::prepare`] forms `g` (and the products read it) instead of
    /// `b` and `p`.
    compact: bool,
    /// Element tangents `K_e` (lower triangles, row >= column).
    pub(crate) ke: Vec<[[f64; 16]; 16]>,
}

impl FiniteStep {
    /// Workspace for `model`.
    pub(crate) fn new(model: &Model) -> FiniteStep {
        let ne = model.disc.elements.len();
        FiniteStep {
            b: Vec::new(),
            p: Vec::new(),
            g: Vec::new(),
            compact: false,
            ke: vec![[[0.0; 16]; 16]; ne],
        }
    }

    /// Whether the next steps are formed in the compact form: per point `G = P L(F)` (13
    /// numbers) instead of `B_L` and `P` (80), so that the products over the points read
    /// `gamma` from the element's shape-function derivatives as the small-strain ones
    /// do (the forward sensitivities' default pass: `multi.rs`). The two forms give the
    /// same operator in another order of the products (round-off); sweeps and the pinned
    /// arithmetic (`Adjoint::set_fused(false)`) keep `B_L` and `P`.
    pub(crate) fn set_compact(&mut self, on: bool) {
        self.compact = on;
    }

    /// Forms `B_L`, `P` (or `G`) and the element tangents at the step's displacement `u`
    /// (all dofs), stresses `t` and law tangents `a = dT/dE` (every Gauss point).
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
        let nq = disc.n_qp();
        if self.compact {
            self.g.resize(nq, PointG::default());
        } else {
            self.b.resize(nq, [[[0.0; 2]; 4]; 8]);
            self.p.resize(nq, Mat4::ZERO);
        }
        for e in 0..disc.elements.len() {
            let ue = disc.gather(e, u);
            let ke = &mut self.ke[e];
            *ke = [[0.0; 16]; 16];
            for g in 0..QP_PER_ELEMENT {
                let q = QP_PER_ELEMENT * e + g;
                let qp = &disc.qp[q];
                let def = Deformation::new(qp, &ue);
                let det = def.det();
                // bound in place: the `Option` and `Result` adaptors moved the log strain
                // (41 numbers) through three copies per point
                let log = if det > 0.0 {
                    LogStrain::from_difference(&def.c_minus_one())
                } else {
                    None
                };
                let Some(ls) = log else {
                    return Err(format!(
                        "finite strain: det F = {det} at Gauss point {q} of a recorded step"
                    ));
                };
                let dm = ls.material_tangent(&a[q], &t[q]);
                def.add_tangent(qp, &dm, &ls.pk2(&t[q]), qp.w, ke);
                if self.compact {
                    self.g[q] = PointG::new(&def, &ls.p);
                } else {
                    self.b[q] = def.b_l(qp);
                    self.p[q] = ls.p;
                }
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
                self.add_force_at(&disc.qp[q], q, &v[q], disc.qp[q].w, &mut fe);
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
                out[q] = self.strain_at(&disc.qp[q], q, &ue);
            }
        }
    }

    /// Adds `w G_q^T v` (`G_q = P B_L` of Gauss point `q`, `qp`) to the element vector
    /// `fe`: one point's term of [`FiniteStep::force`].
    #[inline]
    pub(crate) fn add_force_at(
        &self,
        qp: &QuadPoint,
        q: usize,
        v: &Vec4,
        w: f64,
        fe: &mut [f64; 16],
    ) {
        if !self.compact {
            let pv = self.p[q].mul_vec(v);
            Deformation::add_bt(&self.b[q], &pv, w, fe);
            return;
        }
        // `w G^T v` over gamma, then each node's `gamma` columns
        let (g, v) = (&self.g[q], &v.0);
        let c: [f64; 4] = std::array::from_fn(|j| {
            w * (g.plane[0][j] * v[0] + g.plane[1][j] * v[1] + g.plane[2][j] * v[3])
        });
        let c4 = w * g.tt * v[2];
        for (a, [dr, dz, nr]) in qp.dn.iter().enumerate() {
            fe[2 * a] += dr * c[0] + dz * c[1] + nr * c4;
            fe[2 * a + 1] += dr * c[2] + dz * c[3];
        }
    }

    /// `G_q ue` at Gauss point `q` (`qp`) for its element's displacement variation `ue`:
    /// one point's term of [`FiniteStep::strains`].
    #[inline]
    pub(crate) fn strain_at(&self, qp: &QuadPoint, q: usize, ue: &[f64; 16]) -> [f64; 4] {
        if !self.compact {
            let mut gl = [0.0; 4];
            for (a, ba) in self.b[q].iter().enumerate() {
                for (row, v) in gl.iter_mut().enumerate() {
                    *v += ba[row][0] * ue[2 * a] + ba[row][1] * ue[2 * a + 1];
                }
            }
            return self.p[q].mul_vec(&Vec4(gl)).0;
        }
        let mut gm = [0.0; 5];
        for (a, [dr, dz, nr]) in qp.dn.iter().enumerate() {
            let (ur, uz) = (ue[2 * a], ue[2 * a + 1]);
            gm[0] += dr * ur;
            gm[1] += dz * ur;
            gm[2] += dr * uz;
            gm[3] += dz * uz;
            gm[4] += nr * ur;
        }
        let g = &self.g[q];
        let row = |r: &[f64; 4]| r[0] * gm[0] + r[1] * gm[1] + r[2] * gm[2] + r[3] * gm[3];
        [
            row(&g.plane[0]),
            row(&g.plane[1]),
            g.tt * gm[4],
            row(&g.plane[2]),
        ]
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

#[cfg(test)]
mod tests {
    use super::*;
    use indentify_contact::{ContactKind, Kinematics, Punch};
    use indentify_mesh::CylinderMesher;

    fn model() -> Model {
        let mesh = CylinderMesher {
            radius: 2.0,
            height: 3.0,
            nr: 3,
            nz: 3,
            grading_r: 1.2,
            grading_z: 1.4,
        }
        .build()
        .unwrap();
        Model::with_contact(mesh, Punch::Sphere { radius: 1.0 }, ContactKind::Normal)
            .unwrap()
            .with_kinematics(Kinematics::Finite)
            .unwrap()
    }

    /// A deterministic field of order `scale`.
    fn field(n: usize, scale: f64, seed: usize) -> Vec<f64> {
        (0..n)
            .map(|k| scale * ((((k + seed) * 7919 + 13) % 101) as f64 / 50.0 - 1.0))
            .collect()
    }

    /// The compact `G = P L(F)` gives the force `sum w G^T v` and the strains `G du` of
    /// `B_L` and `P` (to round-off: 1e-14 of the largest entry), at a large deformation
    /// (displacement gradients of order 0.1), with the same element tangents.
    #[test]
    fn compact_operator_equals_b_l_and_p() {
        let m = model();
        let (nd, nq) = (m.disc.n_dofs(), m.disc.n_qp());
        let u = field(nd, 0.02, 1);
        let t: Vec<Vec4> = (0..nq)
            .map(|q| Vec4(std::array::from_fn(|i| field(4, 300.0, 4 * q + i)[i])))
            .collect();
        let a = vec![Mat4::one_one() * 1000.0 + Mat4::IDENTITY * 1400.0; nq];
        let (mut full, mut compact) = (FiniteStep::new(&m), FiniteStep::new(&m));
        compact.set_compact(true);
        full.prepare(&m, &u, &t, &a).unwrap();
        compact.prepare(&m, &u, &t, &a).unwrap();
        assert_eq!(full.ke, compact.ke, "the element tangents differ");
        let v: Vec<Vec4> = (0..nq)
            .map(|q| Vec4(std::array::from_fn(|i| field(4, 50.0, 3 * q + i)[i])))
            .collect();
        let (mut f0, mut f1) = (vec![0.0; nd], vec![0.0; nd]);
        full.force(&m, &v, &mut f0);
        compact.force(&m, &v, &mut f1);
        let scale = f0.iter().fold(0.0f64, |s, x| s.max(x.abs()));
        assert!(scale > 0.0);
        for (x, y) in f0.iter().zip(&f1) {
            assert!((x - y).abs() <= 1e-14 * scale, "force {x} vs {y}");
        }
        let du = field(nd, 1e-3, 5);
        let (mut e0, mut e1) = (vec![[0.0; 4]; nq], vec![[0.0; 4]; nq]);
        full.strains(&m, &du, &mut e0);
        compact.strains(&m, &du, &mut e1);
        let scale = e0.iter().flatten().fold(0.0f64, |s, x| s.max(x.abs()));
        assert!(scale > 0.0);
        let mut differ = false;
        for (x, y) in e0.iter().flatten().zip(e1.iter().flatten()) {
            assert!((x - y).abs() <= 1e-14 * scale, "strain {x} vs {y}");
            differ |= x != y;
        }
        // another order of the products: some bits differ, so both forms ran
        assert!(differ || f0 != f1, "the compact form gave the same bits");
    }
}
