//! Minimization of `J` over the box of free parameters: the configuration
//! ([`IdentifyConfig`]), the run ([`identify`], [`resume`], [`multistart`]), the iteration
//! history delivered to an observer callback as it goes, and the result.
//!
//! The optimizers work on the scaled variables `y` of [`Parameterization`] and on the
//! internal objective `f(y) = kappa J(c(P(y))) / J_ref` with `J_ref` the
//! [`Problem::reference_cost`] and `kappa` chosen at the start so that the first
//! steepest-descent step has length [`IdentifyConfig::initial_step`] in `y` (infinity
//! norm): with identity as the initial inverse Hessian, BFGS's first trial point then moves
//! the parameters by at most a factor `exp(initial_step)` (log scaling), whatever the
//! units of `J`. Stopping rules are expressed on `J / J_ref` (see [`StopCriteria`]).
//!
//! Methods ([`Method`]):
//! - `Bfgs`: argmin BFGS with backtracking line search under the Armijo condition (the
//!   paper's algorithm, §4.2, after Gill-Murray-Wright); bounds by projection. Its initial
//!   inverse Hessian is [`IdentifyConfig::bfgs_start`]: `kappa I` (the paper's) or the
//!   inverse of the damped Gauss-Newton matrix at the start ([`BfgsStart::GaussNewton`]).
//! - `Lbfgs`: argmin L-BFGS with the More-Thuente line search; bounds by projection.
//! - `Lbfgsb`: L-BFGS-B (rcompat-lbfgsb), bounds handled by the method itself.
//! - `LevenbergMarquardt`: projected LM on the sensitivity Jacobian (one forward and one
//!   sensitivity solve per accepted iteration).

use std::cell::{Cell, RefCell};

use argmin::core::{Error as ArgminError, Executor};
use argmin::solver::linesearch::condition::ArmijoCondition;
use argmin::solver::linesearch::{BacktrackingLineSearch, MoreThuenteLineSearch};
use argmin::solver::quasinewton::{BFGS, LBFGS};

use crate::IdentifyError;
use crate::argmin_glue::{ArgminObjective, Monitored};
use crate::identifiability::{Column, Forces, Identifiability, NoiseModel};
use crate::linalg::{norm_inf, norm2};
pub use crate::lm::{LmDamping, LmStrategy};
use crate::params::{ParamSpec, Parameterization};
use crate::problem::{Evaluator, Prefetch, Problem};

/// The optimization method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// BFGS with Armijo backtracking (the paper's algorithm); bounds by projection.
    Bfgs,
    /// L-BFGS (memory `m`) with the More-Thuente line search; bounds by projection.
    Lbfgs {
        /// Stored correction pairs.
        memory: usize,
    },
    /// L-BFGS-B (memory `m`): bounds handled by the method (rcompat-lbfgsb, feature `lbfgsb`).
    Lbfgsb {
        /// Stored correction pairs.
        memory: usize,
    },
    /// Projected Levenberg-Marquardt on the forward-sensitivity Jacobian.
    LevenbergMarquardt,
}

impl Method {
    /// Short name for reports (`bfgs`, `lbfgs`, `lbfgsb`, `lm`).
    pub fn name(&self) -> &'static str {
        match self {
            Method::Bfgs => "bfgs",
            Method::Lbfgs { .. } => "lbfgs",
            Method::Lbfgsb { .. } => "lbfgsb",
            Method::LevenbergMarquardt => "lm",
        }
    }

    /// The method of a name as [`Method::name`] gives it (memory 5 for the limited-memory ones).
    pub fn from_name(name: &str) -> Option<Method> {
        match name {
            "bfgs" => Some(Method::Bfgs),
            "lbfgs" => Some(Method::Lbfgs { memory: 5 }),
            "lbfgsb" => Some(Method::Lbfgsb { memory: 5 }),
            "lm" => Some(Method::LevenbergMarquardt),
            _ => None,
        }
    }
}

/// The inverse Hessian that BFGS starts from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BfgsStart {
    /// The identity in the internal objective, `kappa I` in terms of `J / J_ref`, with
    /// `kappa` making the first step [`IdentifyConfig::initial_step`] long (the paper's).
    #[default]
    Scaled,
    /// The inverse of the Gauss-Newton matrix `A^T A` of the scaled residuals at the start
    /// (one forward-sensitivity solve), damped as Levenberg-Marquardt's first step
    /// (`A^T A + 1e-3 diag(A^T A)`) and scaled down, if needed, so that the first step is
    /// at most [`GN_MAX_STEP`] long in the scaled variables (infinity norm). BFGS then
    /// starts with the curvature of the data instead of learning it from secant pairs;
    /// an update skipped for `s.y <= 0`, or a step that the line search had to shorten,
    /// restarts from the Gauss-Newton matrix of the current iterate (one more sensitivity
    /// solve); full steps update the matrix by BFGS.
    GaussNewton,
}

/// The longest first step (infinity norm in the scaled variables) of
/// [`BfgsStart::GaussNewton`]: a factor e^2 = 7.4 on a log-scaled parameter.
pub const GN_MAX_STEP: f64 = 2.0;

impl BfgsStart {
    /// The name in configurations (`Scaled`, `GaussNewton`).
    pub fn name(&self) -> &'static str {
        match self {
            BfgsStart::Scaled => "Scaled",
            BfgsStart::GaussNewton => "GaussNewton",
        }
    }
}

/// When to stop. Costs are relative, `J / J_ref` with `J_ref = 1/2 sum w_i (F_i^exp)^2`;
/// gradients are `|P grad_y J| / J_ref` (2-norm of the projected gradient with respect
/// to the scaled variables, so that each parameter counts by its relative change).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StopCriteria {
    /// Stop when `|P grad_y J| / J_ref <= gradient_tol`.
    pub gradient_tol: f64,
    /// Stop when one iteration decreases `J` by at most `relative_decrease_tol * J`.
    pub relative_decrease_tol: f64,
    /// Stop when `J / J_ref <= target_cost` (0 disables it).
    pub target_cost: f64,
    /// Iteration limit (counted from the original start across resumes).
    pub max_iterations: usize,
    /// A line search (or an LM step-size search) that needs more trial points than this
    /// has stalled.
    pub max_line_search_evaluations: usize,
    /// A stall at `J / J_ref` below this is the round-off floor of the forward solver:
    /// reported as converged ([`StopReason::RoundOff`]).
    pub roundoff_cost: f64,
    /// Statistical stop of [`Method::LevenbergMarquardt`] (the other methods have no
    /// Jacobian at their iterates and ignore it): stop when the last accepted step moved
    /// every free parameter by less than this fraction of its Gauss-Newton standard
    /// deviation at the new iterate, and the undamped Gauss-Newton step from there would
    /// too ([`StopReason::StepBelowSigma`]). The deviations are those of the
    /// identifiability summary (the run's [`NoiseModel`]) at the iterate. A parameter the
    /// data leave undetermined there (the others' deviations are then conditional on it,
    /// and a valley moves them together), or one on a bound that the Gauss-Newton step
    /// pushes out, never stops a run this way: the other rules do, with the undetermined
    /// status as before. `None`: off (the default here; configurations
    /// default to [`DEFAULT_STEP_SIGMA`]).
    pub step_sigma: Option<f64>,
    /// With [`StopCriteria::step_sigma`] `= Some(f)`, where the data leave a parameter
    /// undetermined at the iterate (the rule above does not apply there): stop when the
    /// last accepted step and the undamped Gauss-Newton step from the new iterate both
    /// change the fit's chi-square (`2 J / sigma^2`, `sigma^2` the noise model's variance)
    /// by less than `f^2`, the chi-square of `f` standard deviations of a determined
    /// parameter ([`StopReason::Chi2BelowSigma`]; the run still ends with the undetermined
    /// status). `true` by default; off, such a run ends by the relative decrease.
    pub chi2_stop: bool,
    /// With [`StopCriteria::step_sigma`] `= Some(f)`: also stop when the Gauss-Newton step
    /// from the new iterate moves every free parameter by less than `f` of its deviation
    /// and the last accepted step's gain ratio (actual over predicted decrease) lies within
    /// [`PROPOSED_GAIN_TOL`] of 1, however long that step was
    /// ([`StopReason::ProposedBelowSigma`]): the quadratic model has just predicted the
    /// cost over the whole last step, so its next step, below `f` of every deviation, is
    /// where the remaining distance to the optimum is read (docs/performance.md, "The
    /// 100-indent batch"). Saves the trial run and the sensitivity pass of the step the
    /// plain rule needs to confirm it. Not with an undetermined parameter or one pushed
    /// out at a bound (as `step_sigma`). `false` by default.
    pub proposed_step: bool,
    /// Levenberg-Marquardt only: stop a crawl along the valley of an undetermined
    /// parameter when the last accepted steps moved every determined combination by less
    /// than a fraction of its conditional deviation and the chi-square by less than a
    /// stated amount ([`crate::ValleyStop`], [`StopReason::ValleyBelowSigma`]; the run
    /// still ends undetermined). `None` (the default): off.
    pub valley_stop: Option<crate::ValleyStop>,
    /// How [`Method::LevenbergMarquardt`] chooses its first damping and its trials after a
    /// rejection (the other methods ignore it; default: the classic run).
    pub lm: LmStrategy,
}

/// The fraction of a standard deviation of [`StopCriteria::step_sigma`] that
/// configurations use unless told otherwise: a step below a tenth of a deviation changes
/// nothing the user reads.
pub const DEFAULT_STEP_SIGMA: f64 = 0.1;

/// How far from 1 the gain ratio of the last accepted Levenberg-Marquardt step may lie for
/// [`StopCriteria::proposed_step`] to trust the Gauss-Newton model's next step: the actual
/// decrease within 10% of the predicted one.
pub const PROPOSED_GAIN_TOL: f64 = 0.1;

impl Default for StopCriteria {
    fn default() -> Self {
        StopCriteria {
            gradient_tol: 1e-9,
            relative_decrease_tol: 1e-10,
            target_cost: 0.0,
            max_iterations: 100,
            max_line_search_evaluations: 30,
            roundoff_cost: 1e-16,
            step_sigma: None,
            chi2_stop: true,
            proposed_step: false,
            valley_stop: None,
            lm: LmStrategy::default(),
        }
    }
}

/// Everything an identification run needs besides the [`Problem`]: what is free, the
/// method and the stopping rules. The CLI builds it from its RON config.
#[derive(Clone, Debug, PartialEq)]
pub struct IdentifyConfig {
    /// One entry per law parameter (free with start / bounds / scaling, or fixed).
    pub params: Vec<ParamSpec>,
    /// Optimization method.
    pub method: Method,
    /// Stopping rules.
    pub stop: StopCriteria,
    /// Length (infinity norm, scaled variables) of the first steepest-descent trial step;
    /// 0.5 = at most a factor e^0.5 = 1.65 on a log-scaled parameter.
    pub initial_step: f64,
    /// The initial inverse Hessian of [`Method::Bfgs`] (ignored by the other methods).
    pub bfgs_start: BfgsStart,
    /// Compute the [`Identifiability`] summary at the end (one sensitivity solve).
    pub identifiability: bool,
    /// What the summary's standard deviations assume about the force noise (default: one
    /// variance for every weighted residual, the classical Gauss-Newton formula).
    pub noise: NoiseModel,
    /// Raised from another thread (a signal handler, a user interface), it ends the run
    /// after the iteration in progress with [`StopReason::Interrupted`].
    pub cancel: Cancel,
}

/// A flag that asks a running identification to stop after its current iteration. Clones
/// share the flag; two flags compare equal when they are the same flag.
#[derive(Clone, Debug, Default)]
pub struct Cancel(std::sync::Arc<std::sync::atomic::AtomicBool>);

impl Cancel {
    /// Asks the run to stop.
    pub fn raise(&self) {
        self.0.store(true, std::sync::atomic::Ordering::SeqCst);
    }

    /// Whether a stop was asked.
    pub fn is_raised(&self) -> bool {
        self.0.load(std::sync::atomic::Ordering::SeqCst)
    }
}

impl PartialEq for Cancel {
    fn eq(&self, other: &Cancel) -> bool {
        std::sync::Arc::ptr_eq(&self.0, &other.0)
    }
}

impl IdentifyConfig {
    /// BFGS-Armijo with default stopping rules and the identifiability summary.
    pub fn new(params: Vec<ParamSpec>) -> IdentifyConfig {
        IdentifyConfig {
            params,
            method: Method::Bfgs,
            stop: StopCriteria::default(),
            initial_step: 0.5,
            bfgs_start: BfgsStart::Scaled,
            identifiability: true,
            noise: NoiseModel::Residual,
            cancel: Cancel::default(),
        }
    }

    pub(crate) fn validate(&self) -> Result<(), IdentifyError> {
        self.noise.validate()?;
        let s = &self.stop;
        let check = |ok: bool, field: &'static str, value: f64, allowed: &'static str| {
            if ok {
                Ok(())
            } else {
                Err(IdentifyError::InvalidOption {
                    field,
                    value: value.to_string(),
                    allowed,
                })
            }
        };
        check(
            s.gradient_tol >= 0.0 && s.gradient_tol.is_finite(),
            "stop.gradient_tol",
            s.gradient_tol,
            "a finite value >= 0",
        )?;
        check(
            s.relative_decrease_tol >= 0.0 && s.relative_decrease_tol < 1.0,
            "stop.relative_decrease_tol",
            s.relative_decrease_tol,
            "a value in [0, 1)",
        )?;
        check(
            s.target_cost >= 0.0 && s.target_cost.is_finite(),
            "stop.target_cost",
            s.target_cost,
            "a finite value >= 0",
        )?;
        if let Some(f) = s.step_sigma {
            check(
                f > 0.0 && f.is_finite(),
                "stop.step_sigma",
                f,
                "a finite fraction > 0 of a standard deviation, or None (off)",
            )?;
        }
        if let Some(v) = s.valley_stop {
            check(
                v.steps >= 1,
                "stop.valley_stop.steps",
                v.steps as f64,
                "an integer >= 1 (accepted steps in a row)",
            )?;
            check(
                v.fraction > 0.0 && v.fraction.is_finite(),
                "stop.valley_stop.fraction",
                v.fraction,
                "a finite fraction > 0 of a standard deviation",
            )?;
            check(
                v.chi2 > 0.0 && v.chi2.is_finite(),
                "stop.valley_stop.chi2",
                v.chi2,
                "a finite chi-square decrease > 0",
            )?;
        }
        check(
            s.max_line_search_evaluations >= 1,
            "stop.max_line_search_evaluations",
            s.max_line_search_evaluations as f64,
            "an integer >= 1",
        )?;
        check(
            self.initial_step > 0.0 && self.initial_step.is_finite(),
            "initial_step",
            self.initial_step,
            "a finite value > 0",
        )?;
        match self.method {
            Method::Lbfgs { memory } | Method::Lbfgsb { memory } => check(
                (1..=100).contains(&memory),
                "method.memory",
                memory as f64,
                "an integer in [1, 100]",
            ),
            _ => Ok(()),
        }
    }
}

/// One line of the iteration history: the iterate after `iteration` iterations.
#[derive(Clone, Debug, PartialEq)]
pub struct IterationRecord {
    /// Iterations done (0 = the start), counted across resumes.
    pub iteration: usize,
    /// Full law parameter vector (physical units, law order).
    pub params: Vec<f64>,
    /// `J` (N^2).
    pub cost: f64,
    /// `|P grad_y J|` (N^2; gradient with respect to the scaled variables, projected).
    pub grad_norm: f64,
    /// Forward solves so far.
    pub forward_solves: usize,
    /// Adjoint sweeps so far.
    pub adjoint_solves: usize,
    /// Sensitivity (Jacobian) solves so far.
    pub sensitivity_solves: usize,
    /// Wall time since the start (s).
    pub seconds: f64,
}

/// Why a run stopped.
#[derive(Clone, Debug, PartialEq)]
pub enum StopReason {
    /// `|P grad_y J| / J_ref <= gradient_tol`.
    GradientNorm,
    /// One iteration decreased `J` by at most `relative_decrease_tol * J`.
    RelativeDecrease,
    /// `J / J_ref <= target_cost`.
    TargetCost,
    /// No further decrease possible with `J` at the forward solver's round-off.
    RoundOff,
    /// Levenberg-Marquardt's last step, and the Gauss-Newton step from where it ended,
    /// moved every free parameter by less than `fraction` of its standard deviation
    /// ([`StopCriteria::step_sigma`]).
    StepBelowSigma {
        /// The fraction of a standard deviation.
        fraction: f64,
    },
    /// With a parameter undetermined, Levenberg-Marquardt's last step and the
    /// Gauss-Newton step from where it ended changed the chi-square by less than
    /// `fraction^2` ([`StopCriteria::chi2_stop`]).
    Chi2BelowSigma {
        /// The fraction of a standard deviation (the chi-square threshold is its square).
        fraction: f64,
    },
    /// Levenberg-Marquardt's last step decreased the cost as the Gauss-Newton model
    /// predicted (gain ratio within [`PROPOSED_GAIN_TOL`] of 1), and the Gauss-Newton step
    /// from where it ended would move every free parameter by less than `fraction` of its
    /// standard deviation ([`StopCriteria::proposed_step`]).
    ProposedBelowSigma {
        /// The fraction of a standard deviation.
        fraction: f64,
        /// The last step's gain ratio.
        gain: f64,
    },
    /// Levenberg-Marquardt crawled along the valley of an undetermined parameter: each
    /// of the last `steps` accepted steps moved every determined combination by less than
    /// `fraction` of its conditional deviation and lowered the chi-square by less than
    /// `chi2` ([`StopCriteria::valley_stop`]).
    ValleyBelowSigma {
        /// The steps in a row.
        steps: usize,
        /// The fraction of a conditional deviation.
        fraction: f64,
        /// The chi-square decrease per step.
        chi2: f64,
    },
    /// With [`LmStrategy::subspace`], where the data leave a parameter undetermined:
    /// Levenberg-Marquardt's steps were kept off the undetermined directions, and the last
    /// step and the next truncated Gauss-Newton step moved every determined combination by
    /// less than `fraction` of its conditional deviation (`crate::subspace`; the run still
    /// ends undetermined).
    SubspaceBelowSigma {
        /// The fraction of a conditional deviation.
        fraction: f64,
    },
    /// The iteration limit.
    MaxIterations,
    /// Stopped on request ([`Cancel::raise`]) after the last recorded iteration.
    Interrupted,
    /// No decrease could be found (line search or LM damping exhausted, or the optimizer
    /// library gave up); the message says why.
    Stalled(String),
    /// A convergence criterion (`met`) held, but the data do not determine some free
    /// parameters (see [`Identifiability::undetermined`]): not converged. A parameter at a
    /// bound whose projected gradient vanishes because it has no effect ends here.
    Undetermined {
        /// The criterion that held.
        met: Box<StopReason>,
        /// The undetermined parameters, each with its bound and the reason, in words.
        params: Vec<String>,
    },
}

impl StopReason {
    /// What to do after a run ended with [`StopReason::Undetermined`].
    pub const UNDETERMINED_ADVICE: &'static str = "hold the undetermined parameters at \
        values known otherwise (Fixed, --fixed), make the test tell them apart (a longer \
        hold, several loading rates or depths, tests fitted together), or change the start \
        (a parameter pushed to a bound where it has no effect may have a better optimum \
        inside)";

    /// `true` for the convergence criteria (gradient, decrease, target, round-off).
    /// [`StopReason::Undetermined`] is not converged.
    pub fn is_converged(&self) -> bool {
        matches!(
            self,
            StopReason::GradientNorm
                | StopReason::RelativeDecrease
                | StopReason::TargetCost
                | StopReason::RoundOff
                | StopReason::StepBelowSigma { .. }
                | StopReason::Chi2BelowSigma { .. }
                | StopReason::ProposedBelowSigma { .. }
                | StopReason::ValleyBelowSigma { .. }
                | StopReason::SubspaceBelowSigma { .. }
        )
    }
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StopReason::GradientNorm => write!(f, "gradient norm below tolerance"),
            StopReason::RelativeDecrease => write!(f, "relative decrease below tolerance"),
            StopReason::TargetCost => write!(f, "target cost reached"),
            StopReason::RoundOff => write!(f, "cost at the solver's round-off"),
            StopReason::StepBelowSigma { fraction } => {
                write!(f, "last step < {fraction} \u{3c3} for every parameter")
            }
            StopReason::Chi2BelowSigma { fraction } => write!(
                f,
                "chi-square change of the last step and the next < {} (the chi-square of {fraction} \u{3c3})",
                // 0.1^2 shown as 0.01, not 0.010000000000000002
                format!("{:.6e}", fraction * fraction)
                    .parse::<f64>()
                    .unwrap_or(fraction * fraction)
            ),
            StopReason::ProposedBelowSigma { fraction, gain } => write!(
                f,
                "next Gauss-Newton step < {fraction} \u{3c3} for every parameter after a step \
                 the model predicted (gain ratio {gain:.3})"
            ),
            StopReason::ValleyBelowSigma {
                steps,
                fraction,
                chi2,
            } => write!(
                f,
                "stopped along an undetermined valley: each of the last {steps} steps moved \
                 every determined combination by < {fraction} \u{3c3} and the chi-square by < \
                 {chi2}"
            ),
            StopReason::SubspaceBelowSigma { fraction } => write!(
                f,
                "steps kept off the undetermined direction: the last step and the next moved \
                 every determined combination by < {fraction} \u{3c3}"
            ),
            StopReason::MaxIterations => write!(f, "iteration limit reached"),
            StopReason::Interrupted => write!(f, "interrupted"),
            StopReason::Stalled(why) => write!(f, "stalled: {why}"),
            StopReason::Undetermined { met, params } => write!(
                f,
                "{met}, but the data do not determine {}",
                params.join("; ")
            ),
        }
    }
}

/// One law parameter at the end of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamOutcome {
    /// Name.
    pub name: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// Identified (`true`) or held fixed.
    pub free: bool,
    /// Start (or fixed value).
    pub start: f64,
    /// Final value.
    pub value: f64,
    /// Lower bound (free ones; the value itself for fixed ones).
    pub lower: f64,
    /// Upper bound.
    pub upper: f64,
    /// The final value sits on its lower bound.
    pub at_lower: bool,
    /// The final value sits on its upper bound.
    pub at_upper: bool,
}

/// The outcome of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct IdentifyResult {
    /// Law name.
    pub law: &'static str,
    /// Method used.
    pub method: Method,
    /// Every law parameter with start, final value and bound hits.
    pub params: Vec<ParamOutcome>,
    /// Final full parameter vector.
    pub c: Vec<f64>,
    /// `J` at the start (N^2).
    pub initial_cost: f64,
    /// `J` at the end (N^2).
    pub cost: f64,
    /// `J_ref` (N^2), the scale of the relative criteria.
    pub reference_cost: f64,
    /// Iterations (across resumes).
    pub iterations: usize,
    /// Forward solves (the cost evaluations that needed a solve).
    pub forward_solves: usize,
    /// Adjoint sweeps.
    pub adjoint_solves: usize,
    /// Sensitivity solves (LM, identifiability).
    pub sensitivity_solves: usize,
    /// Levenberg-Marquardt trials that did not decrease the cost (each one forward solve
    /// spent without progress; 0 for the other methods; this run only, not across resumes).
    pub rejected_trials: usize,
    /// Newton iterations of this run's forward solves, summed over their steps (this run
    /// only, not across resumes).
    pub newton_iterations: u64,
    /// Numeric factorizations of this run's forward solves (this run only).
    pub factorizations: usize,
    /// Forward solves of rejected Levenberg-Marquardt trials stopped between steps
    /// ([`crate::LmStrategy::stop_rejected`]; this run only).
    pub stopped_runs: usize,
    /// Schedule steps this run's forward solves ran (stopped ones up to where they
    /// stopped, failed ones left out).
    pub schedule_steps: u64,
    /// Schedule steps the stopped forward solves did not run (this run only).
    pub steps_skipped: u64,
    /// Requests (cost, gradient, forces, Jacobian) answered by the evaluation cache.
    pub cache_hits: usize,
    /// Distinct parameter points requested by this run (excluding a resumed run's past).
    pub distinct_points: usize,
    /// Why it stopped.
    pub stop_reason: StopReason,
    /// Wall time (s, across resumes).
    pub seconds: f64,
    /// The history, as delivered to the observer.
    pub history: Vec<IterationRecord>,
    /// Forces at the schedule times for the start (N; index 0 = initial state).
    pub initial_forces: Vec<f64>,
    /// Forces at the schedule times for the final parameters (N).
    pub forces: Vec<f64>,
    /// Identifiability at the end (if asked for and computable).
    pub identifiability: Option<Identifiability>,
}

impl IdentifyResult {
    /// `Ok` when the run met a convergence criterion.
    ///
    /// # Errors
    /// [`IdentifyError::Stalled`] otherwise (iteration limit or stall), with the reason.
    pub fn ensure_converged(&self) -> Result<(), IdentifyError> {
        if self.stop_reason.is_converged() {
            Ok(())
        } else {
            Err(IdentifyError::Stalled {
                iterations: self.iterations,
                cost: self.cost,
                reason: self.stop_reason.to_string(),
            })
        }
    }

    /// Final values of the free parameters (law order).
    pub fn free_values(&self) -> Vec<f64> {
        self.params
            .iter()
            .filter(|p| p.free)
            .map(|p| p.value)
            .collect()
    }
}

/// A point with its internal cost and gradient: `(y, f, g)`.
pub(crate) type Point = (Vec<f64>, f64, Vec<f64>);

/// The scaled objective shared by all methods: `f(y) = kappa J(c(P(y))) / J_ref` and its
/// gradient, on top of the cached [`Evaluator`].
pub(crate) struct Objective<'p> {
    pub eval: RefCell<Evaluator<'p>>,
    pub param: Parameterization,
    pub j_ref: f64,
    pub kappa: Cell<f64>,
    /// Cost-only evaluations since the last gradient (a line search in progress).
    line_evals: Cell<usize>,
    max_line_evals: usize,
    /// The error behind the last failed call (argmin only carries text).
    error: RefCell<Option<IdentifyError>>,
    /// Last point with a gradient, in internal units.
    pub last: RefCell<Option<Point>>,
}

impl<'p> Objective<'p> {
    fn new(eval: Evaluator<'p>, param: Parameterization, max_line_evals: usize) -> Objective<'p> {
        let j_ref = eval.problem().reference_cost();
        Objective {
            eval: RefCell::new(eval),
            param,
            j_ref,
            kappa: Cell::new(1.0),
            line_evals: Cell::new(0),
            max_line_evals,
            error: RefCell::new(None),
            last: RefCell::new(None),
        }
    }

    /// `f(y)`.
    pub fn value(&self, y: &[f64]) -> Result<f64, IdentifyError> {
        let n = self.line_evals.get() + 1;
        self.line_evals.set(n);
        if n > self.max_line_evals {
            return Err(IdentifyError::Stalled {
                iterations: 0,
                cost: f64::NAN,
                reason: format!(
                    "the line search found no acceptable point in {} trial points",
                    self.max_line_evals
                ),
            });
        }
        if y.iter().any(|v| !v.is_finite()) {
            return Ok(f64::INFINITY);
        }
        let c = self.param.to_physical(y);
        let j = self.eval.borrow_mut().cost(&c)?;
        Ok(self.kappa.get() * j / self.j_ref)
    }

    /// `(f(y), grad f(y))`.
    pub fn value_and_gradient(&self, y: &[f64]) -> Result<(f64, Vec<f64>), IdentifyError> {
        self.line_evals.set(0);
        let c = self.param.to_physical(y);
        let (j, dj) = self.eval.borrow_mut().cost_and_gradient(&c)?;
        let s = self.kappa.get() / self.j_ref;
        let g: Vec<f64> = self
            .param
            .scaled_gradient(y, &c, &dj)
            .iter()
            .map(|v| v * s)
            .collect();
        let f = s * j;
        *self.last.borrow_mut() = Some((y.to_vec(), f, g.clone()));
        Ok((f, g))
    }

    /// `grad f(y)` from the sensitivity Jacobian, `sum_i w_i (F_i - F_i^exp) dF_i/dc` (the
    /// adjoint gradient to round-off), for a method that needs the Jacobian at `y` anyway.
    fn gradient_from_jacobian(&self, y: &[f64]) -> Result<Vec<f64>, IdentifyError> {
        let c = self.param.to_physical(y);
        let (forces, jac) = {
            let mut ev = self.eval.borrow_mut();
            (ev.forces(&c)?, ev.jacobian(&c)?)
        };
        let p = self.eval.borrow().problem();
        let mut dj = vec![0.0; c.len()];
        for ((row, w), (f, d)) in jac.iter().zip(&p.weights).zip(forces.iter().zip(&p.target)) {
            let r = w * (f - d);
            for (g, j) in dj.iter_mut().zip(row) {
                *g += r * j;
            }
        }
        let s = self.kappa.get() / self.j_ref;
        Ok(self
            .param
            .scaled_gradient(y, &c, &dj)
            .iter()
            .map(|v| v * s)
            .collect())
    }

    /// Keeps `e` for the caller and gives argmin its text.
    pub fn fail(&self, e: IdentifyError) -> ArgminError {
        let msg = e.to_string();
        *self.error.borrow_mut() = Some(e);
        ArgminError::msg(msg)
    }

    fn take_error(&self) -> Option<IdentifyError> {
        self.error.borrow_mut().take()
    }
}

/// History, observer and stopping rules, consulted after every iteration.
/// A linearization at an iterate, for the stopping rules ([`Monitor::linearize`]).
struct Linearized {
    forces: Vec<f64>,
    jac: Vec<Vec<f64>>,
    columns: Vec<Column>,
    id: Identifiability,
}

/// A linearization where a parameter is undetermined ([`Monitor::chi2_below`],
/// [`Monitor::valley_holds`]): the noise variance and the Gauss-Newton model's predicted
/// chi-square decrease for the next step.
struct Undetermined {
    lin: Linearized,
    var: f64,
    next: Option<f64>,
}

pub(crate) struct Monitor<'a, 'p> {
    pub objective: &'a Objective<'p>,
    stop: StopCriteria,
    observer: RefCell<&'a mut dyn FnMut(&IterationRecord)>,
    pub history: RefCell<Vec<IterationRecord>>,
    offset: IterationRecord,
    prev_cost: Cell<f64>,
    pub reason: RefCell<Option<StopReason>>,
    /// BFGS updates skipped because the curvature condition failed.
    pub skipped_updates: Cell<usize>,
    /// Levenberg-Marquardt trials that did not decrease the cost (one forward run each).
    pub rejected_trials: Cell<usize>,
    /// The run's stop request.
    cancel: Cancel,
    /// [`StopCriteria::step_sigma`] when the method honours it (Levenberg-Marquardt).
    step_sigma: Option<f64>,
    /// The noise model of the deviations [`StopCriteria::step_sigma`] compares with.
    noise: NoiseModel,
    /// The gain ratio of the last accepted Levenberg-Marquardt step (NaN before one).
    pub last_gain: Cell<f64>,
    /// [`StopCriteria::valley_stop`] when the method honours it (Levenberg-Marquardt).
    valley: Option<crate::ValleyStop>,
}

impl<'a, 'p> Monitor<'a, 'p> {
    /// Records the iterate `y` after `iter` iterations of this run, with internal cost `f`
    /// and gradient `g`; returns a stop reason when a criterion is met.
    pub fn iterate(&self, iter: usize, y: &[f64], f: f64, g: &[f64]) -> Option<StopReason> {
        let o = self.objective;
        let to_j = o.j_ref / o.kappa.get();
        let cost = f * to_j;
        let yp = o.param.project(y);
        let pg = o.param.projected_gradient(&yp, g);
        let grad_norm = norm2(&pg) * to_j;
        let counts = o.eval.borrow().counts();
        let seconds = o.eval.borrow().elapsed();
        let rec = IterationRecord {
            iteration: self.offset.iteration + iter,
            params: o.param.to_physical(y),
            cost,
            grad_norm,
            forward_solves: self.offset.forward_solves + counts.forward,
            adjoint_solves: self.offset.adjoint_solves + counts.adjoint,
            sensitivity_solves: self.offset.sensitivity_solves + counts.sensitivities,
            seconds: self.offset.seconds + seconds,
        };
        // the same iterate may be reported twice (argmin's final check): record it once
        let previous = self.history.borrow().last().cloned();
        let repeated = previous
            .as_ref()
            .is_some_and(|l| l.iteration == rec.iteration && l.params == rec.params);
        if !repeated {
            (self.observer.borrow_mut())(&rec);
            self.history.borrow_mut().push(rec.clone());
        }
        let prev = self.prev_cost.replace(cost);
        let s = &self.stop;
        let reason = if cost / o.j_ref <= s.target_cost {
            Some(StopReason::TargetCost)
        } else if grad_norm / o.j_ref <= s.gradient_tol {
            Some(StopReason::GradientNorm)
        } else if iter > 0 && prev.is_finite() && prev - cost <= s.relative_decrease_tol * prev {
            Some(StopReason::RelativeDecrease)
        } else if let Some(fraction) =
            self.step_sigma
                .filter(|_| iter > 0 && !repeated)
                .filter(|&fr| {
                    previous
                        .as_ref()
                        .is_some_and(|p| self.steps_below_sigma(fr, Some(&p.params), &rec.params))
                })
        {
            Some(StopReason::StepBelowSigma { fraction })
        } else if let Some(fraction) = self
            .step_sigma
            .filter(|_| s.lm.subspace && iter > 0 && !repeated)
            .filter(|&fr| {
                previous
                    .as_ref()
                    .is_some_and(|p| self.subspace_below(fr, &p.params, &rec.params))
            })
        {
            Some(StopReason::SubspaceBelowSigma { fraction })
        } else if let Some(fraction) = self
            .step_sigma
            .filter(|_| s.proposed_step && iter > 0 && !repeated)
            .filter(|_| (self.last_gain.get() - 1.0).abs() <= PROPOSED_GAIN_TOL)
            .filter(|&fr| self.steps_below_sigma(fr, None, &rec.params))
        {
            Some(StopReason::ProposedBelowSigma {
                fraction,
                gain: self.last_gain.get(),
            })
        } else if let Some(fraction) = self
            .step_sigma
            .filter(|_| s.chi2_stop && iter > 0 && !repeated)
            .filter(|&fr| {
                previous
                    .as_ref()
                    .is_some_and(|p| self.chi2_below(fr * fr, p.cost, cost, &rec.params))
            })
        {
            Some(StopReason::Chi2BelowSigma { fraction })
        } else if let Some(rule) = self
            .valley
            .filter(|_| iter > 0 && !repeated)
            .filter(|rule| self.valley_holds(rule, &rec.params))
        {
            Some(StopReason::ValleyBelowSigma {
                steps: rule.steps,
                fraction: rule.fraction,
                chi2: rule.chi2,
            })
        } else if rec.iteration >= s.max_iterations {
            Some(StopReason::MaxIterations)
        } else if self.cancel.is_raised() {
            Some(StopReason::Interrupted)
        } else {
            None
        };
        if reason.is_some() {
            *self.reason.borrow_mut() = reason.clone();
        }
        reason
    }

    /// The forces, Jacobian, free columns and identifiability at `c` (physical
    /// parameters), the first two from the evaluator's cache (Levenberg-Marquardt has just
    /// linearized there); `None` when either cannot be computed.
    fn linearize(&self, p: &Problem, c: &[f64]) -> Option<Linearized> {
        let o = self.objective;
        let (forces, jac) = {
            let mut ev = o.eval.borrow_mut();
            (ev.forces(c).ok()?, ev.jacobian(c).ok()?)
        };
        let columns: Vec<Column> = o
            .param
            .free
            .iter()
            .map(|f| Column::of(f, c[f.index]))
            .collect();
        let id = Identifiability::with_noise(
            &jac,
            &p.weights,
            p.cost_of(&forces),
            c,
            &columns,
            self.noise,
            Some(Forces {
                fitted: &forces,
                measured: &p.target,
            }),
        );
        Some(Linearized {
            forces,
            jac,
            columns,
            id,
        })
    }

    /// Whether the step from `prev` to `c` (physical parameters; no such test without
    /// `prev`) and the undamped
    /// Gauss-Newton step from `c` move every free parameter by less than `fraction` of its
    /// standard deviation at `c` ([`StopCriteria::step_sigma`]); false when a parameter is
    /// undetermined at `c` or anything cannot be computed. The forces and the Jacobian at
    /// `c` come from the evaluator's cache (Levenberg-Marquardt has just linearized there).
    fn steps_below_sigma(&self, fraction: f64, prev: Option<&[f64]>, c: &[f64]) -> bool {
        let p = self.objective.eval.borrow().problem();
        let Some(Linearized {
            forces,
            jac,
            columns,
            id,
        }) = self.linearize(p, c)
        else {
            return false;
        };
        // with a parameter undetermined the others' deviations are conditional on it
        // (held), while a valley lets them move with it: never stop this way then (on
        // anon-nh, with sY undetermined, stopping on the others' steps left m 1 sigma away)
        if !id.undetermined.is_empty() {
            return false;
        }
        let Some(gn) = gauss_newton_step(&jac, &forces, p, &columns) else {
            return false;
        };
        columns.iter().zip(&gn).all(|(col, dy)| {
            let Some(sd) = id
                .names
                .iter()
                .position(|n| *n == col.name)
                .map(|k| id.std_dev[k])
                .filter(|sd| sd.is_finite() && *sd > 0.0)
            else {
                return false;
            };
            let k = col.index;
            // the Gauss-Newton step projected onto the box: a parameter on a bound that
            // the step pushes out does not move (and is not called converged by this rule)
            let next = (c[k] + dy * col.dc_dy).clamp(col.lower, col.upper);
            let at_bound = next == col.lower || next == col.upper;
            prev.is_none_or(|prev| (c[k] - prev[k]).abs() < fraction * sd)
                && (next - c[k]).abs() < fraction * sd
                && !(at_bound && (dy * col.dc_dy).abs() >= fraction * sd)
        })
    }

    /// Whether, with a parameter undetermined at `c` (physical parameters, cost `cost`),
    /// the last step's chi-square decrease (from `prev_cost`) and the one the Gauss-Newton
    /// model predicts for the next step are both below `threshold`
    /// ([`StopCriteria::chi2_stop`], `crate::chi2_stop`); false when every parameter is
    /// determined (the step rule serves then) or anything cannot be computed.
    fn chi2_below(&self, threshold: f64, prev_cost: f64, cost: f64, c: &[f64]) -> bool {
        let Some(u) = self.undetermined_at(c) else {
            return false;
        };
        let last = 2.0 * (prev_cost - cost) / u.var;
        last.is_finite() && last < threshold && u.next.is_some_and(|n| n < threshold)
    }

    /// The linearization at `c` (physical parameters) when a parameter is undetermined
    /// there, with the noise variance and the chi-square decrease the Gauss-Newton model
    /// predicts for the next step (`crate::chi2_stop`); `None` when every parameter is
    /// determined or the linearization or the variance cannot be computed.
    fn undetermined_at(&self, c: &[f64]) -> Option<Undetermined> {
        let p = self.objective.eval.borrow().problem();
        let lin = self.linearize(p, c)?;
        if lin.id.undetermined.is_empty() {
            return None;
        }
        let var = crate::chi2_stop::noise_variance(&lin.id)?;
        let next = crate::chi2_stop::predicted_chi2_decrease(
            &lin.jac,
            &lin.forces,
            (&p.weights, &p.target),
            &lin.columns,
            &lin.id,
        );
        Some(Undetermined { lin, var, next })
    }

    /// Whether the valley stop `rule` holds at `c` (physical parameters; its iterate the
    /// history's last): the last `rule.steps` accepted steps, from the history
    /// (`crate::valley_stop`).
    fn valley_holds(&self, rule: &crate::ValleyStop, c: &[f64]) -> bool {
        let Some(Undetermined { lin, var, next }) = self.undetermined_at(c) else {
            return false;
        };
        // the Gauss-Newton model sees no larger decrease ahead either: a plateau far from
        // the optimum (a viscosity so high that the law is elastic there) is no valley
        if !next.is_some_and(|n| n < rule.chi2) {
            return false;
        }
        let h = self.history.borrow();
        let need = rule.steps.max(1) + 1;
        if h.len() < need {
            return false;
        }
        let recent: Vec<(Vec<f64>, f64)> = h[h.len() - need..]
            .iter()
            .map(|r| {
                (
                    lin.columns.iter().map(|col| r.params[col.index]).collect(),
                    r.cost,
                )
            })
            .collect();
        crate::valley_stop::holds(rule, &lin.id, &recent, var)
    }

    /// The determined subspace at `c` (physical parameters; Levenberg-Marquardt has just
    /// linearized there) for [`LmStrategy::subspace`] (`crate::subspace::determined_basis`);
    /// `None` for full steps.
    pub fn determined_basis(&self, c: &[f64]) -> Option<Vec<Vec<f64>>> {
        let p = self.objective.eval.borrow().problem();
        let lin = self.linearize(p, c)?;
        if lin.id.undetermined.is_empty() {
            return None;
        }
        let var = crate::chi2_stop::noise_variance(&lin.id)?;
        let g = crate::subspace::scaled_gradient(
            &lin.jac,
            &lin.forces,
            (&p.weights, &p.target),
            &lin.columns,
        );
        crate::subspace::determined_basis(&lin.id, &g, var)
    }

    /// Whether the statistical stop of [`LmStrategy::subspace`] holds at `c` (physical
    /// parameters) after the step from `prev`: the steps are in the determined subspace
    /// there, and the last step and the next truncated Gauss-Newton step move every
    /// determined combination by less than `fraction` of its conditional deviation
    /// (`crate::subspace::determined_steps_below`).
    fn subspace_below(&self, fraction: f64, prev: &[f64], c: &[f64]) -> bool {
        let p = self.objective.eval.borrow().problem();
        let Some(lin) = self.linearize(p, c) else {
            return false;
        };
        if lin.id.undetermined.is_empty() {
            return false;
        }
        let Some(var) = crate::chi2_stop::noise_variance(&lin.id) else {
            return false;
        };
        let g = crate::subspace::scaled_gradient(
            &lin.jac,
            &lin.forces,
            (&p.weights, &p.target),
            &lin.columns,
        );
        if crate::subspace::determined_basis(&lin.id, &g, var).is_none() {
            return false;
        }
        let at = |x: &[f64]| -> Vec<f64> { lin.columns.iter().map(|col| x[col.index]).collect() };
        crate::subspace::determined_steps_below(
            &lin.id,
            &lin.columns,
            &g,
            fraction,
            Some(&at(prev)),
            &at(c),
        )
    }

    /// The stopping rules.
    pub fn stop_criteria(&self) -> &StopCriteria {
        &self.stop
    }

    fn last(&self) -> Option<IterationRecord> {
        self.history.borrow().last().cloned()
    }
}

/// Runs an identification from the starts in `config` and delivers every iterate (the
/// start included) to `observer` as soon as it is accepted.
///
/// # Errors
/// Configuration errors ([`Parameterization::new`]'s, [`IdentifyError::InvalidOption`],
/// [`IdentifyError::TooFewPoints`] when there are not more weighted data than free
/// parameters, [`IdentifyError::MethodUnavailable`]); [`IdentifyError::Forward`] /
/// [`IdentifyError::Adjoint`] when the start itself cannot be solved or differentiated.
/// A failure later in the run ends it with [`StopReason::Stalled`] and the best iterate,
/// not with an error.
pub fn identify(
    problem: &Problem,
    config: &IdentifyConfig,
    observer: &mut dyn FnMut(&IterationRecord),
) -> Result<IdentifyResult, IdentifyError> {
    run(problem, config, None, observer)
}

/// Continues a run from its last recorded iterate `last` (as written by the observer):
/// the start is `last.params`, iterations, solve counts and time continue from the
/// record's. Quasi-Newton curvature is not recorded and starts afresh.
///
/// # Errors
/// As [`identify`]; [`IdentifyError::StartOutsideBounds`] if the record lies outside the
/// configured bounds; [`IdentifyError::InvalidSpec`] if it has the wrong length.
pub fn resume(
    problem: &Problem,
    config: &IdentifyConfig,
    last: &IterationRecord,
    observer: &mut dyn FnMut(&IterationRecord),
) -> Result<IdentifyResult, IdentifyError> {
    run(problem, config, Some(last), observer)
}

/// Results of a multi-start identification.
#[derive(Debug)]
pub struct MultiStart {
    /// One outcome per start, in order.
    pub runs: Vec<Result<IdentifyResult, IdentifyError>>,
    /// Index of the run with the lowest final cost among the successful ones.
    pub best: Option<usize>,
}

/// Runs [`identify`] from each of `starts` (values of the free parameters, in law order;
/// the rest of `config` is shared). The observer receives the start index with each
/// record. Runs are sequential; callers wanting parallel runs call [`identify`] from
/// threads (a [`Problem`] is `Sync`).
///
/// # Errors
/// [`IdentifyError::InvalidSpec`] when a start has the wrong number of values; errors of
/// single runs are kept in [`MultiStart::runs`].
pub fn multistart(
    problem: &Problem,
    config: &IdentifyConfig,
    starts: &[Vec<f64>],
    observer: &mut dyn FnMut(usize, &IterationRecord),
) -> Result<MultiStart, IdentifyError> {
    let n_free = config.params.iter().filter(|p| p.free).count();
    let mut runs = Vec::new();
    for (i, s) in starts.iter().enumerate() {
        if s.len() != n_free {
            return Err(IdentifyError::InvalidSpec {
                name: format!("starts[{i}]"),
                why: format!("{} values for {n_free} free parameters", s.len()),
            });
        }
        let cfg = with_starts(config, s);
        runs.push(identify(problem, &cfg, &mut |r| observer(i, r)));
    }
    let best = runs
        .iter()
        .enumerate()
        .filter_map(|(i, r)| r.as_ref().ok().map(|r| (i, r.cost)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i);
    Ok(MultiStart { runs, best })
}

/// `config` with the free parameters' starts replaced by `starts` (law order).
pub fn with_starts(config: &IdentifyConfig, starts: &[f64]) -> IdentifyConfig {
    let mut cfg = config.clone();
    for (p, &s) in cfg.params.iter_mut().filter(|p| p.free).zip(starts) {
        p.value = Some(s);
    }
    cfg
}

/// The identifiability summary at the last iterate (`None` when its forces or Jacobian
/// cannot be computed).
fn final_identifiability(
    objective: &Objective<'_>,
    problem: &Problem,
    config: &IdentifyConfig,
    last: &IterationRecord,
) -> Option<Identifiability> {
    let param = &objective.param;
    let mut ev = objective.eval.borrow_mut();
    let fitted = ev.forces(&last.params).ok();
    ev.jacobian(&last.params).ok().map(|jac| {
        let columns: Vec<Column> = param
            .free
            .iter()
            .map(|f| Column::of(f, last.params[f.index]))
            .collect();
        Identifiability::with_noise_observed(
            &jac,
            &problem.weights,
            last.cost,
            &last.params,
            &columns,
            config.noise,
            fitted.as_deref().map(|f| Forces {
                fitted: f,
                measured: &problem.target,
            }),
            problem.observed(),
        )
    })
}

fn run(
    problem: &Problem,
    config: &IdentifyConfig,
    resume_from: Option<&IterationRecord>,
    observer: &mut dyn FnMut(&IterationRecord),
) -> Result<IdentifyResult, IdentifyError> {
    config.validate()?;
    let mut param = Parameterization::new(&*problem.law, &config.params)?;
    let starts = param.base.clone();
    let offset = match resume_from {
        Some(r) => {
            if r.params.len() != param.base.len() {
                return Err(IdentifyError::InvalidSpec {
                    name: "resume".into(),
                    why: format!(
                        "the record has {} parameters, law `{}` has {}",
                        r.params.len(),
                        param.law,
                        param.base.len()
                    ),
                });
            }
            param.check_inside(&r.params)?;
            for f in param.free.iter_mut() {
                param.base[f.index] = r.params[f.index];
                f.start = r.params[f.index];
            }
            r.clone()
        }
        None => IterationRecord {
            iteration: 0,
            params: vec![],
            cost: f64::NAN,
            grad_norm: f64::NAN,
            forward_solves: 0,
            adjoint_solves: 0,
            sensitivity_solves: 0,
            seconds: 0.0,
        },
    };
    let n_data = problem.n_data();
    if n_data <= param.n_free() {
        return Err(IdentifyError::TooFewPoints {
            got: n_data,
            needed: param.n_free() + 1,
            why: format!(
                "more weighted data than the {} free parameters",
                param.n_free()
            ),
        });
    }
    if matches!(config.method, Method::Lbfgsb { .. }) && !cfg!(feature = "lbfgsb") {
        return Err(IdentifyError::MethodUnavailable("lbfgsb"));
    }
    let mut eval = Evaluator::new(problem)?;
    // what the method asks for after a cost: a gradient after an accepted line-search point,
    // a Jacobian after an accepted Levenberg-Marquardt trial (computed on idle cores only)
    eval.set_prefetch(match config.method {
        Method::LevenbergMarquardt => Prefetch::Jacobian,
        _ => Prefetch::Gradient,
    });
    // every Jacobian of a run serves the free parameters only: the fixed ones' never formed
    eval.set_jacobian_columns(Some(param.free.iter().map(|f| f.index).collect()));
    let objective = Objective::new(eval, param, config.stop.max_line_search_evaluations);
    let y0 = objective.param.to_scaled(&objective.param.base);
    // kappa from the start's gradient: one forward + one adjoint, cached for the optimizer;
    // Levenberg-Marquardt takes it from the sensitivities it needs there anyway
    let g0 = match config.method {
        Method::LevenbergMarquardt => objective.gradient_from_jacobian(&y0)?,
        _ => objective.value_and_gradient(&y0)?.1,
    };
    let c0 = objective.param.to_physical(&y0);
    let initial_cost = objective.eval.borrow_mut().cost(&c0)?;
    let initial_forces = objective.eval.borrow_mut().forces(&c0)?;
    let gmax = norm_inf(&g0);
    if gmax > 0.0 && gmax.is_finite() {
        objective.kappa.set(config.initial_step / gmax);
    }
    *objective.last.borrow_mut() = None;
    let monitor = Monitor {
        objective: &objective,
        stop: config.stop,
        observer: RefCell::new(observer),
        history: RefCell::new(Vec::new()),
        offset,
        prev_cost: Cell::new(f64::NAN),
        reason: RefCell::new(None),
        skipped_updates: Cell::new(0),
        rejected_trials: Cell::new(0),
        cancel: config.cancel.clone(),
        step_sigma: config
            .stop
            .step_sigma
            .filter(|_| config.method == Method::LevenbergMarquardt),
        noise: config.noise,
        last_gain: Cell::new(f64::NAN),
        valley: config
            .stop
            .valley_stop
            .filter(|_| config.method == Method::LevenbergMarquardt),
    };
    let outcome = match config.method {
        Method::Bfgs => run_bfgs(&monitor, &y0, config.bfgs_start),
        Method::Lbfgs { memory } => run_lbfgs(&monitor, &y0, memory),
        Method::Lbfgsb { memory } => run_lbfgsb(&monitor, &y0, memory, &config.stop),
        Method::LevenbergMarquardt => crate::lm::run(&monitor, &y0),
    };
    // a failure inside the run ends it as a stall at the last recorded iterate
    let mut reason = match outcome {
        Ok(()) => monitor
            .reason
            .borrow()
            .clone()
            .unwrap_or(StopReason::Stalled(
                "the optimizer stopped without a reason".into(),
            )),
        Err(e) => {
            let e = objective.take_error().unwrap_or(e);
            if monitor.history.borrow().is_empty() {
                return Err(e);
            }
            match e {
                IdentifyError::Stalled { reason, .. } => StopReason::Stalled(reason),
                other => StopReason::Stalled(other.to_string()),
            }
        }
    };
    let Some(last) = monitor.last() else {
        return Err(IdentifyError::Optimizer("no iterate was recorded".into()));
    };
    if matches!(reason, StopReason::Stalled(_))
        && last.cost / objective.j_ref <= config.stop.roundoff_cost
    {
        reason = StopReason::RoundOff;
    }
    let monitor_rejected = monitor.rejected_trials.get();
    let history = monitor.history.into_inner();
    let param = &objective.param;
    let identifiability = if config.identifiability {
        final_identifiability(&objective, problem, config, &last)
    } else {
        None
    };
    // honest stops: a first-order point where the data leave a parameter undetermined
    // has not identified it
    if let Some(id) = identifiability
        .as_ref()
        .filter(|i| !i.undetermined.is_empty())
    {
        if reason.is_converged() {
            let params = id
                .undetermined
                .iter()
                .zip(&id.reasons)
                .map(|(name, why)| {
                    let f = param.free.iter().find(|f| f.name == *name);
                    let at = f.and_then(|f| {
                        let v = last.params[f.index];
                        if v <= f.lower {
                            Some(format!("at its lower bound {}", f.lower))
                        } else if v >= f.upper {
                            Some(format!("at its upper bound {}", f.upper))
                        } else {
                            None
                        }
                    });
                    match at {
                        Some(at) => format!("{name} ({at}: {why})"),
                        None => format!("{name} ({why})"),
                    }
                })
                .collect();
            reason = StopReason::Undetermined {
                met: Box::new(reason),
                params,
            };
        }
    }
    let forces = objective
        .eval
        .borrow_mut()
        .forces(&last.params)
        .unwrap_or_default();
    let counts = objective.eval.borrow().counts();
    let seconds = objective.eval.borrow().elapsed();
    let infos = problem.law.params();
    let params = infos
        .iter()
        .enumerate()
        .map(|(k, info)| {
            let f = param.free.iter().find(|f| f.index == k);
            let v = last.params[k];
            ParamOutcome {
                name: info.name,
                unit: info.unit,
                free: f.is_some(),
                start: starts[k],
                value: v,
                lower: f.map_or(v, |f| f.lower),
                upper: f.map_or(v, |f| f.upper),
                at_lower: f.is_some_and(|f| v <= f.lower),
                at_upper: f.is_some_and(|f| v >= f.upper),
            }
        })
        .collect();
    Ok(IdentifyResult {
        law: problem.law.name(),
        method: config.method,
        params,
        c: last.params.clone(),
        initial_cost: if resume_from.is_some() {
            history.first().map_or(initial_cost, |h| h.cost)
        } else {
            initial_cost
        },
        cost: last.cost,
        reference_cost: objective.j_ref,
        iterations: last.iteration,
        forward_solves: offset_sum(resume_from, |r| r.forward_solves) + counts.forward,
        adjoint_solves: offset_sum(resume_from, |r| r.adjoint_solves) + counts.adjoint,
        sensitivity_solves: offset_sum(resume_from, |r| r.sensitivity_solves)
            + counts.sensitivities,
        rejected_trials: monitor_rejected,
        newton_iterations: counts.newton_iterations,
        factorizations: counts.factorizations,
        stopped_runs: counts.stopped,
        schedule_steps: counts.schedule_steps,
        steps_skipped: counts.steps_skipped,
        cache_hits: counts.cache_hits,
        distinct_points: counts.distinct_points,
        stop_reason: reason,
        seconds: offset_sum(resume_from, |r| r.seconds) + seconds,
        history,
        initial_forces,
        forces,
        identifiability,
    })
}

/// The undamped Gauss-Newton step `dy = -(S^T S)^-1 S^T r` in the scaled variables of
/// `columns` at a point with forces `forces` and Jacobian `jac` (physical, one row per
/// datum); `S_ik = sqrt(w_i) dF_i/dc_k dc_k/dy_k`, `r_i = sqrt(w_i) (F_i - F_i^exp)`.
/// `None` when `S^T S` is not numerically positive definite.
fn gauss_newton_step(
    jac: &[Vec<f64>],
    forces: &[f64],
    p: &Problem,
    columns: &[Column],
) -> Option<Vec<f64>> {
    let n = columns.len();
    let mut ata = vec![vec![0.0; n]; n];
    let mut atr = vec![0.0; n];
    for ((row, w), (f, d)) in jac.iter().zip(&p.weights).zip(forces.iter().zip(&p.target)) {
        if *w <= 0.0 {
            continue;
        }
        let sw = w.sqrt();
        let s: Vec<f64> = columns
            .iter()
            .map(|col| sw * row[col.index] * col.dc_dy)
            .collect();
        let r = sw * (f - d);
        for a in 0..n {
            atr[a] += s[a] * r;
            for b in 0..n {
                ata[a][b] += s[a] * s[b];
            }
        }
    }
    let d = crate::linalg::solve_spd(&ata, &atr)?;
    let d: Vec<f64> = d.iter().map(|v| -v).collect();
    d.iter().all(|v| v.is_finite()).then_some(d)
}

fn offset_sum<T: Default>(r: Option<&IterationRecord>, f: impl Fn(&IterationRecord) -> T) -> T {
    r.map(f).unwrap_or_default()
}

fn argmin_outcome(r: Result<(), ArgminError>) -> Result<(), IdentifyError> {
    r.map_err(|e| IdentifyError::Optimizer(e.to_string()))
}

fn run_bfgs(monitor: &Monitor<'_, '_>, y0: &[f64], start: BfgsStart) -> Result<(), IdentifyError> {
    let n = y0.len();
    let armijo = ArmijoCondition::new(1e-4).map_err(|e| IdentifyError::Optimizer(e.to_string()))?;
    let ls = BacktrackingLineSearch::new(armijo)
        .rho(0.5)
        .map_err(|e| IdentifyError::Optimizer(e.to_string()))?;
    let bfgs: BFGS<_, f64> = BFGS::new(ls)
        .with_tolerance_grad(0.0)
        .and_then(|b| b.with_tolerance_cost(0.0))
        .map_err(|e| IdentifyError::Optimizer(e.to_string()))?;
    let eye: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
        .collect();
    let (h0, restart) = match start {
        BfgsStart::Scaled => (eye, false),
        BfgsStart::GaussNewton => (crate::lm::gauss_newton_inverse(monitor, y0)?, true),
    };
    let solver = Monitored {
        inner: bfgs,
        monitor,
        restart_gauss_newton: restart,
    };
    let problem = ArgminObjective {
        objective: monitor.objective,
    };
    argmin_outcome(
        Executor::new(problem, solver)
            .configure(|s| s.param(y0.to_vec()).inv_hessian(h0))
            .ctrlc(false)
            .timer(false)
            .run()
            .map(|_| ()),
    )
}

fn run_lbfgs(monitor: &Monitor<'_, '_>, y0: &[f64], memory: usize) -> Result<(), IdentifyError> {
    let ls: MoreThuenteLineSearch<Vec<f64>, Vec<f64>, f64> = MoreThuenteLineSearch::new();
    let lbfgs: LBFGS<_, Vec<f64>, Vec<f64>, f64> = LBFGS::new(ls, memory)
        .with_tolerance_grad(0.0)
        .and_then(|b| b.with_tolerance_cost(0.0))
        .map_err(|e| IdentifyError::Optimizer(e.to_string()))?;
    let solver = Monitored {
        inner: lbfgs,
        monitor,
        restart_gauss_newton: false,
    };
    let problem = ArgminObjective {
        objective: monitor.objective,
    };
    argmin_outcome(
        Executor::new(problem, solver)
            .configure(|s| s.param(y0.to_vec()))
            .ctrlc(false)
            .timer(false)
            .run()
            .map(|_| ()),
    )
}

#[cfg(feature = "lbfgsb")]
fn run_lbfgsb(
    monitor: &Monitor<'_, '_>,
    y0: &[f64],
    memory: usize,
    stop: &StopCriteria,
) -> Result<(), IdentifyError> {
    use rcompat_lbfgsb::{
        ArithmeticProfile, Bounds, OptimControl, OptimEvent, optim_lbfgsb_with_gradient_observed,
    };
    let o = monitor.objective;
    let (lo, hi) = o.param.scaled_bounds();
    let bounds = Bounds::new(lo, hi).map_err(|e| IdentifyError::Optimizer(e.to_string()))?;
    let mut control = OptimControl::default_for_dimension(y0.len());
    control.maxit = stop.max_iterations.saturating_sub(monitor.offset.iteration);
    control.lmm = memory;
    // pgtol acts on the infinity norm of the projected internal gradient; the 2-norm
    // rule is applied by the monitor after each accepted step
    control.pgtol = stop.gradient_tol * o.kappa.get() / (y0.len() as f64).sqrt();
    control.factr = stop.relative_decrease_tol / f64::EPSILON;
    let failed: RefCell<Option<IdentifyError>> = RefCell::new(None);
    let stopped = Cell::new(false);
    let fcall = |y: &[f64]| -> f64 {
        if stopped.get() {
            return f64::INFINITY;
        }
        match o.value(y) {
            Ok(f) => f,
            Err(e) => {
                failed.borrow_mut().get_or_insert(e);
                f64::INFINITY
            }
        }
    };
    let gcall = |y: &[f64]| -> Vec<f64> {
        match o.value_and_gradient(y) {
            Ok((_, g)) => g,
            Err(e) => {
                failed.borrow_mut().get_or_insert(e);
                vec![0.0; y.len()]
            }
        }
    };
    let iter = Cell::new(0usize);
    let report = |iteration: usize| {
        if let Some((y, f, g)) = o.last.borrow().clone() {
            if monitor.iterate(iteration, &y, f, &g).is_some() {
                stopped.set(true);
            }
        }
    };
    report(0);
    if stopped.get() {
        return Ok(());
    }
    let observer = |ev: OptimEvent| {
        if let OptimEvent::Accepted { iteration, .. } = ev {
            iter.set(iteration);
            report(iteration);
        }
    };
    let res = optim_lbfgsb_with_gradient_observed(
        y0.to_vec(),
        bounds,
        fcall,
        gcall,
        control,
        ArithmeticProfile::legacy(),
        observer,
    )
    .map_err(|e| IdentifyError::Optimizer(e.to_string()))?;
    if let Some(e) = failed.into_inner() {
        if !stopped.get() {
            return Err(e);
        }
    }
    if monitor.reason.borrow().is_none() {
        let reason = match res.convergence {
            0 => StopReason::RelativeDecrease,
            1 => StopReason::MaxIterations,
            _ => StopReason::Stalled(format!("L-BFGS-B: {}", res.message)),
        };
        *monitor.reason.borrow_mut() = Some(reason);
    }
    Ok(())
}

#[cfg(not(feature = "lbfgsb"))]
fn run_lbfgsb(
    _monitor: &Monitor<'_, '_>,
    _y0: &[f64],
    _memory: usize,
    _stop: &StopCriteria,
) -> Result<(), IdentifyError> {
    Err(IdentifyError::MethodUnavailable("lbfgsb"))
}
