//! Linear isotropic elasticity `S = ((1+nu) I4 - nu 1(x)1) / E`, parameters `[E, nu]`.

use crate::law::{Law, LocalFailure, LocalUpdate, ParamInfo};
use crate::mandel::{Mat4, Vec4};

/// Parameters: `E` (MPa) and `nu`; no flow (`g = 0`, `H = 0`).
#[derive(Clone, Copy, Debug, Default)]
pub struct Elastic;

/// Metadata shared by every law that starts with `[E, nu]`.
pub(crate) const E_INFO: ParamInfo = ParamInfo {
    name: "E",
    unit: "MPa",
    description: "Young's modulus",
    min: 0.0,
    min_inclusive: false,
    max: f64::INFINITY,
    max_inclusive: false,
};
/// Poisson's ratio metadata.
pub(crate) const NU_INFO: ParamInfo = ParamInfo {
    name: "nu",
    unit: "-",
    description: "Poisson's ratio",
    min: -1.0,
    min_inclusive: false,
    max: 0.5,
    max_inclusive: false,
};

const PARAMS: [ParamInfo; 2] = [E_INFO, NU_INFO];

/// Isotropic compliance `((1+nu) I4 - nu 1(x)1)/E` (paper eq. 42).
pub fn isotropic_compliance(e: f64, nu: f64) -> Mat4 {
    (Mat4::IDENTITY * (1.0 + nu) - Mat4::one_one() * nu) * (1.0 / e)
}

/// Isotropic stiffness `2G I4 + lambda 1(x)1`, the inverse of [`isotropic_compliance`].
pub fn isotropic_stiffness(e: f64, nu: f64) -> Mat4 {
    let g2 = e / (1.0 + nu);
    let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    Mat4::IDENTITY * g2 + Mat4::one_one() * lambda
}

/// The isotropic operator `a P + b J`, `J = 1(x)1/3` the spherical projector: `P` and `J`
/// are orthogonal projectors, so `(a P + b J)^-1 = P/a + J/b`.
#[inline]
pub(crate) fn isotropic_operator(a: f64, b: f64) -> Mat4 {
    Mat4::deviatoric_projector() * a + Mat4::one_one() * (b / 3.0)
}

/// `dS/dc_k` for `k` = 0 (E) or 1 (nu); zero otherwise.
pub(crate) fn isotropic_compliance_derivative(c: &[f64], k: usize) -> Mat4 {
    let (e, nu) = (c[0], c[1]);
    match k {
        0 => isotropic_compliance(e, nu) * (-1.0 / e),
        1 => (Mat4::IDENTITY - Mat4::one_one()) * (1.0 / e),
        _ => Mat4::ZERO,
    }
}

impl Law for Elastic {
    fn name(&self) -> &'static str {
        "elastic"
    }
    fn params(&self) -> &'static [ParamInfo] {
        &PARAMS
    }
    fn compliance(&self, c: &[f64]) -> Mat4 {
        isotropic_compliance(c[0], c[1])
    }
    fn compliance_derivative(&self, c: &[f64], k: usize) -> Mat4 {
        isotropic_compliance_derivative(c, k)
    }
    fn flow(&self, _c: &[f64], _sigma: &Vec4) -> Vec4 {
        Vec4::ZERO
    }
    fn flow_hessian(&self, _c: &[f64], _sigma: &Vec4) -> Mat4 {
        Mat4::ZERO
    }
    fn flow_param_derivative(&self, _c: &[f64], _sigma: &Vec4, _k: usize) -> Vec4 {
        Vec4::ZERO
    }
    fn is_linear(&self) -> bool {
        true
    }
    fn tangent(&self, c: &[f64], _sigma: &Vec4, _dt: f64) -> Result<Mat4, LocalFailure> {
        Ok(isotropic_stiffness(c[0], c[1]))
    }
    /// `A = I`, `C` the isotropic stiffness.
    fn affine_update(&self, c: &[f64], _dt: f64) -> Option<(Mat4, Mat4)> {
        Some((Mat4::IDENTITY, isotropic_stiffness(c[0], c[1])))
    }
    fn update(
        &self,
        c: &[f64],
        s0: &Vec4,
        deps: &Vec4,
        _dt: f64,
    ) -> Result<LocalUpdate, LocalFailure> {
        let tangent = isotropic_stiffness(c[0], c[1]);
        Ok(LocalUpdate {
            sigma: *s0 + tangent.mul_vec(deps),
            tangent,
            iterations: 0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{Profile, law_consistency_tests, log_uniform, relative_param_step};
    use proptest::prelude::*;

    const PROFILE: Profile = Profile {
        law: &Elastic,
        stress_scale,
        smooth_length,
        param_step: relative_param_step,
    };
    fn stress_scale(c: &[f64]) -> f64 {
        1e-3 * c[0]
    }
    fn smooth_length(_c: &[f64], _sigma: &Vec4) -> f64 {
        f64::INFINITY
    }
    fn params() -> impl Strategy<Value = Vec<f64>> {
        (log_uniform(1e2, 1e6), -0.9..0.49f64).prop_map(|(e, nu)| vec![e, nu])
    }
    law_consistency_tests!(consistency, PROFILE, params());

    #[test]
    fn stiffness_inverts_compliance() {
        let s = isotropic_compliance(20000.0, 0.3);
        let c = isotropic_stiffness(20000.0, 0.3);
        assert!((s.mul_mat(&c) - Mat4::IDENTITY).max_abs() < 1e-13);
    }

    #[test]
    fn uniaxial_stress_gives_lateral_contraction() {
        let s = isotropic_compliance(200.0, 0.25);
        let eps = s.mul_vec(&Vec4([0.0, 100.0, 0.0, 0.0]));
        assert!((eps[1] - 0.5).abs() < 1e-14);
        assert!((eps[0] + 0.125).abs() < 1e-14);
        assert!((eps[2] + 0.125).abs() < 1e-14);
    }

    #[test]
    fn parameter_ranges_are_enforced() {
        assert!(Elastic.check_params(&[1.0, 0.3]).is_ok());
        let err = Elastic.check_params(&[1.0, 0.5]).unwrap_err().to_string();
        assert!(err.contains("nu") && err.contains("(-1, 0.5)"), "{err}");
        let err = Elastic.check_params(&[-3.0, 0.2]).unwrap_err().to_string();
        assert!(err.contains('E') && err.contains("-3"), "{err}");
    }
}
