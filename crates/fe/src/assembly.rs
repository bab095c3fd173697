//! Fixed sparsity pattern (lower triangle, CSC, over equations) built once from the mesh,
//! refilled by [`Pattern::assemble_b_c_b`] and modified for Dirichlet constraints by
//! [`Pattern::constrain`] without changing the structure.

use indentify_laws::Mat4;

use crate::dofs::{DofMap, NO_EQ};
use crate::geometry::{Discretization, QP_PER_ELEMENT};

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
    /// Element `e`'s lower-triangle entries `(a >= b)` kept by the pattern are
    /// `scatter[scatter_ptr[e]..scatter_ptr[e + 1]]`: (value position, `16 a + b`).
    scatter: Vec<(u32, u32)>,
    scatter_ptr: Vec<usize>,
    /// Positions of row `i`'s entries left of the diagonal (the lower triangle by rows):
    /// `row_pos[row_ptr[i]..row_ptr[i + 1]]`, in the columns `row_col[..]` alike.
    row_ptr: Vec<usize>,
    row_pos: Vec<usize>,
    row_col: Vec<usize>,
    /// `paired[j]`: columns `j` and `j + 1` hold the same rows below `j + 1` (both dofs of a
    /// node), and column `j` holds row `j + 1` (see [`Pattern::sym_mul_add`]).
    paired: Vec<bool>,
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
        // the element's entry (a, b) lands at (eq a, eq b) when that is in the lower
        // triangle, else at its mirror (eq b, eq a) with the entry (b, a): each pair of
        // distinct dofs once, read from the lower triangle a >= b of the element matrix
        let mut scatter = Vec::with_capacity(136 * ne);
        let mut scatter_ptr = Vec::with_capacity(ne + 1);
        scatter_ptr.push(0);
        for e in 0..ne {
            let eqs = disc.element_dofs(e).map(|d| dofs.eq[d]);
            for a in 0..16 {
                for b in 0..16 {
                    let (i, j) = (eqs[a], eqs[b]);
                    if i != NO_EQ && j != NO_EQ && i >= j {
                        let (i, j) = (i as usize, j as usize);
                        let col = &row_idx[col_ptr[j]..col_ptr[j + 1]];
                        let pos = col_ptr[j] + col.binary_search(&i).expect("entry in pattern");
                        let (ea, eb) = if a >= b { (a, b) } else { (b, a) };
                        scatter.push((pos as u32, (16 * ea + eb) as u32));
                    }
                }
            }
            scatter_ptr.push(scatter.len());
        }
        let mut row_ptr = vec![0usize; n + 1];
        for &i in &row_idx {
            row_ptr[i + 1] += 1;
        }
        for j in 0..n {
            // the diagonal is not left of itself
            row_ptr[j + 1] -= 1;
            row_ptr[j + 1] += row_ptr[j];
        }
        let mut fill = row_ptr.clone();
        let mut row_pos = vec![0usize; row_ptr[n]];
        let mut row_col = vec![0usize; row_ptr[n]];
        for j in 0..n {
            for (p, &i) in row_idx
                .iter()
                .enumerate()
                .take(col_ptr[j + 1])
                .skip(diag[j] + 1)
            {
                row_pos[fill[i]] = p;
                row_col[fill[i]] = j;
                fill[i] += 1;
            }
        }
        let paired = (0..n)
            .map(|j| {
                j + 1 < n && {
                    let c0 = &row_idx[diag[j]..col_ptr[j + 1]];
                    let c1 = &row_idx[diag[j + 1]..col_ptr[j + 2]];
                    c0.len() == c1.len() + 1 && c0[1] == j + 1 && c0[2..] == c1[1..]
                }
            })
            .collect();
        Pattern {
            n,
            col_ptr,
            row_idx,
            diag,
            scatter,
            scatter_ptr,
            row_ptr,
            row_pos,
            row_col,
            paired,
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
    /// Gauss-point tangents differ (bit for bit) from those `cache` formed them with (in a
    /// viscoplastic step most of the body stays elastic and keeps its tangent). The result is the
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
        cache.summed = false;
        for e in 0..ne {
            cache.refresh(disc, c, e);
            self.scatter_add(e, &cache.ke[e], values);
        }
    }

    /// As [`Pattern::assemble_b_c_b_cached`], but when `values` still hold the previous
    /// assembly with this `cache` (the caller's promise; see [`ElementCache::forget_sum`])
    /// only the changed elements are touched: `values += k_e,new - k_e,old`, with neither a
    /// zero fill nor a scatter of the unchanged elements. The result equals a fresh assembly
    /// to round-off (the first assembly after `forget_sum` bit for bit).
    pub fn assemble_b_c_b_delta(
        &self,
        disc: &Discretization,
        c: &[Mat4],
        cache: &mut ElementCache,
        values: &mut [f64],
    ) {
        let ne = disc.elements.len();
        if !cache.summed || cache.ke.len() != ne || cache.tangents.len() != c.len() {
            self.assemble_b_c_b_cached(disc, c, cache, values);
            cache.summed = true;
            return;
        }
        cache.recomputed = 0;
        for e in 0..ne {
            if let Some(old) = cache.refresh(disc, c, e) {
                let (new, old) = (cache.ke[e].as_flattened(), old.as_flattened());
                for &(pos, ab) in &self.scatter[self.scatter_ptr[e]..self.scatter_ptr[e + 1]] {
                    values[pos as usize] += new[ab as usize] - old[ab as usize];
                }
            }
        }
    }

    /// Assembles given element matrices (their lower triangles, `a >= b`) into `values`
    /// (overwritten): the finite-strain tangent, whose element matrices are not
    /// `sum w B^T C B` with a fixed `B` ([`crate::finite`]).
    pub fn assemble_elements(&self, ke: &[[[f64; 16]; 16]], values: &mut [f64]) {
        values.fill(0.0);
        for (e, k) in ke.iter().enumerate() {
            self.scatter_add(e, k, values);
        }
    }

    /// Adds the lower triangle (`a >= b`) of element `e`'s matrix at its pattern positions.
    #[inline]
    fn scatter_add(&self, e: usize, ke: &[[f64; 16]; 16], values: &mut [f64]) {
        let ke = ke.as_flattened();
        for &(pos, ab) in &self.scatter[self.scatter_ptr[e]..self.scatter_ptr[e + 1]] {
            values[pos as usize] += ke[ab as usize];
        }
    }

    /// Calls `f(i, p)` for every stored entry of row and column `k` off the diagonal: `i`
    /// the other index, `p` the value position (column `k` below the diagonal, then row `k`
    /// left of it). With `x` zero but at a few equations, `K x` is the sum of these
    /// columns: a handful of entries instead of a product over the whole matrix.
    pub fn for_each_off_diagonal(&self, k: usize, mut f: impl FnMut(usize, usize)) {
        for p in self.diag[k] + 1..self.col_ptr[k + 1] {
            f(self.row_idx[p], p);
        }
        let range = self.row_ptr[k]..self.row_ptr[k + 1];
        for (&p, &j) in self.row_pos[range.clone()].iter().zip(&self.row_col[range]) {
            f(j, p);
        }
    }

    /// Row `k` of the symmetric matrix stored as its lower triangle in `values` times `x`:
    /// the diagonal's product, then the off-diagonal entries' in
    /// [`Pattern::for_each_off_diagonal`]'s order (a handful of entries: one reaction).
    pub fn row_dot(&self, values: &[f64], k: usize, x: &[f64]) -> f64 {
        let mut acc = values[self.diag[k]] * x[k];
        self.for_each_off_diagonal(k, |i, p| acc += values[p] * x[i]);
        acc
    }

    /// `y += K x` for the symmetric matrix stored as its lower triangle in `values`.
    /// Paired columns (the two dofs of a node share their rows) go through their rows
    /// together: one index, one `x` and one `y` access for two entries.
    pub fn sym_mul_add(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        let mut j = 0;
        while j < self.n {
            // the diagonal is each column's first entry (rows sorted, all >= the column)
            let (d, end) = (self.diag[j], self.col_ptr[j + 1]);
            if self.paired[j] {
                let (d1, end1) = (self.diag[j + 1], self.col_ptr[j + 2]);
                let (x0, x1) = (x[j], x[j + 1]);
                let v01 = values[d + 1];
                let mut acc0 = values[d] * x0 + v01 * x1;
                let mut acc1 = v01 * x0 + values[d1] * x1;
                let rows = &self.row_idx[d + 2..end];
                for ((&i, &v0), &v1) in rows
                    .iter()
                    .zip(&values[d + 2..end])
                    .zip(&values[d1 + 1..end1])
                {
                    let xi = x[i];
                    y[i] += v0 * x0 + v1 * x1;
                    acc0 += v0 * xi;
                    acc1 += v1 * xi;
                }
                y[j] += acc0;
                y[j + 1] += acc1;
                j += 2;
                continue;
            }
            let xj = x[j];
            let mut acc = values[d] * xj;
            for (&i, &v) in self.row_idx[d + 1..end].iter().zip(&values[d + 1..end]) {
                y[i] += v * xj;
                acc += v * x[i];
            }
            y[j] += acc;
            j += 1;
        }
    }

    /// `y += K_a x_a + K_b x_b` for two symmetric matrices on this pattern (lower
    /// triangles in `va`, `vb`) in one pass over the structure: one index and one `y`
    /// access for the four entries of a paired column's row ([`Pattern::sym_mul_add`]'s
    /// loop, the two products summed per entry: round-off apart from two calls).
    pub fn sym_mul_add_pair(
        &self,
        (va, xa): (&[f64], &[f64]),
        (vb, xb): (&[f64], &[f64]),
        y: &mut [f64],
    ) {
        let mut j = 0;
        while j < self.n {
            let (d, end) = (self.diag[j], self.col_ptr[j + 1]);
            if self.paired[j] {
                let (d1, end1) = (self.diag[j + 1], self.col_ptr[j + 2]);
                let (a0, a1, b0, b1) = (xa[j], xa[j + 1], xb[j], xb[j + 1]);
                let (u01, w01) = (va[d + 1], vb[d + 1]);
                let mut acc0 = va[d] * a0 + u01 * a1 + vb[d] * b0 + w01 * b1;
                let mut acc1 = u01 * a0 + va[d1] * a1 + w01 * b0 + vb[d1] * b1;
                let rows = &self.row_idx[d + 2..end];
                for (((&i, (&u0, &w0)), &u1), &w1) in rows
                    .iter()
                    .zip(va[d + 2..end].iter().zip(&vb[d + 2..end]))
                    .zip(&va[d1 + 1..end1])
                    .zip(&vb[d1 + 1..end1])
                {
                    let (ai, bi) = (xa[i], xb[i]);
                    y[i] += (u0 * a0 + u1 * a1) + (w0 * b0 + w1 * b1);
                    acc0 += u0 * ai + w0 * bi;
                    acc1 += u1 * ai + w1 * bi;
                }
                y[j] += acc0;
                y[j + 1] += acc1;
                j += 2;
                continue;
            }
            let (aj, bj) = (xa[j], xb[j]);
            let mut acc = va[d] * aj + vb[d] * bj;
            for (&i, (&u, &w)) in self.row_idx[d + 1..end]
                .iter()
                .zip(va[d + 1..end].iter().zip(&vb[d + 1..end]))
            {
                y[i] += u * aj + w * bj;
                acc += u * xa[i] + w * xb[i];
            }
            y[j] += acc;
            j += 1;
        }
    }

    /// The symmetric matrix whose lower triangle `values` holds (on this pattern) as a full
    /// `sprs` CSC matrix over the equations, for users who inspect or reuse the matrices
    /// (scipy reads it through Matrix Market, `sprs::io::write_matrix_market`). Entries that
    /// are exactly zero (the rows and columns of constrained equations) are not stored.
    ///
    /// # Panics
    /// If `values` does not have [`Pattern::nnz`] entries.
    pub fn to_csmat(&self, values: &[f64]) -> sprs::CsMat<f64> {
        assert_eq!(values.len(), self.nnz(), "one value per pattern entry");
        let mut tri = sprs::TriMat::with_capacity((self.n, self.n), 2 * values.len());
        for j in 0..self.n {
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[p];
                if values[p] == 0.0 {
                    continue;
                }
                tri.add_triplet(i, j, values[p]);
                if i != j {
                    tri.add_triplet(j, i, values[p]);
                }
            }
        }
        tri.to_csc()
    }

    /// Copies `src` into `dst` with the rows and columns of the constrained equations
    /// replaced by the identity scaled by the original diagonal (kept for conditioning).
    /// Returns nothing; the constrained equation `k` then reads `K_kk x_k = K_kk xbar_k`.
    pub fn constrain(&self, src: &[f64], constrained: &[bool], dst: &mut [f64]) {
        dst.copy_from_slice(src);
        for (k, _) in constrained.iter().enumerate().filter(|(_, c)| **c) {
            // column k below the diagonal, then row k left of it
            dst[self.diag[k] + 1..self.col_ptr[k + 1]].fill(0.0);
            for &p in &self.row_pos[self.row_ptr[k]..self.row_ptr[k + 1]] {
                dst[p] = 0.0;
            }
        }
    }
}

/// Element matrices of the last cached assembly and the Gauss-point tangents they were
/// formed with ([`Pattern::assemble_b_c_b_cached`], [`Pattern::assemble_b_c_b_delta`]).
#[derive(Clone, Debug, Default)]
pub struct ElementCache {
    tangents: Vec<Mat4>,
    ke: Vec<[[f64; 16]; 16]>,
    /// Element matrices recomputed by the last assembly.
    pub recomputed: usize,
    /// The values of the last assembly are the sum of `ke` (a delta assembly may update them).
    summed: bool,
}

impl ElementCache {
    /// Re-forms element `e`'s matrix if its nine tangents in `c` differ (bit for bit) from
    /// those it was formed with; returns the previous matrix then.
    #[inline]
    fn refresh(&mut self, disc: &Discretization, c: &[Mat4], e: usize) -> Option<[[f64; 16]; 16]> {
        let qs = QP_PER_ELEMENT * e..QP_PER_ELEMENT * (e + 1);
        if same_bits(&c[qs.clone()], &self.tangents[qs.clone()]) {
            return None;
        }
        let old = std::mem::replace(&mut self.ke[e], element_matrix(disc, e, |q| &c[q]));
        self.tangents[qs.clone()].copy_from_slice(&c[qs]);
        self.recomputed += 1;
        Some(old)
    }

    /// Makes the next [`Pattern::assemble_b_c_b_delta`] sum every element afresh: its result
    /// then depends on the tangents alone, not on the assemblies before (call it where a
    /// computation must repeat bit for bit from a saved state, or when the values were
    /// written by anything else).
    pub fn forget_sum(&mut self) {
        self.summed = false;
    }
}

/// Whether two runs of tangents are equal bit for bit (no early exit: vectorizable).
#[inline]
fn same_bits(a: &[Mat4], b: &[Mat4]) -> bool {
    let mut diff = 0u64;
    for (x, y) in a.iter().zip(b) {
        for (u, v) in x.0.as_flattened().iter().zip(y.0.as_flattened()) {
            diff |= u.to_bits() ^ v.to_bits();
        }
    }
    diff == 0 && a.len() == b.len()
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

    /// A graded 4 x 3 cylinder with its supports: the discretization and the pattern.
    fn small_problem() -> (Discretization, Pattern) {
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
        let pat = Pattern::new(&disc, &DofMap::cylinder(&m));
        (disc, pat)
    }

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

    /// `sym_mul_add`, `sym_mul_add_pair` and `constrain` against the dense matrix, on a mesh with eliminated
    /// dofs (axis and bottom) and non-uniform tangents, so that paired and unpaired
    /// columns both occur.
    #[test]
    fn products_and_constraints_match_the_dense_matrix() {
        let (disc, pat) = small_problem();
        let n = pat.n;
        let tangents: Vec<Mat4> = (0..disc.n_qp())
            .map(|q| isotropic_stiffness(100.0 + q as f64, 0.2 + 1e-3 * q as f64))
            .collect();
        let mut k = vec![0.0; pat.nnz()];
        pat.assemble_b_c_b(&disc, &tangents, &mut k);
        let dense = |values: &[f64]| {
            let mut a = vec![vec![0.0; n]; n];
            for j in 0..n {
                for p in pat.col_ptr[j]..pat.col_ptr[j + 1] {
                    a[pat.row_idx[p]][j] = values[p];
                    a[j][pat.row_idx[p]] = values[p];
                }
            }
            a
        };
        let a = dense(&k);
        let x: Vec<f64> = (0..n).map(|i| ((i * 7) % 11) as f64 - 5.0).collect();
        let mut y: Vec<f64> = (0..n).map(|i| i as f64).collect();
        pat.sym_mul_add(&k, &x, &mut y);
        let scale = a.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
        for i in 0..n {
            let yi = i as f64 + (0..n).map(|j| a[i][j] * x[j]).sum::<f64>();
            assert!((y[i] - yi).abs() <= 1e-12 * scale * n as f64, "row {i}");
        }
        // the pair product: K x + K2 x2 in one pass, against the dense matrices
        let k2: Vec<f64> = k
            .iter()
            .enumerate()
            .map(|(p, v)| v * (0.5 + (p % 3) as f64))
            .collect();
        let a2 = dense(&k2);
        let x2: Vec<f64> = (0..n).map(|i| ((i * 5) % 7) as f64 - 3.0).collect();
        let mut y2: Vec<f64> = (0..n).map(|i| i as f64).collect();
        pat.sym_mul_add_pair((&k, &x), (&k2, &x2), &mut y2);
        for i in 0..n {
            let yi = i as f64
                + (0..n)
                    .map(|j| a[i][j] * x[j] + a2[i][j] * x2[j])
                    .sum::<f64>();
            assert!(
                (y2[i] - yi).abs() <= 1e-12 * 4.0 * scale * n as f64,
                "pair, row {i}"
            );
        }
        // columns as sym_mul_add walks them: a pair, or a single column
        let (mut paired, mut single, mut j) = (0, 0, 0);
        while j < n {
            if pat.paired[j] {
                paired += 1;
                j += 2;
            } else {
                single += 1;
                j += 1;
            }
        }
        assert!(
            paired > 0 && single > 0,
            "{paired} pairs, {single} single columns"
        );
        // row k of the matrix from its diagonal and off-diagonal entries
        for r in 0..n {
            let mut row = vec![0.0; n];
            row[r] = k[pat.diag[r]];
            pat.for_each_off_diagonal(r, |i, p| row[i] += k[p]);
            assert_eq!(row, a[r], "row {r}");
        }
        // constrain: rows and columns of the constrained equations are zero but for the diagonal
        let constrained: Vec<bool> = (0..n).map(|i| i % 5 == 1 || i == n - 1).collect();
        let mut kc = vec![f64::NAN; pat.nnz()];
        pat.constrain(&k, &constrained, &mut kc);
        let c = dense(&kc);
        for i in 0..n {
            for j in 0..n {
                let want = if i != j && (constrained[i] || constrained[j]) {
                    0.0
                } else {
                    a[i][j]
                };
                assert_eq!(c[i][j], want, "({i}, {j})");
            }
        }
    }

    /// The cached assembly equals a fresh one bit for bit and recomputes exactly the
    /// elements whose tangents changed.
    #[test]
    fn cached_assembly_recomputes_only_changed_elements() {
        let (disc, pat) = small_problem();
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

    /// The delta assembly follows a sequence of tangent changes to round-off of a fresh
    /// assembly, touches only the changed elements, and is bit-identical to a fresh one
    /// right after `forget_sum`.
    #[test]
    fn delta_assembly_tracks_fresh_assemblies() {
        let (disc, pat) = small_problem();
        let mut tangents = vec![isotropic_stiffness(100.0, 0.3); disc.n_qp()];
        let mut cache = ElementCache::default();
        let (mut fresh, mut delta) = (vec![0.0; pat.nnz()], vec![f64::NAN; pat.nnz()]);
        pat.assemble_b_c_b_delta(&disc, &tangents, &mut cache, &mut delta);
        pat.assemble_b_c_b(&disc, &tangents, &mut fresh);
        assert_eq!(fresh, delta);
        let scale = fresh.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        for round in 0..20 {
            // a moving "plastic zone": three elements soften, then recover
            let e0 = round % 10;
            for (q, t) in tangents.iter_mut().enumerate() {
                let e = q / QP_PER_ELEMENT;
                *t = if (e0..e0 + 3).contains(&e) {
                    isotropic_stiffness(100.0 / (2.0 + (q + round) as f64 * 0.1), 0.3)
                } else {
                    isotropic_stiffness(100.0, 0.3)
                };
            }
            pat.assemble_b_c_b_delta(&disc, &tangents, &mut cache, &mut delta);
            assert!(cache.recomputed <= 6, "round {round}: {}", cache.recomputed);
            pat.assemble_b_c_b(&disc, &tangents, &mut fresh);
            for (p, (a, b)) in fresh.iter().zip(&delta).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-13 * scale,
                    "round {round}, entry {p}: {a} vs {b}"
                );
            }
        }
        cache.forget_sum();
        pat.assemble_b_c_b_delta(&disc, &tangents, &mut cache, &mut delta);
        assert_eq!(fresh, delta);
    }
}
