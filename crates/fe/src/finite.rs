//! Total-Lagrangian axisymmetric kinematics of the Q8 element for finite strain: the
//! deformation gradient with its hoop stretch, the right Cauchy-Green tensor, the
//! Green-Lagrange variation operator `B_L(u)`, and the element's internal force and
//! consistent tangent (material and geometric parts) from the second Piola-Kirchhoff
//! stress and its derivative.
//!
//! With `X = (R, Z)` the reference position, `u = (u_r, u_z)` the displacement:
//! `F = [[1 + u_r,R, u_r,Z, 0], [u_z,R, 1 + u_z,Z, 0], [0, 0, 1 + u_r/R]]` (rows r, z, t)
//! and `C = F^T F` in Mandel form `[RR, ZZ, tt, sqrt2*RZ]`. The variation of
//! `E_GL = (C - 1)/2` is `dE_GL = B_L du_e` with, per node `a` (`[dN/dR, dN/dZ, N/R]`):
//!
//! - row RR: `(F_rr dN/dR, F_zr dN/dR)`; row ZZ: `(F_rz dN/dZ, F_zz dN/dZ)`;
//! - row tt: `(F_tt N/R, 0)`;
//! - row sqrt2*RZ: `((F_rr dN/dZ + F_rz dN/dR)/sqrt2, (F_zr dN/dZ + F_zz dN/dR)/sqrt2)`.
//!
//! At `u = 0`, `B_L` is the small-strain `B` ([`QuadPoint::b`]). The internal force is
//! `sum w0 B_L^T S` (the reference full-circle weights of [`QuadPoint`]); its derivative
//! `sum w0 (B_L^T D B_L + G)` with `D = dS/dE_GL` and the geometric part
//! `G_(ai)(bj) = delta_ij (S_RR N_a,R N_b,R + S_ZZ N_a,Z N_b,Z + S_RZ (N_a,R N_b,Z +
//! N_a,Z N_b,R)) + delta_ir delta_jr S_tt N_a N_b / R^2`.

use indentify_laws::mandel::SQRT2;
use indentify_laws::{Mat4, Vec4};

use crate::geometry::QuadPoint;

/// The deformation gradient at one Gauss point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deformation {
    /// In-plane block `[[F_rR, F_rZ], [F_zR, F_zZ]]`.
    pub f: [[f64; 2]; 2],
    /// Hoop stretch `F_tt = 1 + u_r/R`.
    pub ftt: f64,
    /// The displacement gradient `F - 1`, in-plane and hoop, summed without the 1 (so that
    /// small strains keep their relative precision in [`Deformation::c_minus_one`]).
    pub h: [[f64; 2]; 2],
    /// `u_r/R`.
    pub htt: f64,
}

impl Deformation {
    /// `F` at Gauss point `qp` for the element displacement `ue` (total, from the
    /// reference configuration).
    #[inline]
    pub fn new(qp: &QuadPoint, ue: &[f64; 16]) -> Deformation {
        let (mut hrr, mut hrz, mut hzr, mut hzz, mut htt) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (a, [dr, dz, nr]) in qp.dn.iter().enumerate() {
            let (ur, uz) = (ue[2 * a], ue[2 * a + 1]);
            hrr += dr * ur;
            hrz += dz * ur;
            hzr += dr * uz;
            hzz += dz * uz;
            htt += nr * ur;
        }
        Deformation::from_gradient([[hrr, hrz], [hzr, hzz]], htt)
    }

    /// The deformation of displacement gradient `h` (in-plane) and `htt = u_r/R`.
    pub fn from_gradient(h: [[f64; 2]; 2], htt: f64) -> Deformation {
        Deformation {
            f: [[1.0 + h[0][0], h[0][1]], [h[1][0], 1.0 + h[1][1]]],
            ftt: 1.0 + htt,
            h,
            htt,
        }
    }

    /// `C - 1` (Mandel), from the displacement gradient: `H + H^T + H^T H`.
    #[inline]
    pub fn c_minus_one(&self) -> Vec4 {
        let [[a, b], [c, d]] = self.h;
        Vec4([
            2.0 * a + a * a + c * c,
            2.0 * d + b * b + d * d,
            self.htt * (2.0 + self.htt),
            SQRT2 * (b + c + a * b + c * d),
        ])
    }

    /// `det F = F_tt (F_rR F_zZ - F_rZ F_zR)`, the volume ratio.
    #[inline]
    pub fn det(&self) -> f64 {
        self.ftt * (self.f[0][0] * self.f[1][1] - self.f[0][1] * self.f[1][0])
    }

    /// The right Cauchy-Green tensor `C = F^T F` (Mandel `[RR, ZZ, tt, sqrt2*RZ]`).
    #[inline]
    pub fn right_cauchy_green(&self) -> Vec4 {
        let [[a, b], [c, d]] = self.f;
        Vec4([
            a * a + c * c,
            b * b + d * d,
            self.ftt * self.ftt,
            SQRT2 * (a * b + c * d),
        ])
    }

    /// The Cauchy stress `sigma = F S F^T / det F` (Mandel `[rr, zz, tt, sqrt2*rz]`, MPa)
    /// of the second Piola-Kirchhoff stress `s`.
    pub fn cauchy(&self, s: &Vec4) -> Vec4 {
        let [[a, b], [c, d]] = self.f;
        let srz = s.0[3] / SQRT2;
        let sm = [[s.0[0], srz], [srz, s.0[1]]];
        let f = [[a, b], [c, d]];
        let fs: [[f64; 2]; 2] = std::array::from_fn(|i| {
            std::array::from_fn(|j| f[i][0] * sm[0][j] + f[i][1] * sm[1][j])
        });
        let out: [[f64; 2]; 2] = std::array::from_fn(|i| {
            std::array::from_fn(|j| fs[i][0] * f[j][0] + fs[i][1] * f[j][1])
        });
        let j = self.det();
        Vec4([
            out[0][0] / j,
            out[1][1] / j,
            self.ftt * self.ftt * s.0[2] / j,
            SQRT2 * out[0][1] / j,
        ])
    }

    /// The Green-Lagrange variation operator `B_L` compactly, per node `a`: the rows RR,
    /// ZZ, tt, sqrt2*RZ of its `u_r` and `u_z` columns.
    #[inline]
    pub fn b_l(&self, qp: &QuadPoint) -> [[[f64; 2]; 4]; 8] {
        let [[frr, frz], [fzr, fzz]] = self.f;
        std::array::from_fn(|a| {
            let [dr, dz, nr] = qp.dn[a];
            [
                [frr * dr, fzr * dr],
                [frz * dz, fzz * dz],
                [self.ftt * nr, 0.0],
                [(frr * dz + frz * dr) / SQRT2, (fzr * dz + fzz * dr) / SQRT2],
            ]
        })
    }

    /// Adds `scale * B_L^T s` to the element vector `fe`.
    #[inline]
    pub fn add_bt(b: &[[[f64; 2]; 4]; 8], s: &Vec4, scale: f64, fe: &mut [f64; 16]) {
        for (a, ba) in b.iter().enumerate() {
            for i in 0..2 {
                fe[2 * a + i] += scale
                    * (ba[0][i] * s.0[0]
                        + ba[1][i] * s.0[1]
                        + ba[2][i] * s.0[2]
                        + ba[3][i] * s.0[3]);
            }
        }
    }

    /// Adds `w (B_L^T D B_L + G(S))` to the lower triangle (`row >= column`) of the element
    /// matrix `ke`: `D = dS/dE_GL`, `s` the second Piola-Kirchhoff stress.
    ///
    /// Both parts go through the gradient of the displacement variation,
    /// `gamma = [du_r,R, du_r,Z, du_z,R, du_z,Z, du_r/R]` (per node `a`: `[dN/dR, dN/dZ, 0, 0,
    /// N/R]` for `u_r`, `[0, 0, dN/dR, dN/dZ, 0]` for `u_z`): `B_L = L(F) gamma` with
    ///
    /// ```text
    /// L = [[F_rR, 0, F_zR, 0, 0], [0, F_rZ, 0, F_zZ, 0], [0, 0, 0, 0, F_tt],
    ///      [F_rZ, F_rR, F_zZ, F_zR, 0]/sqrt2 (last row)]
    /// ```
    ///
    /// and the geometric part is `gamma^T Sigma gamma` with `Sigma = diag(S2, S2, S_tt)`
    /// (`S2` the in-plane block of `S`). So the tangent is `gamma^T N gamma` with the 5 x 5
    /// `N = w (L^T D L + Sigma)`, formed once per point, and each node pair's 2 x 2 block
    /// costs 10 products.
    #[inline]
    pub fn add_tangent(
        &self,
        qp: &QuadPoint,
        d: &Mat4,
        s: &Vec4,
        w: f64,
        ke: &mut [[f64; 16]; 16],
    ) {
        let [[frr, frz], [fzr, fzz]] = self.f;
        let r2 = std::f64::consts::FRAC_1_SQRT_2;
        let d = &d.0;
        // D L (4 x 5), by the columns of L (at most two entries each)
        let mut dl = [[0.0; 5]; 4];
        for (row, di) in dl.iter_mut().zip(d) {
            *row = [
                di[0] * frr + di[3] * (frz * r2),
                di[1] * frz + di[3] * (frr * r2),
                di[0] * fzr + di[3] * (fzz * r2),
                di[1] * fzz + di[3] * (fzr * r2),
                di[2] * self.ftt,
            ];
        }
        // N = w (L^T (D L) + Sigma), row by row (rows of L^T = columns of L)
        let (s0, s1, s2, srz) = (s.0[0], s.0[1], s.0[2], s.0[3] * r2);
        let lt = |a: f64, i: usize, b: f64, j: usize| -> [f64; 5] {
            [
                a * dl[i][0] + b * dl[j][0],
                a * dl[i][1] + b * dl[j][1],
                a * dl[i][2] + b * dl[j][2],
                a * dl[i][3] + b * dl[j][3],
                a * dl[i][4] + b * dl[j][4],
            ]
        };
        let mut n = [
            lt(frr, 0, frz * r2, 3),
            lt(frz, 1, frr * r2, 3),
            lt(fzr, 0, fzz * r2, 3),
            lt(fzz, 1, fzr * r2, 3),
            lt(self.ftt, 2, 0.0, 2),
        ];
        n[0][0] += s0;
        n[0][1] += srz;
        n[1][0] += srz;
        n[1][1] += s1;
        n[2][2] += s0;
        n[2][3] += srz;
        n[3][2] += srz;
        n[3][3] += s1;
        n[4][4] += s2;
        for row in &mut n {
            for v in row {
                *v *= w;
            }
        }
        // per node b, N gamma of its u_r column and of its u_z column, interleaved:
        // v[b][c] = [(N gamma_r)_c, (N gamma_z)_c]
        let mut v = [[[0.0; 2]; 5]; 8];
        for (vb, &[dr, dz, nr]) in v.iter_mut().zip(&qp.dn) {
            for (vc, nc) in vb.iter_mut().zip(&n) {
                *vc = [
                    nc[0] * dr + nc[1] * dz + nc[4] * nr,
                    nc[2] * dr + nc[3] * dz,
                ];
            }
        }
        for a in 0..8 {
            let [dr, dz, nr] = qp.dn[a];
            let (row_r, row_z) = ke.split_at_mut(2 * a + 1);
            let (row_r, row_z) = (&mut row_r[2 * a], &mut row_z[0]);
            for (b, vb) in v.iter().enumerate().take(a) {
                for i in 0..2 {
                    row_r[2 * b + i] += dr * vb[0][i] + dz * vb[1][i] + nr * vb[4][i];
                    row_z[2 * b + i] += dr * vb[2][i] + dz * vb[3][i];
                }
            }
            let va = &v[a];
            row_r[2 * a] += dr * va[0][0] + dz * va[1][0] + nr * va[4][0];
            row_z[2 * a] += dr * va[2][0] + dz * va[3][0];
            row_z[2 * a + 1] += dr * va[2][1] + dz * va[3][1];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Discretization;
    use indentify_laws::LogStrain;
    use indentify_mesh::CylinderMesher;

    fn disc() -> Discretization {
        let m = CylinderMesher {
            radius: 2.0,
            height: 3.0,
            nr: 2,
            nz: 2,
            grading_r: 1.2,
            grading_z: 1.4,
        }
        .build()
        .unwrap();
        Discretization::new(&m)
    }

    fn displacement(scale: f64) -> [f64; 16] {
        std::array::from_fn(|k| scale * (((k * 7 + 3) % 11) as f64 * 0.1 - 0.4))
    }

    /// A hyperelastic Hencky material: `T = lambda tr(E) 1 + 2 mu E`, `S = P T`.
    fn element_force(disc: &Discretization, e: usize, ue: &[f64; 16]) -> [f64; 16] {
        let a = hencky();
        let mut fe = [0.0; 16];
        for q in &disc.qp[9 * e..9 * e + 9] {
            let def = Deformation::new(q, ue);
            let ls = LogStrain::from_difference(&def.c_minus_one()).unwrap();
            let t = a.mul_vec(&ls.e);
            Deformation::add_bt(&def.b_l(q), &ls.pk2(&t), q.w, &mut fe);
        }
        fe
    }

    /// The tangent by the direct form `B_L^T D B_L + G`, entry by entry (reference for
    /// [`Deformation::add_tangent`]).
    fn add_tangent_direct(
        qp: &QuadPoint,
        b: &[[[f64; 2]; 4]; 8],
        d: &Mat4,
        s: &Vec4,
        w: f64,
        ke: &mut [[f64; 16]; 16],
    ) {
        // DB: 4 x 16
        let mut db = [[0.0; 16]; 4];
        for (a, ba) in b.iter().enumerate() {
            for i in 0..2 {
                for (row, drow) in db.iter_mut().zip(&d.0) {
                    row[2 * a + i] = drow[0] * ba[0][i]
                        + drow[1] * ba[1][i]
                        + drow[2] * ba[2][i]
                        + drow[3] * ba[3][i];
                }
            }
        }
        let srz = s.0[3] / SQRT2;
        for (p, kp) in ke.iter_mut().enumerate() {
            let (a, i) = (p / 2, p % 2);
            let bp = &b[a];
            let [dra, dza, nra] = qp.dn[a];
            for (q, v) in kp.iter_mut().enumerate().take(p + 1) {
                let mut m = bp[0][i] * db[0][q]
                    + bp[1][i] * db[1][q]
                    + bp[2][i] * db[2][q]
                    + bp[3][i] * db[3][q];
                let (bn, j) = (q / 2, q % 2);
                if i == j {
                    let [drb, dzb, nrb] = qp.dn[bn];
                    m += s.0[0] * dra * drb + s.0[1] * dza * dzb + srz * (dra * dzb + dza * drb);
                    if i == 0 {
                        m += s.0[2] * nra * nrb;
                    }
                }
                *v += w * m;
            }
        }
    }

    fn hencky() -> Mat4 {
        let (lam, mu) = (1000.0, 700.0);
        Mat4::one_one() * lam + Mat4::IDENTITY * (2.0 * mu)
    }

    #[test]
    fn small_displacements_give_the_small_strain_operator() {
        let d = disc();
        let ue = [0.0; 16];
        for q in &d.qp {
            let b = Deformation::new(q, &ue).b_l(q);
            let bs = q.b();
            for (a, ba) in b.iter().enumerate() {
                for row in 0..4 {
                    for i in 0..2 {
                        assert!((ba[row][i] - bs[row][2 * a + i]).abs() < 1e-15);
                    }
                }
            }
        }
    }

    /// The element tangent is the derivative of the element force (central differences),
    /// at a large deformation (stretches of order 0.5).
    #[test]
    fn element_tangent_matches_finite_differences() {
        let d = disc();
        let a = hencky();
        for e in 0..4 {
            let ue = displacement(0.25);
            let mut ke = [[0.0; 16]; 16];
            for q in &d.qp[9 * e..9 * e + 9] {
                let def = Deformation::new(q, &ue);
                assert!(def.det() > 0.0);
                let ls = LogStrain::from_difference(&def.c_minus_one()).unwrap();
                let t = a.mul_vec(&ls.e);
                let dm = ls.material_tangent(&a, &t);
                def.add_tangent(q, &dm, &ls.pk2(&t), q.w, &mut ke);
            }
            let scale = ke.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            for k in 0..16 {
                let h = 1e-6;
                let (mut up, mut um) = (ue, ue);
                up[k] += h;
                um[k] -= h;
                let (fp, fm) = (element_force(&d, e, &up), element_force(&d, e, &um));
                for p in 0..16 {
                    let fd = (fp[p] - fm[p]) / (2.0 * h);
                    let an = if p >= k { ke[p][k] } else { ke[k][p] };
                    assert!(
                        (fd - an).abs() < 1e-6 * scale,
                        "element {e} ({p}, {k}): fd {fd} vs {an}"
                    );
                }
            }
        }
    }

    /// The reduced form `gamma^T N gamma` of [`Deformation::add_tangent`] equals the direct
    /// `B_L^T D B_L + G` entry by entry (to round-off), for a full non-symmetric `D` and a
    /// large deformation, at every Gauss point of every element, accumulated over points.
    #[test]
    fn reduced_tangent_equals_the_direct_form() {
        let d = disc();
        let dm = Mat4(std::array::from_fn(|i| {
            std::array::from_fn(|j| 1000.0 * (1.0 + ((i * 5 + j * 3) % 7) as f64))
        }));
        let s = Vec4([120.0, -80.0, 45.0, 60.0]);
        for e in 0..4 {
            let ue = displacement(0.3);
            let (mut k0, mut k1) = ([[0.0; 16]; 16], [[0.0; 16]; 16]);
            for q in &d.qp[9 * e..9 * e + 9] {
                let def = Deformation::new(q, &ue);
                add_tangent_direct(q, &def.b_l(q), &dm, &s, q.w, &mut k0);
                def.add_tangent(q, &dm, &s, q.w, &mut k1);
            }
            let scale = k0.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            for p in 0..16 {
                for q in 0..16 {
                    let (a, b) = (k0[p][q], k1[p][q]);
                    assert!((a - b).abs() <= 1e-14 * scale, "({p}, {q}): {a} vs {b}");
                    if q > p {
                        assert_eq!(b, 0.0, "upper triangle ({p}, {q}) written");
                    }
                }
            }
        }
    }

    /// Objectivity: a rigid rotation Q of the in-plane block (about the hoop axis) leaves
    /// C, hence E, T and S, unchanged and rotates the Cauchy stress, sigma(QF) = Q sigma Q^T.
    #[test]
    fn a_rigid_rotation_rotates_the_cauchy_stress_and_keeps_the_log_stress() {
        let a = hencky();
        let def = Deformation::from_gradient([[0.3, 0.2], [-0.1, -0.2]], 0.1);
        let th: f64 = 0.7;
        let q = [[th.cos(), -th.sin()], [th.sin(), th.cos()]];
        let qf: [[f64; 2]; 2] = std::array::from_fn(|i| {
            std::array::from_fn(|j| q[i][0] * def.f[0][j] + q[i][1] * def.f[1][j])
        });
        let rot = Deformation::from_gradient(
            [[qf[0][0] - 1.0, qf[0][1]], [qf[1][0], qf[1][1] - 1.0]],
            0.1,
        );
        let (c0, c1) = (def.right_cauchy_green(), rot.right_cauchy_green());
        assert!((c0 - c1).max_abs() < 1e-14);
        assert!((def.c_minus_one() + Vec4::ONE - c0).max_abs() < 1e-15);
        let (l0, l1) = (LogStrain::new(&c0).unwrap(), LogStrain::new(&c1).unwrap());
        let (t0, t1) = (a.mul_vec(&l0.e), a.mul_vec(&l1.e));
        assert!((t0 - t1).max_abs() < 1e-11);
        let s0 = def.cauchy(&l0.pk2(&t0));
        let s1 = rot.cauchy(&l1.pk2(&t1));
        let m = [[s0.0[0], s0.0[3] / SQRT2], [s0.0[3] / SQRT2, s0.0[1]]];
        let qm: [[f64; 2]; 2] = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                (0..2)
                    .map(|k| (0..2).map(|l| q[i][k] * m[k][l] * q[j][l]).sum::<f64>())
                    .sum()
            })
        });
        let expected = Vec4([qm[0][0], qm[1][1], s0.0[2], SQRT2 * qm[0][1]]);
        assert!(
            (s1 - expected).max_abs() < 1e-10 * s0.max_abs(),
            "{s1:?} vs {expected:?}"
        );
        // the isotropic Hencky law: sigma = R T R^T / J, so sigma and T share invariants
        assert!((s0.trace() * def.det() - t0.trace()).abs() < 1e-10 * t0.max_abs());
    }
}
