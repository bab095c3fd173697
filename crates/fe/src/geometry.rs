//! Mapped Q8 elements: the axisymmetric B operator in Mandel form and full-circle weights,
//! precomputed once for every Gauss point of a mesh.

use indentify_laws::Vec4;
use indentify_laws::mandel::SQRT2;
use indentify_mesh::{Mesh, q8};

/// Number of Gauss points per element (3x3 rule).
pub const QP_PER_ELEMENT: usize = 9;

/// Geometry of one Gauss point: position, full-circle weight and B operator (kept
/// compactly: 28 numbers instead of B's 64, so that a pass over all points streams a
/// third of the memory; [`QuadPoint::b`] expands it).
///
/// `eps = B u_e` with `u_e = [u_r0, u_z0, u_r1, u_z1, ..., u_z7]` and strain rows
/// `[rr, zz, tt, sqrt2*rz]`: `eps_rr = dN/dr u_r`, `eps_zz = dN/dz u_z`,
/// `eps_tt = N/r u_r` (hoop), `sqrt2 eps_rz = (dN/dz u_r + dN/dr u_z)/sqrt2`.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadPoint {
    /// Radius of the point (mm).
    pub r: f64,
    /// Height of the point (mm).
    pub z: f64,
    /// Weight `w = 2 pi r detJ w_gauss` (mm^3): integrals are over the full circle.
    pub w: f64,
    /// The B operator compactly, per node a: `[dN_a/dr, dN_a/dz, N_a/r]` (1/mm).
    pub dn: [[f64; 3]; 8],
}

impl QuadPoint {
    /// The B operator, 4 rows x 16 columns (1/mm): rows `[rr, zz, tt, sqrt2*rz]`.
    pub fn b(&self) -> [[f64; 16]; 4] {
        let mut b = [[0.0; 16]; 4];
        for (a, [dr, dz, nr]) in self.dn.iter().enumerate() {
            b[0][2 * a] = *dr;
            b[1][2 * a + 1] = *dz;
            b[2][2 * a] = *nr;
            b[3][2 * a] = dz / SQRT2;
            b[3][2 * a + 1] = dr / SQRT2;
        }
        b
    }

    /// `B u_e` for the element's 16 displacement components.
    #[inline]
    pub fn strain(&self, ue: &[f64; 16]) -> [f64; 4] {
        let (mut rr, mut zz, mut tt, mut rz) = (0.0, 0.0, 0.0, 0.0);
        for (a, [dr, dz, nr]) in self.dn.iter().enumerate() {
            let (ur, uz) = (ue[2 * a], ue[2 * a + 1]);
            rr += dr * ur;
            zz += dz * uz;
            tt += nr * ur;
            rz += dz * ur + dr * uz;
        }
        [rr, zz, tt, rz / SQRT2]
    }

    /// Adds `scale * B^T s` to the element vector `fe`.
    #[inline]
    pub fn add_bt(&self, s: &[f64; 4], scale: f64, fe: &mut [f64; 16]) {
        let (s0, s1, s2, s3) = (
            s[0] * scale,
            s[1] * scale,
            s[2] * scale,
            s[3] * scale / SQRT2,
        );
        for (a, [dr, dz, nr]) in self.dn.iter().enumerate() {
            fe[2 * a] += dr * s0 + nr * s2 + dz * s3;
            fe[2 * a + 1] += dz * s1 + dr * s3;
        }
    }
}

/// Gauss-point geometry of a whole mesh, element-major (`QP_PER_ELEMENT` per element).
#[derive(Clone, Debug)]
pub struct Discretization {
    /// All Gauss points; those of element `e` are `qp[9e..9e+9]`.
    pub qp: Vec<QuadPoint>,
    /// Connectivity copied from the mesh.
    pub elements: Vec<[usize; 8]>,
    /// Number of mesh nodes.
    pub n_nodes: usize,
}

impl Discretization {
    /// Precomputes positions, weights and B operators of every Gauss point.
    ///
    /// The mesh is assumed to have passed [`Mesh::check_quality`] (positive Jacobians).
    pub fn new(mesh: &Mesh) -> Discretization {
        let rule = q8::gauss3x3();
        let mut qp = Vec::with_capacity(QP_PER_ELEMENT * mesh.elements.len());
        for e in 0..mesh.elements.len() {
            let x = mesh.element_coords(e);
            for ([xi, eta], wg) in &rule {
                let n = q8::shape(*xi, *eta);
                let d = q8::shape_gradients(*xi, *eta);
                let (j, det) = q8::jacobian(&x, *xi, *eta);
                // inverse Jacobian: [dxi/dr, dxi/dz; deta/dr, deta/dz]
                let inv = [
                    [j[1][1] / det, -j[0][1] / det],
                    [-j[1][0] / det, j[0][0] / det],
                ];
                let (mut r, mut z) = (0.0, 0.0);
                for a in 0..8 {
                    r += n[a] * x[a][0];
                    z += n[a] * x[a][1];
                }
                let mut dn = [[0.0; 3]; 8];
                for a in 0..8 {
                    let dr = d[a][0] * inv[0][0] + d[a][1] * inv[1][0];
                    let dz = d[a][0] * inv[0][1] + d[a][1] * inv[1][1];
                    dn[a] = [dr, dz, n[a] / r];
                }
                qp.push(QuadPoint {
                    dn,
                    r,
                    z,
                    w: 2.0 * std::f64::consts::PI * r * det * wg,
                });
            }
        }
        Discretization {
            qp,
            elements: mesh.elements.clone(),
            n_nodes: mesh.nodes.len(),
        }
    }

    /// Number of Gauss points.
    pub fn n_qp(&self) -> usize {
        self.qp.len()
    }

    /// Number of displacement dofs (2 per node: `2n` = u_r, `2n+1` = u_z).
    pub fn n_dofs(&self) -> usize {
        2 * self.n_nodes
    }

    /// Global dof indices of element `e` in local order.
    #[inline]
    pub fn element_dofs(&self, e: usize) -> [usize; 16] {
        let conn = &self.elements[e];
        std::array::from_fn(|k| 2 * conn[k / 2] + k % 2)
    }

    /// Gathers the element displacement vector from the global one.
    #[inline]
    pub fn gather(&self, e: usize, u: &[f64]) -> [f64; 16] {
        self.element_dofs(e).map(|d| u[d])
    }

    /// Strain `B u` at every Gauss point into `eps` (length `n_qp`).
    pub fn strains(&self, u: &[f64], eps: &mut [[f64; 4]]) {
        for e in 0..self.elements.len() {
            let ue = self.gather(e, u);
            for g in 0..QP_PER_ELEMENT {
                let q = QP_PER_ELEMENT * e + g;
                eps[q] = self.qp[q].strain(&ue);
            }
        }
    }

    /// Internal force `f = sum_g w_g B_g^T s_g` over all dofs (N, full circle), overwriting `f`.
    pub fn internal_force(&self, s: &[Vec4], f: &mut [f64]) {
        f.fill(0.0);
        for e in 0..self.elements.len() {
            let mut fe = [0.0; 16];
            for g in 0..QP_PER_ELEMENT {
                let q = QP_PER_ELEMENT * e + g;
                self.qp[q].add_bt(&s[q].0, self.qp[q].w, &mut fe);
            }
            for (d, v) in self.element_dofs(e).iter().zip(fe) {
                f[*d] += v;
            }
        }
    }

    /// Volume of the body (mm^3), `sum w_g`: a check of the full-circle weights.
    pub fn volume(&self) -> f64 {
        self.qp.iter().map(|q| q.w).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use indentify_mesh::CylinderMesher;

    #[test]
    fn compact_kernels_match_the_dense_b_operator() {
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
        let d = Discretization::new(&m);
        let ue: [f64; 16] = std::array::from_fn(|k| ((k * 7 + 3) % 11) as f64 * 0.1 - 0.4);
        let s = [1.5, -0.7, 0.3, 2.2];
        for q in &d.qp {
            let b = q.b();
            let dense: Vec<f64> = b
                .iter()
                .map(|row| row.iter().zip(&ue).map(|(b, u)| b * u).sum())
                .collect();
            let compact = q.strain(&ue);
            let mut fe = [0.0; 16];
            q.add_bt(&s, 2.0, &mut fe);
            for i in 0..4 {
                assert!((dense[i] - compact[i]).abs() < 1e-13);
            }
            for k in 0..16 {
                let dense_bt: f64 = (0..4).map(|i| b[i][k] * s[i] * 2.0).sum();
                assert!((dense_bt - fe[k]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn weights_integrate_the_cylinder_volume() {
        let m = CylinderMesher {
            radius: 2.0,
            height: 3.0,
            nr: 4,
            nz: 5,
            grading_r: 1.2,
            grading_z: 1.4,
        }
        .build()
        .unwrap();
        let d = Discretization::new(&m);
        let exact = std::f64::consts::PI * 4.0 * 3.0;
        assert!((d.volume() - exact).abs() < 1e-12 * exact);
    }
}
