//! The bridge between argmin and the identification: the scaled objective as an argmin
//! problem, and a wrapper solver that records the history and applies this crate's
//! stopping rules after every iteration (argmin's own tolerances are switched off).

use argmin::core::{
    CostFunction, Error, Gradient, IterState, KV, Problem as ArgminProblem, Solver, State,
    TerminationReason, TerminationStatus,
};

use crate::linalg::norm2;
use crate::optimize::{Monitor, Objective, StopReason};

/// `&Objective` as an argmin problem in the scaled variables `y`.
pub(crate) struct ArgminObjective<'a, 'p> {
    pub objective: &'a Objective<'p>,
}

impl CostFunction for ArgminObjective<'_, '_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, y: &Vec<f64>) -> Result<f64, Error> {
        self.objective.value(y).map_err(|e| self.objective.fail(e))
    }
}

impl Gradient for ArgminObjective<'_, '_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, y: &Vec<f64>) -> Result<Vec<f64>, Error> {
        self.objective
            .value_and_gradient(y)
            .map(|(_, g)| g)
            .map_err(|e| self.objective.fail(e))
    }
}

/// An argmin solver wrapped so that, before each iteration (and after the last), the
/// current iterate is recorded and the stopping rules are checked.
pub(crate) struct Monitored<'a, 'm, 'p, S> {
    pub inner: S,
    pub monitor: &'a Monitor<'m, 'p>,
    /// BFGS: when an update is skipped, or when the line search had to shorten the
    /// quasi-Newton step (the matrix's model of the cost was wrong along it), restart from
    /// the Gauss-Newton inverse Hessian of the new iterate instead of updating the old
    /// matrix.
    pub restart_gauss_newton: bool,
}

/// Inverse Hessians the wrapper can rebuild (BFGS's dense matrix); `()` for the solvers
/// that keep none.
pub(crate) trait GaussNewtonRestart: Sized {
    /// The Gauss-Newton inverse Hessian at `y`, if this type can hold one.
    fn gauss_newton(monitor: &Monitor<'_, '_>, y: &[f64]) -> Option<Result<Self, Error>>;

    /// The length (2-norm) of the quasi-Newton step `H g`, if this type holds `H`.
    fn step_length(&self, g: &[f64]) -> Option<f64>;
}

impl GaussNewtonRestart for Vec<Vec<f64>> {
    fn gauss_newton(monitor: &Monitor<'_, '_>, y: &[f64]) -> Option<Result<Self, Error>> {
        Some(crate::lm::gauss_newton_inverse(monitor, y).map_err(|e| monitor.objective.fail(e)))
    }

    fn step_length(&self, g: &[f64]) -> Option<f64> {
        let step: Vec<f64> = self
            .iter()
            .map(|row| row.iter().zip(g).map(|(h, v)| h * v).sum())
            .collect();
        Some(norm2(&step))
    }
}

impl GaussNewtonRestart for () {
    fn gauss_newton(_: &Monitor<'_, '_>, _: &[f64]) -> Option<Result<Self, Error>> {
        None
    }

    fn step_length(&self, _: &[f64]) -> Option<f64> {
        None
    }
}

/// A step shorter than this fraction of the quasi-Newton step `H g` was shortened by the
/// line search (backtracking halves it: the first shortened step is 0.5).
const SHORTENED: f64 = 1.0 - 1e-9;

impl<O, S, H: Clone + GaussNewtonRestart> Solver<O, IterState<Vec<f64>, Vec<f64>, (), H, (), f64>>
    for Monitored<'_, '_, '_, S>
where
    S: Solver<O, IterState<Vec<f64>, Vec<f64>, (), H, (), f64>>,
{
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn init(
        &mut self,
        problem: &mut ArgminProblem<O>,
        state: IterState<Vec<f64>, Vec<f64>, (), H, (), f64>,
    ) -> Result<(IterState<Vec<f64>, Vec<f64>, (), H, (), f64>, Option<KV>), Error> {
        self.inner.init(problem, state)
    }

    /// One inner iteration; for BFGS (an inverse Hessian in the state) the update is
    /// skipped when the curvature condition `s.y > 0` fails, which an Armijo-only line
    /// search does not guarantee (J is not convex in log-scaled parameters far from the
    /// optimum) and which argmin's BFGS does not check: an indefinite `H` would give an
    /// ascent direction and the next line search would stall. With
    /// `restart_gauss_newton` the skipped update is replaced by the Gauss-Newton inverse
    /// Hessian of the new iterate, and so is the update after a step that the line search
    /// shortened: far from the optimum a secant update carries the curvature of a region
    /// the iterates are leaving, the Gauss-Newton matrix that of the data where they are
    /// (with exact data it tends to the Hessian at the optimum, where full steps are
    /// taken and the BFGS updates build on it).
    fn next_iter(
        &mut self,
        problem: &mut ArgminProblem<O>,
        state: IterState<Vec<f64>, Vec<f64>, (), H, (), f64>,
    ) -> Result<(IterState<Vec<f64>, Vec<f64>, (), H, (), f64>, Option<KV>), Error> {
        let x0 = state.get_param().cloned();
        let g0 = state.get_gradient().cloned();
        let h0 = state.get_inv_hessian().cloned();
        let (mut next, kv) = self.inner.next_iter(problem, state)?;
        if let (Some(x0), Some(g0), Some(h0), Some(x1), Some(g1)) =
            (x0, g0, h0, next.get_param(), next.get_gradient())
        {
            let s: Vec<f64> = x1.iter().zip(&x0).map(|(a, b)| a - b).collect();
            let y: Vec<f64> = g1.iter().zip(&g0).map(|(a, b)| a - b).collect();
            let sy: f64 = s.iter().zip(&y).map(|(a, b)| a * b).sum();
            let skipped = !(sy > 1e-12 * norm2(&s) * norm2(&y));
            let shortened = h0
                .step_length(&g0)
                .is_some_and(|full| norm2(&s) < SHORTENED * full);
            let restart = if self.restart_gauss_newton && (skipped || shortened) {
                H::gauss_newton(self.monitor, x1)
            } else {
                None
            };
            match restart {
                Some(h) => next = next.inv_hessian(h?),
                None if skipped => next = next.inv_hessian(h0),
                None => {}
            }
            if skipped {
                self.monitor
                    .skipped_updates
                    .set(self.monitor.skipped_updates.get() + 1);
            }
        }
        Ok((next, kv))
    }

    fn terminate(
        &mut self,
        state: &IterState<Vec<f64>, Vec<f64>, (), H, (), f64>,
    ) -> TerminationStatus {
        let (Some(y), Some(g)) = (state.get_param(), state.get_gradient()) else {
            return TerminationStatus::NotTerminated;
        };
        match self
            .monitor
            .iterate(state.get_iter() as usize, y, state.get_cost(), g)
        {
            Some(StopReason::MaxIterations) => {
                TerminationStatus::Terminated(TerminationReason::MaxItersReached)
            }
            Some(_) => TerminationStatus::Terminated(TerminationReason::SolverConverged),
            None => TerminationStatus::NotTerminated,
        }
    }
}
