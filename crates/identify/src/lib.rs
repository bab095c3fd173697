//! Parameter identification from indentation curves (paper §3-5, docs/theory.md §6): the
//! least-squares force misfit `J(c) = 1/2 sum_i w_i (F_i(c) - F_i^exp)^2` at the
//! simulation's schedule times, its exact adjoint gradient, and the optimizers that
//! minimize it over a box of admissible parameters.
//!
//! Map of the crate:
//!
//! - [`data`]: the experimental record `(t, F)` and its interpolation onto the schedule.
//! - [`problem`]: [`Problem`] (model, law, schedule, data, weights) and
//!   [`Evaluator`], the cached cost / gradient / Jacobian oracle (one forward and one
//!   adjoint solve per parameter point, keyed on the exact parameter bits).
//! - [`instrument`]: the instrument's parameters identified beside the law's (frame
//!   compliance `Cf`, drift rate `vd`, a depth offset `h0` per test; load control).
//! - [`params`]: free and fixed parameters, bounds and scaling ([`ParamSpec`],
//!   [`Parameterization`]).
//! - [`optimize`]: [`IdentifyConfig`], [`identify`], [`resume`], [`multistart()`]: argmin
//!   BFGS with Armijo backtracking (the paper's algorithm), L-BFGS with More-Thuente,
//!   L-BFGS-B (bounds, feature `lbfgsb`), Levenberg-Marquardt on the sensitivity
//!   Jacobian; stopping rules, iteration history through an observer callback.
//! - [`mod@multistart`]: seeded Latin-hypercube starts in the scaled box and the clustering
//!   of the runs' end points into distinct local minima.
//! - [`profile`]: profile-likelihood chains (constrained re-fits stepping away from the
//!   optimum) and their chi-square intervals.
//! - [`identifiability`]: singular values and directions of the scaled sensitivity
//!   matrix, Gauss-Newton standard deviations, correlations, the parameters the data do
//!   not determine (a converged run with such parameters ends with
//!   [`StopReason::Undetermined`]) and the weakest direction in words.
//! - [`noise`]: seeded multiplicative noise (SplitMix64, reproducible everywhere).
//! - [`linalg`]: thin wrappers over nalgebra (ordered SVD, Cholesky solves, norms).
//!
//! Use (what `indentify identify` does):
//!
//! ```no_run
//! use indentify_contact::{Model, Punch, Schedule, SolverOptions, trapezoid};
//! use indentify_identify::{ForceRecord, IdentifyConfig, Method, ParamSpec, Problem, identify};
//! use indentify_mesh::CylinderMesher;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let mesh = CylinderMesher::REFERENCE.build()?;
//! let model = Model::new(mesh, Punch::Cone { half_angle_deg: 68.0 })?;
//! let schedule = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30))?;
//! let record = ForceRecord::new(vec![0.0, 1.0, 2.0, 3.0], vec![0.0, 250.0, 200.0, 0.0])?;
//! let law = indentify_laws::law_by_name("maxwell").unwrap();
//! let problem = Problem::new(model, law, schedule, &record, None, SolverOptions::default())?;
//! let mut config = IdentifyConfig::new(vec![
//!     ParamSpec::free("E", 4000.0, 1e3, 1e6),      // start, lower, upper (log-scaled)
//!     ParamSpec::fixed("nu", 0.3),
//!     ParamSpec::free("eta", 70000.0, 1e3, 1e7),
//! ]);
//! config.method = Method::Bfgs;
//! let result = identify(&problem, &config, &mut |rec| {
//!     // one line of history.csv per accepted iterate, written as it comes
//!     println!("{} {:?} {:e} {:e}", rec.iteration, rec.params, rec.cost, rec.grad_norm);
//! })?;
//! for p in &result.params {
//!     println!("{} = {} {} (start {}, bound hit: {})", p.name, p.value, p.unit, p.start,
//!         p.at_lower || p.at_upper);
//! }
//! result.ensure_converged()?; // a stall or the iteration limit becomes an error here
//! # Ok(()) }
//! ```
//!
//! Invariants: this crate does no file IO and prints nothing (the CLI and xtask write
//! histories and reports from the observer callback and the result structs); it alone
//! knows argmin; every parameter vector it hands to other crates is the law's full vector
//! in the law's order, physical units.

pub mod data;
pub mod identifiability;
pub mod instrument;
pub mod linalg;
pub mod multistart;
pub mod noise;
pub mod optimize;
pub mod params;
pub mod problem;
pub mod profile;

mod argmin_glue;
mod chi2_stop;
mod lm;
mod subspace;
mod tasks;
mod valley_stop;

pub use data::ForceRecord;
pub use identifiability::{Identifiability, NoiseModel, Observed};
pub use instrument::{Instrument, Instrumented};
pub use noise::{SplitMix64, multiplicative_noise};
pub use optimize::{
    BfgsStart, Cancel, DEFAULT_STEP_SIGMA, IdentifyConfig, IdentifyResult, IterationRecord,
    LmDamping, LmStrategy, Method, MultiStart, PROPOSED_GAIN_TOL, ParamOutcome, StopCriteria,
    StopReason, identify, multistart, resume,
};
pub use params::{ParamSpec, Parameterization, Scaling};
pub use problem::{Evaluator, IntoMaterial, Prefetch, Problem, Test};
pub use valley_stop::ValleyStop;

use indentify_adjoint::AdjointError;
use indentify_contact::ContactError;

/// Errors of identification: bad configuration or data (caught before any solve), and
/// failures of the direct or adjoint solves or of the optimizer (with the parameters).
#[derive(Debug, thiserror::Error)]
pub enum IdentifyError {
    /// A parameter name that the law does not have.
    #[error("law `{law}` has no parameter `{name}`; its parameters are {expected}")]
    UnknownParameter {
        /// Law name.
        law: &'static str,
        /// The name given.
        name: String,
        /// The law's parameter names.
        expected: String,
    },
    /// A parameter given twice.
    #[error("parameter `{name}` is given twice")]
    DuplicateParameter {
        /// Parameter name.
        name: String,
    },
    /// A law parameter given neither as free nor as fixed.
    #[error(
        "parameter `{name}` of law `{law}` is missing: give it as free (with a start) or fixed (with a value)"
    )]
    MissingParameter {
        /// Law name.
        law: &'static str,
        /// Parameter name.
        name: &'static str,
    },
    /// A fixed parameter without a value.
    #[error("parameter `{name}` is fixed but has no value")]
    FixedWithoutValue {
        /// Parameter name.
        name: String,
    },
    /// A free parameter without a starting value.
    #[error("parameter `{name}` is free but has no starting value")]
    StartMissing {
        /// Parameter name.
        name: String,
    },
    /// Lower bound above upper bound (or not finite where needed).
    #[error("bounds of `{name}` exclude each other: lower {lower} > upper {upper}")]
    BoundsExclude {
        /// Parameter name.
        name: String,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// A start (or resume point, or fixed value) outside the bounds.
    #[error("start of `{name}` = {value} lies outside its bounds [{lower}, {upper}]")]
    StartOutsideBounds {
        /// Parameter name.
        name: String,
        /// Offending value.
        value: f64,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// A parameter specification that is inconsistent in another way.
    #[error("parameter `{name}`: {why}")]
    InvalidSpec {
        /// Parameter name.
        name: String,
        /// What is wrong and what is allowed.
        why: String,
    },
    /// Every parameter is fixed.
    #[error("no free parameter: nothing to identify")]
    NothingFree,
    /// A data record with too few points for the use made of it.
    #[error("the data record has {got} usable points; at least {needed} are needed ({why})")]
    TooFewPoints {
        /// Points given (or with non-zero weight).
        got: usize,
        /// Points needed.
        needed: usize,
        /// Why that many.
        why: String,
    },
    /// A data record with a bad value.
    #[error("data record, point {index}: {why}")]
    InvalidRecord {
        /// Index of the offending point.
        index: usize,
        /// What is wrong.
        why: String,
    },
    /// A data record whose time range does not cover the simulated history.
    #[error(
        "the data record covers t in [{record_start}, {record_end}] s but the simulation runs over [{sim_start}, {sim_end}] s: the record must cover the whole history"
    )]
    RecordDoesNotCover {
        /// First time of the record (s).
        record_start: f64,
        /// Last time of the record (s).
        record_end: f64,
        /// First schedule time (s).
        sim_start: f64,
        /// Last schedule time (s).
        sim_end: f64,
    },
    /// Weights of the wrong length or value.
    #[error("weights: {why}")]
    InvalidWeights {
        /// What is wrong.
        why: String,
    },
    /// An option of the optimizer outside its range.
    #[error("option `{field}` = {value} is not allowed: expected {allowed}")]
    InvalidOption {
        /// Field name.
        field: &'static str,
        /// Offending value, as text.
        value: String,
        /// What is allowed.
        allowed: &'static str,
    },
    /// A method that this build does not include.
    #[error("method `{0}` is not available in this build (enable the crate feature `lbfgsb`)")]
    MethodUnavailable(&'static str),
    /// The direct problem failed.
    #[error("direct problem failed at c = {params:?}: {source}")]
    Forward {
        /// Parameters of the failed run (law order).
        params: Vec<f64>,
        /// The solver's error.
        #[source]
        source: ContactError,
    },
    /// The adjoint or sensitivity computation failed.
    #[error("adjoint failed at c = {params:?}: {source}")]
    Adjoint {
        /// Parameters (law order).
        params: Vec<f64>,
        /// The adjoint's error.
        #[source]
        source: AdjointError,
    },
    /// The optimizer library reported an error.
    #[error("optimizer error: {0}")]
    Optimizer(String),
    /// The optimizer stopped without meeting a convergence criterion.
    #[error(
        "the optimizer stalled after {iterations} iterations at J = {cost:.6e}: {reason} (the history up to here was delivered to the observer)"
    )]
    Stalled {
        /// Iterations done.
        iterations: usize,
        /// Cost at the best point.
        cost: f64,
        /// Why it stopped.
        reason: String,
    },
}
