//! Symmetric tensors in Mandel form `[rr, zz, tt, sqrt2*rz]` and fourth-order operators as 4x4 matrices.
//!
//! In Mandel form the double contraction `sigma:eps` is the dot product of the
//! 4-vectors and the fourth-order identity is the 4x4 identity, so compliance and
//! stiffness operators compose as ordinary matrices.

use std::ops::{Add, AddAssign, Index, IndexMut, Mul, Neg, Sub, SubAssign};

/// `sqrt(2)`, the Mandel weight of the shear component.
pub const SQRT2: f64 = std::f64::consts::SQRT_2;

/// A symmetric second-order tensor in Mandel form `[rr, zz, tt, sqrt2*rz]`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec4(pub [f64; 4]);

/// A fourth-order tensor with minor symmetries acting on Mandel vectors (row-major 4x4).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Mat4(pub [[f64; 4]; 4]);

impl Vec4 {
    /// The zero tensor.
    pub const ZERO: Vec4 = Vec4([0.0; 4]);
    /// The second-order identity `1 = [1, 1, 1, 0]`.
    pub const ONE: Vec4 = Vec4([1.0, 1.0, 1.0, 0.0]);

    /// Dot product, equal to the double contraction `a:b` of the tensors.
    #[inline]
    pub fn dot(&self, o: &Vec4) -> f64 {
        self.0[0] * o.0[0] + self.0[1] * o.0[1] + self.0[2] * o.0[2] + self.0[3] * o.0[3]
    }
    /// Euclidean (Frobenius) norm.
    #[inline]
    pub fn norm(&self) -> f64 {
        self.dot(self).sqrt()
    }
    /// Trace `rr + zz + tt`.
    #[inline]
    pub fn trace(&self) -> f64 {
        self.0[0] + self.0[1] + self.0[2]
    }
    /// Deviatoric part `s = sigma - tr(sigma)/3 1`.
    #[inline]
    pub fn deviator(&self) -> Vec4 {
        let p = self.trace() / 3.0;
        Vec4([self.0[0] - p, self.0[1] - p, self.0[2] - p, self.0[3]])
    }
    /// von Mises equivalent stress `sqrt(3/2 s:s)`.
    #[inline]
    pub fn von_mises(&self) -> f64 {
        let s = self.deviator();
        (1.5 * s.dot(&s)).sqrt()
    }
    /// Outer product `a (x) b` as a 4x4 operator.
    #[inline]
    pub fn outer(&self, o: &Vec4) -> Mat4 {
        let mut m = [[0.0; 4]; 4];
        for (i, row) in m.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = self.0[i] * o.0[j];
            }
        }
        Mat4(m)
    }
    /// Maximum absolute component.
    #[inline]
    pub fn max_abs(&self) -> f64 {
        self.0.iter().fold(0.0_f64, |m, v| m.max(v.abs()))
    }
    /// `true` when every component is finite.
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.0.iter().all(|v| v.is_finite())
    }
}

impl Mat4 {
    /// The zero operator.
    pub const ZERO: Mat4 = Mat4([[0.0; 4]; 4]);
    /// The fourth-order identity `I4`.
    pub const IDENTITY: Mat4 = Mat4([
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]);

    /// The deviatoric projector `P = I4 - 1(x)1/3`.
    #[inline]
    pub fn deviatoric_projector() -> Mat4 {
        Mat4::IDENTITY - Vec4::ONE.outer(&Vec4::ONE) * (1.0 / 3.0)
    }
    /// `1 (x) 1`.
    #[inline]
    pub fn one_one() -> Mat4 {
        Vec4::ONE.outer(&Vec4::ONE)
    }
    /// Transpose.
    pub fn transpose(&self) -> Mat4 {
        let mut m = [[0.0; 4]; 4];
        for (i, row) in m.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = self.0[j][i];
            }
        }
        Mat4(m)
    }
    /// Matrix-vector product.
    #[inline]
    pub fn mul_vec(&self, v: &Vec4) -> Vec4 {
        let mut out = [0.0; 4];
        for (o, row) in out.iter_mut().zip(&self.0) {
            *o = row[0] * v.0[0] + row[1] * v.0[1] + row[2] * v.0[2] + row[3] * v.0[3];
        }
        Vec4(out)
    }
    /// Matrix-matrix product.
    pub fn mul_mat(&self, o: &Mat4) -> Mat4 {
        let mut m = [[0.0; 4]; 4];
        for (i, row) in m.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = (0..4).map(|k| self.0[i][k] * o.0[k][j]).sum();
            }
        }
        Mat4(m)
    }
    /// Inverse by Gauss-Jordan elimination with partial pivoting; `None` if numerically
    /// singular (a pivot below `1e-13` times the largest entry) or not finite.
    pub fn inverse(&self) -> Option<Mat4> {
        let mut a = self.0;
        let mut inv = Mat4::IDENTITY.0;
        let tiny = 1e-13 * self.max_abs();
        for col in 0..4 {
            let piv = (col..4).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
            if a[piv][col].abs() <= tiny || !a[piv][col].is_finite() {
                return None;
            }
            a.swap(col, piv);
            inv.swap(col, piv);
            let d = 1.0 / a[col][col];
            for k in 0..4 {
                a[col][k] *= d;
                inv[col][k] *= d;
            }
            for row in 0..4 {
                if row != col {
                    let f = a[row][col];
                    if f != 0.0 {
                        for k in 0..4 {
                            a[row][k] -= f * a[col][k];
                            inv[row][k] -= f * inv[col][k];
                        }
                    }
                }
            }
        }
        Some(Mat4(inv))
    }
    /// Maximum absolute entry.
    pub fn max_abs(&self) -> f64 {
        self.0.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()))
    }
}

macro_rules! elementwise {
    ($t:ident, $tr:ident, $f:ident, $op:tt, $tra:ident, $fa:ident, $opa:tt) => {
        impl $tr for $t {
            type Output = $t;
            #[inline]
            fn $f(self, o: $t) -> $t {
                let mut r = self;
                r $opa o;
                r
            }
        }
        impl $tra for $t {
            #[inline]
            fn $fa(&mut self, o: $t) {
                for (a, b) in self.as_flat_mut().iter_mut().zip(o.as_flat()) {
                    *a $opa *b;
                }
            }
        }
    };
}

impl Vec4 {
    #[inline]
    fn as_flat(&self) -> &[f64] {
        &self.0
    }
    #[inline]
    fn as_flat_mut(&mut self) -> &mut [f64] {
        &mut self.0
    }
}
impl Mat4 {
    #[inline]
    fn as_flat(&self) -> &[f64] {
        self.0.as_flattened()
    }
    #[inline]
    fn as_flat_mut(&mut self) -> &mut [f64] {
        self.0.as_flattened_mut()
    }
}

elementwise!(Vec4, Add, add, +, AddAssign, add_assign, +=);
elementwise!(Vec4, Sub, sub, -, SubAssign, sub_assign, -=);
elementwise!(Mat4, Add, add, +, AddAssign, add_assign, +=);
elementwise!(Mat4, Sub, sub, -, SubAssign, sub_assign, -=);

impl Mul<f64> for Vec4 {
    type Output = Vec4;
    #[inline]
    fn mul(self, s: f64) -> Vec4 {
        // (plain loops: the optimizer left `array::map`'s adapters as calls in the laws'
        // per-point work; the same products)
        let mut r = self;
        for v in &mut r.0 {
            *v *= s;
        }
        r
    }
}
impl Mul<f64> for Mat4 {
    type Output = Mat4;
    #[inline]
    fn mul(self, s: f64) -> Mat4 {
        let mut r = self;
        for v in r.0.as_flattened_mut() {
            *v *= s;
        }
        r
    }
}
impl Neg for Vec4 {
    type Output = Vec4;
    #[inline]
    fn neg(self) -> Vec4 {
        self * -1.0
    }
}
impl Index<usize> for Vec4 {
    type Output = f64;
    #[inline]
    fn index(&self, i: usize) -> &f64 {
        &self.0[i]
    }
}
impl IndexMut<usize> for Vec4 {
    #[inline]
    fn index_mut(&mut self, i: usize) -> &mut f64 {
        &mut self.0[i]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_of_projector_plus_identity() {
        let a = Mat4::IDENTITY * 2.0 + Mat4::deviatoric_projector() * 3.0;
        let inv = a.inverse().unwrap();
        let id = a.mul_mat(&inv);
        assert!((id - Mat4::IDENTITY).max_abs() < 1e-14);
    }

    #[test]
    fn singular_matrix_has_no_inverse() {
        assert!(Mat4::deviatoric_projector().inverse().is_none());
    }

    #[test]
    fn von_mises_of_uniaxial_stress_is_the_stress() {
        let s = Vec4([0.0, 7.0, 0.0, 0.0]);
        assert!((s.von_mises() - 7.0).abs() < 1e-14);
        // pure shear tau: sigma_eq = sqrt(3) tau; Mandel component sqrt2*tau
        let t = Vec4([0.0, 0.0, 0.0, SQRT2 * 2.0]);
        assert!((t.von_mises() - 3f64.sqrt() * 2.0).abs() < 1e-14);
    }
}
