//! Profile likelihoods: for one free parameter held at values stepping away from the
//! optimum, the cost minimized over the other free parameters, and the interval where the
//! rise of that profile stays below the chi-square threshold.
//!
//! Statistics (Gaussian residuals of equal variance, `J = 1/2 sum_i w_i r_i^2`):
//! the residual variance is estimated at the optimum as `s^2 = 2 J* / (n - p)` (n weighted
//! data, p free parameters, as in [`crate::identifiability`]); the profile of parameter
//! `c_k` is `J_k(v) = min { J(c) : c_k = v }`, and the likelihood-ratio statistic
//! `2 (J_k(v) - J*) / s^2` is compared with `chi2_1(0.95) = 3.841`: the 95% interval is the
//! set where `J_k(v) - J* <= chi2_1(0.95) s^2 / 2 = chi2_1(0.95) J* / (n - p)`
//! ([`threshold`]). Under a stated or estimated noise model (multiplicative, additive) the
//! standard deviations are the sandwich ones of that model, and the front end uses for each
//! parameter `s_k^2 = Cov_kk / (S^T S)^-1_kk` instead
//! ([`crate::identifiability::Identifiability::profile_variance`]): the interval and the
//! deviation then follow the same noise model. For a linear model this interval is the
//! Gauss-Newton `+-1.96 sigma`; for
//! the indentation models it may be asymmetric, or open on one side (the profile never
//! rises enough before the parameter's bound), which the Gauss-Newton deviations cannot
//! show.
//!
//! One side of a profile is a chain ([`profile_side`]): the points step away from the
//! optimum in the parameter's scaled variable, each a constrained re-fit started from its
//! neighbour's optimum, so a chain is sequential; the chains of different parameters and
//! directions are independent (a front end runs them in parallel).

use crate::IdentifyError;
use crate::optimize::{IdentifyConfig, identify};
use crate::params::{ParamSpec, Parameterization};
use crate::problem::{Evaluator, Problem};

/// `chi2_1(0.95)`: the 95% quantile of the chi-square distribution with one degree of
/// freedom (`1.959964^2`).
pub const CHI2_1_95: f64 = 3.841_458_820_694_124;

/// The rise of `J` above `J*` that bounds the 95% profile interval:
/// `chi2_1(0.95) s^2 / 2` with `s^2 = 2 J* / (n - p)`.
pub fn threshold(cost: f64, n_data: usize, n_free: usize) -> f64 {
    if n_data > n_free {
        CHI2_1_95 * cost / (n_data - n_free) as f64
    } else {
        f64::NAN
    }
}

/// One point of a profile.
#[derive(Clone, Debug, PartialEq)]
pub struct ProfilePoint {
    /// The profiled parameter's value (physical units).
    pub value: f64,
    /// Its scaled variable.
    pub y: f64,
    /// `J_k(value)`: the cost minimized over the other free parameters (N^2).
    pub cost: f64,
    /// The minimizing full parameter vector (law order).
    pub c: Vec<f64>,
    /// Whether the re-fit met a convergence criterion (always true with one free parameter:
    /// there is nothing to re-fit).
    pub converged: bool,
    /// Iterations of the re-fit.
    pub iterations: usize,
}

/// How one side of a profile ended.
#[derive(Clone, Debug, PartialEq)]
pub enum SideEnd {
    /// The rise passed the stopping level ([`ProfileSettings::stop_factor`] times the
    /// threshold).
    Risen,
    /// The parameter reached its bound.
    Bound,
    /// All [`ProfileSettings::points_per_side`] points were used.
    Points,
    /// A re-fit failed (its message).
    Failed(String),
}

/// How the profiles are sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProfileSettings {
    /// Points on each side of the optimum, at most.
    pub points_per_side: usize,
    /// Step in the scaled variable; `None`: half the Gauss-Newton standard deviation of the
    /// scaled variable, clamped to `[1e-4, 0.25]` (0.1 when it is not finite).
    pub step: Option<f64>,
    /// A side stops once `J_k - J*` exceeds this many thresholds (2: about 1.4 times the
    /// interval's half-width for a quadratic profile).
    pub stop_factor: f64,
}

impl Default for ProfileSettings {
    fn default() -> Self {
        ProfileSettings {
            points_per_side: 8,
            step: None,
            stop_factor: 2.0,
        }
    }
}

impl ProfileSettings {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`IdentifyError::InvalidOption`] naming the field.
    pub fn validate(&self) -> Result<(), IdentifyError> {
        if !(1..=1000).contains(&self.points_per_side) {
            return Err(IdentifyError::InvalidOption {
                field: "profile points per side",
                value: self.points_per_side.to_string(),
                allowed: "an integer in [1, 1000]",
            });
        }
        if let Some(s) = self.step.filter(|s| !(*s > 0.0 && s.is_finite())) {
            return Err(IdentifyError::InvalidOption {
                field: "profile step",
                value: s.to_string(),
                allowed: "a finite value > 0 (scaled variable)",
            });
        }
        if !(self.stop_factor >= 1.0 && self.stop_factor.is_finite()) {
            return Err(IdentifyError::InvalidOption {
                field: "profile stop factor",
                value: self.stop_factor.to_string(),
                allowed: "a finite value >= 1",
            });
        }
        Ok(())
    }

    /// The step for a parameter whose scaled variable has Gauss-Newton deviation `sigma_y`.
    pub fn step_for(&self, sigma_y: f64) -> f64 {
        match self.step {
            Some(s) => s,
            None if sigma_y.is_finite() && sigma_y > 0.0 => (0.5 * sigma_y).clamp(1e-4, 0.25),
            None => 0.1,
        }
    }
}

/// One side of the profile of free parameter number `k` (index among the free ones, law
/// order) from the optimum `c_opt` of cost `cost_opt`: points at `y* + i step` for
/// `i = 1, 2, ...` (`step` signed), each re-fit with `config`'s method and stopping rules
/// from its neighbour's optimum (the first from `c_opt`), until `J - cost_opt` exceeds
/// `stop_rise`, the bound is reached, `points` points are done or a re-fit fails.
///
/// # Errors
/// [`Parameterization::new`]'s errors for `config`; `k` out of range
/// ([`IdentifyError::InvalidSpec`]). Failures of the re-fits end the side
/// ([`SideEnd::Failed`]) instead.
#[allow(clippy::too_many_arguments)]
pub fn profile_side(
    problem: &Problem,
    config: &IdentifyConfig,
    c_opt: &[f64],
    cost_opt: f64,
    k: usize,
    step: f64,
    points: usize,
    stop_rise: f64,
) -> Result<(Vec<ProfilePoint>, SideEnd), IdentifyError> {
    let param = Parameterization::new(&*problem.law, &config.params)?;
    let f = param
        .free
        .get(k)
        .ok_or_else(|| IdentifyError::InvalidSpec {
            name: "profile".into(),
            why: format!(
                "free parameter number {k} asked, there are {}",
                param.free.len()
            ),
        })?
        .clone();
    let (lo, hi) = f.scaled_bounds();
    let y0 = f.to_scaled(c_opt[f.index]);
    let single = param.free.len() == 1;
    let mut eval = if single {
        Some(Evaluator::new(problem)?)
    } else {
        None
    };
    let mut out: Vec<ProfilePoint> = Vec::new();
    let mut from = c_opt.to_vec();
    for i in 1..=points {
        if config.cancel.is_raised() {
            // a stop request ends the side after the re-fit in progress
            return Ok((
                out,
                SideEnd::Failed("interrupted (a stop was asked)".into()),
            ));
        }
        let y = (y0 + i as f64 * step).clamp(lo, hi);
        if out.last().map_or(y == y0, |p| p.y == y) {
            return Ok((out, SideEnd::Bound));
        }
        let value = f.to_physical(y).clamp(f.lower, f.upper);
        let point = if let Some(ev) = eval.as_mut() {
            let mut c = from.clone();
            c[f.index] = value;
            match ev.cost(&c) {
                Ok(j) if j.is_finite() => ProfilePoint {
                    value,
                    y,
                    cost: j,
                    c,
                    converged: true,
                    iterations: 0,
                },
                Ok(_) => {
                    return Ok((
                        out,
                        SideEnd::Failed(format!(
                            "the direct problem fails at {} = {value}",
                            f.name
                        )),
                    ));
                }
                Err(e) => return Ok((out, SideEnd::Failed(e.to_string()))),
            }
        } else {
            let cfg = constrained(config, &param, f.index, value, &from);
            match identify(problem, &cfg, &mut |_| {}) {
                Ok(r) if r.cost.is_finite() => ProfilePoint {
                    value,
                    y,
                    cost: r.cost,
                    converged: r.stop_reason.is_converged(),
                    iterations: r.iterations,
                    c: r.c,
                },
                Ok(r) => {
                    return Ok((
                        out,
                        SideEnd::Failed(format!("the re-fit ended at J = {}", r.cost)),
                    ));
                }
                Err(e) => return Ok((out, SideEnd::Failed(e.to_string()))),
            }
        };
        from.clone_from(&point.c);
        let risen = point.cost - cost_opt > stop_rise;
        let at_bound = y == lo || y == hi;
        out.push(point);
        if risen {
            return Ok((out, SideEnd::Risen));
        }
        if at_bound {
            return Ok((out, SideEnd::Bound));
        }
    }
    Ok((out, SideEnd::Points))
}

/// `config` with law parameter `index` held at `value` and the other free parameters
/// starting from `from` (clamped into their bounds), no identifiability summary.
fn constrained(
    config: &IdentifyConfig,
    param: &Parameterization,
    index: usize,
    value: f64,
    from: &[f64],
) -> IdentifyConfig {
    let mut cfg = config.clone();
    cfg.identifiability = false;
    let names: Vec<&str> = param.free.iter().map(|f| f.name).collect();
    for spec in cfg.params.iter_mut() {
        let Some(k) = names.iter().position(|n| *n == spec.name) else {
            continue;
        };
        let f = &param.free[k];
        if f.index == index {
            *spec = ParamSpec::fixed(f.name, value);
        } else {
            spec.value = Some(from[f.index].clamp(f.lower, f.upper));
        }
    }
    cfg
}

/// One end of a profile interval.
#[derive(Clone, Debug, PartialEq)]
pub enum Limit {
    /// The profile crosses the threshold here (linear interpolation between the two points
    /// around the crossing, in the scaled variable).
    At(f64),
    /// The profile stays below the threshold up to the parameter's bound (this value):
    /// unbounded within the bounds.
    Unbounded(f64),
    /// The profile stays below the threshold as far as it was computed (this value), which
    /// is not the bound: the points ran out or a re-fit failed.
    NotReached(f64),
}

impl Limit {
    /// The value, whatever the kind.
    pub fn value(&self) -> f64 {
        match self {
            Limit::At(v) | Limit::Unbounded(v) | Limit::NotReached(v) => *v,
        }
    }
}

/// The profile of one free parameter and its 95% interval.
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    /// Parameter name.
    pub name: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// Law index.
    pub index: usize,
    /// Value at the optimum.
    pub optimum: f64,
    /// `J*` (N^2).
    pub cost: f64,
    /// `chi2_1(0.95) s^2 / 2` (N^2).
    pub threshold: f64,
    /// The points, increasing in value, the optimum included.
    pub points: Vec<ProfilePoint>,
    /// Lower end of the interval.
    pub lower: Limit,
    /// Upper end.
    pub upper: Limit,
    /// How each side ended (below, above).
    pub ends: (SideEnd, SideEnd),
    /// The lowest profile cost when it is below `J*` by more than 1e-9 relative: the fit
    /// was not at the minimum (the re-fits found a better point).
    pub lower_cost_found: Option<f64>,
}

impl Profile {
    /// Assembles a profile from its two sides (each in order away from the optimum) and
    /// computes its interval. `y_opt` is the optimum's scaled variable.
    #[allow(clippy::too_many_arguments)]
    pub fn assemble(
        name: &'static str,
        unit: &'static str,
        index: usize,
        c_opt: &[f64],
        y_opt: f64,
        cost: f64,
        threshold: f64,
        below: (Vec<ProfilePoint>, SideEnd),
        above: (Vec<ProfilePoint>, SideEnd),
        to_physical: impl Fn(f64) -> f64,
    ) -> Profile {
        let optimum = c_opt[index];
        let centre = ProfilePoint {
            value: optimum,
            y: y_opt,
            cost,
            c: c_opt.to_vec(),
            converged: true,
            iterations: 0,
        };
        let limit = |side: &[ProfilePoint], end: &SideEnd| -> Limit {
            let mut prev = &centre;
            for p in side {
                let (da, db) = (prev.cost - cost, p.cost - cost);
                if db > threshold {
                    let t = if db > da {
                        ((threshold - da) / (db - da)).clamp(0.0, 1.0)
                    } else {
                        1.0
                    };
                    return Limit::At(to_physical(prev.y + t * (p.y - prev.y)));
                }
                prev = p;
            }
            match end {
                SideEnd::Bound => Limit::Unbounded(prev.value),
                _ => Limit::NotReached(prev.value),
            }
        };
        let lower = limit(&below.0, &below.1);
        let upper = limit(&above.0, &above.1);
        let mut points: Vec<ProfilePoint> = below.0.iter().rev().cloned().collect();
        points.push(centre);
        points.extend(above.0.iter().cloned());
        let min = points.iter().map(|p| p.cost).fold(f64::INFINITY, f64::min);
        let lower_cost_found = (min < cost - 1e-9 * cost.abs()).then_some(min);
        Profile {
            name,
            unit,
            index,
            optimum,
            cost,
            threshold,
            points,
            lower,
            upper,
            ends: (below.1, above.1),
            lower_cost_found,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(y: f64, cost: f64) -> ProfilePoint {
        ProfilePoint {
            value: y,
            y,
            cost,
            c: vec![y],
            converged: true,
            iterations: 0,
        }
    }

    /// For a parabola J = J* + (y - 1)^2 sampled every 0.25, the interval shall be where
    /// (y - 1)^2 = threshold, to the interpolation error of one chord; a side that reaches
    /// its bound below the threshold is unbounded there, one that ran out of points is not
    /// reached.
    #[test]
    fn interval_of_a_parabola_and_open_sides() {
        let thr = 0.5;
        let side = |dir: f64| -> Vec<ProfilePoint> {
            (1..=6)
                .map(|i| {
                    let y = 1.0 + dir * 0.25 * i as f64;
                    pt(y, 2.0 + (y - 1.0).powi(2))
                })
                .collect()
        };
        let p = Profile::assemble(
            "a",
            "-",
            0,
            &[1.0],
            1.0,
            2.0,
            thr,
            (side(-1.0), SideEnd::Risen),
            (side(1.0), SideEnd::Risen),
            |y| y,
        );
        // chord between y - 1 = 0.5 (0.25) and 0.75 (0.5625): crossing at 0.5 + 0.25 * 0.4
        let half = 0.5 + 0.25 * (0.5 - 0.25) / (0.5625 - 0.25);
        assert!(
            (p.upper.value() - (1.0 + half)).abs() < 1e-12,
            "{:?}",
            p.upper
        );
        assert!(
            (p.lower.value() - (1.0 - half)).abs() < 1e-12,
            "{:?}",
            p.lower
        );
        assert!((half - thr.sqrt()).abs() < 0.02);
        assert_eq!(p.points.len(), 13);
        assert!(p.points.windows(2).all(|w| w[0].value < w[1].value));
        assert_eq!(p.lower_cost_found, None);
        let flat: Vec<ProfilePoint> = (1..=3).map(|i| pt(1.0 + i as f64, 2.1)).collect();
        let q = Profile::assemble(
            "a",
            "-",
            0,
            &[1.0],
            1.0,
            2.0,
            thr,
            (flat.clone(), SideEnd::Points),
            (flat, SideEnd::Bound),
            |y| y,
        );
        assert_eq!(q.upper, Limit::Unbounded(4.0));
        assert_eq!(q.lower, Limit::NotReached(4.0));
    }

    #[test]
    fn threshold_is_chi2_times_the_variance_over_two() {
        // J* = 5, n = 12, p = 2: s^2 = 1, threshold = 3.841 / 2
        assert!((threshold(5.0, 12, 2) - CHI2_1_95 / 2.0).abs() < 1e-15);
        assert!(threshold(5.0, 2, 2).is_nan());
    }
}
