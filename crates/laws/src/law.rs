//! The standard-generalized-material trait: compliance `S(c)`, flow `g = dPhi/dsigma`, its
//! Hessian `H`, parameter derivatives and the implicit (backward Euler) local update.

use crate::LawError;
use crate::mandel::{Mat4, Vec4};

/// Metadata of one material parameter: name, unit and admissible range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamInfo {
    /// Short name as used in configs and reports (`E`, `nu`, `eta`, `K`, `m`, `sY`).
    pub name: &'static str,
    /// Unit in the internal system (N, mm, s, MPa).
    pub unit: &'static str,
    /// One-line description.
    pub description: &'static str,
    /// Lower bound of the admissible range.
    pub min: f64,
    /// Whether `min` itself is admissible.
    pub min_inclusive: bool,
    /// Upper bound of the admissible range.
    pub max: f64,
    /// Whether `max` itself is admissible.
    pub max_inclusive: bool,
}

impl ParamInfo {
    /// `true` when `v` is finite and inside the admissible range.
    pub fn admits(&self, v: f64) -> bool {
        v.is_finite()
            && (v > self.min || (self.min_inclusive && v == self.min))
            && (v < self.max || (self.max_inclusive && v == self.max))
    }
    /// The admissible range in interval notation, e.g. `(0, inf)` or `(-1, 0.5)`.
    pub fn range_text(&self) -> String {
        let fmt = |v: f64| {
            if v.is_infinite() {
                if v > 0.0 { "inf".into() } else { "-inf".into() }
            } else {
                format!("{v}")
            }
        };
        format!(
            "{}{}, {}{}",
            if self.min_inclusive { '[' } else { '(' },
            fmt(self.min),
            fmt(self.max),
            if self.max_inclusive { ']' } else { ')' }
        )
    }
}

/// Converged result of a local update at one quadrature point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalUpdate {
    /// End-of-step stress `sigma_i` (MPa, Mandel).
    pub sigma: Vec4,
    /// Consistent tangent `C_i = (S + dt H(sigma_i))^-1` (MPa).
    pub tangent: Mat4,
    /// Local Newton iterations used (0 for closed-form updates).
    pub iterations: u32,
}

/// The elastic domain of a law with a yield stress: wherever the trial stress
/// `sigma_0 + C deps` has a von Mises stress of at most `yield_stress`, the update is that
/// trial stress with the tangent `C` ([`Law::elastic_domain`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElasticDomain {
    /// The elastic stiffness `C` (MPa).
    pub stiffness: Mat4,
    /// The von Mises stress up to which a step stays elastic (MPa).
    pub yield_stress: f64,
}

impl ElasticDomain {
    /// The update of `s0` by `deps` when the step stays in the domain, `None` otherwise
    /// (or when the trial stress is not finite).
    #[inline]
    pub fn update(&self, s0: &Vec4, deps: &Vec4) -> Option<Vec4> {
        let trial = *s0 + self.stiffness.mul_vec(deps);
        (trial.von_mises() <= self.yield_stress).then_some(trial)
    }
}

/// Why a local update failed, with a suggested factor for the time step.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalFailure {
    /// What went wrong.
    pub reason: String,
    /// Suggested factor (< 1) by which to multiply the time step before retrying.
    pub suggested_dt_factor: f64,
}

impl std::fmt::Display for LocalFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} (suggested step factor {})",
            self.reason, self.suggested_dt_factor
        )
    }
}

/// A standard generalized material without hardening (paper §2.1): state is the stress
/// alone; `eps = S(c) sigma + eps_p`, `d eps_p/dt = g(sigma, c) = dPhi/dsigma`.
///
/// Parameters `c` are an *input* of every method, never a field of the law, so that an
/// optimizer only swaps the slice. Components follow [`Vec4`]'s Mandel order.
///
/// The backward-Euler local residual at step i (docs/theory.md §1) is
/// `r(sigma_i) = S (sigma_i - sigma_{i-1}) + dt g(sigma_i) - deps = 0`, with Jacobian
/// `A = S + dt H` and consistent tangent `C = A^-1`.
pub trait Law: Send + Sync + std::fmt::Debug {
    /// Name used in configs (`elastic`, `maxwell`, `norton-hoff`).
    fn name(&self) -> &'static str;

    /// Parameter metadata, in the order of the slice `c`.
    fn params(&self) -> &'static [ParamInfo];

    /// Compliance `S(c)` (1/MPa).
    fn compliance(&self, c: &[f64]) -> Mat4;

    /// `dS/dc_k`.
    fn compliance_derivative(&self, c: &[f64], k: usize) -> Mat4;

    /// Flow `g(sigma, c) = dPhi/dsigma` (1/s).
    fn flow(&self, c: &[f64], sigma: &Vec4) -> Vec4;

    /// Flow Hessian `H = d2Phi/dsigma2 = dg/dsigma`.
    fn flow_hessian(&self, c: &[f64], sigma: &Vec4) -> Mat4;

    /// `dg/dc_k` at fixed stress.
    fn flow_param_derivative(&self, c: &[f64], sigma: &Vec4, k: usize) -> Vec4;

    /// `dg/dc_k` at fixed stress for every `k < out.len()` at once, into `out`: equal, bit
    /// for bit, to [`Law::flow_param_derivative`] for each `k` (the adjoint sweep asks
    /// for all of them at every stressed Gauss point); a law overrides it to share the
    /// work between the parameters.
    fn flow_param_derivatives(&self, c: &[f64], sigma: &Vec4, out: &mut [Vec4]) {
        for (k, o) in out.iter_mut().enumerate() {
            *o = self.flow_param_derivative(c, sigma, k);
        }
    }

    /// `true` when the consistent tangent depends only on `c` and `dt`, not on the state
    /// (elasticity, Maxwell): the global tangent can then be reused across iterations and
    /// steps of equal length.
    fn is_linear(&self) -> bool {
        false
    }

    /// The update in affine form, `sigma_1 = A sigma_0 + C deps` with `(A, C)` depending
    /// only on `c` and `dt`, for laws where [`Law::update`] is exactly that (elasticity:
    /// `A = I`; Maxwell); `None` (the default) otherwise. `C` is the consistent tangent.
    /// Must agree with `update` to round-off (checked for every law by the shared tests);
    /// the solvers use it to update every Gauss point with two 4x4 products and to
    /// assemble one uniform tangent. Laws returning `Some` must also be
    /// [`Law::is_linear`].
    fn affine_update(&self, _c: &[f64], _dt: f64) -> Option<(Mat4, Mat4)> {
        None
    }

    /// The elastic domain of laws with a yield stress (Norton-Hoff with `sY > 0`): inside
    /// it [`Law::update`] is the elastic trial stress, so a solver can update most Gauss
    /// points of an indentation with one 4x4 product and a von Mises check, calling
    /// `update` only where the trial stress yields. `None` (the default) otherwise. Must
    /// agree with `update` to round-off inside the domain (checked for every law by the
    /// shared tests).
    fn elastic_domain(&self, _c: &[f64], _dt: f64) -> Option<ElasticDomain> {
        None
    }

    /// Checks every parameter against its admissible range.
    ///
    /// # Errors
    /// [`LawError::Parameter`] naming the first offending parameter, its value and range.
    fn check_params(&self, c: &[f64]) -> Result<(), LawError> {
        let infos = self.params();
        if c.len() != infos.len() {
            return Err(LawError::ParameterCount {
                law: self.name(),
                expected: infos.len(),
                got: c.len(),
            });
        }
        for (info, &v) in infos.iter().zip(c) {
            if !info.admits(v) {
                return Err(LawError::Parameter {
                    law: self.name(),
                    name: info.name,
                    value: v,
                    range: info.range_text(),
                });
            }
        }
        Ok(())
    }

    /// Whether `J(c)` is differentiable at `c` with respect to every parameter (the
    /// adjoint needs `Phi` twice differentiable).
    ///
    /// # Errors
    /// A message naming the parameter and why, e.g. Norton-Hoff with `m <= 1`.
    fn check_differentiable(&self, _c: &[f64]) -> Result<(), LawError> {
        Ok(())
    }

    /// Derivative of the local residual with respect to `c_k` at the converged state:
    /// `dr/dc_k = dS/dc_k (s1 - s0) + dt dg/dc_k(s1)`.
    fn residual_param_derivative(
        &self,
        c: &[f64],
        s0: &Vec4,
        s1: &Vec4,
        dt: f64,
        k: usize,
    ) -> Vec4 {
        self.compliance_derivative(c, k).mul_vec(&(*s1 - *s0))
            + self.flow_param_derivative(c, s1, k) * dt
    }

    /// [`Law::residual_param_derivative`] for every `k < out.len()` at once, into `out`,
    /// bit for bit (the forward sensitivities ask for all of them at every Gauss point of
    /// every step). The default shares the flow's derivatives
    /// ([`Law::flow_param_derivatives`]) between the parameters; a law that overrides
    /// [`Law::residual_param_derivative`] must override this too.
    fn residual_param_derivatives(
        &self,
        c: &[f64],
        s0: &Vec4,
        s1: &Vec4,
        dt: f64,
        out: &mut [Vec4],
    ) {
        self.flow_param_derivatives(c, s1, out);
        let ds = *s1 - *s0;
        for (k, o) in out.iter_mut().enumerate() {
            *o = self.compliance_derivative(c, k).mul_vec(&ds) + *o * dt;
        }
    }

    /// Consistent tangent `C = (S + dt H(sigma))^-1` at a given end-of-step stress.
    ///
    /// # Errors
    /// [`LocalFailure`] when `S + dt H` is singular.
    fn tangent(&self, c: &[f64], sigma: &Vec4, dt: f64) -> Result<Mat4, LocalFailure> {
        let a = self.compliance(c) + self.flow_hessian(c, sigma) * dt;
        a.inverse().ok_or_else(|| LocalFailure {
            reason: "singular local Jacobian S + dt H".into(),
            suggested_dt_factor: 0.5,
        })
    }

    /// Implicit local update from `s0` under the strain increment `deps` over `dt`.
    ///
    /// The default is a Newton iteration on `r(sigma)` started from the elastic trial
    /// stress, with a backtracking line search on `|r|`; laws with a closed form or a
    /// scalar return map override it.
    ///
    /// # Errors
    /// [`LocalFailure`] with a suggested step factor when Newton does not converge.
    fn update(
        &self,
        c: &[f64],
        s0: &Vec4,
        deps: &Vec4,
        dt: f64,
    ) -> Result<LocalUpdate, LocalFailure> {
        default_newton_update(self, c, s0, deps, dt)
    }
}

/// Generic backward-Euler Newton update used by [`Law::update`]'s default: Newton on
/// `r(sigma)` from the elastic trial stress, converged when `|r|` is below 1e-12 of the
/// size of its terms (`|S sigma| + |S s0| + |deps| + dt |g(sigma)| + dt |H| |sigma|`).
///
/// # Errors
/// [`LocalFailure`] after 50 iterations or on a singular Jacobian.
pub fn default_newton_update<L: Law + ?Sized>(
    law: &L,
    c: &[f64],
    s0: &Vec4,
    deps: &Vec4,
    dt: f64,
) -> Result<LocalUpdate, LocalFailure> {
    let s = law.compliance(c);
    let stiff = s.inverse().ok_or_else(|| LocalFailure {
        reason: "singular compliance".into(),
        suggested_dt_factor: 0.5,
    })?;
    let mut sigma = *s0 + stiff.mul_vec(deps);
    let residual = |sig: &Vec4| s.mul_vec(&(*sig - *s0)) + law.flow(c, sig) * dt - *deps;
    // the size of the residual's terms at `sig`, and of the round-off the stress's own
    // last bits put into the flow term (`dt |H| |sigma| eps`): the residual cannot go below
    // a few ulps of it, while a scale of the trial stress alone can (when the flow term
    // dominates), and Newton would never stop
    let scale = |sig: &Vec4| {
        (s.mul_vec(sig).max_abs()
            + s.mul_vec(s0).max_abs()
            + deps.max_abs()
            + dt * law.flow(c, sig).max_abs()
            + dt * law.flow_hessian(c, sig).max_abs() * sig.max_abs())
        .max(1e-300)
    };
    let mut r = residual(&sigma);
    for it in 0..50 {
        if r.max_abs() <= 1e-12 * scale(&sigma) {
            let tangent = law.tangent(c, &sigma, dt)?;
            return Ok(LocalUpdate {
                sigma,
                tangent,
                iterations: it,
            });
        }
        let a = s + law.flow_hessian(c, &sigma) * dt;
        let ainv = a.inverse().ok_or_else(|| LocalFailure {
            reason: format!("singular local Jacobian at iteration {it}"),
            suggested_dt_factor: 0.5,
        })?;
        let step = ainv.mul_vec(&r);
        let mut alpha = 1.0;
        let r0 = r.norm();
        loop {
            let trial = sigma - step * alpha;
            let rt = residual(&trial);
            if rt.is_finite() && (rt.norm() < r0 || alpha < 1e-4) {
                sigma = trial;
                r = rt;
                break;
            }
            alpha *= 0.5;
        }
    }
    Err(LocalFailure {
        reason: format!(
            "local Newton did not converge in 50 iterations (|r| = {:.3e})",
            r.norm()
        ),
        suggested_dt_factor: 0.25,
    })
}
