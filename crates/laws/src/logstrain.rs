//! The logarithmic (Hencky) strain of an axisymmetric right Cauchy-Green tensor and its
//! first two derivatives in closed form (Miehe, Apel & Lambrecht 2002), so that every law
//! keeps its small-strain update and tangent in logarithmic strain space.
//!
//! `C` is given in Mandel form `[RR, ZZ, tt, sqrt2*RZ]`; the hoop direction is principal,
//! so `E_tt = ln(C_tt)/2` alone, and the in-plane 2x2 block `C2 = m 1 + D` (`m` the mean of
//! its eigenvalues, `D` its deviator, `s = D:D/2 = rho^2` with `m +- rho` the eigenvalues)
//! maps to `E2 = g0(m, s) 1 + g1(m, s) D`, with `g0 = ln(m^2 - s)/4` and
//! `g1 = (ln(m + rho) - ln(m - rho))/(4 rho) = h(s/m^2)/(2m)`, `h(y) = artanh(sqrt y)/sqrt y`.
//! Both are smooth functions of `s`, so equal eigenvalues (`s = 0`) need no special case
//! beyond the Taylor series of `h` near `y = 0` (where its closed form cancels).
//!
//! With `P = 2 dE/dC` and `L = 4 d2E/dC2`, the stress `T` conjugate to `E` gives the second
//! Piola-Kirchhoff stress `S = P : T` and, for `dT/dE = A` (the law's consistent tangent),
//! the material tangent `dS/dE_GL = P : A : P + T : L` (`E_GL = (C - 1)/2`).

use crate::mandel::{Mat4, Vec4};

/// The logarithmic strain of one right Cauchy-Green tensor and its derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogStrain {
    /// `E = ln(C)/2` (Mandel).
    pub e: Vec4,
    /// `P = 2 dE/dC` (Mandel 4x4, symmetric).
    pub p: Mat4,
    /// The second derivatives `d2E/dC2`, by the scalars they are made of.
    second: Second,
}

/// The second derivatives of `E` in compact form: with `g0`, `g1` functions of `(m, s)`,
/// `d2E_j/dC_k dC_l = 1_j H(g0)_kl + D_j H(g1)_kl + Pd_jl dg1_k + Pd_jk dg1_l` in plane
/// (`H(g) = g_mm dm dm + g_ms (dm D + D dm) + g_ss D D + g_s Pd`, `dm = [1/2, 1/2, 0, 0]`,
/// `Pd` the in-plane deviatoric projector) and `d2E_tt/dC_tt2 = -1/(2 C_tt^2)`. A
/// contraction with `T` is then one Hessian of the same form with the coefficients
/// `T:1 g0_.. + T:D g1_..` ([`LogStrain::t_l`]): 15 products instead of the 64 entries
/// of the full third-order array.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Second {
    /// `[g_mm, g_ms, g_ss, g_s]` of `g0` and of `g1`.
    g0: [f64; 4],
    g1: [f64; 4],
    /// The gradient of `g1` over `C` (Mandel; hoop entry 0).
    dg1: [f64; 4],
    /// The in-plane deviator `D = [d0, -d0, 0, x3]` of `C`.
    dvec: [f64; 4],
    /// `C_tt`.
    ct: f64,
}

/// Series bound: below it `h`, `h'` and `h''` come from their Taylor series.
const Y_SERIES: f64 = 0.05;

/// The Taylor coefficients of `h = sum y^k/(2k + 1)` (16 terms: the remainder is below
/// `0.05^16 ~ 1.5e-21`), of `h'` (`k c_k`, index `k`) and of `h''` (`k (k - 1) c_k`).
const H_SERIES: [[f64; 16]; 3] = {
    let mut c = [[0.0; 16]; 3];
    let mut k = 0;
    while k < 16 {
        let ck = 1.0 / (2 * k + 1) as f64;
        let kf = k as f64;
        c[0][k] = ck;
        c[1][k] = kf * ck;
        c[2][k] = kf * (kf - 1.0) * ck;
        k += 1;
    }
    c
};

/// `h(y) = artanh(sqrt y)/sqrt y` and its first two derivatives, for `0 <= y < 1`.
#[inline]
fn h_and_derivatives(y: f64) -> (f64, f64, f64) {
    if y < Y_SERIES {
        // Horner: h = sum c_k y^k, h' = sum k c_k y^(k-1), h'' = sum k(k-1) c_k y^(k-2)
        let [c0, c1, c2] = &H_SERIES;
        let (mut h, mut h1, mut h2) = (0.0, 0.0, 0.0);
        for k in (0..16).rev() {
            h = h * y + c0[k];
        }
        for k in (1..16).rev() {
            h1 = h1 * y + c1[k];
        }
        for k in (2..16).rev() {
            h2 = h2 * y + c2[k];
        }
        return (h, h1, h2);
    }
    let x = y.sqrt();
    let h = x.atanh() / x;
    let h1 = (1.0 / (1.0 - y) - h) / (2.0 * y);
    let h2 = (1.0 / ((1.0 - y) * (1.0 - y)) - 3.0 * h1) / (2.0 * y);
    (h, h1, h2)
}

impl LogStrain {
    /// `E`, `P` and the second derivatives at `c` (Mandel); `None` unless `C` is positive
    /// definite and finite. Near `C = 1` prefer [`LogStrain::from_difference`].
    pub fn new(c: &Vec4) -> Option<LogStrain> {
        LogStrain::from_difference(&(*c - Vec4::ONE))
    }

    /// As [`LogStrain::new`] for `C = 1 + c1`, given `c1 = C - 1` (twice the Green-Lagrange
    /// strain): the strain then keeps its relative precision however small it is (as the
    /// small-strain `B u` does), where `ln` of `C` itself would carry an absolute round-off
    /// of 1e-16.
    pub fn from_difference(c1: &Vec4) -> Option<LogStrain> {
        let [a1, d1, ct1, x3] = c1.0;
        let m1 = 0.5 * (a1 + d1);
        let m = 1.0 + m1;
        let d0 = 0.5 * (a1 - d1);
        // D in Mandel (in-plane): [d0, -d0, 0, x3]; s = d0^2 + x3^2/2
        let s = d0 * d0 + 0.5 * x3 * x3;
        // q = m^2 - s = 1 + q1
        let q1 = 2.0 * m1 + m1 * m1 - s;
        let q = 1.0 + q1;
        let ct = 1.0 + ct1;
        if !(ct > 0.0 && m > 0.0 && q > 0.0 && c1.is_finite()) {
            return None;
        }
        let y = s / (m * m);
        let (h, h1, h2) = h_and_derivatives(y);
        // g0 = ln(q)/4 and its partials in (m, s)
        let g0 = 0.25 * q1.ln_1p();
        let g0_m = m / (2.0 * q);
        let g0_s = -1.0 / (4.0 * q);
        let g0_mm = (q - 2.0 * m * m) / (2.0 * q * q);
        let g0_ms = m / (2.0 * q * q);
        let g0_ss = -1.0 / (4.0 * q * q);
        // g1 = h(s/m^2)/(2m)
        let (m2, m3) = (m * m, m * m * m);
        let (m4, m5) = (m2 * m2, m2 * m3);
        let g1 = h / (2.0 * m);
        let g1_s = h1 / (2.0 * m3);
        let g1_m = -h1 * s / m4 - h / (2.0 * m2);
        let g1_ss = h2 / (2.0 * m5);
        let g1_ms = -h2 * s / (m3 * m3) - 1.5 * h1 / m4;
        let g1_mm = 2.0 * s * s * h2 / (m5 * m2) + 5.0 * s * h1 / m5 + h / m3;
        // gradients over the Mandel components (hoop index 2 excluded: zero)
        let dm = [0.5, 0.5, 0.0, 0.0];
        let dvec = [d0, -d0, 0.0, x3]; // ds/dC = D
        // d2s/dC2: the in-plane deviatoric projector
        let pd = [
            [0.5, -0.5, 0.0, 0.0],
            [-0.5, 0.5, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ];
        let one2 = [1.0, 1.0, 0.0, 0.0];
        let grad = |gm: f64, gs: f64| -> [f64; 4] {
            [
                gm * dm[0] + gs * dvec[0],
                gm * dm[1] + gs * dvec[1],
                gm * dm[2] + gs * dvec[2],
                gm * dm[3] + gs * dvec[3],
            ]
        };
        let dg0 = grad(g0_m, g0_s);
        let dg1 = grad(g1_m, g1_s);
        let mut e = [0.0; 4];
        let mut p = [[0.0; 4]; 4];
        for j in [0, 1, 3] {
            e[j] = g0 * one2[j] + g1 * dvec[j];
            for k in [0, 1, 3] {
                p[j][k] = 2.0 * (one2[j] * dg0[k] + dvec[j] * dg1[k] + g1 * pd[j][k]);
            }
        }
        e[2] = 0.5 * ct1.ln_1p();
        p[2][2] = 1.0 / ct;
        Some(LogStrain {
            e: Vec4(e),
            p: Mat4(p),
            second: Second {
                g0: [g0_mm, g0_ms, g0_ss, g0_s],
                g1: [g1_mm, g1_ms, g1_ss, g1_s],
                dg1,
                dvec,
                ct,
            },
        })
    }

    /// `T : L = 4 sum_j T_j d2E_j/dC dC` (Mandel 4x4, symmetric): the part of the material
    /// tangent `dS/dE_GL` from the change of `P`.
    pub fn t_l(&self, t: &Vec4) -> Mat4 {
        let Second {
            g0,
            g1,
            dg1,
            dvec,
            ct,
        } = &self.second;
        let t = &t.0;
        // sum_j T_j 1_j and sum_j T_j D_j weigh the Hessians of g0 and g1; Pd T
        let (t1, td) = (t[0] + t[1], dvec[0] * (t[0] - t[1]) + dvec[3] * t[3]);
        let dt = 0.5 * (t[0] - t[1]);
        let pt = [dt, -dt, 0.0, t[3]];
        let coef = |i: usize| 4.0 * (t1 * g0[i] + td * g1[i]);
        let (gmm, gms, gss, gs) = (coef(0), coef(1), coef(2), coef(3));
        let dm = [0.5, 0.5, 0.0, 0.0];
        const PD: [[f64; 4]; 4] = [
            [0.5, -0.5, 0.0, 0.0],
            [-0.5, 0.5, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ];
        let mut m = [[0.0; 4]; 4];
        for k in [0, 1, 3] {
            for l in [0, 1, 3] {
                m[k][l] = gmm * dm[k] * dm[l]
                    + gms * (dm[k] * dvec[l] + dvec[k] * dm[l])
                    + gss * dvec[k] * dvec[l]
                    + gs * PD[k][l]
                    + 4.0 * (dg1[k] * pt[l] + pt[k] * dg1[l]);
            }
        }
        m[2][2] = -2.0 * t[2] / (ct * ct);
        Mat4(m)
    }

    /// The second Piola-Kirchhoff stress `S = P : T`.
    pub fn pk2(&self, t: &Vec4) -> Vec4 {
        self.p.mul_vec(t)
    }

    /// The material tangent `dS/dE_GL = P : A : P + T : L` for the law's tangent
    /// `A = dT/dE`. (`P` couples the in-plane components `[0, 1, 3]` only among
    /// themselves, its hoop entry stands alone: the products skip its zeros.)
    #[inline]
    pub fn material_tangent(&self, a: &Mat4, t: &Vec4) -> Mat4 {
        let (p, a) = (&self.p.0, &a.0);
        const PLANE: [usize; 3] = [0, 1, 3];
        // A P, then P (A P)
        let mut ap = [[0.0; 4]; 4];
        for i in 0..4 {
            for l in PLANE {
                ap[i][l] = a[i][0] * p[0][l] + a[i][1] * p[1][l] + a[i][3] * p[3][l];
            }
            ap[i][2] = a[i][2] * p[2][2];
        }
        let mut m = self.t_l(t).0;
        for k in PLANE {
            for l in 0..4 {
                m[k][l] += p[k][0] * ap[0][l] + p[k][1] * ap[1][l] + p[k][3] * ap[3][l];
            }
        }
        for l in 0..4 {
            m[2][l] += p[2][2] * ap[2][l];
        }
        Mat4(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `ln` of a symmetric 2x2 matrix by its eigen-decomposition (reference).
    fn log_reference(c: &Vec4) -> Vec4 {
        let [a, d, ct, x3] = c.0;
        let b = x3 / std::f64::consts::SQRT_2;
        let m = 0.5 * (a + d);
        let rho = (0.25 * (a - d) * (a - d) + b * b).sqrt();
        let (l1, l2) = (m + rho, m - rho);
        if rho == 0.0 {
            return Vec4([0.5 * a.ln(), 0.5 * d.ln(), 0.5 * ct.ln(), 0.0]);
        }
        // eigenvector of l1: (b, l1 - a) or (l1 - d, b)
        let (vx, vy) = if (l1 - d).abs() > b.abs() {
            (l1 - d, b)
        } else {
            (b, l1 - a)
        };
        let n = (vx * vx + vy * vy).sqrt();
        let (vx, vy) = (vx / n, vy / n);
        let (f1, f2) = (0.5 * l1.ln(), 0.5 * l2.ln());
        // E = f1 v v^T + f2 (I - v v^T)
        let err = f2 + (f1 - f2) * vx * vx;
        let ezz = f2 + (f1 - f2) * vy * vy;
        let erz = (f1 - f2) * vx * vy;
        Vec4([err, ezz, 0.5 * ct.ln(), std::f64::consts::SQRT_2 * erz])
    }

    fn samples() -> Vec<Vec4> {
        vec![
            Vec4([1.3, 0.7, 1.1, 0.4]),
            Vec4([2.5, 0.3, 0.6, -0.5]),
            Vec4([1.0, 1.0, 1.0, 0.0]),
            // nearly equal eigenvalues: the series branch
            Vec4([1.2, 1.2 + 1e-9, 0.9, 1e-9]),
            Vec4([0.8, 0.81, 1.4, 0.02]),
            // just above the series bound
            Vec4([1.0, 1.6, 1.2, 0.1]),
        ]
    }

    #[test]
    fn log_matches_the_eigen_decomposition() {
        for c in samples() {
            let l = LogStrain::new(&c).unwrap();
            let r = log_reference(&c);
            assert!((l.e - r).max_abs() < 1e-14, "{c:?}: {:?} vs {:?}", l.e, r);
        }
    }

    /// From `C - 1`, a strain of 1e-12 keeps its relative precision: `E = (C - 1)/2` to
    /// second order (1e-12 relative), where going through `C` would lose 1e-4.
    #[test]
    fn tiny_strains_keep_their_relative_precision() {
        let c1 = Vec4([2e-12, -1e-12, 3e-12, 1e-12]);
        let l = LogStrain::from_difference(&c1).unwrap();
        for j in 0..4 {
            assert!(
                (l.e.0[j] - 0.5 * c1.0[j]).abs() < 1e-11 * c1.0[j].abs(),
                "{:?}",
                l.e
            );
        }
    }

    #[test]
    fn h_series_and_closed_form_agree_at_the_bound() {
        let (a, a1, a2) = h_and_derivatives(Y_SERIES * (1.0 - 1e-12));
        let (b, b1, b2) = h_and_derivatives(Y_SERIES * (1.0 + 1e-12));
        assert!((a - b).abs() < 1e-13 && (a1 - b1).abs() < 1e-11 && (a2 - b2).abs() < 1e-8);
        // and the closed form at 0.3 against a direct evaluation of artanh
        let y: f64 = 0.3;
        let (h, _, _) = h_and_derivatives(y);
        assert!((h - y.sqrt().atanh() / y.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn first_and_second_derivatives_match_finite_differences() {
        let t = Vec4([3.0, -2.0, 1.5, 0.7]);
        for c in samples() {
            let l = LogStrain::new(&c).unwrap();
            let tl = l.t_l(&t);
            for k in 0..4 {
                let hstep = 1e-6;
                let mut cp = c;
                let mut cm = c;
                cp.0[k] += hstep;
                cm.0[k] -= hstep;
                let (lp, lm) = (LogStrain::new(&cp).unwrap(), LogStrain::new(&cm).unwrap());
                for j in 0..4 {
                    let fd = (lp.e.0[j] - lm.e.0[j]) / (2.0 * hstep);
                    assert!((2.0 * fd - l.p.0[j][k]).abs() < 1e-8, "P {j}{k} at {c:?}");
                }
                // d(P^T T)/dC_k * 2 = column k of T:L
                let sp = lp.pk2(&t);
                let sm = lm.pk2(&t);
                for i in 0..4 {
                    let fd = 2.0 * (sp.0[i] - sm.0[i]) / (2.0 * hstep);
                    assert!(
                        (fd - tl.0[i][k]).abs() < 1e-6 * (1.0 + tl.0[i][k].abs()),
                        "T:L {i}{k} at {c:?}: {fd} vs {}",
                        tl.0[i][k]
                    );
                }
            }
            // symmetry
            assert!((l.p - l.p.transpose()).max_abs() < 1e-14);
            assert!((tl - tl.transpose()).max_abs() < 1e-12);
        }
    }

    #[test]
    fn identity_maps_to_zero_strain_and_identity_projection() {
        let l = LogStrain::new(&Vec4::ONE).unwrap();
        assert!(l.e.max_abs() < 1e-16);
        // P = 2 dE/dC = I at C = 1 (dE = dC/2)
        assert!((l.p - Mat4::IDENTITY).max_abs() < 1e-15);
    }

    #[test]
    fn non_positive_tensors_are_refused() {
        assert!(LogStrain::new(&Vec4([1.0, 1.0, 0.0, 0.0])).is_none());
        assert!(LogStrain::new(&Vec4([1.0, 1.0, 1.0, 2.0])).is_none());
        assert!(LogStrain::new(&Vec4([f64::NAN, 1.0, 1.0, 0.0])).is_none());
    }
}
