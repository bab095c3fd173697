//! Multi-start identification: seeded Latin-hypercube starts in the scaled box of the free
//! parameters, and the clustering of the runs' end points into distinct local minima.
//!
//! Starts are drawn in the optimizer's scaled variables `y` ([`Parameterization`]: `ln c`
//! for a log-scaled parameter), so a log-scaled parameter is sampled uniformly in its
//! logarithm. For `n` starts, each free parameter's scaled interval `[y_lo, y_hi]` is cut
//! into `n` equal strata; start `i` takes stratum `pi_k(i)` of parameter `k` (`pi_k` a
//! random permutation) at a uniform position inside it: every stratum of every parameter
//! is used exactly once (a Latin hypercube, McKay, Beckman and Conover 1979). The draws come
//! from [`SplitMix64`] seeded with the user's seed, parameter by parameter (first the
//! Fisher-Yates permutation, then the `n` offsets), so a seed gives the same starts on every
//! machine and thread count.
//!
//! The runs themselves are independent ([`run_start`]); a front end may run them in
//! parallel (the `study` crate does, with rayon) and hand them back in start order to
//! [`cluster`], whose result does not depend on the order they finished in.

use crate::IdentifyError;
use crate::noise::SplitMix64;
use crate::optimize::{IdentifyConfig, IdentifyResult, identify, with_starts};
use crate::params::Parameterization;
use crate::problem::Problem;

/// The default clustering tolerance: end points whose scaled variables differ by at most
/// this (infinity norm; 0.01 = 1% on a log-scaled parameter) are the same minimum.
pub const DEFAULT_CLUSTER_TOL: f64 = 1e-2;

/// Largest number of starts [`latin_hypercube`] accepts.
pub const MAX_STARTS: usize = 10_000;

/// `n` Latin-hypercube starts (values of the free parameters, physical units, law order)
/// within the bounds of `param`, from `seed`.
///
/// # Errors
/// [`IdentifyError::InvalidOption`] for `n` outside `[1, MAX_STARTS]`;
/// [`IdentifyError::InvalidSpec`] for a free parameter whose scaled bounds are not finite
/// (an infinite bound, or a zero lower bound of a log-scaled parameter).
pub fn latin_hypercube(
    param: &Parameterization,
    n: usize,
    seed: u64,
) -> Result<Vec<Vec<f64>>, IdentifyError> {
    if !(1..=MAX_STARTS).contains(&n) {
        return Err(IdentifyError::InvalidOption {
            field: "starts",
            value: n.to_string(),
            allowed: "an integer in [1, 10000]",
        });
    }
    let mut rng = SplitMix64::new(seed);
    let mut starts = vec![Vec::with_capacity(param.free.len()); n];
    for f in &param.free {
        let (lo, hi) = f.scaled_bounds();
        if !(lo.is_finite() && hi.is_finite()) {
            return Err(IdentifyError::InvalidSpec {
                name: f.name.to_string(),
                why: format!(
                    "multi-start draws starts within the bounds, and [{}, {}] is not a finite \
                     interval of the scaled variable: give finite bounds (a lower bound > 0 for \
                     a log-scaled parameter)",
                    f.lower, f.upper
                ),
            });
        }
        let mut perm: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            let j = (rng.next_u64() % (i as u64 + 1)) as usize;
            perm.swap(i, j);
        }
        for (start, &stratum) in starts.iter_mut().zip(&perm) {
            let u = (stratum as f64 + rng.next_f64()) / n as f64;
            let c = f.to_physical(lo + u * (hi - lo));
            // round-off of exp/ln must not put a start outside its own box
            start.push(c.clamp(f.lower, f.upper));
        }
    }
    Ok(starts)
}

/// One run of a multi-start: [`identify`] from `start` (the free parameters' values, law
/// order), the rest of `config` shared, no observer.
///
/// # Errors
/// As [`identify`]; [`IdentifyError::InvalidSpec`] for a start of the wrong length.
pub fn run_start(
    problem: &Problem,
    config: &IdentifyConfig,
    start: &[f64],
) -> Result<IdentifyResult, IdentifyError> {
    let n_free = config.params.iter().filter(|p| p.free).count();
    if start.len() != n_free {
        return Err(IdentifyError::InvalidSpec {
            name: "start".into(),
            why: format!("{} values for {n_free} free parameters", start.len()),
        });
    }
    identify(problem, &with_starts(config, start), &mut |_| {})
}

/// A distinct local minimum: the runs that ended within the tolerance of its best point.
#[derive(Clone, Debug, PartialEq)]
pub struct Minimum {
    /// The best end point of the cluster (full law vector, physical units).
    pub c: Vec<f64>,
    /// `J` there (N^2).
    pub cost: f64,
    /// The run that reached it (index into the starts).
    pub best_start: usize,
    /// Every start whose run ended in this cluster, increasing.
    pub starts: Vec<usize>,
    /// How many of them met a convergence criterion.
    pub converged: usize,
    /// Free parameters at a bound at the best point.
    pub at_bound: Vec<&'static str>,
    /// Free parameters the data do not determine at the best point (its identifiability
    /// summary): they were not compared when runs were grouped into this minimum.
    pub undetermined: Vec<&'static str>,
}

/// The end points of a multi-start grouped into minima.
#[derive(Clone, Debug, PartialEq)]
pub struct Clusters {
    /// Minima, lowest cost first.
    pub minima: Vec<Minimum>,
    /// Runs that failed (start index and message).
    pub failed: Vec<(usize, String)>,
    /// The clustering tolerance (scaled variables, infinity norm).
    pub tol: f64,
}

/// Groups the runs' end points: runs are taken by increasing final cost (ties by start
/// index); each joins the first minimum whose best point lies within `tol` of its end point
/// in every scaled variable of a *determined* parameter, or founds a new one. A parameter
/// the data do not determine (undetermined in the identifiability summary of the run or of
/// the minimum's best run) takes any value along its valley at the same cost, so it is not
/// compared: one basin is counted once however far its undetermined parameter wandered.
/// Failed runs are listed apart.
pub fn cluster(
    param: &Parameterization,
    runs: &[Result<IdentifyResult, IdentifyError>],
    tol: f64,
) -> Clusters {
    let scaled =
        |c: &[f64]| -> Vec<f64> { param.free.iter().map(|f| f.to_scaled(c[f.index])).collect() };
    let mut order: Vec<(usize, &IdentifyResult)> = Vec::new();
    let mut failed = Vec::new();
    for (i, r) in runs.iter().enumerate() {
        match r {
            Ok(r) if r.cost.is_finite() => order.push((i, r)),
            Ok(r) => failed.push((i, format!("final cost {}", r.cost))),
            Err(e) => failed.push((i, e.to_string())),
        }
    }
    order.sort_by(|a, b| a.1.cost.total_cmp(&b.1.cost).then(a.0.cmp(&b.0)));
    let undetermined_of = |r: &IdentifyResult| -> Vec<&'static str> {
        r.identifiability
            .as_ref()
            .map_or_else(Vec::new, |i| i.undetermined.clone())
    };
    let mut minima: Vec<(Vec<f64>, Minimum)> = Vec::new();
    for (i, r) in order {
        let y = scaled(&r.c);
        let converged = usize::from(r.stop_reason.is_converged());
        let undetermined = undetermined_of(r);
        let home = minima.iter_mut().find(|(yb, m)| {
            yb.iter().zip(&y).zip(&param.free).all(|((a, b), f)| {
                (a - b).abs() <= tol
                    || a == b
                    || undetermined.contains(&f.name)
                    || m.undetermined.contains(&f.name)
            })
        });
        match home {
            Some((_, m)) => {
                m.starts.push(i);
                m.converged += converged;
            }
            None => {
                let at_bound = r
                    .params
                    .iter()
                    .filter(|p| p.free && (p.at_lower || p.at_upper))
                    .map(|p| p.name)
                    .collect();
                minima.push((
                    y,
                    Minimum {
                        c: r.c.clone(),
                        cost: r.cost,
                        best_start: i,
                        starts: vec![i],
                        converged,
                        at_bound,
                        undetermined,
                    },
                ));
            }
        }
    }
    let minima = minima
        .into_iter()
        .map(|(_, mut m)| {
            m.starts.sort_unstable();
            m
        })
        .collect();
    Clusters {
        minima,
        failed,
        tol,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identifiability::Identifiability;
    use crate::optimize::{ParamOutcome, StopReason};
    use crate::params::{ParamSpec, Scaling};

    fn param() -> Parameterization {
        let law = indentify_laws::law_by_name("maxwell").unwrap();
        Parameterization::new(
            &indentify_laws::LawMaterial(law),
            &[
                ParamSpec::free("E", 4000.0, 1e3, 1e6),
                ParamSpec::fixed("nu", 0.3),
                ParamSpec::free("eta", 7e4, 1e3, 1e7).with_scaling(Scaling::Bounds),
            ],
        )
        .unwrap()
    }

    /// The starts shall be a Latin hypercube of the scaled box: each of the n strata of
    /// each parameter used once, the same for the same seed, different for another.
    #[test]
    fn latin_hypercube_fills_every_stratum_once() {
        let p = param();
        let n = 17;
        let s = latin_hypercube(&p, n, 7).unwrap();
        assert_eq!(s.len(), n);
        for (k, f) in p.free.iter().enumerate() {
            let (lo, hi) = f.scaled_bounds();
            let mut strata: Vec<usize> = s
                .iter()
                .map(|v| {
                    assert!(v[k] >= f.lower && v[k] <= f.upper);
                    ((f.to_scaled(v[k]) - lo) / (hi - lo) * n as f64).floor() as usize
                })
                .collect();
            strata.sort_unstable();
            assert_eq!(strata, (0..n).collect::<Vec<_>>(), "parameter {}", f.name);
        }
        assert_eq!(s, latin_hypercube(&p, n, 7).unwrap());
        assert_ne!(s, latin_hypercube(&p, n, 8).unwrap());
    }

    #[test]
    fn bad_starts_are_errors_naming_the_option() {
        let p = param();
        let e = latin_hypercube(&p, 0, 1).unwrap_err().to_string();
        assert!(e.contains("starts") && e.contains("[1, 10000]"), "{e}");
        let law = indentify_laws::law_by_name("maxwell").unwrap();
        let open = Parameterization::new(
            &indentify_laws::LawMaterial(law),
            &[
                ParamSpec::free("E", 4000.0, 0.0, 1e6),
                ParamSpec::fixed("nu", 0.3),
                ParamSpec::fixed("eta", 7e4),
            ],
        )
        .unwrap();
        let e = latin_hypercube(&open, 3, 1).unwrap_err().to_string();
        assert!(e.contains("`E`") && e.contains("finite"), "{e}");
    }

    /// An end point of a run of `param()` (E, eta free) at `(e, eta)` with cost `cost`,
    /// whose identifiability summary comes from a synthetic Jacobian in which eta acts
    /// (`eta_acts`) or has no effect (then eta is undetermined).
    fn end_point(e: f64, eta: f64, cost: f64, eta_acts: bool) -> IdentifyResult {
        let c = vec![e, 0.3, eta];
        let jac: Vec<Vec<f64>> = (0..10)
            .map(|i| {
                let t = i as f64;
                vec![1.0 + t, 0.0, if eta_acts { 1.0 - 0.1 * t * t } else { 0.0 }]
            })
            .collect();
        let p = param();
        let columns: Vec<crate::identifiability::Column> = p
            .free
            .iter()
            .map(|f| crate::identifiability::Column::of(f, c[f.index]))
            .collect();
        let id = Identifiability::from_columns(&jac, &[1.0; 10], cost, &c, &columns);
        assert_eq!(id.undetermined.is_empty(), eta_acts, "{:?}", id.reasons);
        let outcome = |name, k: usize| ParamOutcome {
            name,
            unit: "",
            free: k != 1,
            start: c[k],
            value: c[k],
            lower: 0.0,
            upper: f64::INFINITY,
            at_lower: false,
            at_upper: false,
        };
        IdentifyResult {
            law: "maxwell",
            method: crate::optimize::Method::Bfgs,
            params: vec![outcome("E", 0), outcome("nu", 1), outcome("eta", 2)],
            c,
            initial_cost: 1.0,
            cost,
            reference_cost: 1.0,
            iterations: 1,
            forward_solves: 1,
            adjoint_solves: 1,
            sensitivity_solves: 0,
            rejected_trials: 0,
            newton_iterations: 0,
            factorizations: 0,
            stopped_runs: 0,
            schedule_steps: 0,
            steps_skipped: 0,
            cache_hits: 0,
            distinct_points: 1,
            stop_reason: StopReason::GradientNorm,
            seconds: 0.0,
            history: Vec::new(),
            initial_forces: Vec::new(),
            forces: Vec::new(),
            identifiability: Some(id),
        }
    }

    /// Three runs end at the same E with eta far apart: when eta is undetermined they are
    /// one minimum (one basin counted once), when it is determined three; a fourth run at
    /// another E is another minimum either way.
    #[test]
    fn minima_are_told_apart_by_the_determined_parameters_only() {
        let p = param();
        for acts in [false, true] {
            let runs: Vec<Result<IdentifyResult, IdentifyError>> = vec![
                Ok(end_point(2e4, 3e4, 1e-3, acts)),
                Ok(end_point(2e4 * 1.001, 3e5, 1e-3, acts)),
                Ok(end_point(2e4, 3e6, 1.1e-3, acts)),
                Ok(end_point(5e4, 3e4, 2e-3, acts)),
            ];
            let c = cluster(&p, &runs, DEFAULT_CLUSTER_TOL);
            let starts: Vec<Vec<usize>> = c.minima.iter().map(|m| m.starts.clone()).collect();
            if acts {
                assert_eq!(starts, [vec![0], vec![1], vec![2], vec![3]]);
                assert!(c.minima.iter().all(|m| m.undetermined.is_empty()));
            } else {
                assert_eq!(starts, [vec![0, 1, 2], vec![3]]);
                assert_eq!(c.minima[0].undetermined, ["eta"]);
            }
        }
    }
}
