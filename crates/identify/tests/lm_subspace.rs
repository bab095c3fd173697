//! Levenberg-Marquardt's steps in the determined subspace (`LmStrategy::subspace`) on a
//! small R1-like problem (Maxwell, cone 68 deg, 8 x 8 Q8, 2% noise; `common::maxwell_problem`):
//!
//! - data of an almost elastic material (eta = 1e11 MPa s: eta undetermined, a flat valley
//!   along it), the chi-square stop off: the fit ends with the undetermined status by the
//!   subspace stop, in fewer iterations than the fit run to the tight rules, with E within
//!   a tenth of its deviation of that fit's and each end point inside the other's 2-sigma
//!   interval of E;
//! - a determined problem (eta = 30000 MPa s) from a far start (E 4000, eta 70000, where
//!   the first version of the valley stop stopped on the elastic plateau): the fit still
//!   reaches the tight fit's optimum, converged.
//!
//! Reference: the same fits with the strategy off, and their Gauss-Newton deviations.

mod common;

use common::maxwell_problem;
use indentify_identify::{IdentifyConfig, Method, ParamSpec, StopReason, identify};

/// The statistical stop on, the chi-square stop off, the strategy on or off, from `start`.
fn config(subspace: bool, start: [f64; 2]) -> IdentifyConfig {
    let mut cfg = IdentifyConfig::new(vec![
        ParamSpec::free("E", start[0], 1000.0, 1e6),
        ParamSpec::fixed("nu", 0.3),
        ParamSpec::free("eta", start[1], 1000.0, 1e13),
    ]);
    cfg.method = Method::LevenbergMarquardt;
    cfg.stop.step_sigma = Some(0.1);
    cfg.stop.chi2_stop = false;
    cfg.stop.lm.subspace = subspace;
    cfg.stop.max_iterations = 40;
    cfg
}

#[test]
fn subspace_steps_end_an_undetermined_eta_fit_early_and_honestly() {
    let p = maxwell_problem(&[20000.0, 0.3, 1e11], 0.02);
    let start = [15000.0, 5e10];
    let tight = identify(&p, &config(false, start), &mut |_| {}).unwrap();
    let on = identify(&p, &config(true, start), &mut |_| {}).unwrap();
    println!(
        "tight: {:?} {} it, {} forward ({}); subspace: {:?} {} it, {} forward ({})",
        tight.c,
        tight.iterations,
        tight.forward_solves,
        tight.stop_reason,
        on.c,
        on.iterations,
        on.forward_solves,
        on.stop_reason
    );
    match &on.stop_reason {
        StopReason::Undetermined { met, params } => {
            assert!(
                matches!(**met, StopReason::SubspaceBelowSigma { .. }),
                "{met}"
            );
            assert!(params.iter().any(|p| p.starts_with("eta")), "{params:?}");
        }
        other => panic!("expected the undetermined status, got {other}"),
    }
    assert!(
        on.stop_reason
            .to_string()
            .starts_with("steps kept off the undetermined direction"),
        "{}",
        on.stop_reason
    );
    assert!(on.iterations < tight.iterations);
    let id = tight.identifiability.as_ref().unwrap();
    let k = id.names.iter().position(|n| *n == "E").unwrap();
    let sd = id.std_dev[k];
    assert!(sd.is_finite() && sd > 0.0);
    let shift = (on.c[0] - tight.c[0]).abs() / sd;
    assert!(shift < 0.1, "E shift {shift} sigma");
    let id_on = on.identifiability.as_ref().unwrap();
    let (lo, hi) = id.intervals[k];
    assert!(lo <= on.c[0] && on.c[0] <= hi);
    let (lo, hi) = id_on.intervals[k];
    assert!(lo <= tight.c[0] && tight.c[0] <= hi);
}

#[test]
fn subspace_steps_reach_the_optimum_from_the_elastic_plateau() {
    let p = maxwell_problem(&[20000.0, 0.3, 30000.0], 0.02);
    let start = [4000.0, 70000.0];
    let on = identify(&p, &config(true, start), &mut |_| {}).unwrap();
    let off = identify(&p, &config(false, start), &mut |_| {}).unwrap();
    println!(
        "off: {:?} {} it ({}); on: {:?} {} it ({})",
        off.c, off.iterations, off.stop_reason, on.c, on.iterations, on.stop_reason
    );
    assert!(on.stop_reason.is_converged(), "{}", on.stop_reason);
    let id = off.identifiability.as_ref().unwrap();
    for (k, name) in id.names.iter().enumerate() {
        let i = if *name == "E" { 0 } else { 2 };
        let shift = (on.c[i] - off.c[i]).abs() / id.std_dev[k];
        assert!(shift < 0.1, "{name}: {shift} sigma");
    }
}
