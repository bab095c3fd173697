//! Norton-Hoff elastoviscoplasticity with a yield stress (paper §2.1 and §5, eqs. 44-46):
//! parameters `[E, nu, K, m, sY]`, scalar radial-return local update, closed-form tangent.

use crate::LawError;
use crate::elastic::{
    E_INFO, NU_INFO, isotropic_compliance, isotropic_compliance_derivative, isotropic_operator,
};
use crate::law::{ElasticDomain, Law, LocalFailure, LocalUpdate, ParamInfo};
use crate::mandel::{Mat4, Vec4};

/// Norton-Hoff law, parameters `c = [E (MPa), nu (-), K (MPa s^(1/m)), m (-), sY (MPa)]`.
///
/// Pseudo-potential (paper §2.1) `Phi = K/(m+1) <(s_eq - sY)/K>_+^(m+1)` with `s` the
/// deviator of `sigma` and `s_eq = sqrt(3/2 s:s)` the von Mises stress. With
/// `x = <(s_eq - sY)/K>_+` (`x^m` in 1/s) and the normal `n = 3 s / (2 s_eq)`
/// (`n:n = 3/2`):
///
/// - flow (eq. 46) `g = dPhi/dsigma = x^m n`; in uniaxial tension `g_zz = x^m`;
/// - Hessian `H = (m/K) x^(m-1) n(x)n + x^m (3/(2 s_eq)) (P - (2/3) n(x)n)`, using
///   `dn/dsigma = (3/(2 s_eq)) (P - (2/3) n(x)n)`;
/// - below yield (`s_eq <= sY`) `g = 0` and `H = 0` (for `m = 1, sY = 0` the law is
///   Maxwell with `eta = 2K/3` and `H = 3P/(2K)` also at `sigma = 0`);
/// - parameter derivatives at fixed stress, from `dx/dK = -x/K` and `dx/dsY = -1/K`:
///   `dg/dK = -(m/K) x^m n`, `dg/dm = x^m ln(x) n` (0 at `x = 0`),
///   `dg/dsY = -(m/K) x^(m-1) n`, as in docs/theory.md §1 (checked against finite
///   differences by the shared consistency tests). `dS/dE`, `dS/dnu` as for elasticity.
///
/// `m = 1` is admitted for forward runs, but the adjoint needs `m > 1`
/// ([`Law::check_differentiable`]): for `m <= 1` the Hessian jumps across the yield
/// surface.
#[derive(Clone, Copy, Debug, Default)]
pub struct NortonHoff;

pub(crate) const K_INFO: ParamInfo = ParamInfo {
    name: "K",
    unit: "MPa s^(1/m)",
    description: "viscosity (drag stress) of the Norton power law",
    min: 0.0,
    min_inclusive: false,
    max: f64::INFINITY,
    max_inclusive: false,
};
pub(crate) const M_INFO: ParamInfo = ParamInfo {
    name: "m",
    unit: "-",
    description: "Norton exponent (m > 1 needed for the adjoint)",
    min: 1.0,
    min_inclusive: true,
    max: f64::INFINITY,
    max_inclusive: false,
};
const SY_INFO: ParamInfo = ParamInfo {
    name: "sY",
    unit: "MPa",
    description: "yield (elasticity limit) stress",
    min: 0.0,
    min_inclusive: true,
    max: f64::INFINITY,
    max_inclusive: false,
};

const PARAMS: [ParamInfo; 5] = [E_INFO, NU_INFO, K_INFO, M_INFO, SY_INFO];

/// Index of `K` in the parameter slice.
const K: usize = 2;
/// Index of `m` in the parameter slice.
const M: usize = 3;
/// Index of `sY` in the parameter slice.
const SY: usize = 4;

/// Viscoplastic state at one stress above yield.
struct Overstress {
    /// `x = (s_eq - sY)/K > 0`.
    x: f64,
    /// von Mises stress `s_eq > 0` (MPa).
    s_eq: f64,
    /// Normal `n = 3 s / (2 s_eq)`.
    n: Vec4,
}

/// The overstress at `sigma`, `None` at or below yield.
fn overstress(c: &[f64], sigma: &Vec4) -> Option<Overstress> {
    let s = sigma.deviator();
    let s_eq = (1.5 * s.dot(&s)).sqrt();
    let x = (s_eq - c[SY]) / c[K];
    (x > 0.0 && s_eq > 0.0).then(|| Overstress {
        x,
        s_eq,
        n: s * (1.5 / s_eq),
    })
}

/// Consistent tangent `(S + dt H)^-1` in closed form.
///
/// With the unit normal `N = sqrt(2/3) n` and `J = 1(x)1/3`,
/// `S = P/(2G) + J/(3 kappa)` and `H = a (P - N(x)N) + (3/2) b N(x)N` where
/// `a = 3 x^m / (2 s_eq)`, `b = (m/K) x^(m-1)`. All three projectors `P - N(x)N`,
/// `N(x)N`, `J` are orthogonal, so
/// `C = (P - N(x)N)/alpha + N(x)N/beta + 3 kappa J` with `alpha = 1/(2G) + dt a` and
/// `beta = 1/(2G) + (3/2) dt b`.
fn closed_tangent(c: &[f64], over: Option<&Overstress>, dt: f64) -> Mat4 {
    let (e, nu, k, m, sy) = (c[0], c[1], c[K], c[M], c[SY]);
    let inv_2g = (1.0 + nu) / e;
    let kappa3 = e / (1.0 - 2.0 * nu);
    match over {
        Some(o) => {
            let xm1 = o.x.powf(m - 1.0);
            let alpha = inv_2g + dt * 1.5 * (xm1 * o.x) / o.s_eq;
            let beta = inv_2g + dt * 1.5 * (m / k) * xm1;
            let unit = o.n * (2.0f64 / 3.0).sqrt();
            let nn = unit.outer(&unit);
            isotropic_operator(1.0 / alpha, kappa3) + nn * (1.0 / beta - 1.0 / alpha)
        }
        // Maxwell limit m = 1, sY = 0 at s = 0: H = 3P/(2K).
        None if m == 1.0 && sy == 0.0 => isotropic_operator(1.0 / (inv_2g + 1.5 * dt / k), kappa3),
        None => isotropic_operator(e / (1.0 + nu), kappa3),
    }
}

fn failure(reason: String) -> LocalFailure {
    LocalFailure {
        reason,
        suggested_dt_factor: 0.25,
    }
}

/// Solves the scalar return equation `K x + b x^m = d` for `x > 0` (`b = 3 G dt >= 0`,
/// `d = s_eq_trial - sY > 0`, `m >= 1`), returning `(x, iterations)`.
///
/// The root lies in `[x_lo, x_hi]` with `x_hi = min(d/K, (d/b)^(1/m))` (one term alone
/// reaches `d`) and `x_lo = min(d/(2K), (d/(2b))^(1/m))` (neither term exceeds `d/2`),
/// a bracket of ratio at most 2. Newton runs on `h(y) = ln(K e^y + b e^(m y)) - ln d`
/// in `y = ln x`: `h` is increasing and convex (log-sum-exp of affine functions), with
/// slope in `[1, m]`, so Newton started at `y_hi` decreases monotonically onto the root
/// whatever `m`, `dt` or the size of the step; all terms are formed in logarithms, so
/// nothing overflows. A bisection fallback guards against round-off, and two Newton
/// steps in `x` polish the root to a relative residual of a few ulps. At most 8
/// iterations over 23,400 cases spanning `m` in [1, 50] and 25 decades of `3G dt`
/// (test `return_equation_converges_fast_over_a_wide_grid`).
///
/// # Errors
/// [`LocalFailure`] when the bracket is not finite (non-positive or non-finite inputs)
/// or after 200 iterations.
pub(crate) fn solve_overstress(k: f64, b: f64, m: f64, d: f64) -> Result<(f64, u32), LocalFailure> {
    if b == 0.0 {
        return Ok((d / k, 0));
    }
    let (ln_k, ln_b, ln_d) = (k.ln(), b.ln(), d.ln());
    let ln_pow = |ln_num: f64| ln_num / m;
    // The exact bounds, widened by a few ulps so that round-off in forming them cannot
    // exclude a root sitting on one of them (e.g. m = 1 and K = 3G dt: x = x_lo).
    let widen = |y: f64| 1e-13 * (1.0 + y.abs());
    let mut y_hi = (ln_d - ln_k).min(ln_pow(ln_d - ln_b));
    y_hi += widen(y_hi);
    let mut y_lo =
        (ln_d - ln_k - std::f64::consts::LN_2).min(ln_pow(ln_d - ln_b - std::f64::consts::LN_2));
    y_lo -= widen(y_lo);
    if !(y_hi.is_finite() && y_lo.is_finite()) {
        return Err(failure(format!(
            "norton-hoff: cannot bracket the return equation (K = {k}, 3G dt = {b}, m = {m}, overstress = {d})"
        )));
    }
    let mut y = y_hi;
    for it in 1..=200u32 {
        // h(y) = ln(K e^y + b e^(m y)) - ln d as a log-sum-exp.
        let (l1, l2) = (ln_k + y, ln_b + m * y);
        let lmax = l1.max(l2);
        let (w1, w2) = ((l1 - lmax).exp(), (l2 - lmax).exp());
        let h = lmax + (w1 + w2).ln() - ln_d;
        let slope = (w1 + m * w2) / (w1 + w2);
        if h > 0.0 {
            y_hi = y;
        } else {
            y_lo = y;
        }
        let dy = -h / slope;
        // Newton converges quadratically: once the step is below 1e-10 (relative in x)
        // the next iterate is exact to round-off; the polish below finishes in x.
        let converged = h == 0.0 || dy.abs() <= 1e-10;
        y = if converged || (y + dy >= y_lo && y + dy <= y_hi) {
            y + dy
        } else {
            // Outside the (closed) bracket, or NaN: bisect.
            0.5 * (y_lo + y_hi)
        };
        if converged || y_hi - y_lo <= 1e-15 * (1.0 + y.abs()) {
            // Polish in x: f(x) = K x + b x^m - d, f' = K + m b x^(m-1).
            let mut x = y.exp();
            for _ in 0..2 {
                let xm1 = x.powf(m - 1.0);
                let f = k * x + b * xm1 * x - d;
                let x_new = x - f / (k + m * b * xm1);
                if x_new.is_finite() && x_new > 0.0 {
                    x = x_new;
                }
            }
            return Ok((x, it));
        }
    }
    Err(failure(format!(
        "norton-hoff: return equation did not converge (K = {k}, 3G dt = {b}, m = {m}, overstress = {d})"
    )))
}

impl Law for NortonHoff {
    fn name(&self) -> &'static str {
        "norton-hoff"
    }
    fn elastic_domain(&self, c: &[f64], dt: f64) -> Option<ElasticDomain> {
        // below yield the tangent is the update's own (sY > 0: not the Maxwell limit)
        (c[SY] > 0.0).then(|| ElasticDomain {
            stiffness: closed_tangent(c, None, dt),
            yield_stress: c[SY],
        })
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
        match overstress(c, sigma) {
            Some(o) => o.n * o.x.powf(c[M]),
            None => Vec4::ZERO,
        }
    }
    fn flow_hessian(&self, c: &[f64], sigma: &Vec4) -> Mat4 {
        let (k, m) = (c[K], c[M]);
        match overstress(c, sigma) {
            Some(o) => {
                let nn = o.n.outer(&o.n);
                let a = o.x.powf(m) * 1.5 / o.s_eq;
                nn * ((m / k) * o.x.powf(m - 1.0))
                    + (Mat4::deviatoric_projector() - nn * (2.0 / 3.0)) * a
            }
            None if m == 1.0 && c[SY] == 0.0 => Mat4::deviatoric_projector() * (1.5 / k),
            None => Mat4::ZERO,
        }
    }
    fn flow_param_derivative(&self, c: &[f64], sigma: &Vec4, k: usize) -> Vec4 {
        let Some(o) = overstress(c, sigma) else {
            return Vec4::ZERO;
        };
        let (kk, m) = (c[K], c[M]);
        match k {
            K => o.n * (-(m / kk) * o.x.powf(m)),
            M => o.n * (o.x.powf(m) * o.x.ln()),
            SY => o.n * (-(m / kk) * o.x.powf(m - 1.0)),
            _ => Vec4::ZERO,
        }
    }
    /// The overstress and `x^m` once for the three parameters of the flow (the same
    /// expressions as [`Law::flow_param_derivative`], so the same bits).
    fn flow_param_derivatives(&self, c: &[f64], sigma: &Vec4, out: &mut [Vec4]) {
        out.fill(Vec4::ZERO);
        let Some(o) = overstress(c, sigma) else {
            return;
        };
        let (kk, m) = (c[K], c[M]);
        let xm = o.x.powf(m);
        for (k, d) in out.iter_mut().enumerate() {
            *d = match k {
                K => o.n * (-(m / kk) * xm),
                M => o.n * (xm * o.x.ln()),
                SY => o.n * (-(m / kk) * o.x.powf(m - 1.0)),
                _ => Vec4::ZERO,
            };
        }
    }
    /// `m > 1` is required: `Phi` must be twice differentiable in `sigma` for the adjoint
    /// state to exist (paper §3.3).
    ///
    /// # Errors
    /// [`LawError::NotDifferentiable`] naming `m` when `m <= 1`.
    fn check_differentiable(&self, c: &[f64]) -> Result<(), LawError> {
        let m = c[M];
        if m > 1.0 {
            Ok(())
        } else {
            Err(LawError::NotDifferentiable {
                law: self.name(),
                name: "m",
                value: m,
                why: "the adjoint needs m > 1: Phi = K/(m+1) <(s_eq - sY)/K>_+^(m+1) must be \
                      twice differentiable in sigma (paper §3.3), and for m <= 1 its Hessian \
                      jumps across the yield surface",
            })
        }
    }
    /// Closed form of `(S + dt H(sigma))^-1`, see [`NortonHoff`]; never singular.
    fn tangent(&self, c: &[f64], sigma: &Vec4, dt: f64) -> Result<Mat4, LocalFailure> {
        Ok(closed_tangent(c, overstress(c, sigma).as_ref(), dt))
    }
    /// Radial return: backward Euler reduced to one scalar equation.
    ///
    /// Split `sigma = s + (tr sigma/3) 1` and `S = P/(2G) + J/(3 kappa)` with
    /// `G = E/(2(1+nu))`, `3 kappa = E/(1-2nu)`. The flow is deviatoric, so the trace
    /// part of `r(sigma1) = S (sigma1 - sigma0) + dt g(sigma1) - deps = 0` gives
    /// `tr sigma1 = tr sigma0 + 3 kappa tr deps`, and the deviatoric part, with the trial
    /// deviator `s_tr = s0 + 2G dev(deps)`, reads
    /// `s1 + 2G dt x1^m (3 s1 / (2 s_eq1)) = s_tr`, i.e.
    /// `s1 (1 + 3G dt x1^m / s_eq1) = s_tr`. The factor is a positive scalar, so `s1` is
    /// parallel to `s_tr`: `s1 = s_tr s_eq1 / s_eq_tr`, and taking von Mises norms,
    /// `s_eq1 + 3G dt <(s_eq1 - sY)/K>_+^m = s_eq_tr`. If `s_eq_tr <= sY` the step is
    /// elastic (`s_eq1 = s_eq_tr` solves it with `x = 0`, and the left side is
    /// increasing, so the root is unique). Otherwise `s_eq1 = sY + K x` with `x > 0` the
    /// root of `K x + 3G dt x^m = s_eq_tr - sY`, solved by a safeguarded Newton in
    /// `ln x` (see the bracket in the source). The tangent is the closed form of
    /// [`Law::tangent`] at the converged state, the exact derivative of this map (below
    /// yield the elastic stiffness, also that of [`Law::elastic_domain`]).
    ///
    /// # Errors
    /// [`LocalFailure`] on non-finite input or a negative `dt`, or when the scalar
    /// equation cannot be solved.
    fn update(
        &self,
        c: &[f64],
        s0: &Vec4,
        deps: &Vec4,
        dt: f64,
    ) -> Result<LocalUpdate, LocalFailure> {
        if !dt.is_finite() || dt < 0.0 || !s0.is_finite() || !deps.is_finite() {
            return Err(failure(format!(
                "norton-hoff: invalid input dt = {dt}, s0 = {s0:?}, deps = {deps:?}"
            )));
        }
        let (e, nu, k, m, sy) = (c[0], c[1], c[K], c[M], c[SY]);
        let g2 = e / (1.0 + nu);
        let kappa3 = e / (1.0 - 2.0 * nu);
        let s_tr = s0.deviator() + deps.deviator() * g2;
        let spherical = Vec4::ONE * ((s0.trace() + kappa3 * deps.trace()) / 3.0);
        let s_eq_tr = (1.5 * s_tr.dot(&s_tr)).sqrt();
        let d = s_eq_tr - sy;
        let (sigma, over, iterations) = if d > 0.0 && s_eq_tr > 0.0 {
            let (x, it) = solve_overstress(k, 1.5 * g2 * dt, m, d)?;
            let s_eq = sy + k * x;
            let s1 = s_tr * (s_eq / s_eq_tr);
            let over = Overstress {
                x,
                s_eq,
                n: s_tr * (1.5 / s_eq_tr),
            };
            (s1 + spherical, Some(over), it)
        } else {
            (s_tr + spherical, None, 0)
        };
        if !sigma.is_finite() {
            return Err(failure(format!(
                "norton-hoff: non-finite stress from s0 = {s0:?}, deps = {deps:?}, dt = {dt}"
            )));
        }
        Ok(LocalUpdate {
            sigma,
            tangent: closed_tangent(c, over.as_ref(), dt),
            iterations,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{Profile, law_consistency_tests, log_uniform, relative_param_step};
    use proptest::prelude::*;

    const PROFILE: Profile = Profile {
        law: &NortonHoff,
        stress_scale,
        smooth_length,
        param_step,
    };
    fn stress_scale(c: &[f64]) -> f64 {
        c[SY] + c[K]
    }
    /// Above yield `x^m` varies on the scale `(s_eq - sY)/m`; below, `g = 0` within the
    /// distance `sY - s_eq` of the yield surface. `m = 1, sY = 0` is linear (Maxwell).
    fn smooth_length(c: &[f64], sigma: &Vec4) -> f64 {
        if c[M] == 1.0 && c[SY] == 0.0 {
            return f64::INFINITY;
        }
        let d = sigma.von_mises() - c[SY];
        if d > 0.0 { d / c[M] } else { -d }
    }
    /// A step in `sY` must not cross the yield surface (even for `m = 1, sY = 0`, where
    /// `g` is smooth in `sigma` but not in `sY`): 1e-3 of `|s_eq - sY| / m`.
    fn param_step(c: &[f64], sigma: &Vec4, k: usize) -> f64 {
        if k == SY {
            let d = (sigma.von_mises() - c[SY]).abs() / c[M];
            1e-3 * d.min(c[K] + c[SY]).max(1e-9 * (c[K] + c[SY]))
        } else {
            relative_param_step(c, sigma, k)
        }
    }
    fn params() -> impl Strategy<Value = Vec<f64>> {
        (
            log_uniform(1e4, 3e5),
            -0.5..0.49f64,
            log_uniform(10.0, 5000.0),
            prop_oneof![Just(1.0), 1.0..20.0f64],
            prop_oneof![Just(0.0), 0.0..1000.0f64],
        )
            .prop_map(|(e, nu, k, m, sy)| vec![e, nu, k, m, sy])
    }
    law_consistency_tests!(consistency, PROFILE, params());

    /// Reference problem R2 (docs/theory.md §11).
    const C: [f64; 5] = [1e5, 0.3, 1500.0, 5.0, 500.0];

    fn residual(c: &[f64], s0: &Vec4, s1: &Vec4, deps: &Vec4, dt: f64) -> Vec4 {
        NortonHoff.compliance(c).mul_vec(&(*s1 - *s0)) + NortonHoff.flow(c, s1) * dt - *deps
    }

    #[test]
    fn uniaxial_flow_is_the_norton_rate() {
        let g = NortonHoff.flow(&C, &Vec4([0.0, 800.0, 0.0, 0.0]));
        let rate = (300.0f64 / 1500.0).powi(5);
        assert!((g[1] - rate).abs() < 1e-15 * rate);
        assert!((g[0] + 0.5 * rate).abs() < 1e-15 * rate);
        assert_eq!(
            NortonHoff.flow(&C, &Vec4([0.0, 499.0, 0.0, 0.0])),
            Vec4::ZERO
        );
    }

    /// Inside the elastic domain the update is the elastic trial stress with the elastic
    /// tangent; a step that crosses the yield surface leaves the domain; without a yield
    /// stress there is no domain.
    #[test]
    fn elastic_domain_is_the_update_below_yield() {
        let domain = NortonHoff.elastic_domain(&C, 0.1).unwrap();
        assert_eq!(domain.yield_stress, 500.0);
        let s0 = Vec4([100.0, -200.0, 50.0, 30.0]);
        let small = Vec4([1e-4, -2e-4, 0.5e-4, 1e-4]);
        let up = NortonHoff.update(&C, &s0, &small, 0.1).unwrap();
        let trial = domain.update(&s0, &small).expect("an elastic step");
        assert!((trial - up.sigma).max_abs() < 1e-12 * up.sigma.max_abs());
        assert!((domain.stiffness - up.tangent).max_abs() < 1e-14 * up.tangent.max_abs());
        assert_eq!(up.iterations, 0);
        let large = small * 50.0;
        assert!(domain.update(&s0, &large).is_none());
        assert!(NortonHoff.update(&C, &s0, &large, 0.1).unwrap().iterations > 0);
        let mut no_yield = C;
        no_yield[SY] = 0.0;
        assert!(NortonHoff.elastic_domain(&no_yield, 0.1).is_none());
    }

    /// The closed-form tangent is the inverse of `S + dt H` built from the Hessian.
    #[test]
    fn closed_tangent_inverts_the_local_jacobian() {
        let sigma = Vec4([100.0, 900.0, -50.0, 300.0]);
        let dt = 0.3;
        let a = NortonHoff.compliance(&C) + NortonHoff.flow_hessian(&C, &sigma) * dt;
        let t = NortonHoff.tangent(&C, &sigma, dt).unwrap();
        assert!((a.mul_mat(&t) - Mat4::IDENTITY).max_abs() < 1e-12);
    }

    /// The scalar return map converges for huge steps and exponents, agreeing with the
    /// backward-Euler residual to round-off. (Re-evaluating `x = (s_eq - sY)/K` from the
    /// stress components loses `eps |sigma| / (K x)` relative accuracy, ~1e-11 for the
    /// worst case here, a 1 MPa overstress on a 1e5 MPa trial stress.)
    #[test]
    fn return_map_survives_huge_steps_and_exponents() {
        for m in [1.0, 1.5, 5.0, 20.0, 100.0] {
            for (scale, dt) in [(1e-6, 1e-6), (1e-2, 1.0), (1.0, 1e3), (10.0, 1e-9)] {
                let c = [1e5, 0.3, 1500.0, m, 500.0];
                let s0 = Vec4([10.0, 20.0, -30.0, 5.0]);
                let deps = Vec4([0.3, -1.0, 0.2, 0.4]) * scale;
                let up = NortonHoff.update(&c, &s0, &deps, dt).unwrap();
                let r = residual(&c, &s0, &up.sigma, &deps, dt);
                let sc = deps.max_abs() + NortonHoff.compliance(&c).mul_vec(&up.sigma).max_abs();
                assert!(r.max_abs() <= 1e-10 * sc, "m {m} scale {scale}: {r:?}");
                assert!(up.iterations <= 8, "m {m}: {} iterations", up.iterations);
            }
        }
    }

    #[test]
    fn non_finite_input_is_a_local_failure() {
        let s0 = Vec4::ZERO;
        let nan = Vec4([f64::NAN, 0.0, 0.0, 0.0]);
        let ok = Vec4([0.0, 1e-2, 0.0, 0.0]);
        let f = NortonHoff.update(&C, &s0, &nan, 0.1).unwrap_err();
        assert!(f.suggested_dt_factor < 1.0 && f.reason.contains("norton-hoff"));
        assert!(NortonHoff.update(&C, &s0, &ok, f64::INFINITY).is_err());
        assert!(NortonHoff.update(&C, &s0, &ok, -1.0).is_err());
        assert!(NortonHoff.update(&C, &nan, &ok, 1.0).is_err());
    }

    #[test]
    fn parameter_ranges_are_enforced() {
        assert!(NortonHoff.check_params(&C).is_ok());
        assert!(
            NortonHoff
                .check_params(&[1e5, 0.3, 1500.0, 1.0, 0.0])
                .is_ok()
        );
        for (bad, name, range) in [
            ([1e5, 0.3, 0.0, 5.0, 500.0], "K", "(0, inf)"),
            ([1e5, 0.3, -2.0, 5.0, 500.0], "K", "(0, inf)"),
            ([1e5, 0.3, 1500.0, 0.5, 500.0], "m", "[1, inf)"),
            ([1e5, 0.3, 1500.0, 5.0, -1.0], "sY", "[0, inf)"),
            ([1e5, 0.5, 1500.0, 5.0, 500.0], "nu", "(-1, 0.5)"),
            ([1e5, -1.2, 1500.0, 5.0, 500.0], "nu", "(-1, 0.5)"),
            ([-1e5, 0.3, 1500.0, 5.0, 500.0], "E", "(0, inf)"),
            ([1e5, 0.3, 1500.0, f64::NAN, 500.0], "m", "[1, inf)"),
        ] {
            let err = NortonHoff.check_params(&bad).unwrap_err();
            match &err {
                LawError::Parameter { name: n, .. } => assert_eq!(*n, name),
                other => panic!("unexpected {other:?}"),
            }
            let text = err.to_string();
            assert!(
                text.contains(&format!("`{name}`")) && text.contains(range),
                "{text}"
            );
        }
        let text = NortonHoff
            .check_params(&[1e5, 0.3, 1500.0, 0.5, 500.0])
            .unwrap_err()
            .to_string();
        assert!(
            text.contains("0.5") && text.contains("norton-hoff"),
            "{text}"
        );
    }

    #[test]
    fn adjoint_requires_m_above_one() {
        assert!(NortonHoff.check_differentiable(&C).is_ok());
        for m in [1.0, 0.7] {
            let err = NortonHoff
                .check_differentiable(&[1e5, 0.3, 1500.0, m, 500.0])
                .unwrap_err();
            assert!(
                matches!(err, LawError::NotDifferentiable { name: "m", value, .. } if value == m)
            );
            assert!(err.to_string().contains("twice differentiable"));
        }
    }

    /// The system shall solve the scalar return equation `K x + 3G dt x^m = d` to a
    /// relative residual of 1e-14 in at most 8 Newton iterations over 23,400 cases:
    /// `m` from 1 to 50, `K` over 9 decades, `3G dt` over 25, overstress `d` over 13.
    #[test]
    fn return_equation_converges_fast_over_a_wide_grid() {
        let mut worst = 0;
        for m in [1.0, 1.1, 1.5, 2.0, 5.0, 10.0, 20.0, 50.0] {
            for lk in -2..=6 {
                for lb in -12..=12 {
                    for ld in -6..=6 {
                        let (k, b, d) = (10f64.powi(lk), 10f64.powi(lb), 10f64.powi(ld));
                        let (x, it) = solve_overstress(k, b, m, d).unwrap();
                        let f = k * x + b * x.powf(m) - d;
                        assert!(f.abs() <= 1e-14 * d, "m {m} K {k} b {b} d {d}: f = {f}");
                        worst = worst.max(it);
                    }
                }
            }
        }
        assert!(worst <= 8, "{worst} iterations");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(crate::testing::proptest_cases()))]

        /// The system shall reduce Norton-Hoff with `m = 1, sY = 0` to Maxwell with
        /// `eta = 2K/3`: `g = x n = (s_eq/K) 3 s/(2 s_eq) = 3 s/(2K) = s/eta`, so the
        /// updates, tangents, flows, Hessians coincide and `dg/dK = (2/3) dg/deta`.
        #[test]
        fn m_one_without_yield_is_maxwell_with_eta_two_thirds_k(
            e in log_uniform(1e3, 1e6),
            nu in -0.9..0.49f64,
            k in log_uniform(1.0, 1e5),
            a in prop::array::uniform4(-1.0..1.0f64),
            b in prop::array::uniform4(-1.0..1.0f64),
            mag in -5.0..0.0f64,
            dt in log_uniform(1e-4, 1e2),
        ) {
            use crate::maxwell::Maxwell;
            let nh = [e, nu, k, 1.0, 0.0];
            let mx = [e, nu, 2.0 * k / 3.0];
            let s0 = Vec4(a) * (1e-3 * e);
            let deps = Vec4(b) * 10f64.powf(mag);
            let u_nh = NortonHoff.update(&nh, &s0, &deps, dt).unwrap();
            let u_mx = Maxwell.update(&mx, &s0, &deps, dt).unwrap();
            let scale = u_mx.sigma.max_abs() + s0.max_abs();
            prop_assert!((u_nh.sigma - u_mx.sigma).max_abs() <= 1e-12 * scale,
                "{:?} vs {:?}", u_nh.sigma, u_mx.sigma);
            prop_assert!((u_nh.tangent - u_mx.tangent).max_abs()
                <= 1e-12 * u_mx.tangent.max_abs());
            for sigma in [s0, u_mx.sigma] {
                let (g_nh, g_mx) = (NortonHoff.flow(&nh, &sigma), Maxwell.flow(&mx, &sigma));
                prop_assert!((g_nh - g_mx).max_abs() <= 1e-12 * g_mx.max_abs());
                let (h_nh, h_mx) =
                    (NortonHoff.flow_hessian(&nh, &sigma), Maxwell.flow_hessian(&mx, &sigma));
                prop_assert!((h_nh - h_mx).max_abs() <= 1e-12 * h_mx.max_abs());
                let dk = NortonHoff.flow_param_derivative(&nh, &sigma, K);
                let deta = Maxwell.flow_param_derivative(&mx, &sigma, 2) * (2.0 / 3.0);
                prop_assert!((dk - deta).max_abs() <= 1e-12 * deta.max_abs());
            }
            // At sigma = 0 too (the Hessian's special case).
            let zero = NortonHoff.flow_hessian(&nh, &Vec4::ZERO);
            prop_assert!((zero - Maxwell.flow_hessian(&mx, &Vec4::ZERO)).max_abs()
                <= 1e-12 * zero.max_abs());
        }
    }

    mod uniaxial {
        //! Material-point validation of Norton-Hoff in uniaxial stress against closed
        //! forms (and one high-accuracy ODE integration).
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
        //! In uniaxial stress `sigma > 0`: `s_eq = sigma`, `n_zz = 1`,
        //! `n_rr = n_tt = -1/2`, so `d eps_zz/dt = (d sigma/dt)/E + <(sigma - sY)/K>_+^m`
        //! and the plastic flow is incompressible. Backward Euler on the 3D law reduces to
        //! backward Euler on this scalar equation. Parameters of R2 (docs/theory.md §11):
        //! `E = 1e5 MPa, nu = 0.3, K = 1500 MPa s^(1/5), m = 5, sY = 500 MPa`.
        use super::*;
        use crate::testing::{Axial, assert_first_order, uniaxial_history};

        const E: f64 = C[0];
        const KK: f64 = C[K];
        const MM: f64 = C[M];
        const SYY: f64 = C[SY];

        fn rate(sigma: f64) -> f64 {
            ((sigma - SYY) / KK).max(0.0).powf(MM)
        }

        /// Norton creep at constant stress.
        ///
        /// Reference: after an instantaneous load `sigma0`, the plastic rate is the
        /// constant `((sigma0 - sY)/K)^m`, so `eps_zz(t) = sigma0/E + rate t` and
        /// `eps_rr(t) = -nu sigma0/E - rate t/2`; below yield no creep. Backward Euler is
        /// exact for a constant rate: the test demands round-off agreement for any step.
        #[test]
        fn norton_hoff_uniaxial_creep() {
            let t_end = 10.0;
            for sigma0 in [400.0, 800.0, 1200.0] {
                let (s_el, e_el) =
                    uniaxial_history(&NortonHoff, &C, Vec4::ZERO, Vec4::ZERO, 0.0, 1, |_| {
                        Axial::Stress(sigma0)
                    });
                assert!((e_el[1] - sigma0 / E).abs() < 1e-15);
                for n in [1, 7, 50] {
                    let dt = t_end / n as f64;
                    let (s, e) = uniaxial_history(&NortonHoff, &C, s_el, e_el, dt, n, |_| {
                        Axial::Stress(sigma0)
                    });
                    let e_zz = sigma0 / E + rate(sigma0) * t_end;
                    let e_rr = -C[1] * sigma0 / E - 0.5 * rate(sigma0) * t_end;
                    assert!((s[1] - sigma0).abs() < 1e-12 * sigma0);
                    assert!(
                        (e[1] - e_zz).abs() < 1e-13 * e_zz,
                        "{sigma0} {n}: {} vs {e_zz}",
                        e[1]
                    );
                    assert!(
                        (e[0] - e_rr).abs() < 1e-13 * e_zz,
                        "{sigma0} {n}: {} vs {e_rr}",
                        e[0]
                    );
                }
            }
            // The plastic rate itself: ((800 - 500)/1500)^5 = 3.2e-4 /s.
            assert!((rate(800.0) - 3.2e-4).abs() < 1e-18);
        }

        /// Norton relaxation at constant strain.
        ///
        /// Reference: with `u = sigma - sY > 0`, constant strain gives
        /// `du/dt = -E (u/K)^m`, separable:
        /// `u(t) = [u0^(1-m) + (m-1) E t / K^m]^(-1/(m-1))` (closed form, `m > 1`, any
        /// `sY >= 0`; `u` stays positive, the stress tends to `sY`). Step: `sigma0 = 1000
        /// MPa` applied instantaneously. Goal: first-order convergence at `T = 1 s`.
        #[test]
        fn norton_hoff_uniaxial_relaxation() {
            let (sigma0, t_end) = (1000.0, 1.0);
            let (s_el, e_el) =
                uniaxial_history(&NortonHoff, &C, Vec4::ZERO, Vec4::ZERO, 0.0, 1, |_| {
                    Axial::Strain(sigma0 / E)
                });
            assert!((s_el[1] - sigma0).abs() < 1e-12 * sigma0);
            let u0: f64 = sigma0 - SYY;
            let exact = SYY
                + (u0.powf(1.0 - MM) + (MM - 1.0) * E * t_end / KK.powf(MM))
                    .powf(-1.0 / (MM - 1.0));
            assert!(exact > SYY + 100.0 && exact < sigma0 - 100.0, "{exact}");
            assert_first_order("norton-hoff relaxation", 20, |n| {
                let dt = t_end / n as f64;
                let (s, _) =
                    uniaxial_history(&NortonHoff, &C, s_el, e_el, dt, n, |_| Axial::Strain(0.0));
                assert!(s[0].abs() < 1e-10 && s[2].abs() < 1e-10);
                (s[1] - exact).abs() / exact
            });
        }

        /// Norton steady flow stress at a constant strain rate.
        ///
        /// Reference: `d sigma/dt = E (rate - ((sigma - sY)/K)^m)` has the stable fixed
        /// point `sigma_ss = sY + K rate^(1/m)`, reached exponentially (rate
        /// `E m x^(m-1)/K`, about 8.4 /s here). Backward Euler has the same fixed point,
        /// so after the transient the computed stress equals `sigma_ss` to round-off
        /// whatever the step. Goal: `sigma(5 s) = sigma_ss` to 1e-9 for 50 and 500 steps.
        #[test]
        fn norton_hoff_steady_stress_at_constant_strain_rate() {
            let (eps_rate, t_end): (f64, f64) = (1e-2, 5.0);
            let sigma_ss = SYY + KK * eps_rate.powf(1.0 / MM);
            for n in [50, 500] {
                let dt = t_end / n as f64;
                let (s, _) =
                    uniaxial_history(&NortonHoff, &C, Vec4::ZERO, Vec4::ZERO, dt, n, |_| {
                        Axial::Strain(eps_rate * dt)
                    });
                assert!(
                    (s[1] - sigma_ss).abs() < 1e-9 * sigma_ss,
                    "n {n}: {} vs {sigma_ss}",
                    s[1]
                );
            }
        }

        /// Norton transient at a constant strain rate.
        ///
        /// Reference: no closed form for the transient of
        /// `d sigma/dt = E (rate - <(sigma - sY)/K>_+^m)`, `sigma(0) = 0`; the reference
        /// is this scalar ODE integrated by classical RK4 with 2^17 steps (error ~1e-15
        /// relative, the right-hand side being C^4 across yield for m = 5). Yield at
        /// 0.5 s; goal: first-order convergence of backward Euler at `T = 0.8 s`.
        #[test]
        fn norton_hoff_constant_strain_rate_transient() {
            let (eps_rate, t_end) = (1e-2, 0.8);
            let f = |sig: f64| E * (eps_rate - rate(sig));
            let steps = 1 << 17;
            let h = t_end / steps as f64;
            let mut sig = 0.0;
            for _ in 0..steps {
                let k1 = f(sig);
                let k2 = f(sig + 0.5 * h * k1);
                let k3 = f(sig + 0.5 * h * k2);
                let k4 = f(sig + h * k3);
                sig += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            }
            let exact = sig;
            assert!(exact > SYY + 100.0, "{exact}");
            assert_first_order("norton-hoff constant strain rate", 40, |n| {
                let dt = t_end / n as f64;
                let (s, _) =
                    uniaxial_history(&NortonHoff, &C, Vec4::ZERO, Vec4::ZERO, dt, n, |_| {
                        Axial::Strain(eps_rate * dt)
                    });
                (s[1] - exact).abs() / exact
            });
        }
    }
}
