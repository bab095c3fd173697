//! Sparse Cholesky (faer, supernodal LL^T) on a fixed pattern: the symbolic analysis with
//! its fill-reducing ordering is done once, numeric factorizations reuse it. Solves run
//! over the supernodes' dense column blocks directly, as products of the off-diagonal
//! block with the diagonal block's unknowns (contiguous, vectorizable) and one gather or
//! scatter per supernode: at FE sizes (a few thousand equations, supernodes of a few
//! columns) faer's general kernels spend more on dispatch than on arithmetic. The block
//! products take four columns per pass in the widest SIMD the CPU offers (pulp's runtime
//! dispatch: AVX2 with FMA on x86-64-v3, plain scalar code otherwise), so results may
//! differ in the last bits between CPUs, as faer's factorization itself does. The matrix's
//! permutation into the factor's ordering is worked out once, at the analysis, as a map of
//! value positions: a numeric factorization gathers the values through it and calls faer's
//! supernodal kernel directly, instead of faer permuting the whole matrix every time (the
//! same matrix reaches the same kernel, so the factor is the same, bit for bit).
//! Several right-hand sides go through one pass over the factor
//! ([`SparseCholesky::solve_multi_with`]): each factor entry broadcast to a SIMD vector of
//! columns, each column with the bits of its own solve.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SparseColMatRef;
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky, supernodal,
};
use faer::sparse::utils::{permute_self_adjoint_scratch, permute_self_adjoint_to_unsorted};
use faer::{Par, Side, Spec};
use pulp::{Arch, Simd, WithSimd};

use crate::FeError;
use crate::assembly::Pattern;

/// A Cholesky factorization bound to one [`Pattern`]: analyse once, factorize many times.
pub struct SparseCholesky {
    symbolic: SymbolicCholesky<usize>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// The lower triangle permuted into the factor's ordering: its column pointers, row
    /// indices (unsorted within a column, as faer's own permutation leaves them), and
    /// for each of its entries the position of that entry in the pattern's values.
    perm_col_ptr: Vec<usize>,
    perm_row_idx: Vec<usize>,
    perm_source: Vec<usize>,
    /// The permuted values (scratch of each factorization).
    perm_values: Vec<f64>,
    l_values: Vec<f64>,
    layout: Layout,
    scratch: SolveScratch,
    mem: MemBuffer,
    factorized: bool,
    /// Number of numeric factorizations done so far.
    pub n_factorizations: usize,
    /// Number of solves done so far.
    pub n_solves: usize,
}

impl std::fmt::Debug for SparseCholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseCholesky")
            .field("n", &self.col_ptr.len().saturating_sub(1))
            .field("l_nnz", &self.l_values.len())
            .field("n_factorizations", &self.n_factorizations)
            .finish()
    }
}

fn llt_params() -> Spec<faer::linalg::cholesky::llt::factor::LltParams, f64> {
    Default::default()
}

impl SparseCholesky {
    /// Symbolic analysis (AMD ordering, supernodal structure) of the pattern.
    ///
    /// # Errors
    /// [`FeError::Factorization`] if faer's analysis fails (out of memory).
    pub fn analyse(pattern: &Pattern) -> Result<SparseCholesky, FeError> {
        let n = pattern.n;
        let sym =
            SymbolicSparseColMatRef::new_checked(n, n, &pattern.col_ptr, None, &pattern.row_idx);
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic =
            factorize_symbolic_cholesky(sym, Side::Lower, SymmetricOrdering::Amd, params)
                .map_err(|e| FeError::Factorization(format!("symbolic analysis failed: {e:?}")))?;
        let req = symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, llt_params());
        let l_values = vec![0.0; symbolic.len_val()];
        let layout = Layout::new(&symbolic)?;
        let (perm_col_ptr, perm_row_idx, perm_source) = permuted_positions(pattern, &symbolic);
        Ok(SparseCholesky {
            perm_values: vec![0.0; perm_source.len()],
            perm_col_ptr,
            perm_row_idx,
            perm_source,
            symbolic,
            col_ptr: pattern.col_ptr.clone(),
            row_idx: pattern.row_idx.clone(),
            l_values,
            scratch: SolveScratch {
                work: vec![0.0; n + layout.max_pattern + layout.max_ncols],
            },
            layout,
            mem: MemBuffer::new(req),
            factorized: false,
            n_factorizations: 0,
            n_solves: 0,
        })
    }

    /// Number of nonzeros of the factor L.
    pub fn factor_nnz(&self) -> usize {
        self.l_values.len()
    }

    /// Numeric factorization of the matrix with the analysed pattern and these values.
    ///
    /// # Errors
    /// [`FeError::NotPositiveDefinite`] if the matrix is not numerically SPD (e.g. a
    /// rigid-body mode left free).
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), FeError> {
        let n = self.col_ptr.len() - 1;
        assert_eq!(values.len(), self.row_idx.len(), "values of the pattern");
        self.factorized = false;
        let SymbolicCholeskyRaw::Supernodal(sn) = self.symbolic.raw() else {
            unreachable!("the analysis forces a supernodal factor (checked by Layout::new)");
        };
        for (v, &src) in self.perm_values.iter_mut().zip(&self.perm_source) {
            *v = values[src];
        }
        let sym = SymbolicSparseColMatRef::new_unsorted_checked(
            n,
            n,
            &self.perm_col_ptr,
            None,
            &self.perm_row_idx,
        );
        let a = SparseColMatRef::new(sym, &self.perm_values);
        let stack = MemStack::new(&mut self.mem);
        supernodal::factorize_supernodal_numeric_llt(
            &mut self.l_values,
            a,
            Default::default(),
            sn,
            Par::Seq,
            stack,
            llt_params(),
        )
        .map_err(|e| FeError::NotPositiveDefinite(format!("{e:?}")))?;
        self.factorized = true;
        self.n_factorizations += 1;
        Ok(())
    }

    /// Solves `K x = b` in place with the last factorization.
    ///
    /// # Panics
    /// If no factorization succeeded yet, or `rhs` has the wrong length.
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) {
        let mut scratch = std::mem::take(&mut self.scratch);
        self.solve_with(rhs, &mut scratch);
        self.scratch = scratch;
        self.n_solves += 1;
    }

    /// The work space of one solve ([`SparseCholesky::solve_with`]).
    pub fn scratch(&self) -> SolveScratch {
        self.scratch.clone()
    }

    /// Solves `K x = b` in place with the last factorization and the given work space
    /// (from [`SparseCholesky::scratch`]), the factorization shared: several threads may
    /// solve with it at once, each with its own scratch. The same arithmetic as
    /// [`SparseCholesky::solve_in_place`] (which does not count these solves).
    ///
    /// # Panics
    /// If no factorization succeeded yet, or `rhs` has the wrong length.
    pub fn solve_with(&self, rhs: &mut [f64], scratch: &mut SolveScratch) {
        assert!(self.factorized, "solve before a successful factorization");
        let n = self.col_ptr.len() - 1;
        assert_eq!(rhs.len(), n, "right-hand side length");
        // a default or another factorization's scratch is sized here
        scratch
            .work
            .resize(n + self.layout.max_pattern + self.layout.max_ncols, 0.0);
        let (x, tmp) = scratch.work.split_at_mut(n);
        let (tmp, dots) = tmp.split_at_mut(self.layout.max_pattern);
        self.layout.solve(&self.l_values, rhs, x, tmp, dots);
    }

    /// Solves `K X = B` in place for the `k` right-hand sides of the column-major `n x k`
    /// block `b` (column `c` is `b[c * n..(c + 1) * n]`) with the last factorization and
    /// the given work space (grown on first use, then reused): each factor entry is loaded
    /// once and applied to the `k` columns together. Each column gets the bits its own
    /// [`SparseCholesky::solve_with`] gives it (the same operations in the same order per
    /// column, interleaved across columns). Not counted.
    ///
    /// # Panics
    /// If no factorization succeeded yet, or `b` is not `n * k` long.
    pub fn solve_multi_with(&self, b: &mut [f64], k: usize, scratch: &mut SolveScratch) {
        assert!(self.factorized, "solve before a successful factorization");
        let n = self.col_ptr.len() - 1;
        assert_eq!(b.len(), n * k, "right-hand sides' length");
        if k == 0 {
            return;
        }
        self.layout.arch.dispatch(SolveMulti {
            layout: &self.layout,
            l: &self.l_values,
            b,
            k,
            work: &mut scratch.work,
        });
    }
}

/// The work space of a solve with a shared [`SparseCholesky`].
#[derive(Clone, Debug, Default)]
pub struct SolveScratch {
    work: Vec<f64>,
}

/// The pattern's lower triangle permuted into the factor's ordering, as faer's numeric
/// factorization would permute it: column pointers, row indices and, per entry, the
/// position of its value in the pattern's values (found by permuting the positions
/// themselves, exact as `f64` below 2^53).
fn permuted_positions(
    pattern: &Pattern,
    symbolic: &SymbolicCholesky<usize>,
) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let n = pattern.n;
    let nnz = pattern.row_idx.len();
    let Some(perm) = symbolic.perm() else {
        // no ordering: the pattern is the factor's ordering already
        return (
            pattern.col_ptr.clone(),
            pattern.row_idx.clone(),
            (0..nnz).collect(),
        );
    };
    let positions: Vec<f64> = (0..nnz).map(|p| p as f64).collect();
    let sym = SymbolicSparseColMatRef::new_checked(n, n, &pattern.col_ptr, None, &pattern.row_idx);
    let a = SparseColMatRef::new(sym, &positions);
    let mut values = vec![0.0; nnz];
    let mut col_ptr = vec![0usize; n + 1];
    let mut row_idx = vec![0usize; nnz];
    let mut mem = MemBuffer::new(permute_self_adjoint_scratch::<usize>(n));
    permute_self_adjoint_to_unsorted(
        &mut values,
        &mut col_ptr,
        &mut row_idx,
        a,
        perm,
        Side::Lower,
        Side::Lower,
        MemStack::new(&mut mem),
    );
    let used = col_ptr[n];
    row_idx.truncate(used);
    let source = values[..used].iter().map(|&v| v as usize).collect();
    (col_ptr, row_idx, source)
}

/// One supernode: columns `start..start + ncols` of the permuted factor, stored from
/// `offset` as a dense column-major block of `ncols + (p1 - p0)` rows: the diagonal
/// block's rows, then the rows `pattern[p0..p1]` (all beyond the supernode) below it.
#[derive(Clone, Copy, Debug)]
struct Supernode {
    start: usize,
    ncols: usize,
    offset: usize,
    p0: usize,
    p1: usize,
}

/// The factor's layout and fill-reducing permutation, copied once from faer's analysis.
#[derive(Clone, Debug, Default)]
struct Layout {
    /// `x_perm[i] = b[fwd[i]]`.
    fwd: Vec<usize>,
    /// `x[i] = x_perm[inv[i]]`.
    inv: Vec<usize>,
    supernodes: Vec<Supernode>,
    pattern: Vec<usize>,
    max_pattern: usize,
    max_ncols: usize,
    /// The SIMD instruction set detected at analysis.
    arch: Arch,
}

impl Layout {
    fn new(symbolic: &SymbolicCholesky<usize>) -> Result<Layout, FeError> {
        let SymbolicCholeskyRaw::Supernodal(sym) = symbolic.raw() else {
            return Err(FeError::Factorization(
                "the symbolic analysis is not supernodal".into(),
            ));
        };
        let n = symbolic.nrows();
        let (fwd, inv) = match symbolic.perm() {
            Some(p) => {
                let (f, i) = p.arrays();
                (f.to_vec(), i.to_vec())
            }
            None => ((0..n).collect(), (0..n).collect()),
        };
        let mut layout = Layout {
            fwd,
            inv,
            arch: Arch::new(),
            ..Default::default()
        };
        let (begin, end) = (sym.supernode_begin(), sym.supernode_end());
        let offsets = sym.col_ptr_for_val();
        for s in 0..sym.n_supernodes() {
            let pat = sym.supernode(s).pattern();
            let p0 = layout.pattern.len();
            layout.pattern.extend_from_slice(pat);
            layout.max_pattern = layout.max_pattern.max(pat.len());
            layout.max_ncols = layout.max_ncols.max(end[s] - begin[s]);
            layout.supernodes.push(Supernode {
                start: begin[s],
                ncols: end[s] - begin[s],
                offset: offsets[s],
                p0,
                p1: layout.pattern.len(),
            });
        }
        Ok(layout)
    }

    /// `b = P^T L^-T L^-1 P b` with the factor values `l`; `x` (length n), `tmp` (the
    /// longest pattern) and `dots` (the widest supernode) are scratch.
    fn solve(&self, l: &[f64], b: &mut [f64], x: &mut [f64], tmp: &mut [f64], dots: &mut [f64]) {
        // one dispatch per solve: the whole sweep is compiled for the detected instruction set
        self.arch.dispatch(Solve {
            layout: self,
            l,
            b,
            x,
            tmp,
            dots,
        });
    }
}

/// [`Layout::solve`] as one SIMD-dispatched operation.
struct Solve<'a> {
    layout: &'a Layout,
    l: &'a [f64],
    b: &'a mut [f64],
    x: &'a mut [f64],
    tmp: &'a mut [f64],
    dots: &'a mut [f64],
}

impl WithSimd for Solve<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let Solve {
            layout: this,
            l,
            b,
            x,
            tmp,
            dots,
        } = self;
        for (xi, &f) in x.iter_mut().zip(&this.fwd) {
            *xi = b[f];
        }
        // forward, L y = P b: the diagonal block, then its column block times its unknowns
        for sn in &this.supernodes {
            let (nc, pat) = (sn.ncols, &this.pattern[sn.p0..sn.p1]);
            let nr = nc + pat.len();
            let block = &l[sn.offset..sn.offset + nr * nc];
            let xs = &mut x[sn.start..sn.start + nc];
            for j in 0..nc {
                let col = &block[j * nr..j * nr + nc];
                let xj = xs[j] / col[j];
                xs[j] = xj;
                for (xi, lij) in xs[j + 1..].iter_mut().zip(&col[j + 1..]) {
                    *xi -= lij * xj;
                }
            }
            let t = &mut tmp[..pat.len()];
            t.fill(0.0);
            block_product(simd, &block[nc..], nr, xs, t);
            for (&r, ti) in pat.iter().zip(t.iter()) {
                x[r] -= ti;
            }
        }
        // backward, L^T z = y: gather the pattern's unknowns, then dot products
        for sn in this.supernodes.iter().rev() {
            let (nc, pat) = (sn.ncols, &this.pattern[sn.p0..sn.p1]);
            let nr = nc + pat.len();
            let block = &l[sn.offset..sn.offset + nr * nc];
            let t = &mut tmp[..pat.len()];
            for (ti, &r) in t.iter_mut().zip(pat) {
                *ti = x[r];
            }
            let d = &mut dots[..nc];
            block_transpose_product(simd, &block[nc..], nr, t, d);
            let xs = &mut x[sn.start..sn.start + nc];
            for j in (0..nc).rev() {
                let col = &block[j * nr..(j + 1) * nr];
                let mut v = xs[j] - d[j];
                for (xi, lij) in xs[j + 1..].iter().zip(&col[j + 1..nc]) {
                    v -= lij * xi;
                }
                xs[j] = v / col[j];
            }
        }
        for (bi, &i) in b.iter_mut().zip(&this.inv) {
            *bi = x[i];
        }
    }
}

/// [`SparseCholesky::solve_multi_with`] as one SIMD-dispatched operation: the columns in
/// groups of the SIMD width, each group's unknowns interleaved by row (one SIMD vector per
/// row, the padding lanes zero), so that each factor entry is broadcast once and meets
/// the group's columns in one vector operation. Per column, the operations of [`Solve`]
/// in its order: the fused multiply-adds where [`block_product`] and
/// [`block_transpose_product`] take the rows in SIMD vectors, their separate products and
/// sums on the rows of the SIMD tail, the lanes of a dot product reduced by the same
/// `reduce_sum`.
struct SolveMulti<'a> {
    layout: &'a Layout,
    l: &'a [f64],
    b: &'a mut [f64],
    k: usize,
    work: &'a mut Vec<f64>,
}

impl WithSimd for SolveMulti<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let SolveMulti {
            layout: this,
            l,
            b,
            k,
            work,
        } = self;
        let lanes = S::F64_LANES;
        let n = this.fwd.len();
        let need = lanes * (n + this.max_pattern + this.max_ncols);
        if work.len() < need {
            work.resize(need, 0.0);
        }
        let (x, rest) = work.split_at_mut(n * lanes);
        let (tmp, rest) = rest.split_at_mut(this.max_pattern * lanes);
        let dots = &mut rest[..this.max_ncols * lanes];
        for c0 in (0..k).step_by(lanes) {
            let kg = lanes.min(k - c0);
            let bg = &mut b[c0 * n..(c0 + kg) * n];
            for (i, &f) in this.fwd.iter().enumerate() {
                let xi = &mut x[i * lanes..(i + 1) * lanes];
                for (c, v) in xi[..kg].iter_mut().enumerate() {
                    *v = bg[c * n + f];
                }
                xi[kg..].fill(0.0);
            }
            solve_group(simd, this, l, x, tmp, dots);
            for (i, &p) in this.inv.iter().enumerate() {
                for c in 0..kg {
                    bg[c * n + i] = x[p * lanes + c];
                }
            }
        }
    }
}

/// One group of [`SolveMulti`]: `x` (`n` SIMD vectors, row-major) in the factor's
/// ordering; `tmp` and `dots` scratch.
#[inline(always)]
fn solve_group<S: Simd>(
    simd: S,
    this: &Layout,
    l: &[f64],
    x: &mut [f64],
    tmp: &mut [f64],
    dots: &mut [f64],
) {
    let lanes = S::F64_LANES;
    let x = S::as_mut_simd_f64s(x).0;
    let zero = simd.splat_f64s(0.0);
    // forward, L y = P b
    for sn in &this.supernodes {
        let (nc, pat) = (sn.ncols, &this.pattern[sn.p0..sn.p1]);
        let (nr, m) = (nc + pat.len(), pat.len());
        let head = m / lanes * lanes;
        let block = &l[sn.offset..sn.offset + nr * nc];
        let xs = &mut x[sn.start..sn.start + nc];
        for j in 0..nc {
            let col = &block[j * nr..j * nr + nc];
            let (xj, below) = xs[j..].split_first_mut().expect("a column");
            *xj = simd.div_f64s(*xj, simd.splat_f64s(col[j]));
            for (xi, &lij) in below.iter_mut().zip(&col[j + 1..]) {
                *xi = simd.sub_f64s(*xi, simd.mul_f64s(simd.splat_f64s(lij), *xj));
            }
        }
        let t = &mut S::as_mut_simd_f64s(&mut tmp[..m * lanes]).0[..m];
        t.fill(zero);
        let off = &block[nc..];
        let col = |j: usize| &off[j * nr..j * nr + m];
        let mut j = 0;
        while j + 4 <= nc {
            let (x0, x1, x2, x3) = (xs[j], xs[j + 1], xs[j + 2], xs[j + 3]);
            let (c0, c1, c2, c3) = (col(j), col(j + 1), col(j + 2), col(j + 3));
            let (th, tt) = t.split_at_mut(head);
            for ((((ti, a0), a1), a2), a3) in th.iter_mut().zip(c0).zip(c1).zip(c2).zip(c3) {
                let v = simd.mul_add_e_f64s(simd.splat_f64s(*a0), x0, *ti);
                let v = simd.mul_add_e_f64s(simd.splat_f64s(*a1), x1, v);
                let v = simd.mul_add_e_f64s(simd.splat_f64s(*a2), x2, v);
                *ti = simd.mul_add_e_f64s(simd.splat_f64s(*a3), x3, v);
            }
            let tails = (&c0[head..], &c1[head..], &c2[head..], &c3[head..]);
            for (i, ti) in tt.iter_mut().enumerate() {
                let p0 = simd.mul_f64s(simd.splat_f64s(tails.0[i]), x0);
                let p1 = simd.mul_f64s(simd.splat_f64s(tails.1[i]), x1);
                let p2 = simd.mul_f64s(simd.splat_f64s(tails.2[i]), x2);
                let p3 = simd.mul_f64s(simd.splat_f64s(tails.3[i]), x3);
                let s = simd.add_f64s(simd.add_f64s(simd.add_f64s(p0, p1), p2), p3);
                *ti = simd.add_f64s(*ti, s);
            }
            j += 4;
        }
        while j < nc {
            let (xj, c) = (xs[j], col(j));
            let (th, tt) = t.split_at_mut(head);
            for (ti, a) in th.iter_mut().zip(c) {
                *ti = simd.mul_add_e_f64s(simd.splat_f64s(*a), xj, *ti);
            }
            for (ti, a) in tt.iter_mut().zip(&c[head..]) {
                *ti = simd.add_f64s(*ti, simd.mul_f64s(simd.splat_f64s(*a), xj));
            }
            j += 1;
        }
        for (&r, ti) in pat.iter().zip(t.iter()) {
            x[r] = simd.sub_f64s(x[r], *ti);
        }
    }
    // backward, L^T z = y
    let mut lane = [0.0f64; 64];
    for sn in this.supernodes.iter().rev() {
        let (nc, pat) = (sn.ncols, &this.pattern[sn.p0..sn.p1]);
        let (nr, m) = (nc + pat.len(), pat.len());
        let head = m / lanes * lanes;
        let block = &l[sn.offset..sn.offset + nr * nc];
        {
            let t = &mut S::as_mut_simd_f64s(&mut tmp[..m * lanes]).0[..m];
            for (ti, &r) in t.iter_mut().zip(pat) {
                *ti = x[r];
            }
        }
        let tf = &tmp[..m * lanes];
        let t = &S::as_simd_f64s(tf).0[..m];
        let d = &mut S::as_mut_simd_f64s(&mut dots[..nc * lanes]).0[..nc];
        let off = &block[nc..];
        for (j, dj) in d.iter_mut().enumerate() {
            let a = &off[j * nr..j * nr + m];
            // lane `q` of the single solve's accumulator: the head rows `i = q mod lanes`
            let mut acc = [zero; 8];
            for (ah, th) in a[..head]
                .chunks_exact(lanes)
                .zip(t[..head].chunks_exact(lanes))
            {
                for q in 0..lanes {
                    acc[q] = simd.mul_add_e_f64s(simd.splat_f64s(ah[q]), th[q], acc[q]);
                }
            }
            S::as_mut_simd_f64s(&mut lane[..lanes * lanes])
                .0
                .copy_from_slice(&acc[..lanes]);
            let mut out = [0.0f64; 8];
            for (c, o) in out[..lanes].iter_mut().enumerate() {
                let mut v = [0.0f64; 8];
                for (q, vq) in v[..lanes].iter_mut().enumerate() {
                    *vq = lane[q * lanes + c];
                }
                let tail: f64 = a[head..]
                    .iter()
                    .enumerate()
                    .map(|(i, ai)| ai * tf[(head + i) * lanes + c])
                    .sum();
                *o = simd.reduce_sum_f64s(simd.partial_load_f64s(&v[..lanes])) + tail;
            }
            *dj = simd.partial_load_f64s(&out[..lanes]);
        }
        let xs = &mut x[sn.start..sn.start + nc];
        for j in (0..nc).rev() {
            let col = &block[j * nr..(j + 1) * nr];
            let (xj, below) = xs[j..].split_first_mut().expect("a column");
            let mut v = simd.sub_f64s(*xj, d[j]);
            for (xi, &lij) in below.iter().zip(&col[j + 1..nc]) {
                v = simd.sub_f64s(v, simd.mul_f64s(simd.splat_f64s(lij), *xi));
            }
            *xj = simd.div_f64s(v, simd.splat_f64s(col[j]));
        }
    }
}

/// `t += A x` for the column-major block `A` of `t.len()` rows and `x.len()` columns, with
/// leading dimension `ld` (`block[j * ld + i] = A_ij`): four columns per pass over `t`.
#[inline(always)]
fn block_product<S: Simd>(simd: S, block: &[f64], ld: usize, x: &[f64], t: &mut [f64]) {
    let m = t.len();
    let col = |j: usize| &block[j * ld..j * ld + m];
    let mut quads = x.chunks_exact(4);
    let mut j = 0;
    for xq in quads.by_ref() {
        let (c0, c0t) = S::as_simd_f64s(col(j));
        let (c1, c1t) = S::as_simd_f64s(col(j + 1));
        let (c2, c2t) = S::as_simd_f64s(col(j + 2));
        let (c3, c3t) = S::as_simd_f64s(col(j + 3));
        let [x0, x1, x2, x3] = [xq[0], xq[1], xq[2], xq[3]].map(|v| simd.splat_f64s(v));
        let (th, tt) = S::as_mut_simd_f64s(t);
        for ((((ti, a0), a1), a2), a3) in th.iter_mut().zip(c0).zip(c1).zip(c2).zip(c3) {
            let v = simd.mul_add_e_f64s(*a0, x0, *ti);
            let v = simd.mul_add_e_f64s(*a1, x1, v);
            let v = simd.mul_add_e_f64s(*a2, x2, v);
            *ti = simd.mul_add_e_f64s(*a3, x3, v);
        }
        for (i, ti) in tt.iter_mut().enumerate() {
            *ti += c0t[i] * xq[0] + c1t[i] * xq[1] + c2t[i] * xq[2] + c3t[i] * xq[3];
        }
        j += 4;
    }
    for &xj in quads.remainder() {
        let (c, ct) = S::as_simd_f64s(col(j));
        let xs = simd.splat_f64s(xj);
        let (th, tt) = S::as_mut_simd_f64s(t);
        for (ti, a) in th.iter_mut().zip(c) {
            *ti = simd.mul_add_e_f64s(*a, xs, *ti);
        }
        for (ti, a) in tt.iter_mut().zip(ct) {
            *ti += a * xj;
        }
        j += 1;
    }
}

/// `d = A^T t` for the block of [`block_product`] (`d.len()` columns): four columns per
/// pass over `t`.
#[inline(always)]
fn block_transpose_product<S: Simd>(simd: S, block: &[f64], ld: usize, t: &[f64], d: &mut [f64]) {
    let m = t.len();
    let col = |j: usize| &block[j * ld..j * ld + m];
    let (th, tt) = S::as_simd_f64s(t);
    let zero = simd.splat_f64s(0.0);
    let mut quads = d.chunks_exact_mut(4);
    let mut j = 0;
    for dq in quads.by_ref() {
        let (c0, c0t) = S::as_simd_f64s(col(j));
        let (c1, c1t) = S::as_simd_f64s(col(j + 1));
        let (c2, c2t) = S::as_simd_f64s(col(j + 2));
        let (c3, c3t) = S::as_simd_f64s(col(j + 3));
        let mut acc = [zero; 4];
        for ((((tv, a0), a1), a2), a3) in th.iter().zip(c0).zip(c1).zip(c2).zip(c3) {
            acc[0] = simd.mul_add_e_f64s(*a0, *tv, acc[0]);
            acc[1] = simd.mul_add_e_f64s(*a1, *tv, acc[1]);
            acc[2] = simd.mul_add_e_f64s(*a2, *tv, acc[2]);
            acc[3] = simd.mul_add_e_f64s(*a3, *tv, acc[3]);
        }
        for (k, (dk, ct)) in dq.iter_mut().zip([c0t, c1t, c2t, c3t]).enumerate() {
            let tail: f64 = ct.iter().zip(tt).map(|(a, b)| a * b).sum();
            *dk = simd.reduce_sum_f64s(acc[k]) + tail;
        }
        j += 4;
    }
    for dj in quads.into_remainder() {
        let (c, ct) = S::as_simd_f64s(col(j));
        let mut acc = zero;
        for (tv, a) in th.iter().zip(c) {
            acc = simd.mul_add_e_f64s(*a, *tv, acc);
        }
        let tail: f64 = ct.iter().zip(tt).map(|(a, b)| a * b).sum();
        *dj = simd.reduce_sum_f64s(acc) + tail;
        j += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Discretization, DofMap};
    use faer::sparse::linalg::cholesky::LltRef;
    use faer::{Conj, MatMut};
    use indentify_laws::elastic::isotropic_stiffness;
    use indentify_mesh::CylinderMesher;

    /// The pattern and the elastic stiffness (E = 2e4 MPa, nu = 0.3) of a graded
    /// `nr x nz` cylinder mesh.
    fn graded_stiffness(nr: usize, nz: usize) -> (Pattern, Vec<f64>) {
        let mesh = CylinderMesher {
            radius: 2.0,
            height: 1.5,
            nr,
            nz,
            grading_r: 1.3,
            grading_z: 1.2,
        }
        .build()
        .unwrap();
        let disc = Discretization::new(&mesh);
        let dofs = DofMap::cylinder(&mesh);
        let pattern = Pattern::new(&disc, &dofs);
        let mut k = vec![0.0; pattern.nnz()];
        pattern.assemble_b_c_b_uniform(&disc, &isotropic_stiffness(2e4, 0.3), &mut k);
        (pattern, k)
    }

    /// The factorization through the precomputed permutation is faer's own numeric
    /// factorization (which permutes the matrix itself), bit for bit, on a matrix whose
    /// values all differ (a wrong position in the map changes the factor).
    #[test]
    fn prepermuted_factorization_is_faers_bit_for_bit() {
        let (pattern, mut k) = graded_stiffness(8, 6);
        // a distinct perturbation of every stored value (small: the matrix stays SPD)
        for (p, v) in k.iter_mut().enumerate() {
            *v *= 1.0 + 1e-3 * ((p * 7919) % 101) as f64 / 101.0;
        }
        let mut chol = SparseCholesky::analyse(&pattern).unwrap();
        assert!(chol.symbolic.perm().is_some(), "AMD orders the pattern");
        chol.factorize(&k).unwrap();
        let n = pattern.n;
        let sym =
            SymbolicSparseColMatRef::new_checked(n, n, &pattern.col_ptr, None, &pattern.row_idx);
        let mut faer_l = vec![0.0; chol.l_values.len()];
        let mut mem = MemBuffer::new(
            chol.symbolic
                .factorize_numeric_llt_scratch::<f64>(Par::Seq, llt_params()),
        );
        chol.symbolic
            .factorize_numeric_llt(
                &mut faer_l,
                SparseColMatRef::new(sym, &k),
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut mem),
                llt_params(),
            )
            .unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&chol.l_values), bits(&faer_l));
        // and a matrix that is not positive definite is refused, not factorized
        let mut bad = k.clone();
        bad[pattern.col_ptr[3]] = -1.0;
        assert!(matches!(
            chol.factorize(&bad),
            Err(FeError::NotPositiveDefinite(_))
        ));
    }

    /// The block solve equals faer's own supernodal solve to round-off and solves the
    /// system (residual), on an elastic stiffness of a graded mesh.
    #[test]
    fn block_solve_matches_faer_and_solves() {
        let (pattern, k) = graded_stiffness(9, 7);
        let mut chol = SparseCholesky::analyse(&pattern).unwrap();
        chol.factorize(&k).unwrap();
        let n = pattern.n;
        let b: Vec<f64> = (0..n).map(|i| ((i * 37) % 23) as f64 - 11.0).collect();
        let mut x = b.clone();
        chol.solve_in_place(&mut x);
        let mut y = b.clone();
        let llt = LltRef::<usize, f64>::new(&chol.symbolic, &chol.l_values);
        let mut mem = MemBuffer::new(
            faer::linalg::temp_mat_scratch::<f64>(n, 1).and(
                chol.symbolic
                    .factorize_numeric_llt_scratch::<f64>(Par::Seq, llt_params()),
            ),
        );
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut y, n, 1),
            Par::Seq,
            MemStack::new(&mut mem),
        );
        let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..n {
            assert!(
                (x[i] - y[i]).abs() <= 1e-12 * scale,
                "x[{i}] {} vs {}",
                x[i],
                y[i]
            );
        }
        let mut kx = vec![0.0; n];
        pattern.sym_mul_add(&k, &x, &mut kx);
        let bmax = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..n {
            assert!((kx[i] - b[i]).abs() <= 1e-9 * bmax, "residual at {i}");
        }
        assert!(chol.layout.supernodes.len() > 1);
        assert!(chol.layout.supernodes.iter().any(|s| s.ncols > 1));
        // the block products ran four-column passes with a remainder over SIMD-long columns
        assert!(
            chol.layout
                .supernodes
                .iter()
                .any(|s| s.ncols > 4 && s.ncols % 4 != 0 && s.p1 - s.p0 >= 8),
            "no supernode exercises the four-column kernel"
        );
    }

    /// The multi-column solve gives every column the bits of its own single-column solve,
    /// for 1 to 5 columns (one SIMD vector of columns, one with padding, two vectors), on
    /// the elastic stiffnesses of graded meshes of several sizes (from one element, whose
    /// supernodes have no rows below, to ones with four-column passes over SIMD-long
    /// blocks and SIMD tails), one with every value perturbed; and solves the systems.
    #[test]
    fn multi_column_solve_is_each_single_solve_bit_for_bit() {
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for (case, (nr, nz, perturb)) in
            [(1, 1, false), (4, 3, false), (9, 7, true), (16, 12, false)]
                .into_iter()
                .enumerate()
        {
            let (pattern, mut kv) = graded_stiffness(nr, nz);
            if perturb {
                for (p, v) in kv.iter_mut().enumerate() {
                    *v *= 1.0 + 1e-3 * ((p * 7919) % 101) as f64 / 101.0;
                }
            }
            let mut chol = SparseCholesky::analyse(&pattern).unwrap();
            chol.factorize(&kv).unwrap();
            let n = pattern.n;
            let mut single = chol.scratch();
            let mut multi = SolveScratch::default();
            for k in 1..=5 {
                // columns of unlike scales and signs
                let b: Vec<f64> = (0..n * k)
                    .map(|i| {
                        let c = i / n;
                        (((i * 37 + c * 11) % 23) as f64 - 11.0) * 10f64.powi(c as i32 - 2)
                    })
                    .collect();
                let mut x = b.clone();
                chol.solve_multi_with(&mut x, k, &mut multi);
                for c in 0..k {
                    let mut y = b[c * n..(c + 1) * n].to_vec();
                    chol.solve_with(&mut y, &mut single);
                    assert_eq!(
                        bits(&x[c * n..(c + 1) * n]),
                        bits(&y),
                        "case {case}, k = {k}: column {c} differs from its single solve"
                    );
                    let mut kx = vec![0.0; n];
                    pattern.sym_mul_add(&kv, &x[c * n..(c + 1) * n], &mut kx);
                    let bc = &b[c * n..(c + 1) * n];
                    let bmax = bc.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    for i in 0..n {
                        assert!(
                            (kx[i] - bc[i]).abs() <= 1e-9 * bmax,
                            "case {case}, k = {k}, column {c}: residual at {i}"
                        );
                    }
                }
            }
            // the largest mesh exercises the four-column passes, their remainder and the
            // SIMD tails of the blocks below the supernodes
            if case == 3 {
                let sns = &chol.layout.supernodes;
                assert!(sns.iter().any(|s| s.ncols > 4 && s.ncols % 4 != 0));
                assert!(
                    sns.iter()
                        .any(|s| (s.p1 - s.p0) % 4 != 0 && s.p1 - s.p0 > 4)
                );
            }
        }
    }

    /// The multi-column solve is the single-column one's arithmetic: on a zero column
    /// beside others it stays zero, and an empty block is a no-op.
    #[test]
    fn multi_column_solve_edge_cases() {
        let (pattern, kv) = graded_stiffness(5, 4);
        let mut chol = SparseCholesky::analyse(&pattern).unwrap();
        chol.factorize(&kv).unwrap();
        let n = pattern.n;
        let mut scratch = SolveScratch::default();
        let mut b = vec![0.0; 3 * n];
        for (i, v) in b[2 * n..].iter_mut().enumerate() {
            *v = (i % 7) as f64 - 3.0;
        }
        chol.solve_multi_with(&mut b, 3, &mut scratch);
        assert!(b[..2 * n].iter().all(|v| *v == 0.0));
        assert!(b[2 * n..].iter().any(|v| *v != 0.0));
        chol.solve_multi_with(&mut [], 0, &mut scratch);
    }
}
