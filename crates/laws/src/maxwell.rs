//! Maxwell viscoelasticity (paper §4, eqs. 41-43): isotropic elasticity in series with a
//! linear deviatoric dashpot, parameters `[E, nu, eta]`, closed-form local update.

use crate::elastic::{E_INFO, NU_INFO, isotropic_compliance, isotropic_compliance_derivative};
use crate::law::{Law, LocalFailure, LocalUpdate, ParamInfo};
use crate::mandel::{Mat4, Vec4};

/// Maxwell viscoelastic law, parameters `c = [E (MPa), nu (-), eta (MPa s)]`.
///
/// Pseudo-potential `Phi = sigma : P : sigma / (2 eta)` (paper §2.1, `M = P / eta`,
/// eq. 43), hence
///
/// - compliance `S = ((1+nu) I4 - nu 1(x)1) / E` (eq. 42),
/// - flow `g = P sigma / eta` (1/s), Hessian `H = P / eta`,
/// - `dg/deta = -g / eta`; `dS/dE = -S/E`, `dS/dnu = (I4 - 1(x)1)/E`.
///
/// With `J = 1(x)1/3` the spherical projector, `S = P/(2G) + J/(3 kappa)` where
/// `1/(2G) = (1+nu)/E` and `1/(3 kappa) = (1-2nu)/E`, so the backward-Euler Jacobian is
/// isotropic, `A = S + dt P/eta = ((1+nu)/E + dt/eta) P + ((1-2nu)/E) J`, and inverts part
/// by part: `C = P / ((1+nu)/E + dt/eta) + J E/(1-2nu)`. The update and tangent use this
/// closed form (no 4x4 elimination); the tangent depends on `(c, dt)` only.
#[derive(Clone, Copy, Debug, Default)]
pub struct Maxwell;

/// Viscosity metadata.
const ETA_INFO: ParamInfo = ParamInfo {
    name: "eta",
    unit: "MPa s",
    description: "viscosity of the deviatoric dashpot (g = P sigma / eta)",
    min: 0.0,
    min_inclusive: false,
    max: f64::INFINITY,
    max_inclusive: false,
};

const PARAMS: [ParamInfo; 3] = [E_INFO, NU_INFO, ETA_INFO];

/// Index of `eta` in the parameter slice.
const ETA: usize = 2;

/// Deviatoric and spherical coefficients `(a_dev, a_sph)` of the Jacobian
/// `A = a_dev P + a_sph J` (1/MPa).
#[inline]
fn jacobian_parts(c: &[f64], dt: f64) -> (f64, f64) {
    let (e, nu, eta) = (c[0], c[1], c[2]);
    ((1.0 + nu) / e + dt / eta, (1.0 - 2.0 * nu) / e)
}

/// The isotropic operator `a P + b J` with `J = 1(x)1/3`.
#[inline]
pub(crate) fn isotropic_operator(a: f64, b: f64) -> Mat4 {
    Mat4::deviatoric_projector() * a + Mat4::one_one() * (b / 3.0)
}

impl Law for Maxwell {
    fn name(&self) -> &'static str {
        "maxwell"
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
    fn flow(&self, c: &[f64], sigma: &Vec4) -> Vec4 {
        sigma.deviator() * (1.0 / c[ETA])
    }
    fn flow_hessian(&self, c: &[f64], _sigma: &Vec4) -> Mat4 {
        Mat4::deviatoric_projector() * (1.0 / c[ETA])
    }
    fn flow_param_derivative(&self, c: &[f64], sigma: &Vec4, k: usize) -> Vec4 {
        if k == ETA {
            let eta = c[ETA];
            sigma.deviator() * (-1.0 / (eta * eta))
        } else {
            Vec4::ZERO
        }
    }
    fn is_linear(&self) -> bool {
        true
    }
    /// Closed form `C = P / ((1+nu)/E + dt/eta) + J E/(1-2nu)`, independent of `sigma`.
    fn tangent(&self, c: &[f64], _sigma: &Vec4, dt: f64) -> Result<Mat4, LocalFailure> {
        let (a_dev, a_sph) = jacobian_parts(c, dt);
        Ok(isotropic_operator(1.0 / a_dev, 1.0 / a_sph))
    }
    /// Closed-form backward Euler: `s1 = (s0/(2G) + deps_dev) / ((1+nu)/E + dt/eta)` for
    /// the deviators and `tr sigma1 = tr sigma0 + E/(1-2nu) tr deps`.
    ///
    /// # Errors
    /// [`LocalFailure`] on a negative or non-finite `dt` or non-finite input.
    fn update(
        &self,
        c: &[f64],
        s0: &Vec4,
        deps: &Vec4,
        dt: f64,
    ) -> Result<LocalUpdate, LocalFailure> {
        if !dt.is_finite() || dt < 0.0 {
            return Err(LocalFailure {
                reason: format!("maxwell: invalid time step dt = {dt}"),
                suggested_dt_factor: 0.5,
            });
        }
        let (a_dev, a_sph) = jacobian_parts(c, dt);
        let inv_2g = (1.0 + c[1]) / c[0];
        let s1_dev = (s0.deviator() * inv_2g + deps.deviator()) * (1.0 / a_dev);
        let tr1 = s0.trace() + deps.trace() / a_sph;
        let sigma = s1_dev + Vec4::ONE * (tr1 / 3.0);
        if !sigma.is_finite() {
            return Err(LocalFailure {
                reason: format!("maxwell: non-finite stress from s0 = {s0:?}, deps = {deps:?}"),
                suggested_dt_factor: 0.5,
            });
        }
        Ok(LocalUpdate {
            sigma,
            tangent: isotropic_operator(1.0 / a_dev, 1.0 / a_sph),
            iterations: 0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const C: [f64; 3] = [20000.0, 0.3, 30000.0];

    /// The closed-form update solves the backward-Euler residual and its tangent is the
    /// inverse of `S + dt P/eta` computed by elimination.
    #[test]
    fn closed_form_matches_the_generic_residual() {
        let s0 = Vec4([12.0, -40.0, 7.0, 3.0]);
        let deps = Vec4([1e-3, -2e-3, 4e-4, 7e-4]);
        let dt = 0.7;
        let up = Maxwell.update(&C, &s0, &deps, dt).unwrap();
        let r = Maxwell.compliance(&C).mul_vec(&(up.sigma - s0)) + Maxwell.flow(&C, &up.sigma) * dt
            - deps;
        assert!(r.max_abs() < 1e-15, "{r:?}");
        let a = Maxwell.compliance(&C) + Maxwell.flow_hessian(&C, &s0) * dt;
        let c_ref = a.inverse().unwrap();
        assert!((c_ref - up.tangent).max_abs() < 1e-11 * c_ref.max_abs());
        let generic = crate::law::default_newton_update(&Maxwell, &C, &s0, &deps, dt).unwrap();
        assert!((generic.sigma - up.sigma).max_abs() < 1e-10 * up.sigma.max_abs());
    }

    #[test]
    fn flow_is_the_scaled_deviator() {
        let sigma = Vec4([0.0, 300.0, 0.0, 0.0]);
        let g = Maxwell.flow(&C, &sigma);
        assert!((g[1] - 200.0 / C[2]).abs() < 1e-15);
        assert!((g[0] + 100.0 / C[2]).abs() < 1e-15);
        assert!(g.trace().abs() < 1e-15);
    }

    #[test]
    fn parameter_ranges_are_enforced() {
        assert!(Maxwell.check_params(&C).is_ok());
        for (bad, name) in [
            ([20000.0, 0.3, 0.0], "eta"),
            ([20000.0, 0.3, -5.0], "eta"),
            ([0.0, 0.3, 1.0], "E"),
            ([1.0, 0.5, 1.0], "nu"),
            ([1.0, -1.0, 1.0], "nu"),
        ] {
            let err = Maxwell.check_params(&bad).unwrap_err();
            match &err {
                crate::LawError::Parameter { name: n, .. } => assert_eq!(*n, name),
                other => panic!("unexpected {other:?}"),
            }
            let text = err.to_string();
            assert!(text.contains(name) && text.contains("maxwell"), "{text}");
        }
        let text = Maxwell
            .check_params(&[1.0, 0.3, -5.0])
            .unwrap_err()
            .to_string();
        assert!(text.contains("-5") && text.contains("(0, inf)"), "{text}");
        assert!(Maxwell.check_params(&[1.0, 0.3]).is_err());
    }
}
