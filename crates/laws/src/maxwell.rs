//! Maxwell viscoelasticity (paper §4, eqs. 41-43): isotropic elasticity in series with a
//! linear deviatoric dashpot, parameters `[E, nu, eta]`, closed-form local update.

use crate::elastic::{
    E_INFO, NU_INFO, isotropic_compliance, isotropic_compliance_derivative, isotropic_operator,
};
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
    /// `A = P (1+nu)/(E a_dev) + J`, `C` the tangent, with `a_dev = (1+nu)/E + dt/eta`:
    /// the closed form of [`Maxwell::update`] as two operators (`None` for an invalid `dt`).
    fn affine_update(&self, c: &[f64], dt: f64) -> Option<(Mat4, Mat4)> {
        if !dt.is_finite() || dt < 0.0 {
            return None;
        }
        let (a_dev, a_sph) = jacobian_parts(c, dt);
        let inv_2g = (1.0 + c[1]) / c[0];
        Some((
            isotropic_operator(inv_2g / a_dev, 1.0),
            isotropic_operator(1.0 / a_dev, 1.0 / a_sph),
        ))
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
    use crate::testing::{Profile, law_consistency_tests, log_uniform, relative_param_step};
    use proptest::prelude::*;

    const PROFILE: Profile = Profile {
        law: &Maxwell,
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
        (log_uniform(1e2, 1e6), -0.9..0.49f64, log_uniform(1e1, 1e7))
            .prop_map(|(e, nu, eta)| vec![e, nu, eta])
    }
    law_consistency_tests!(consistency, PROFILE, params());

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

    mod uniaxial {
        //! Material-point validation of Maxwell in uniaxial stress against closed forms.
        //!
        //! ```text
        //!        sigma_zz (strain or stress controlled)
        //!           ^
        //!      +----|----+   sigma_rr = sigma_tt = sigma_rz = 0
        //!      |  one    |   (lateral strains free, found by Newton
        //!      |  point  |    with the consistent tangent)
        //!      +---------+
        //! ```
        //!
        //! Axially, with `P sigma = sigma (-1/3, 2/3, -1/3)`, the law reads
        //! `d eps_zz/dt = (d sigma/dt)/E + 2 sigma/(3 eta)`: a spring `E` in series with a
        //! dashpot `3 eta/2`, relaxation time `tau = 3 eta/(2E)`. Parameters of R1
        //! (docs/theory.md §11): `E = 20000 MPa, nu = 0.3, eta = 30000 MPa s`, `tau = 1.125 s`.
        use super::*;
        use crate::testing::{Axial, assert_first_order, uniaxial_history};

        const C: [f64; 3] = [20000.0, 0.3, 30000.0];
        const TAU: f64 = 1.5 * 30000.0 / 20000.0;

        /// Instantaneous (dt = 0, elastic) axial strain step from rest.
        fn strain_step(eps0: f64) -> (Vec4, Vec4) {
            uniaxial_history(&Maxwell, &C, Vec4::ZERO, Vec4::ZERO, 0.0, 1, |_| {
                Axial::Strain(eps0)
            })
        }

        /// Maxwell uniaxial relaxation.
        ///
        /// Reference: `sigma(t) = E eps0 exp(-t/tau)` after a step `eps0` at `t = 0`
        /// (solution of `d sigma/dt = -sigma/tau` at constant strain); backward Euler
        /// gives exactly `sigma_n = E eps0 (1 + dt/tau)^-n`. Goal: the 3D update under
        /// uniaxial stress reproduces the scalar scheme to round-off, and its error to
        /// the exact curve at `T = 2 s` falls at first order.
        #[test]
        fn maxwell_uniaxial_relaxation() {
            let (eps0, t_end) = (1e-3, 2.0);
            let (s_el, e_el) = strain_step(eps0);
            assert!((s_el[1] - C[0] * eps0).abs() < 1e-12 * C[0] * eps0);
            assert!((e_el[0] + C[1] * eps0).abs() < 1e-15 && (e_el[2] - e_el[0]).abs() < 1e-15);
            let exact = C[0] * eps0 * (-t_end / TAU).exp();
            assert_first_order("maxwell relaxation", 10, |n| {
                let dt = t_end / n as f64;
                let (s, _) =
                    uniaxial_history(&Maxwell, &C, s_el, e_el, dt, n, |_| Axial::Strain(0.0));
                let scheme = C[0] * eps0 * (1.0 + dt / TAU).powi(-(n as i32));
                assert!(
                    (s[1] - scheme).abs() < 1e-12 * scheme,
                    "{} vs {scheme}",
                    s[1]
                );
                assert!(s[0].abs() < 1e-12 && s[2].abs() < 1e-12);
                (s[1] - exact).abs() / exact
            });
        }

        /// Maxwell at a constant strain rate.
        ///
        /// Reference: `d sigma/dt = E rate - sigma/tau`, `sigma(0) = 0`, hence
        /// `sigma(t) = E rate tau (1 - exp(-t/tau))`. Goal: first-order convergence of
        /// backward Euler at `T = 2 s`.
        #[test]
        fn maxwell_constant_strain_rate() {
            let (rate, t_end) = (1e-3, 2.0);
            let exact = C[0] * rate * TAU * (1.0 - (-t_end / TAU).exp());
            assert_first_order("maxwell constant strain rate", 10, |n| {
                let dt = t_end / n as f64;
                let (s, e) = uniaxial_history(&Maxwell, &C, Vec4::ZERO, Vec4::ZERO, dt, n, |_| {
                    Axial::Strain(rate * dt)
                });
                assert!((e[1] - rate * t_end).abs() < 1e-15);
                (s[1] - exact).abs() / exact
            });
        }

        /// Maxwell creep under constant stress.
        ///
        /// Reference: after an instantaneous load `sigma0`,
        /// `eps_zz(t) = sigma0/E + 2 sigma0 t/(3 eta)` and
        /// `eps_rr(t) = -nu sigma0/E - sigma0 t/(3 eta)` (incompressible dashpot). The
        /// viscous rate is constant, so backward Euler is *exact* for any step: no
        /// convergence order to observe, the test demands round-off agreement instead.
        #[test]
        fn maxwell_uniaxial_creep() {
            let (sigma0, t_end) = (20.0, 3.0);
            let (s_el, e_el) =
                uniaxial_history(&Maxwell, &C, Vec4::ZERO, Vec4::ZERO, 0.0, 1, |_| {
                    Axial::Stress(sigma0)
                });
            for n in [1, 7, 50] {
                let dt = t_end / n as f64;
                let (s, e) =
                    uniaxial_history(&Maxwell, &C, s_el, e_el, dt, n, |_| Axial::Stress(sigma0));
                let (e_zz, e_rr) = (
                    sigma0 / C[0] + 2.0 * sigma0 * t_end / (3.0 * C[2]),
                    -C[1] * sigma0 / C[0] - sigma0 * t_end / (3.0 * C[2]),
                );
                assert!((s[1] - sigma0).abs() < 1e-12 * sigma0);
                assert!(
                    (e[1] - e_zz).abs() < 1e-13 * e_zz,
                    "n {n}: {} vs {e_zz}",
                    e[1]
                );
                assert!(
                    (e[0] - e_rr).abs() < 1e-13 * e_zz,
                    "n {n}: {} vs {e_rr}",
                    e[0]
                );
                assert!((e[2] - e_rr).abs() < 1e-13 * e_zz);
            }
        }
    }
}
