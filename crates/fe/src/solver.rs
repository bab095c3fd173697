//! Sparse Cholesky (faer, supernodal LL^T) on a fixed pattern: the symbolic analysis with
//! its fill-reducing ordering is done once, numeric factorizations reuse it.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::SparseColMatRef;
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::{Conj, MatMut, Par, Side, Spec};

use crate::FeError;
use crate::assembly::Pattern;

/// A Cholesky factorization bound to one [`Pattern`]: analyse once, factorize many times.
pub struct SparseCholesky {
    symbolic: SymbolicCholesky<usize>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    l_values: Vec<f64>,
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
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, llt_params()),
            faer::linalg::temp_mat_scratch::<f64>(n, 1).and(StackReq::new::<usize>(4 * n)),
        ]);
        let l_values = vec![0.0; symbolic.len_val()];
        Ok(SparseCholesky {
            symbolic,
            col_ptr: pattern.col_ptr.clone(),
            row_idx: pattern.row_idx.clone(),
            l_values,
            mem: MemBuffer::new(req.and(StackReq::new::<f64>(8 * n))),
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
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx);
        let a = SparseColMatRef::new(sym, values);
        self.factorized = false;
        let stack = MemStack::new(&mut self.mem);
        self.symbolic
            .factorize_numeric_llt(
                &mut self.l_values,
                a,
                Side::Lower,
                Default::default(),
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
        assert!(self.factorized, "solve before a successful factorization");
        let n = rhs.len();
        let llt = LltRef::<usize, f64>::new(&self.symbolic, &self.l_values);
        let stack = MemStack::new(&mut self.mem);
        let mat = MatMut::from_column_major_slice_mut(rhs, n, 1);
        llt.solve_in_place_with_conj(Conj::No, mat, Par::Seq, stack);
        self.n_solves += 1;
    }
}
