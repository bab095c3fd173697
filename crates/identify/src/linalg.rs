//! Thin wrappers over nalgebra for the dense parameter-space algebra (matrices of the
//! parameter count, p <= ~10, and `n x p` sensitivity matrices): norms, the ordered
//! singular value decomposition, Cholesky solves of the small normal systems.

use nalgebra::{DMatrix, DVector};

/// Euclidean norm.
pub fn norm2(v: &[f64]) -> f64 {
    DVector::from_column_slice(v).norm()
}

/// Largest absolute entry.
pub fn norm_inf(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// The `n x p` matrix whose rows are `rows` (each of length `p`).
pub fn from_rows(rows: &[Vec<f64>], p: usize) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), p, |i, k| rows[i][k])
}

/// Singular value decomposition `A = U diag(s) V^T` of an `n x p` matrix, right side only:
/// the singular values in descending order and, for each, its right singular vector
/// (unit length, sign fixed so that its largest component is positive). When `n < p` the
/// missing values are 0 and their vectors complete the basis (`A` is padded with zero
/// rows, which leave `A^T A` unchanged). `None` when `A` holds a non-finite entry or the
/// iteration does not converge.
pub fn right_svd(a: &DMatrix<f64>) -> Option<(Vec<f64>, Vec<Vec<f64>>)> {
    let p = a.ncols();
    if p == 0 {
        return Some((Vec::new(), Vec::new()));
    }
    if a.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let padded;
    let m = if a.nrows() < p {
        padded = a.clone().resize_vertically(p, 0.0);
        &padded
    } else {
        a
    };
    let svd = nalgebra::linalg::SVD::try_new(m.clone(), false, true, f64::EPSILON, 1000)?;
    let v_t = svd.v_t?;
    let mut pairs: Vec<(f64, Vec<f64>)> = (0..p)
        .map(|i| {
            let mut v: Vec<f64> = v_t.row(i).iter().copied().collect();
            let big = v
                .iter()
                .copied()
                .max_by(|x, y| x.abs().total_cmp(&y.abs()))
                .unwrap_or(0.0);
            if big < 0.0 {
                v.iter_mut().for_each(|x| *x = -*x);
            }
            (svd.singular_values[i].max(0.0), v)
        })
        .collect();
    pairs.sort_by(|x, y| y.0.total_cmp(&x.0));
    Some(pairs.into_iter().unzip())
}

/// Solves `M x = b` for a symmetric positive definite `M` (given by rows) by Cholesky;
/// `None` when `M` is not numerically positive definite.
pub fn solve_spd(m: &[Vec<f64>], b: &[f64]) -> Option<Vec<f64>> {
    let n = b.len();
    let mat = from_rows(m, n);
    let chol = mat.cholesky()?;
    let x = chol.solve(&DVector::from_column_slice(b));
    x.iter()
        .all(|v| v.is_finite())
        .then(|| x.iter().copied().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solve_of_a_small_system() {
        let a = vec![
            vec![4.0, 1.0, 0.5],
            vec![1.0, 3.0, 0.2],
            vec![0.5, 0.2, 2.0],
        ];
        let x_true = [1.0, -2.0, 0.5];
        let b: Vec<f64> = a
            .iter()
            .map(|r| r.iter().zip(&x_true).map(|(u, v)| u * v).sum())
            .collect();
        let x = solve_spd(&a, &b).unwrap();
        for (u, v) in x.iter().zip(&x_true) {
            assert!((u - v).abs() < 1e-14, "{x:?}");
        }
        assert!(solve_spd(&[vec![1.0, 2.0], vec![2.0, 1.0]], &[1.0, 1.0]).is_none());
    }

    /// The SVD of a matrix built from a known orthogonal V and singular values shall give
    /// them back (ordered, up to sign), also for fewer rows than columns.
    #[test]
    fn right_svd_recovers_a_constructed_decomposition() {
        let (c, s) = (0.6f64, 0.8f64);
        // A = U diag(5, 0.01) V^T with U = I (2 rows of a 3-row matrix) and V a rotation
        let v = [[c, -s], [s, c]];
        let sig = [5.0, 0.01];
        let a = DMatrix::from_fn(3, 2, |i, k| if i < 2 { sig[i] * v[k][i] } else { 0.0 });
        let (vals, vecs) = right_svd(&a).unwrap();
        assert!((vals[0] - 5.0).abs() < 1e-14 && (vals[1] - 0.01).abs() < 1e-14);
        assert!((vecs[0][0] - c).abs() < 1e-14 && (vecs[0][1] - s).abs() < 1e-14);
        // second vector (-s, c), turned so that its largest entry is positive: (s, -c)
        assert!((vecs[1][0] - s).abs() < 1e-14 && (vecs[1][1] + c).abs() < 1e-14);
        // one row, two columns: one value, and a zero for the null vector (-2, 1)/sqrt(5)
        let a = DMatrix::from_row_slice(1, 2, &[1.0, 2.0]);
        let (vals, vecs) = right_svd(&a).unwrap();
        assert!((vals[0] - 5f64.sqrt()).abs() < 1e-14 && vals[1].abs() < 1e-14);
        assert!((vecs[1][0].abs() - 2.0 / 5f64.sqrt()).abs() < 1e-14);
        assert!(right_svd(&DMatrix::from_row_slice(1, 1, &[f64::NAN])).is_none());
    }
}
