//! Fixed sparsity pattern (lower triangle, CSC, over equations) built once from the mesh,
//! refilled by [`Pattern::assemble_b_c_b`] and modified for Dirichlet constraints by
//! [`Pattern::constrain`] without changing the structure.

use indentify_laws::Mat4;

use crate::dofs::{DofMap, NO_EQ};
use crate::geometry::{Discretization, QP_PER_ELEMENT};

const NONE: u32 = u32::MAX;

/// Lower-triangular CSC structure of the global stiffness over equations, and the
/// scatter map from element entries to value positions.
#[derive(Clone, Debug)]
pub struct Pattern {
    /// Number of equations.
    pub n: usize,
    /// Column pointers (length n+1).
    pub col_ptr: Vec<usize>,
    /// Row indices, sorted within each column, all `>= column`.
    pub row_idx: Vec<usize>,
    /// Position of the diagonal entry of each column.
    pub diag: Vec<usize>,
    /// For element `e`, entry `(a, b)` of its 16x16 matrix goes to `scatter[256 e + 16 a + b]`
    /// (or nowhere, `u32::MAX`: an eliminated dof or the upper triangle).
    scatter: Vec<u32>,
}

impl Pattern {
    /// Builds the structure from the element connectivity and dof map.
    pub fn new(disc: &Discretization, dofs: &DofMap) -> Pattern {
        let n = dofs.n_eq;
        let ne = disc.elements.len();
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        for e in 0..ne {
            let eqs = disc.element_dofs(e).map(|d| dofs.eq[d]);
            for &i in &eqs {
                for &j in &eqs {
                    if i != NO_EQ && j != NO_EQ && i >= j {
                        cols[j as usize].push(i as usize);
                    }
                }
            }
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        let mut diag = Vec::with_capacity(n);
        col_ptr.push(0);
        for (j, c) in cols.iter_mut().enumerate() {
            c.sort_unstable();
            c.dedup();
            diag.push(row_idx.len());
            debug_assert_eq!(c.first(), Some(&j));
            row_idx.extend_from_slice(c);
            col_ptr.push(row_idx.len());
        }
        let mut scatter = vec![NONE; 256 * ne];
        for e in 0..ne {
            let eqs = disc.element_dofs(e).map(|d| dofs.eq[d]);
            for a in 0..16 {
                for b in 0..16 {
                    let (i, j) = (eqs[a], eqs[b]);
                    if i != NO_EQ && j != NO_EQ && i >= j {
                        let (i, j) = (i as usize, j as usize);
                        let col = &row_idx[col_ptr[j]..col_ptr[j + 1]];
                        let pos = col_ptr[j] + col.binary_search(&i).expect("entry in pattern");
                        scatter[256 * e + 16 * a + b] = pos as u32;
                    }
                }
            }
        }
        Pattern {
            n,
            col_ptr,
            row_idx,
            diag,
            scatter,
        }
    }

    /// Number of stored (lower-triangle) entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Assembles `K = sum_g w_g B_g^T C_g B_g` into `values` (overwritten), with one
    /// tangent `C_g` per Gauss point.
    pub fn assemble_b_c_b(&self, disc: &Discretization, c: &[Mat4], values: &mut [f64]) {
        self.assemble_with(disc, |q| &c[q], values);
    }

    /// As [`Pattern::assemble_b_c_b`] with the same tangent at every Gauss point.
    pub fn assemble_b_c_b_uniform(&self, disc: &Discretization, c: &Mat4, values: &mut [f64]) {
        self.assemble_with(disc, |_| c, values);
    }

    fn assemble_with<'a>(
        &self,
        disc: &Discretization,
        c: impl Fn(usize) -> &'a Mat4,
        values: &mut [f64],
    ) {
        values.fill(0.0);
        for e in 0..disc.elements.len() {
            let ke = element_matrix(disc, e, &c);
            self.scatter_add(e, &ke, values);
        }
    }

    /// As [`Pattern::assemble_b_c_b`], recomputing only the element matrices whose nine
    /// Gauss-point tangents differ from those `cache` formed them with (in a viscoplastic
    /// step most of the body stays elastic and keeps its tangent). The result is the
    /// same, bit for bit, as a fresh assembly: every element matrix is formed by the same
    /// code from the same tangents and summed in the same order.
    pub fn assemble_b_c_b_cached(
        &self,
        disc: &Discretization,
        c: &[Mat4],
        cache: &mut ElementCache,
        values: &mut [f64],
    ) {
        let ne = disc.elements.len();
        if cache.ke.len() != ne || cache.tangents.len() != c.len() {
            cache.ke = vec![[[0.0; 16]; 16]; ne];
            cache.tangents = vec![Mat4([[f64::NAN; 4]; 4]); c.len()];
        }
        values.fill(0.0);
        cache.recomputed = 0;
        for e in 0..ne {
            let qs = QP_PER_ELEMENT * e..QP_PER_ELEMENT * (e + 1);
            if c[qs.clone()] != cache.tangents[qs.clone()] {
                cache.ke[e] = element_matrix(disc, e, |q| &c[q]);
                cache.tangents[qs.clone()].copy_from_slice(&c[qs]);
                cache.recomputed += 1;
            }
            self.scatter_add(e, &cache.ke[e], values);
        }
    }

    /// Adds the lower triangle (`a >= b`) of element `e`'s matrix at its pattern positions.
    #[inline]
    fn scatter_add(&self, e: usize, ke: &[[f64; 16]; 16], values: &mut [f64]) {
        let map = &self.scatter[256 * e..256 * (e + 1)];
        for a in 0..16 {
            for b in 0..16 {
                let pos = map[16 * a + b];
                if pos != NONE {
                    // ke holds the lower triangle a >= b; use symmetry otherwise.
                    values[pos as usize] += if a >= b { ke[a][b] } else { ke[b][a] };
                }
            }
        }
    }

    /// `y += K x` for the symmetric matrix stored as its lower triangle in `values`.
    pub fn sym_mul_add(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        for j in 0..self.n {
            let xj = x[j];
            // the diagonal is each column's first entry (rows sorted, all >= the column)
            let (d, end) = (self.diag[j], self.col_ptr[j + 1]);
            let mut acc = values[d] * xj;
            for (&i, &v) in self.row_idx[d + 1..end].iter().zip(&values[d + 1..end]) {
                y[i] += v * xj;
                acc += v * x[i];
            }
            y[j] += acc;
        }
    }

    /// Copies `src` into `dst` with the rows and columns of the constrained equations
    /// replaced by the identity scaled by the original diagonal (kept for conditioning).
    /// Returns nothing; the constrained equation `k` then reads `K_kk x_k = K_kk xbar_k`.
    pub fn constrain(&self, src: &[f64], constrained: &[bool], dst: &mut [f64]) {
        dst.copy_from_slice(src);
        for j in 0..self.n {
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[p];
                if (constrained[i] || constrained[j]) && i != j {
                    dst[p] = 0.0;
                }
            }
        }
    }
}

/// Element matrices of the last cached assembly and the Gauss-point tangents they were
/// formed with ([`Pattern::assemble_b_c_b_cached`]).
#[derive(Clone, Debug, Default)]
pub struct ElementCache {
    tangents: Vec<Mat4>,
    ke: Vec<[[f64; 16]; 16]>,
    /// Element matrices recomputed by the last assembly.
    pub recomputed: usize,
}

/// `k_e = sum_g w_g B_g^T C_g B_g` of element `e`, lower triangle (`a >= b`) filled.
#[inline]
fn element_matrix<'a>(
    disc: &Discretization,
    e: usize,
    c: impl Fn(usize) -> &'a Mat4,
) -> [[f64; 16]; 16] {
    let mut ke = [[0.0; 16]; 16];
    for g in 0..QP_PER_ELEMENT {
        let q = QP_PER_ELEMENT * e + g;
        let qp = &disc.qp[q];
        let cm = &(c(q).0);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        // cb = w C B (4 x 16), using the sparsity of B's columns:
        // u_r of node b -> [dr, 0, nr, dz/sqrt2], u_z -> [0, dz, 0, dr/sqrt2]
        let mut cb = [[0.0; 16]; 4];
        for (b, [dr, dz, nr]) in qp.dn.iter().enumerate() {
            let (br0, br2, br3) = (dr * qp.w, nr * qp.w, dz * h * qp.w);
            let (bz1, bz3) = (dz * qp.w, dr * h * qp.w);
            for i in 0..4 {
                let row = &cm[i];
                cb[i][2 * b] = row[0] * br0 + row[2] * br2 + row[3] * br3;
                cb[i][2 * b + 1] = row[1] * bz1 + row[3] * bz3;
            }
        }
        // ke += B^T cb, lower triangle only
        for (a, [dr, dz, nr]) in qp.dn.iter().enumerate() {
            let (ar0, ar2, ar3) = (*dr, *nr, dz * h);
            let (az1, az3) = (*dz, dr * h);
            let ra = 2 * a;
            for k in 0..=ra {
                ke[ra][k] += ar0 * cb[0][k] + ar2 * cb[2][k] + ar3 * cb[3][k];
            }
            for k in 0..=ra + 1 {
                ke[ra + 1][k] += az1 * cb[1][k] + az3 * cb[3][k];
            }
        }
    }
    ke
}

#[cfg(test)]
mod tests {
    use super::*;
    use indentify_laws::elastic::isotropic_stiffness;
    use indentify_mesh::CylinderMesher;

    #[test]
    fn rigid_translation_along_z_is_in_the_kernel() {
        let m = CylinderMesher {
            radius: 1.0,
            height: 1.0,
            nr: 3,
            nz: 2,
            grading_r: 1.2,
            grading_z: 1.0,
        }
        .build()
        .unwrap();
        let disc = Discretization::new(&m);
        let dofs = DofMap::new(disc.n_dofs(), &[]);
        let pat = Pattern::new(&disc, &dofs);
        let mut k = vec![0.0; pat.nnz()];
        pat.assemble_b_c_b_uniform(&disc, &isotropic_stiffness(100.0, 0.3), &mut k);
        let x: Vec<f64> = (0..dofs.n_eq).map(|d| (d % 2) as f64).collect();
        let mut y = vec![0.0; dofs.n_eq];
        pat.sym_mul_add(&k, &x, &mut y);
        assert!(
            y.iter().all(|v| v.abs() < 1e-10),
            "{:?}",
            y.iter().cloned().fold(0.0, f64::max)
        );
        // and the energy of a radial expansion u_r = r is positive
        let x: Vec<f64> = (0..dofs.n_eq)
            .map(|d| if d % 2 == 0 { m.nodes[d / 2][0] } else { 0.0 })
            .collect();
        let mut y = vec![0.0; dofs.n_eq];
        pat.sym_mul_add(&k, &x, &mut y);
        assert!(x.iter().zip(&y).map(|(a, b)| a * b).sum::<f64>() > 0.0);
    }

    /// The cached assembly equals a fresh one bit for bit and recomputes exactly the
    /// elements whose tangents changed.
    #[test]
    fn cached_assembly_recomputes_only_changed_elements() {
        let m = CylinderMesher {
            radius: 1.0,
            height: 1.0,
            nr: 4,
            nz: 3,
            grading_r: 1.2,
            grading_z: 1.1,
        }
        .build()
        .unwrap();
        let disc = Discretization::new(&m);
        let dofs = DofMap::cylinder(&m);
        let pat = Pattern::new(&disc, &dofs);
        let mut tangents = vec![isotropic_stiffness(100.0, 0.3); disc.n_qp()];
        let mut cache = ElementCache::default();
        let (mut fresh, mut cached) = (vec![0.0; pat.nnz()], vec![0.0; pat.nnz()]);
        pat.assemble_b_c_b_cached(&disc, &tangents, &mut cache, &mut cached);
        assert_eq!(cache.recomputed, 12);
        pat.assemble_b_c_b_cached(&disc, &tangents, &mut cache, &mut cached);
        assert_eq!(cache.recomputed, 0);
        // soften one Gauss point of element 5 and every point of element 9
        tangents[9 * 5 + 4] = isotropic_stiffness(50.0, 0.3);
        for t in &mut tangents[81..90] {
            *t = isotropic_stiffness(70.0, 0.25);
        }
        pat.assemble_b_c_b_cached(&disc, &tangents, &mut cache, &mut cached);
        assert_eq!(cache.recomputed, 2);
        pat.assemble_b_c_b(&disc, &tangents, &mut fresh);
        assert_eq!(fresh, cached);
    }
}
