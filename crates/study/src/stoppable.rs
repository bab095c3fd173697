//! A material that lets a pipeline stop a forward run between steps without a stop
//! request in the solver: it forwards every call to the material it wraps (the same
//! computations, so the same bits) until the [`Cancel`] is raised; from then on the step
//! the solver begins fails at its first local update (a stress-only law: a law whose
//! updates fail; a law with internal variables: a non-finite local residual), the solver
//! cuts it until `max_cuts` and ends with `StepFailed`, carrying the trajectory up to the
//! last converged step. The solver asks [`Material::as_law`] once per step attempt, so
//! the stop is seen at the next step.

use indentify_identify::Cancel;
use indentify_laws::{
    ElasticDomain, InternalInfo, Law, LawError, LocalFailure, LocalUpdate, Mat4, Material,
    MaterialUpdate, ParamInfo, Step, Vec4,
};

/// The reason a stopped step gives (the failure message contains it).
pub const STOPPED: &str = "stopped on request";

/// `inner`, stoppable by `cancel` between steps.
#[derive(Debug)]
pub struct Stoppable<'a> {
    inner: &'a dyn Material,
    stop: Option<Stopped<'a>>,
    cancel: Cancel,
}

impl<'a> Stoppable<'a> {
    /// Wraps `inner`.
    pub fn new(inner: &'a dyn Material, cancel: Cancel) -> Stoppable<'a> {
        Stoppable {
            inner,
            stop: inner.as_law().map(|law| Stopped { law }),
            cancel,
        }
    }
}

fn failure() -> LocalFailure {
    LocalFailure {
        reason: STOPPED.into(),
        suggested_dt_factor: 0.5,
    }
}

impl Material for Stoppable<'_> {
    fn name(&self) -> &'static str {
        self.inner.name()
    }
    fn params(&self) -> &[ParamInfo] {
        self.inner.params()
    }
    fn internal(&self) -> &[InternalInfo] {
        self.inner.internal()
    }
    fn n_internal(&self) -> usize {
        self.inner.n_internal()
    }
    fn state_len(&self) -> usize {
        self.inner.state_len()
    }
    fn check_params(&self, c: &[f64]) -> Result<(), LawError> {
        self.inner.check_params(c)
    }
    fn check_differentiable(&self, c: &[f64]) -> Result<(), LawError> {
        self.inner.check_differentiable(c)
    }
    fn is_linear(&self) -> bool {
        self.inner.is_linear()
    }
    fn as_law(&self) -> Option<&dyn Law> {
        match &self.stop {
            Some(s) if self.cancel.is_raised() => Some(s),
            _ => self.inner.as_law(),
        }
    }
    fn residual(&self, c: &[f64], step: &Step<'_>, r: &mut [f64]) {
        if self.cancel.is_raised() {
            r.fill(f64::NAN);
        } else {
            self.inner.residual(c, step, r);
        }
    }
    fn jac_state(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.inner.jac_state(c, step, out);
    }
    fn jac_previous(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.inner.jac_previous(c, step, out);
    }
    fn jac_strain(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.inner.jac_strain(c, step, out);
    }
    fn jac_params(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.inner.jac_params(c, step, out);
    }
    fn jac_blocks(
        &self,
        c: &[f64],
        step: &Step<'_>,
        a: &mut [f64],
        d: &mut [f64],
        e: &mut [f64],
        p: &mut [f64],
    ) {
        self.inner.jac_blocks(c, step, a, d, e, p);
    }
    fn jac_params_transpose(
        &self,
        c: &[f64],
        step: &Step<'_>,
        mu: &[f64],
        weight: f64,
        scratch: &mut [f64],
        out: &mut [f64],
    ) {
        self.inner
            .jac_params_transpose(c, step, mu, weight, scratch, out);
    }
    fn update(
        &self,
        c: &[f64],
        y0: &[f64],
        deps: &Vec4,
        dt: f64,
        y1: &mut [f64],
    ) -> Result<MaterialUpdate, LocalFailure> {
        if self.cancel.is_raised() {
            return Err(failure());
        }
        self.inner.update(c, y0, deps, dt, y1)
    }
}

/// A stress-only law after the stop: its description forwarded, every update failing.
#[derive(Debug)]
struct Stopped<'a> {
    law: &'a dyn Law,
}

impl Law for Stopped<'_> {
    fn name(&self) -> &'static str {
        self.law.name()
    }
    fn params(&self) -> &'static [ParamInfo] {
        self.law.params()
    }
    fn compliance(&self, c: &[f64]) -> Mat4 {
        self.law.compliance(c)
    }
    fn compliance_derivative(&self, c: &[f64], k: usize) -> Mat4 {
        self.law.compliance_derivative(c, k)
    }
    fn flow(&self, c: &[f64], sigma: &Vec4) -> Vec4 {
        self.law.flow(c, sigma)
    }
    fn flow_hessian(&self, c: &[f64], sigma: &Vec4) -> Mat4 {
        self.law.flow_hessian(c, sigma)
    }
    fn flow_param_derivative(&self, c: &[f64], sigma: &Vec4, k: usize) -> Vec4 {
        self.law.flow_param_derivative(c, sigma, k)
    }
    fn affine_update(&self, _c: &[f64], _dt: f64) -> Option<(Mat4, Mat4)> {
        None
    }
    fn elastic_domain(&self, _c: &[f64], _dt: f64) -> Option<ElasticDomain> {
        None
    }
    fn tangent(&self, _c: &[f64], _sigma: &Vec4, _dt: f64) -> Result<Mat4, LocalFailure> {
        Err(failure())
    }
    fn update(
        &self,
        _c: &[f64],
        _s0: &Vec4,
        _deps: &Vec4,
        _dt: f64,
    ) -> Result<LocalUpdate, LocalFailure> {
        Err(failure())
    }
}
