//! The stop along an undetermined valley (`StopCriteria::valley_stop`): on a small R1-like
//! problem (Maxwell, cone 68 deg, 8 x 8 Q8) with data of an almost elastic material (eta
//! = 1e11 MPa s: no relaxation during the test, eta undetermined, a flat valley along eta)
//! and 2% noise, with the chi-square stop off, the fit shall stop by it, end with the
//! undetermined status, in fewer iterations than the fit run to the tight rules (the
//! relative decrease), with E within a tenth of its standard deviation of that fit's. On a
//! determined problem (eta = 30000 MPa s) it shall change nothing, bit for bit.
//!
//! Reference: the same fit run to the tight rules, and its Gauss-Newton deviation of E.

mod common;

use common::maxwell_problem;
use indentify_identify::{
    IdentifyConfig, Method, ParamSpec, Problem, StopReason, ValleyStop, identify,
};

/// The small R1-like problem at `truth` with 2% noise.
fn problem(truth: &[f64]) -> Problem {
    maxwell_problem(truth, 0.02)
}

/// The statistical stop on, the chi-square stop off, the valley stop on or off, from
/// `start` (E, eta).
fn config(valley: bool, start: [f64; 2]) -> IdentifyConfig {
    let mut cfg = IdentifyConfig::new(vec![
        ParamSpec::free("E", start[0], 1000.0, 1e6),
        ParamSpec::fixed("nu", 0.3),
        ParamSpec::free("eta", start[1], 1000.0, 1e13),
    ]);
    cfg.method = Method::LevenbergMarquardt;
    cfg.stop.step_sigma = Some(0.1);
    cfg.stop.chi2_stop = false;
    cfg.stop.valley_stop = valley.then(ValleyStop::default);
    cfg.stop.max_iterations = 40;
    cfg
}

#[test]
fn the_valley_stop_ends_a_crawl_along_an_undetermined_eta() {
    let p = problem(&[20000.0, 0.3, 1e11]);
    let start = [15000.0, 5e10];
    let tight = identify(&p, &config(false, start), &mut |_| {}).unwrap();
    let valley = identify(&p, &config(true, start), &mut |_| {}).unwrap();
    println!(
        "tight: {:?} {} it, {} forward ({}); valley: {:?} {} it, {} forward ({})",
        tight.c,
        tight.iterations,
        tight.forward_solves,
        tight.stop_reason,
        valley.c,
        valley.iterations,
        valley.forward_solves,
        valley.stop_reason
    );
    match &valley.stop_reason {
        StopReason::Undetermined { met, params } => {
            assert!(
                matches!(**met, StopReason::ValleyBelowSigma { steps: 2, .. }),
                "{met}"
            );
            assert!(params.iter().any(|p| p.starts_with("eta")), "{params:?}");
        }
        other => panic!("expected the undetermined status, got {other}"),
    }
    assert!(!valley.stop_reason.is_converged());
    assert!(
        valley
            .stop_reason
            .to_string()
            .starts_with("stopped along an undetermined valley"),
        "{}",
        valley.stop_reason
    );
    assert!(valley.iterations < tight.iterations);
    let id = tight.identifiability.as_ref().unwrap();
    let k = id.names.iter().position(|n| *n == "E").unwrap();
    let sd = id.std_dev[k];
    assert!(sd.is_finite() && sd > 0.0);
    let shift = (valley.c[0] - tight.c[0]).abs() / sd;
    assert!(shift < 0.1, "E shift {shift} sigma");
}

#[test]
fn the_valley_stop_leaves_a_determined_fit_alone() {
    let p = problem(&[20000.0, 0.3, 30000.0]);
    let start = [4000.0, 70000.0];
    let a = identify(&p, &config(true, start), &mut |_| {}).unwrap();
    let b = identify(&p, &config(false, start), &mut |_| {}).unwrap();
    assert_eq!(a.c, b.c);
    assert_eq!(a.iterations, b.iterations);
    assert_eq!(a.forward_solves, b.forward_solves);
    assert_eq!(a.stop_reason, b.stop_reason);
    assert!(a.stop_reason.is_converged(), "{}", a.stop_reason);
}
