//! The worked example of docs/adding-a-law.md, compiled and tested so that the guide
//! cannot drift from the trait: a Maxwell law with a bulk dashpot besides the deviatoric
//! one. Test-only: it is not registered in [`crate::law_by_name`] (the guide lists what
//! registering it takes).

use crate::elastic::{E_INFO, NU_INFO, isotropic_compliance, isotropic_compliance_derivative};
use crate::law::{Law, ParamInfo};
use crate::mandel::{Mat4, Vec4};

/// Maxwell with a bulk viscosity, parameters `c = [E (MPa), nu (-), eta (MPa s), zeta
/// (MPa s)]`: pseudo-potential `Phi = s : s / (2 eta) + (tr sigma)^2 / (18 zeta)`, so
/// `g = P sigma / eta + 1 tr(sigma) / (9 zeta)` (the mean stress `p` creeps the volume at
/// the rate `p / zeta`) and `H = P / eta + 1 (x) 1 / (9 zeta)`.
#[derive(Clone, Copy, Debug, Default)]
pub struct BulkMaxwell;

const ETA: usize = 2;
const ZETA: usize = 3;

const PARAMS: [ParamInfo; 4] = [
    E_INFO,
    NU_INFO,
    ParamInfo {
        name: "eta",
        unit: "MPa s",
        description: "viscosity of the deviatoric dashpot",
        min: 0.0,
        min_inclusive: false,
        max: f64::INFINITY,
        max_inclusive: false,
    },
    ParamInfo {
        name: "zeta",
        unit: "MPa s",
        description: "viscosity of the bulk dashpot (volume creep rate p / zeta)",
        min: 0.0,
        min_inclusive: false,
        max: f64::INFINITY,
        max_inclusive: false,
    },
];

impl Law for BulkMaxwell {
    fn name(&self) -> &'static str {
        "maxwell-bulk"
    }
    fn params(&self) -> &'static [ParamInfo] {
        &PARAMS
    }
    fn compliance(&self, c: &[f64]) -> Mat4 {
        isotropic_compliance(c[0], c[1])
    }
    fn compliance_derivative(&self, c: &[f64], k: usize) -> Mat4 {
        isotropic_compliance_derivative(c, k) // zero for eta and zeta
    }
    fn flow(&self, c: &[f64], sigma: &Vec4) -> Vec4 {
        sigma.deviator() * (1.0 / c[ETA]) + Vec4::ONE * (sigma.trace() / (9.0 * c[ZETA]))
    }
    fn flow_hessian(&self, c: &[f64], _sigma: &Vec4) -> Mat4 {
        Mat4::deviatoric_projector() * (1.0 / c[ETA]) + Mat4::one_one() * (1.0 / (9.0 * c[ZETA]))
    }
    fn flow_param_derivative(&self, c: &[f64], sigma: &Vec4, k: usize) -> Vec4 {
        match k {
            ETA => sigma.deviator() * (-1.0 / (c[ETA] * c[ETA])),
            ZETA => Vec4::ONE * (-sigma.trace() / (9.0 * c[ZETA] * c[ZETA])),
            _ => Vec4::ZERO,
        }
    }
    fn is_linear(&self) -> bool {
        true // H does not depend on sigma: the tangent depends on (c, dt) only
    }
    // `update` and `tangent` keep the trait's defaults: a Newton iteration on the
    // backward-Euler residual (one step for this linear flow) and `(S + dt H)^-1`.
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{Profile, law_consistency_tests, log_uniform, relative_param_step};
    use proptest::prelude::*;

    const PROFILE: Profile = Profile {
        law: &BulkMaxwell,
        stress_scale: |c| 1e-3 * c[0],       // stresses of order 1e-3 E
        smooth_length: |_, _| f64::INFINITY, // g is smooth everywhere
        param_step: relative_param_step,     // finite-difference steps 1e-4 |c_k|
    };

    fn params() -> impl Strategy<Value = Vec<f64>> {
        (
            log_uniform(1e2, 1e6),
            // up to 0.49 like the other laws: near nu = 0.5 the volume's elastic compliance
            // 3 (1 - 2 nu) / E vanishes beside the bulk dashpot's and the local system is
            // ill-conditioned, which the harness' round-off allowance now measures
            -0.9..0.49f64,
            log_uniform(1e1, 1e7),
            log_uniform(1e1, 1e7),
        )
            .prop_map(|(e, nu, eta, zeta)| vec![e, nu, eta, zeta])
    }

    // tangent, dsigma1/dsigma0, dr/dc, H, dg/dc against finite differences; the update's
    // residual; affine form and elastic domain (none here): eight proptests of 256 cases
    law_consistency_tests!(consistency, PROFILE, params());

    /// A closed form: under a constant mean stress p (and no deviator) the volume creeps
    /// at p / zeta besides its elastic part, `tr deps = 3 (1 - 2 nu) dp / E + dt p / zeta`
    /// in one backward-Euler step from rest.
    #[test]
    fn mean_stress_creeps_the_volume_at_p_over_zeta() {
        let c = [1000.0, 0.3, 5e4, 2e3];
        let (p, dt) = (-30.0, 0.5);
        let deps = Vec4::ONE * ((3.0 * (1.0 - 2.0 * 0.3) * p / c[0] + dt * p / c[3]) / 3.0);
        let up = BulkMaxwell.update(&c, &Vec4::ZERO, &deps, dt).unwrap();
        assert!(
            (up.sigma - Vec4::ONE * p).max_abs() < 1e-9 * p.abs(),
            "{:?}",
            up.sigma
        );
    }
}
