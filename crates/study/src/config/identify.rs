//! The optional `identify` section of a configuration — which law parameters are identified
//! (start, bounds, scaling) and which are held, the optimizer and its stopping rules — its
//! command-line overrides (`--free`, `--fixed`, `--start`, `--method`, `--max-iter`), and
//! its mapping onto [`indentify_identify::IdentifyConfig`].
//!
//! Resolution, per law parameter: an entry of `identify.params` if there is one; a
//! parameter that `params` does not list is held at its `law` value; without the section
//! (or with an empty `params`) every parameter but `nu` is free from its `law` value. An
//! omitted start or fixed value is the `law` value; omitted bounds are the law's admissible
//! range; the default scaling is `Log`, or `Linear` when the lower bound is negative.
//!
//! Instrument parameters (`Cf`, `vd`, `h0`; load control, docs/theory.md §13.6) exist when
//! a name in `params`, `--free`, `--fixed` or `--start` asks for them ([`instrument_of`]);
//! their `law` value is 0, their default scaling `Linear`. `h0` names every test's offset
//! (`h0[1]`, `h0[2]`, ... in a joint configuration), `h0[k]` one of them (its setting wins
//! over `h0`'s).

use std::collections::BTreeMap;

use anyhow::{Context, Result, anyhow, bail};
use indentify_identify::{
    BfgsStart, DEFAULT_STEP_SIGMA, IdentifyConfig, Instrument, LmDamping, LmStrategy, Method,
    NoiseModel, ParamSpec, Parameterization, Scaling, StopCriteria,
};
use indentify_laws::Material;
use serde::{Deserialize, Serialize};

use super::LawSpec;

/// The `identify: (...)` section.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "identify")]
pub struct IdentifySection {
    /// Law parameters by name (`"E"`, `"nu"`, `"eta"`, ...): free or fixed.
    #[serde(default)]
    pub params: BTreeMap<String, ParamSetting>,
    /// The optimizer.
    #[serde(default)]
    pub method: MethodName,
    /// Correction pairs kept by `Lbfgs` and `Lbfgsb`.
    #[serde(default = "default_memory")]
    pub memory: usize,
    /// First trial step, infinity norm in the scaled variables (0.5: at most a factor
    /// e^0.5 on a log-scaled parameter).
    #[serde(default = "default_initial_step")]
    pub initial_step: f64,
    /// The initial inverse Hessian of `Bfgs`: `Scaled` (the paper's, the default) or
    /// `GaussNewton` (the damped Gauss-Newton matrix of the start; docs/joint-fits.md).
    #[serde(default, skip_serializing_if = "BfgsStartName::is_scaled")]
    pub bfgs_start: BfgsStartName,
    /// Stopping rules.
    #[serde(default)]
    pub stop: StopSection,
    /// Compute the identifiability summary at the end (one sensitivity solve).
    #[serde(default = "default_true")]
    pub identifiability: bool,
    /// What the standard deviations assume about the force noise (see [`NoiseSetting`]);
    /// default `Residual`.
    #[serde(default, skip_serializing_if = "NoiseSetting::is_residual")]
    pub noise: NoiseSetting,
    /// The fidelity schedule: the fit's first iterations on the 2x coarser model, then the
    /// full-fidelity fit from the coarse optimum (`None`, the default: full fidelity
    /// throughout; see [`CoarseToFineSetting`] and `crate::coarse_to_fine`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coarse_to_fine: Option<CoarseToFineSetting>,
}

/// `identify.coarse_to_fine: Some((iterations: N))`: at most `iterations` iterations on
/// the model 2x coarser in space (and in time where the schedule allows it), with the
/// section's other stopping rules, then the full-fidelity fit from the coarse optimum.
/// Measured in docs/performance.md ("Coarse to fine on R2, its noisy copy and an R1 map
/// indent").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoarseToFineSetting {
    /// The coarse phase's iteration limit (>= 1).
    pub iterations: usize,
}

/// The noise model of the standard deviations (`identify.noise`), as written in
/// configurations; see `indentify_identify::NoiseModel`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum NoiseSetting {
    /// One variance for every weighted residual, `2J/(n-p)` (the classical Gauss-Newton
    /// deviations).
    #[default]
    Residual,
    /// Multiplicative noise: the standard deviation of each force is this fraction of the
    /// force (uniform noise `F (1 + a xi)`, xi in [-1, 1], has `a / sqrt(3)`).
    Relative(f64),
    /// Multiplicative noise of a level estimated from the residuals.
    RelativeEstimated,
    /// Additive noise of this standard deviation (N).
    Absolute(f64),
}

impl NoiseSetting {
    fn is_residual(&self) -> bool {
        *self == NoiseSetting::Residual
    }

    /// The library's model.
    pub fn model(self) -> NoiseModel {
        match self {
            NoiseSetting::Residual => NoiseModel::Residual,
            NoiseSetting::Relative(v) => NoiseModel::Relative(v),
            NoiseSetting::RelativeEstimated => NoiseModel::RelativeEstimated,
            NoiseSetting::Absolute(v) => NoiseModel::Absolute(v),
        }
    }

    /// Checks a stated level (finite, > 0), naming `field`.
    ///
    /// # Errors
    /// A level that is not a finite number > 0.
    pub fn check(self, field: &str) -> Result<()> {
        match self {
            NoiseSetting::Relative(v) | NoiseSetting::Absolute(v)
                if !(v.is_finite() && v > 0.0) =>
            {
                bail!(
                    "{field} = {self:?} is not allowed: the noise level must be a finite number > 0 \
                     (Relative(f): standard deviation f x |F|, e.g. Relative(0.01) for 1%; \
                     Absolute(s): standard deviation s in N; or RelativeEstimated, Residual)"
                )
            }
            _ => Ok(()),
        }
    }
}

/// The initial inverse Hessian of BFGS (`identify.bfgs_start`), as written in
/// configurations; see `indentify_identify::BfgsStart`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum BfgsStartName {
    /// `kappa I`, the first step `initial_step` long (the paper's).
    #[default]
    Scaled,
    /// The inverse of the damped Gauss-Newton matrix at the start (one sensitivity solve),
    /// and again after an update skipped for lack of curvature.
    GaussNewton,
}

impl BfgsStartName {
    fn is_scaled(&self) -> bool {
        *self == BfgsStartName::Scaled
    }

    /// The library's value.
    pub fn start(self) -> BfgsStart {
        match self {
            BfgsStartName::Scaled => BfgsStart::Scaled,
            BfgsStartName::GaussNewton => BfgsStart::GaussNewton,
        }
    }
}

fn default_memory() -> usize {
    5
}

fn default_initial_step() -> f64 {
    IdentifyConfig::new(vec![]).initial_step
}

fn default_true() -> bool {
    true
}

impl Default for IdentifySection {
    fn default() -> Self {
        IdentifySection {
            params: BTreeMap::new(),
            method: MethodName::default(),
            memory: default_memory(),
            initial_step: default_initial_step(),
            bfgs_start: BfgsStartName::Scaled,
            stop: StopSection::default(),
            identifiability: true,
            noise: NoiseSetting::Residual,
            coarse_to_fine: None,
        }
    }
}

/// One law parameter: identified or held.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ParamSetting {
    /// Identified from `start` within `[lower, upper]`.
    Free {
        /// Start (default: the `law` value).
        #[serde(default)]
        start: Option<f64>,
        /// Lower bound (default: the law's admissible minimum).
        #[serde(default)]
        lower: Option<f64>,
        /// Upper bound (default: the law's admissible maximum).
        #[serde(default)]
        upper: Option<f64>,
        /// Scaling of the optimizer variable (default: `Log` when the lower bound is >= 0,
        /// else `Linear`).
        #[serde(default)]
        scaling: Option<ScalingName>,
    },
    /// Held at `value` (default: the `law` value).
    Fixed {
        /// The value.
        #[serde(default)]
        value: Option<f64>,
    },
}

impl ParamSetting {
    /// Free with every value defaulted.
    pub const FREE: ParamSetting = ParamSetting::Free {
        start: None,
        lower: None,
        upper: None,
        scaling: None,
    };
    /// Held at the `law` value.
    pub const FIXED: ParamSetting = ParamSetting::Fixed { value: None };
}

/// The optimizers, as named in configs (`Bfgs`) and on the command line (`bfgs`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum MethodName {
    /// BFGS with Armijo backtracking (the paper's algorithm); bounds by projection.
    #[default]
    Bfgs,
    /// L-BFGS with the More-Thuente line search; bounds by projection.
    Lbfgs,
    /// L-BFGS-B: bounds handled by the method.
    Lbfgsb,
    /// Projected Levenberg-Marquardt on the forward-sensitivity Jacobian.
    Lm,
}

impl MethodName {
    /// Every method, in the order of the documentation.
    pub const ALL: [MethodName; 4] = [
        MethodName::Bfgs,
        MethodName::Lbfgs,
        MethodName::Lbfgsb,
        MethodName::Lm,
    ];

    /// The command-line name (`bfgs`, `lbfgs`, `lbfgsb`, `lm`).
    pub fn cli_name(self) -> &'static str {
        match self {
            MethodName::Bfgs => "bfgs",
            MethodName::Lbfgs => "lbfgs",
            MethodName::Lbfgsb => "lbfgsb",
            MethodName::Lm => "lm",
        }
    }

    /// Parses a command-line name, case-insensitively.
    ///
    /// # Errors
    /// An unknown name, with the allowed ones.
    pub fn parse(text: &str) -> Result<MethodName> {
        MethodName::ALL
            .into_iter()
            .find(|m| m.cli_name().eq_ignore_ascii_case(text.trim()))
            .ok_or_else(|| {
                anyhow::anyhow!("unknown method `{text}`: expected one of bfgs, lbfgs, lbfgsb, lm")
            })
    }

    /// The library's method.
    pub fn method(self, memory: usize) -> Method {
        match self {
            MethodName::Bfgs => Method::Bfgs,
            MethodName::Lbfgs => Method::Lbfgs { memory },
            MethodName::Lbfgsb => Method::Lbfgsb { memory },
            MethodName::Lm => Method::LevenbergMarquardt,
        }
    }
}

/// Scalings of a free parameter (see `indentify_identify::Scaling`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ScalingName {
    /// `y = ln c`.
    #[default]
    Log,
    /// `y = (c - lower) / (upper - lower)` (finite bounds).
    Bounds,
    /// `y = c / |start|`.
    Linear,
}

impl ScalingName {
    fn scaling(self) -> Scaling {
        match self {
            ScalingName::Log => Scaling::Log,
            ScalingName::Bounds => Scaling::Bounds,
            ScalingName::Linear => Scaling::Linear,
        }
    }
}

/// The default `identify.stop.lm_radius` of configurations: Levenberg-Marquardt's first
/// step at most 1 long in the scaled variables (a factor e on a log-scaled parameter).
/// Measured in docs/performance.md ("A cheaper start of Levenberg-Marquardt"): R2 from its
/// start 11 forward runs and 11 sensitivity passes instead of 17 and 13; fits whose first
/// step is shorter run bit for bit as before.
pub const DEFAULT_LM_RADIUS: Option<f64> = Some(1.0);

/// The default `identify.stop.proposed_step` of configurations: on. Measured in
/// docs/performance.md ("Seeded starts, the stop on the proposed step, the start curve
/// kept") on every single-fit Levenberg-Marquardt example and the map batch: where it
/// ends a fit, every parameter within a tenth of its standard deviation of the fit
/// without it and the outcome the same; it never ends one with a parameter undetermined
/// or pushed against a bound.
pub const DEFAULT_PROPOSED_STEP: bool = true;

/// The default `identify.stop.lm_stop_rejected` of configurations: on. A
/// Levenberg-Marquardt trial's forward runs stop once their cost so far already rejects
/// it; every decision and result is the run's without it, bit for bit (measured in
/// docs/performance.md, "Rejected trials stopped early").
pub const DEFAULT_LM_STOP_REJECTED: bool = true;

/// The damping updates of Levenberg-Marquardt, as named in configs
/// (`identify.stop.lm_damping`; see `indentify_identify::LmDamping`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum LmDampingName {
    /// `lambda /= 3` after an accepted trial, `x 4` after a rejected one.
    #[default]
    Classic,
    /// Nielsen's update from the gain ratio, `nu` doubling after a rejection.
    Nielsen,
    /// `/3` only when the gain ratio is above 0.75, `x 2` below 0.25.
    MarquardtFletcher,
    /// The classic decrease capped by the gain ratio: `lambda /= 1 + 2 rho`.
    GainCapped,
    /// `/2` after an accepted trial, `x 3` after a rejected one.
    Delayed,
}

/// [`LmDampingName`] as read, for an error that names the field.
#[derive(Deserialize)]
#[serde(rename = "LmDampingName")]
enum LmDampingRead {
    Classic,
    Nielsen,
    MarquardtFletcher,
    GainCapped,
    Delayed,
}

impl<'de> Deserialize<'de> for LmDampingName {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error;
        let read = LmDampingRead::deserialize(d).map_err(|e| {
            D::Error::custom(format!(
                "stop.lm_damping: {e} (expected Classic, Nielsen, MarquardtFletcher, \
                 GainCapped or Delayed)"
            ))
        })?;
        Ok(match read {
            LmDampingRead::Classic => LmDampingName::Classic,
            LmDampingRead::Nielsen => LmDampingName::Nielsen,
            LmDampingRead::MarquardtFletcher => LmDampingName::MarquardtFletcher,
            LmDampingRead::GainCapped => LmDampingName::GainCapped,
            LmDampingRead::Delayed => LmDampingName::Delayed,
        })
    }
}

impl LmDampingName {
    /// The library's update.
    pub fn damping(self) -> LmDamping {
        match self {
            LmDampingName::Classic => LmDamping::Classic,
            LmDampingName::Nielsen => LmDamping::Nielsen,
            LmDampingName::MarquardtFletcher => LmDamping::MarquardtFletcher,
            LmDampingName::GainCapped => LmDamping::GainCapped,
            LmDampingName::Delayed => LmDamping::Delayed,
        }
    }
}

/// The default `identify.stop.lm_damping` of configurations: the classic update. The
/// gain-ratio updates were measured on the fit-cost cases and none paid on all of them
/// (docs/performance.md, "Gain-ratio damping updates without a trust radius").
pub const DEFAULT_LM_DAMPING: LmDampingName = LmDampingName::Classic;

/// Stopping rules (see `indentify_identify::StopCriteria`); costs relative to
/// `J_ref = 1/2 sum F_exp,i^2`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StopSection {
    /// Stop when `|projected scaled gradient| / J_ref` is at most this.
    pub gradient_tol: f64,
    /// Stop when an iteration decreases `J` by at most this fraction.
    pub relative_decrease_tol: f64,
    /// Stop when `J / J_ref` is at most this (0: off).
    pub target_cost: f64,
    /// Iteration limit.
    pub max_iterations: usize,
    /// Trial points of one line search before it has stalled.
    pub max_line_search_evaluations: usize,
    /// A stall with `J / J_ref` below this is the solver's round-off: converged.
    pub roundoff_cost: f64,
    /// Levenberg-Marquardt only: stop when the last step, and the Gauss-Newton step from
    /// where it ended, move every free parameter by less than this fraction of its
    /// standard deviation (`None`: off; default
    /// `indentify_identify::DEFAULT_STEP_SIGMA` = 0.1).
    pub step_sigma: Option<f64>,
    /// Levenberg-Marquardt only: the first damping is raised (linear solves only) until
    /// the first step moves no scaled parameter by more than this (1: a factor e on a
    /// log-scaled parameter); `None`: the classic first damping `1e-3` (see
    /// `indentify_identify::LmStrategy::first_radius`).
    pub lm_radius: Option<f64>,
    /// Levenberg-Marquardt with `step_sigma` only: also stop when the Gauss-Newton step
    /// from the new iterate moves every free parameter by less than `step_sigma` of its
    /// deviation and the last step's decrease was the one the model predicted (gain ratio
    /// within 0.1 of 1), however long that step was (see
    /// `indentify_identify::StopCriteria::proposed_step`). Default true in configurations
    /// ([`DEFAULT_PROPOSED_STEP`]; the library's default is off); `false`, or
    /// `step_sigma: None`, turns it off.
    pub proposed_step: bool,
    /// Levenberg-Marquardt only: stop a trial's forward runs between steps once the cost
    /// over the steps run already rejects the trial (see
    /// `indentify_identify::LmStrategy::stop_rejected`; the same results bit for bit).
    /// Default true in configurations ([`DEFAULT_LM_STOP_REJECTED`]; off in the library).
    pub lm_stop_rejected: bool,
    /// Levenberg-Marquardt only: the update of the damping after each trial (`Classic`,
    /// `Nielsen`, `MarquardtFletcher`, `GainCapped`, `Delayed`; see
    /// `indentify_identify::LmDamping`). Default [`DEFAULT_LM_DAMPING`].
    pub lm_damping: LmDampingName,
    /// Levenberg-Marquardt only: while the identifiability summary at an iterate says a
    /// parameter is undetermined, solve the damped step orthogonally to the undetermined
    /// directions and stop on the determined combinations' steps (see
    /// `indentify_identify::LmStrategy::subspace`). Default false
    /// ([`DEFAULT_LM_SUBSPACE`]).
    #[serde(deserialize_with = "read_lm_subspace")]
    pub lm_subspace: bool,
}

/// The default `identify.stop.lm_subspace` of configurations: off. Measured in
/// docs/performance.md ("Steps in the determined subspace").
pub const DEFAULT_LM_SUBSPACE: bool = false;

/// `identify.stop.lm_subspace` as read, for an error that names the field.
fn read_lm_subspace<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<bool, D::Error> {
    use serde::de::Error;
    bool::deserialize(d)
        .map_err(|e| D::Error::custom(format!("stop.lm_subspace: {e} (expected true or false)")))
}

impl Default for StopSection {
    fn default() -> Self {
        let d = StopCriteria::default();
        StopSection {
            gradient_tol: d.gradient_tol,
            relative_decrease_tol: d.relative_decrease_tol,
            target_cost: d.target_cost,
            max_iterations: d.max_iterations,
            max_line_search_evaluations: d.max_line_search_evaluations,
            roundoff_cost: d.roundoff_cost,
            step_sigma: Some(DEFAULT_STEP_SIGMA),
            lm_radius: DEFAULT_LM_RADIUS,
            proposed_step: DEFAULT_PROPOSED_STEP,
            lm_stop_rejected: DEFAULT_LM_STOP_REJECTED,
            lm_damping: DEFAULT_LM_DAMPING,
            lm_subspace: DEFAULT_LM_SUBSPACE,
        }
    }
}

impl StopSection {
    fn criteria(&self) -> StopCriteria {
        StopCriteria {
            gradient_tol: self.gradient_tol,
            relative_decrease_tol: self.relative_decrease_tol,
            target_cost: self.target_cost,
            max_iterations: self.max_iterations,
            max_line_search_evaluations: self.max_line_search_evaluations,
            roundoff_cost: self.roundoff_cost,
            step_sigma: self.step_sigma,
            proposed_step: self.proposed_step,
            lm: LmStrategy {
                first_radius: self.lm_radius,
                stop_rejected: self.lm_stop_rejected,
                damping: self.lm_damping.damping(),
                subspace: self.lm_subspace,
                ..LmStrategy::default()
            },
            ..StopCriteria::default()
        }
    }
}

/// What the command line changes in the section.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overrides {
    /// `--free`: exactly these parameters are identified, the others held.
    pub free: Option<Vec<String>>,
    /// `--fixed name[=value]`.
    pub fixed: Vec<(String, Option<f64>)>,
    /// `--start name=value`.
    pub starts: Vec<(String, f64)>,
    /// `--method`.
    pub method: Option<MethodName>,
    /// `--max-iter`.
    pub max_iterations: Option<usize>,
    /// The noise model of the deviations (replaces `identify.noise`).
    pub noise: Option<NoiseSetting>,
    /// The initial inverse Hessian of BFGS (replaces `identify.bfgs_start`).
    pub bfgs_start: Option<BfgsStartName>,
}

/// Parses `name=value` (`flag` names the option in messages).
///
/// # Errors
/// No `=`, an empty name or value, or a value that is not a finite number.
pub fn name_value(flag: &str, text: &str) -> Result<(String, f64)> {
    let (name, value) = text
        .split_once('=')
        .ok_or_else(|| anyhow!("{flag} {text}: expected name=value (e.g. {flag} E=5000)"))?;
    let (name, value) = (name.trim(), value.trim());
    if name.is_empty() {
        bail!("{flag} {text}: no parameter name before `=`");
    }
    if value.is_empty() {
        bail!("{flag} {text}: no value after `=` (e.g. {flag} {name}=0.3)");
    }
    let v: f64 = value
        .parse()
        .map_err(|_| anyhow!("{flag} {text}: `{value}` is not a number"))?;
    if !v.is_finite() {
        bail!("{flag} {text}: expected a finite number");
    }
    Ok((name.to_string(), v))
}

/// Parses a `--fixed` item: `name` (held at its `law` value) or `name=value`.
///
/// # Errors
/// As [`name_value`] (`nu=` without a value included).
pub fn fixed_item(text: &str) -> Result<(String, Option<f64>)> {
    if text.contains('=') {
        let (n, v) = name_value("--fixed", text).map_err(|e| {
            anyhow!(
                "{e}; or write --fixed {} to hold it at its law value",
                text.split('=').next().unwrap_or(text).trim()
            )
        })?;
        Ok((n, Some(v)))
    } else if text.trim().is_empty() {
        bail!("--fixed: empty parameter name")
    } else {
        Ok((text.trim().to_string(), None))
    }
}

/// `law` with the parameters of `instrument` for `n_tests` tests appended, and its values
/// (the law's, then 0 for each instrument parameter).
pub fn instrumented(
    law: std::sync::Arc<dyn Material>,
    values: &[f64],
    instrument: Instrument,
    n_tests: usize,
) -> (std::sync::Arc<dyn Material>, Vec<f64>) {
    let w = indentify_identify::Instrumented::new(law, instrument, n_tests);
    let mut v = values.to_vec();
    v.resize(w.params().len(), 0.0);
    (std::sync::Arc::new(w), v)
}

/// Whether the setting key `key` applies to parameter `name`: the same name, or `h0`
/// for every test's offset `h0[k]`.
fn key_matches(key: &str, name: &str) -> bool {
    key == name || (key == "h0" && Instrument::offset_test(name).is_some())
}

/// The instrument parameters the names of `section` and `overrides` ask for (`Cf`, `vd`,
/// `h0` or `h0[k]`), and the largest test index an `h0[k]` names (0 without).
pub fn instrument_of(
    section: Option<&IdentifySection>,
    overrides: &Overrides,
) -> (Instrument, usize) {
    let mut names: Vec<&str> = Vec::new();
    if let Some(s) = section {
        names.extend(s.params.keys().map(String::as_str));
    }
    if let Some(f) = &overrides.free {
        names.extend(f.iter().map(String::as_str));
    }
    names.extend(overrides.fixed.iter().map(|(n, _)| n.as_str()));
    names.extend(overrides.starts.iter().map(|(n, _)| n.as_str()));
    let mut i = Instrument::default();
    let mut k_max = 0;
    for n in names {
        match n {
            "Cf" => i.compliance = true,
            "vd" => i.drift = true,
            _ => {
                if let Some(k) = Instrument::offset_test(n) {
                    i.offset = true;
                    k_max = k_max.max(k.unwrap_or(0));
                }
            }
        }
    }
    (i, k_max)
}

/// `--start name=v` on setting `k`: the start of a free parameter; an error for a held one.
fn set_start(
    settings: &mut [(&'static str, ParamSetting)],
    k: usize,
    name: &str,
    v: f64,
) -> Result<()> {
    match &mut settings[k].1 {
        ParamSetting::Free { start, .. } => *start = Some(v),
        ParamSetting::Fixed { .. } => {
            let free: Vec<&str> = settings
                .iter()
                .filter(|(_, s)| matches!(s, ParamSetting::Free { .. }))
                .map(|(n, _)| *n)
                .collect();
            bail!(
                "--start {name}={v}: `{name}` is held fixed (the free parameters are {}); \
                 make it free with --free or in identify.params",
                if free.is_empty() {
                    "none".to_string()
                } else {
                    free.join(", ")
                }
            );
        }
    }
    Ok(())
}

impl IdentifySection {
    /// The parameter settings in the law's order, after the resolution rules of the module
    /// and the command-line `overrides`.
    ///
    /// # Errors
    /// A parameter name the law does not have (in the section or on the command line), a
    /// parameter both in `--free` and `--fixed`, a `--start` for a held parameter.
    pub fn settings(
        section: Option<&IdentifySection>,
        law: &dyn Material,
        overrides: &Overrides,
    ) -> Result<Vec<(&'static str, ParamSetting)>> {
        let names: Vec<&'static str> = law.params().iter().map(|i| i.name).collect();
        let unknown = |what: &str, name: &str| {
            anyhow!(
                "{what}: law `{}` has no parameter `{name}`; its parameters are {}",
                law.name(),
                names.join(", ")
            )
        };
        let known = |key: &str| names.iter().any(|n| key_matches(key, n));
        let listed = section.map(|s| &s.params).filter(|p| !p.is_empty());
        if let Some(params) = listed {
            if let Some(n) = params.keys().find(|n| !known(n)) {
                return Err(unknown(&format!("identify.params.{n}"), n));
            }
        }
        let mut settings: Vec<(&'static str, ParamSetting)> = names
            .iter()
            .map(|&n| {
                let s = match listed {
                    Some(p) => p
                        .get(n)
                        .or_else(|| p.get("h0").filter(|_| key_matches("h0", n)))
                        .copied()
                        .unwrap_or(ParamSetting::FIXED),
                    None if n == "nu" => ParamSetting::FIXED,
                    None => ParamSetting::FREE,
                };
                (n, s)
            })
            .collect();
        if let Some(free) = &overrides.free {
            if let Some(n) = free.iter().find(|n| !known(n)) {
                return Err(unknown(&format!("--free {}", free.join(",")), n));
            }
            for (n, s) in &mut settings {
                let wanted = free.iter().any(|f| key_matches(f, n));
                match (wanted, &s) {
                    (true, ParamSetting::Fixed { .. }) => *s = ParamSetting::FREE,
                    (false, ParamSetting::Free { .. }) => *s = ParamSetting::FIXED,
                    _ => {}
                }
            }
        }
        let indices = |key: &str| -> Vec<usize> {
            (0..names.len())
                .filter(|&k| key_matches(key, names[k]))
                .collect()
        };
        for (name, value) in &overrides.fixed {
            let ks = indices(name);
            if ks.is_empty() {
                return Err(unknown(&format!("--fixed {name}"), name));
            }
            if overrides
                .free
                .as_ref()
                .is_some_and(|f| f.iter().any(|f| f == name))
            {
                bail!("`{name}` is both in --free and in --fixed");
            }
            for k in ks {
                settings[k].1 = ParamSetting::Fixed { value: *value };
            }
        }
        for (name, v) in &overrides.starts {
            let ks = indices(name);
            if ks.is_empty() {
                return Err(unknown(&format!("--start {name}={v}"), name));
            }
            for k in ks {
                set_start(&mut settings, k, name, *v)?;
            }
        }
        Ok(settings)
    }

    /// The identification library's configuration: the section (or its defaults) with the
    /// overrides, every omitted value taken from `law`, checked by the library's
    /// [`Parameterization`] before any solve.
    ///
    /// # Errors
    /// As [`IdentifySection::settings`]; a start outside its bounds, bounds that exclude each
    /// other, a bound outside the law's range, an option out of range (each naming the
    /// parameter or field).
    pub fn resolve(
        section: Option<&IdentifySection>,
        law: &LawSpec,
        overrides: &Overrides,
    ) -> Result<IdentifyConfig> {
        let built = law.material()?;
        IdentifySection::resolve_with(section, built.material.as_ref(), &built.params, overrides)
    }

    /// [`IdentifySection::resolve`] for a built material `mat` whose `law` values are
    /// `values` (an [`indentify_identify::Instrumented`] law: the law's values, then 0 for
    /// each instrument parameter).
    ///
    /// # Errors
    /// As [`IdentifySection::resolve`].
    pub fn resolve_with(
        section: Option<&IdentifySection>,
        mat: &dyn Material,
        values: &[f64],
        overrides: &Overrides,
    ) -> Result<IdentifyConfig> {
        let defaults = IdentifySection::default();
        let s = section.unwrap_or(&defaults);
        s.validate_options()?;
        let settings = IdentifySection::settings(section, mat, overrides)?;
        let specs: Vec<ParamSpec> = settings
            .iter()
            .zip(values)
            .map(|((name, setting), &law_value)| match *setting {
                ParamSetting::Free {
                    start,
                    lower,
                    upper,
                    scaling,
                } => {
                    let min = info_min(mat, name);
                    let auto = if !Instrument::is_name(name) && lower.unwrap_or(min) >= 0.0 {
                        ScalingName::Log
                    } else {
                        ScalingName::Linear
                    };
                    ParamSpec {
                        name: name.to_string(),
                        free: true,
                        value: Some(start.unwrap_or(law_value)),
                        lower,
                        upper,
                        scaling: scaling.unwrap_or(auto).scaling(),
                    }
                }
                ParamSetting::Fixed { value } => ParamSpec {
                    name: name.to_string(),
                    free: false,
                    value: Some(value.unwrap_or(law_value)),
                    lower: None,
                    upper: None,
                    scaling: Scaling::Log,
                },
            })
            .collect();
        IdentifySection::check_specs(mat, &specs)?;
        let mut stop = s.stop.criteria();
        if let Some(n) = overrides.max_iterations {
            stop.max_iterations = n;
        }
        Ok(IdentifyConfig {
            params: specs,
            method: overrides.method.unwrap_or(s.method).method(s.memory),
            stop,
            initial_step: s.initial_step,
            bfgs_start: overrides.bfgs_start.unwrap_or(s.bfgs_start).start(),
            identifiability: s.identifiability,
            noise: match overrides.noise {
                Some(n) => {
                    n.check("the noise model")?;
                    n.model()
                }
                None => s.noise.model(),
            },
            cancel: Default::default(),
        })
    }
    /// The identification library's check of the parameter specifications (starts within
    /// bounds, bounds within the law's range, something free), naming the parameter.
    fn check_specs(lib_law: &dyn Material, specs: &[ParamSpec]) -> Result<()> {
        Parameterization::new(lib_law, specs).map_err(|e| {
            let field = match &e {
                indentify_identify::IdentifyError::NothingFree => "identify.params".to_string(),
                _ => specs
                    .iter()
                    .find(|p| e.to_string().contains(&format!("`{}`", p.name)))
                    .map_or("identify.params".to_string(), |p| {
                        format!("identify.params.{}", p.name)
                    }),
            };
            anyhow!(e).context(format!("invalid identification setting `{field}`"))
        })?;
        Ok(())
    }

    /// Range checks of the options (the library repeats them; here they name the field).
    fn validate_options(&self) -> Result<()> {
        let st = &self.stop;
        let field = |name: &str, v: String, allowed: &str| {
            anyhow!("identify.{name} = {v} is not allowed: expected {allowed}")
        };
        self.noise.check("identify.noise")?;
        if !(1..=100).contains(&self.memory) {
            return Err(field(
                "memory",
                self.memory.to_string(),
                "an integer in [1, 100]",
            ));
        }
        if !(self.initial_step > 0.0 && self.initial_step.is_finite()) {
            return Err(field(
                "initial_step",
                self.initial_step.to_string(),
                "a finite value > 0",
            ));
        }
        for (name, v) in [
            ("stop.gradient_tol", st.gradient_tol),
            ("stop.target_cost", st.target_cost),
            ("stop.roundoff_cost", st.roundoff_cost),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(field(name, v.to_string(), "a finite value >= 0"));
            }
        }
        if !(st.relative_decrease_tol >= 0.0 && st.relative_decrease_tol < 1.0) {
            return Err(field(
                "stop.relative_decrease_tol",
                st.relative_decrease_tol.to_string(),
                "a value in [0, 1)",
            ));
        }
        if let Some(f) = st.step_sigma {
            if !(f > 0.0 && f.is_finite()) {
                return Err(field(
                    "stop.step_sigma",
                    f.to_string(),
                    "a finite fraction > 0 of a standard deviation, or None (off)",
                ));
            }
        }
        if let Some(r) = st.lm_radius {
            if !(r > 0.0 && r.is_finite()) {
                return Err(field(
                    "stop.lm_radius",
                    r.to_string(),
                    "a finite length > 0 in the scaled variables (1: a factor e), or None (off)",
                ));
            }
        }
        if let Some(c) = self.coarse_to_fine {
            if c.iterations == 0 {
                return Err(field(
                    "coarse_to_fine.iterations",
                    "0".into(),
                    "an integer >= 1 (the coarse phase's iteration limit), or \
                     coarse_to_fine: None (full fidelity throughout)",
                ));
            }
        }
        if st.max_line_search_evaluations == 0 {
            return Err(field(
                "stop.max_line_search_evaluations",
                "0".into(),
                "an integer >= 1",
            ));
        }
        Ok(())
    }

    /// Checks the section against the configuration's law (what `indentify check` reports).
    ///
    /// # Errors
    /// As [`IdentifySection::resolve`] without overrides.
    /// Instrument parameters are checked for as many tests as an `h0[k]` names (the run
    /// checks them against the configuration's tests).
    pub fn validate(&self, law: &LawSpec) -> Result<()> {
        let ov = Overrides::default();
        let (instrument, k_max) = instrument_of(Some(self), &ov);
        if instrument.is_empty() {
            return IdentifySection::resolve(Some(self), law, &ov)
                .map(|_| ())
                .context("invalid `identify` section");
        }
        let built = law.material()?;
        let (mat, values) = instrumented(
            std::sync::Arc::from(built.material),
            &built.params,
            instrument,
            k_max.max(1),
        );
        IdentifySection::resolve_with(Some(self), &*mat, &values, &ov)
            .map(|_| ())
            .context("invalid `identify` section")
    }
}

/// The admissible minimum of parameter `name` of `law`.
fn info_min(law: &dyn Material, name: &str) -> f64 {
    law.params()
        .iter()
        .find(|i| i.name == name)
        .map_or(0.0, |i| i.min)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Reference;

    fn maxwell() -> LawSpec {
        Reference::R1Maxwell.config().law
    }

    fn free_names(cfg: &IdentifyConfig) -> Vec<&str> {
        cfg.params
            .iter()
            .filter(|p| p.free)
            .map(|p| p.name.as_str())
            .collect()
    }

    #[test]
    fn without_a_section_every_parameter_but_nu_is_free_from_the_law() {
        let cfg = IdentifySection::resolve(None, &maxwell(), &Overrides::default()).unwrap();
        assert_eq!(free_names(&cfg), ["E", "eta"]);
        assert_eq!(cfg.params[0].value, Some(20000.0));
        assert_eq!(cfg.params[1].value, Some(0.3));
        assert_eq!(cfg.method, Method::Bfgs);
    }

    #[test]
    fn overrides_free_fix_start_and_limit() {
        let ov = Overrides {
            free: Some(vec!["E".into(), "nu".into()]),
            fixed: vec![],
            starts: vec![("nu".into(), 0.25)],
            method: Some(MethodName::Lbfgs),
            max_iterations: Some(7),
            noise: None,
            bfgs_start: None,
        };
        let cfg = IdentifySection::resolve(None, &maxwell(), &ov).unwrap();
        assert_eq!(free_names(&cfg), ["E", "nu"]);
        assert_eq!(cfg.params[1].value, Some(0.25));
        assert_eq!(cfg.params[2].value, Some(30000.0));
        assert_eq!(cfg.method, Method::Lbfgs { memory: 5 });
        assert_eq!(cfg.stop.max_iterations, 7);
        let ov = Overrides {
            fixed: vec![("eta".into(), Some(1e4))],
            ..Default::default()
        };
        let cfg = IdentifySection::resolve(None, &maxwell(), &ov).unwrap();
        assert_eq!(free_names(&cfg), ["E"]);
        assert_eq!(cfg.params[2].value, Some(1e4));
    }

    #[test]
    fn bad_settings_name_the_parameter() {
        let err = |section: Option<&IdentifySection>, ov: Overrides| {
            format!(
                "{:#}",
                IdentifySection::resolve(section, &maxwell(), &ov).unwrap_err()
            )
        };
        let e = err(
            None,
            Overrides {
                starts: vec![("nu".into(), 0.2)],
                ..Default::default()
            },
        );
        assert!(
            e.contains("`nu` is held fixed") && e.contains("E, eta"),
            "{e}"
        );
        let e = err(
            None,
            Overrides {
                free: Some(vec!["G".into()]),
                ..Default::default()
            },
        );
        assert!(
            e.contains("no parameter `G`") && e.contains("E, nu, eta"),
            "{e}"
        );
        let mut s = IdentifySection::default();
        s.params.insert(
            "E".into(),
            ParamSetting::Free {
                start: Some(500.0),
                lower: Some(1000.0),
                upper: Some(1e6),
                scaling: None,
            },
        );
        let e = err(Some(&s), Overrides::default());
        assert!(
            e.contains("identify.params.E") && e.contains("outside its bounds"),
            "{e}"
        );
        s.params.insert(
            "E".into(),
            ParamSetting::Free {
                start: Some(5000.0),
                lower: Some(1e6),
                upper: Some(1000.0),
                scaling: Some(ScalingName::Log),
            },
        );
        let e = err(Some(&s), Overrides::default());
        assert!(e.contains("exclude each other"), "{e}");
        let e = err(
            None,
            Overrides {
                free: Some(vec![]),
                ..Default::default()
            },
        );
        assert!(e.contains("no free parameter"), "{e}");
    }

    #[test]
    fn command_line_items_parse_with_clear_errors() {
        assert_eq!(
            name_value("--start", "E=5e3").unwrap(),
            ("E".into(), 5000.0)
        );
        assert_eq!(fixed_item("nu").unwrap(), ("nu".into(), None));
        assert_eq!(fixed_item("nu=0.25").unwrap(), ("nu".into(), Some(0.25)));
        let e = fixed_item("nu=").unwrap_err().to_string();
        assert!(e.contains("no value") && e.contains("--fixed nu"), "{e}");
        let e = name_value("--start", "E").unwrap_err().to_string();
        assert!(e.contains("name=value"), "{e}");
        let e = name_value("--start", "E=abc").unwrap_err().to_string();
        assert!(e.contains("`abc` is not a number"), "{e}");
    }
}
