//! The stop of a Levenberg-Marquardt fit crawling along the valley of an undetermined
//! parameter ([`crate::StopCriteria::valley_stop`], [`crate::StopReason::ValleyBelowSigma`]).
//!
//! Where the identifiability summary at the iterate says a parameter is undetermined, the
//! statistical stop (`step_sigma`) does not apply and the chi-square stop waits for a step
//! that changes the chi-square by less than `0.01`; along a curved valley the Gauss-Newton
//! model under-predicts the decrease and the fit crawls. This rule stops the crawl when
//! each of the last `steps` accepted steps
//!
//! - moved every **determined combination** by less than `fraction` of its deviation: the
//!   step `dy` (scaled variables, `dy_k = dc_k / (dc/dy)_k` at the iterate) projected off
//!   the undetermined singular directions (the right singular vectors of the scaled
//!   sensitivity matrix `S` with the `n_u` smallest singular values, `n_u` the number of
//!   undetermined parameters), each determined parameter's component in its conditional
//!   standard deviation (the summary's, the undetermined ones held);
//! - and lowered the chi-square `2 J / sigma^2` by less than `chi2` (`sigma^2` the noise
//!   variance of `crate::chi2_stop`);
//!
//! and the undamped Gauss-Newton step from the iterate predicts a chi-square decrease
//! below `chi2` too (`crate::chi2_stop::predicted_chi2_decrease`): without that guard the
//! rule stopped a fit of R1-like data from a far start on the plateau where the viscosity
//! is so high that the law is elastic (E 13118 against the optimum's 19781:
//! `tests/valley_stop.rs`).
//!
//! The run then ends with the undetermined outcome as before ("stopped along an
//! undetermined valley: ..., but the data do not determine K"). Measured in
//! docs/performance.md ("A stop along an undetermined valley"): it does not fire on the
//! real records ht-nh, anon-nh and the joint ht-nh; without the predicted-decrease guard
//! it stops anon-nh at iteration 6 of 25 with m 3.8 deviations from the tight fit. It is
//! off by default.

use crate::identifiability::Identifiability;

/// The rule's settings ([`crate::StopCriteria::valley_stop`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ValleyStop {
    /// Accepted steps in a row that must satisfy the rule (at least 1).
    pub steps: usize,
    /// The fraction of a conditional deviation each determined combination may move.
    pub fraction: f64,
    /// The chi-square decrease each step may have.
    pub chi2: f64,
}

impl Default for ValleyStop {
    /// Two steps, a tenth of a deviation, a chi-square decrease below 1 each (the
    /// chi-square of one deviation of one parameter).
    fn default() -> Self {
        ValleyStop {
            steps: 2,
            fraction: 0.1,
            chi2: 1.0,
        }
    }
}

/// The largest move, in conditional deviations, of a determined parameter in the step
/// from `prev` to `c` (physical values of the free parameters, in `id`'s order) projected
/// off the undetermined singular directions of `id`; `None` without an undetermined
/// parameter or when a deviation cannot serve.
pub(crate) fn determined_move(id: &Identifiability, prev: &[f64], c: &[f64]) -> Option<f64> {
    let n = id.names.len();
    let n_u = id.undetermined.len();
    if n_u == 0 || n_u >= n || id.directions.len() != n || prev.len() != n || c.len() != n {
        return None;
    }
    let mut dy: Vec<f64> = (0..n).map(|k| (c[k] - prev[k]) / id.dc_dy[k]).collect();
    if dy.iter().any(|v| !v.is_finite()) {
        return None;
    }
    // off the n_u weakest directions (singular values descending)
    for v in &id.directions[n - n_u..] {
        let a: f64 = v.iter().zip(&dy).map(|(x, y)| x * y).sum();
        for (d, x) in dy.iter_mut().zip(v) {
            *d -= a * x;
        }
    }
    let mut worst: f64 = 0.0;
    for k in 0..n {
        if id.undetermined.contains(&id.names[k]) {
            continue;
        }
        let sd = id.std_dev[k];
        if !(sd.is_finite() && sd > 0.0) {
            return None;
        }
        worst = worst.max((dy[k] * id.dc_dy[k]).abs() / sd);
    }
    Some(worst)
}

/// Whether the rule's step conditions hold at the iterate with summary `id` (the caller
/// checks the predicted decrease): `recent` holds the last
/// `rule.steps + 1` accepted iterates, oldest first, each as (free parameters' values in
/// `id`'s order, cost `J`); `var` is the noise variance of the chi-square.
pub(crate) fn holds(
    rule: &ValleyStop,
    id: &Identifiability,
    recent: &[(Vec<f64>, f64)],
    var: f64,
) -> bool {
    if id.undetermined.is_empty() || recent.len() < rule.steps.max(1) + 1 || !(var > 0.0) {
        return false;
    }
    recent.windows(2).all(|w| {
        let chi2 = 2.0 * (w[0].1 - w[1].1) / var;
        chi2.is_finite()
            && chi2 < rule.chi2
            && determined_move(id, &w[0].0, &w[1].0).is_some_and(|m| m < rule.fraction)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::NoiseModel;
    use crate::identifiability::Column;
    use crate::params::Scaling;

    fn column(index: usize) -> Column {
        Column {
            index,
            name: ["a", "b"][index],
            scaling: Scaling::Linear,
            dc_dy: 1.0,
            lower: f64::NEG_INFINITY,
            upper: f64::INFINITY,
        }
    }

    /// Residuals `r_i = x_i a + eps x_i^2 b - d_i` (noise `d`): `b` barely acts on the data,
    /// so it is undetermined; the summary at `(a, b)`.
    fn summary(a: f64, b: f64, eps: f64) -> (Identifiability, Vec<Vec<f64>>) {
        let xs: Vec<f64> = (0..20).map(|i| 0.1 + f64::from(i) * 0.05).collect();
        let d: Vec<f64> = xs
            .iter()
            .enumerate()
            .map(|(i, x)| 2.0 * x + 0.01 * (f64::from(i as u32) * 1.7).sin())
            .collect();
        let jac: Vec<Vec<f64>> = xs.iter().map(|x| vec![*x, eps * x * x]).collect();
        let forces: Vec<f64> = xs.iter().map(|x| x * a + eps * x * x * b).collect();
        let w = vec![1.0; xs.len()];
        let j: f64 = forces
            .iter()
            .zip(&d)
            .map(|(f, d)| 0.5 * (f - d) * (f - d))
            .sum();
        let cols: Vec<Column> = (0..2).map(column).collect();
        let id =
            Identifiability::with_noise(&jac, &w, j, &[a, b], &cols, NoiseModel::Residual, None);
        (id, jac)
    }

    /// A step along the flat direction (b alone, which the data do not see) moves no
    /// determined combination; a step of `a` by its deviation moves it by one deviation.
    #[test]
    fn a_step_along_the_flat_direction_moves_no_determined_combination() {
        let (id, _) = summary(2.0, 1.0, 1e-9);
        assert_eq!(id.undetermined, vec!["b"], "{:?}", id.reasons);
        let along = determined_move(&id, &[2.0, 1.0], &[2.0, 5.0]).unwrap();
        assert!(along < 1e-4, "{along}");
        let sd = id.std_dev[0];
        let across = determined_move(&id, &[2.0, 1.0], &[2.0 + sd, 1.0]).unwrap();
        assert!((across - 1.0).abs() < 1e-4, "{across}");
        // two steps along the valley with chi-square falls of 0.1: the rule holds; with a
        // fall of 2 on one step, or a step of a across its deviation, it does not
        let var = crate::chi2_stop::noise_variance(&id).unwrap();
        let j0 = 1.0;
        let rule = ValleyStop::default();
        let fall = |chi2: f64| chi2 * var / 2.0;
        let recent = vec![
            (vec![2.0, 1.0], j0),
            (vec![2.0, 3.0], j0 - fall(0.1)),
            (vec![2.0, 5.0], j0 - fall(0.2)),
        ];
        assert!(holds(&rule, &id, &recent, var));
        let mut steep = recent.clone();
        steep[2].1 = j0 - fall(2.2);
        assert!(!holds(&rule, &id, &steep, var));
        let mut across = recent.clone();
        across[2].0[0] = 2.0 + 0.5 * sd;
        assert!(!holds(&rule, &id, &across, var));
        // too few steps
        assert!(!holds(&rule, &id, &recent[1..], var));
    }

    /// Settings that cannot be honoured are refused naming the field.
    #[test]
    fn bad_settings_are_refused_naming_the_field() {
        use crate::{IdentifyConfig, ParamSpec};
        for (rule, field) in [
            (
                ValleyStop {
                    steps: 0,
                    ..ValleyStop::default()
                },
                "stop.valley_stop.steps",
            ),
            (
                ValleyStop {
                    fraction: 0.0,
                    ..ValleyStop::default()
                },
                "stop.valley_stop.fraction",
            ),
            (
                ValleyStop {
                    chi2: f64::NAN,
                    ..ValleyStop::default()
                },
                "stop.valley_stop.chi2",
            ),
        ] {
            let mut cfg = IdentifyConfig::new(vec![ParamSpec::free("E", 1.0, 0.1, 10.0)]);
            cfg.stop.valley_stop = Some(rule);
            let e = cfg.validate().unwrap_err().to_string();
            assert!(e.contains(field), "{e}");
        }
    }

    /// With every parameter determined the rule never holds.
    #[test]
    fn a_determined_problem_is_left_alone() {
        let (id, _) = summary(2.0, 1.0, 1.0);
        assert!(id.undetermined.is_empty(), "{:?}", id.reasons);
        assert_eq!(determined_move(&id, &[2.0, 1.0], &[2.0, 1.0]), None);
        let recent = vec![(vec![2.0, 1.0], 1.0); 3];
        assert!(!holds(&ValleyStop::default(), &id, &recent, 1.0));
    }
}
