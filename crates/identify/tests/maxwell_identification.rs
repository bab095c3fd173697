//! Identification of Maxwell parameters (paper §4, Table I in miniature) from synthetic
//! indentation curves: recovery from several starts, the evaluation cache, bounds,
//! scalings, resume, noise reproducibility and the bad-input errors.
//!
//! Reference: the truth that generated the data (exact synthetic data: J(truth) = 0).
//! Goal: the identified (E, eta) shall match it to 1e-4 relative.
//!
//! ```text
//!      cone 68 deg, depth 0 -> 0.1 mm (1 s) -> hold (1 s) -> 0 (1 s), 6 steps/segment
//!        \   /
//!   z=0 --\-/--------------  top: contact candidates
//!        |                |  4 x 4 mm cylinder, 8 x 8 Q8 graded 1.45
//!  axis  |                |  towards the axis and the top
//!  u_r=0 |                |
//!        +----------------+  bottom: u_z = 0
//! ```
//! Parameters: E = 20000 MPa, nu = 0.3 (fixed), eta = 30000 MPa s.

mod common;

use common::maxwell_specs as specs;
use indentify_contact::{DirectSolver, Schedule, SolverOptions, trapezoid};
use indentify_identify::{
    Evaluator, ForceRecord, IdentifyConfig, IdentifyError, Method, ParamSpec, Problem, Scaling,
    StopReason, identify, multiplicative_noise, multistart, resume,
};
use indentify_laws::Maxwell;
use indentify_testkit::cone_model as model;

const TRUTH: [f64; 3] = [20000.0, 0.3, 30000.0];

fn schedule() -> Schedule {
    Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 6)).unwrap()
}

/// The synthetic record of the truth, at the schedule times.
fn exact_record() -> ForceRecord {
    let m = model();
    let s = schedule();
    let f = DirectSolver::new(&m)
        .unwrap()
        .run(
            &indentify_laws::LawMaterial(&Maxwell),
            &TRUTH,
            &s,
            &SolverOptions::default(),
        )
        .unwrap()
        .forces();
    ForceRecord::new(s.t.clone(), f).unwrap()
}

fn problem(record: &ForceRecord) -> Problem {
    Problem::new(
        model(),
        &Maxwell,
        schedule(),
        record,
        None,
        SolverOptions::default(),
    )
    .unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The system shall recover Maxwell's (E, eta) from exact data within 1e-4 relative from
/// two of the paper's starting points (BFGS with Armijo backtracking, multi-start).
#[test]
fn bfgs_recovers_maxwell_from_two_paper_starts() {
    let p = problem(&exact_record());
    let cfg = IdentifyConfig::new(specs(4000.0, 70000.0));
    let starts = vec![vec![4000.0, 70000.0], vec![60000.0, 10000.0]];
    let mut lines = 0;
    let ms = multistart(&p, &cfg, &starts, &mut |_, _| lines += 1).unwrap();
    assert!(ms.best.is_some());
    let mut total_records = 0;
    for run in &ms.runs {
        let r = run.as_ref().unwrap();
        println!(
            "start {:?}: {:?} after {} it, {} fwd, {} adj, J = {:.3e}, {}",
            &r.history[0].params,
            r.c,
            r.iterations,
            r.forward_solves,
            r.adjoint_solves,
            r.cost,
            r.stop_reason
        );
        assert!(r.stop_reason.is_converged(), "{}", r.stop_reason);
        assert!(rel(r.c[0], TRUTH[0]) < 1e-4, "E = {}", r.c[0]);
        assert!(rel(r.c[2], TRUTH[2]) < 1e-4, "eta = {}", r.c[2]);
        assert_eq!(r.c[1], 0.3, "nu stays fixed");
        assert!(r.iterations <= 40);
        assert!(r.cost < 1e-8 * r.initial_cost);
        total_records += r.history.len();
        // the history starts at the start and ends at the result
        assert_eq!(r.history[0].iteration, 0);
        assert_eq!(r.history.last().unwrap().params, r.c);
        assert!(r.params[0].free && !r.params[1].free);
        let id = r.identifiability.as_ref().unwrap();
        assert_eq!(id.names, vec!["E", "eta"]);
        assert!(id.correlation[0][1].abs() <= 1.0 + 1e-12);
        assert!(id.condition_number >= 1.0);
    }
    // every record went to the observer as it came
    assert_eq!(lines, total_records);
}

/// The cache shall make one forward solve and one adjoint sweep serve all requests at a
/// point: cost, gradient and forces at the same parameters.
#[test]
fn one_forward_and_one_adjoint_per_point() {
    let p = problem(&exact_record());
    let mut ev = Evaluator::new(&p).unwrap();
    let c = [15000.0, 0.3, 45000.0];
    let j = ev.cost(&c).unwrap();
    let (j2, g) = ev.cost_and_gradient(&c).unwrap();
    let (j3, g2) = ev.cost_and_gradient(&c).unwrap();
    let f = ev.forces(&c).unwrap();
    assert_eq!(j, j2);
    assert_eq!(j, j3);
    assert_eq!(g, g2);
    assert_eq!(f.len(), p.schedule().t.len());
    let n = ev.counts();
    assert_eq!((n.forward, n.adjoint), (1, 1), "{n:?}");
    // a different bit pattern is a different point
    let c2 = [f64::from_bits(15000.0f64.to_bits() + 1), 0.3, 45000.0];
    ev.cost(&c2).unwrap();
    assert_eq!(ev.counts().forward, 2);
}

/// Over a whole BFGS-Armijo run, no point shall be solved twice and exactly one adjoint
/// sweep shall be spent per recorded iterate (argmin asks cost and gradient separately,
/// and the gradient again after the line search).
#[test]
fn bfgs_run_spends_one_adjoint_per_iterate_and_no_repeated_forward() {
    let p = problem(&exact_record());
    for method in [Method::Bfgs, Method::Lbfgs { memory: 5 }] {
        let mut cfg = IdentifyConfig::new(specs(10000.0, 5000.0));
        cfg.method = method;
        cfg.identifiability = false;
        let r = identify(&p, &cfg, &mut |_| {}).unwrap();
        println!(
            "{method:?}: {} it, {} fwd, {} adj, {} records",
            r.iterations,
            r.forward_solves,
            r.adjoint_solves,
            r.history.len()
        );
        assert!(r.stop_reason.is_converged(), "{}", r.stop_reason);
        if method == Method::Bfgs {
            assert_eq!(r.adjoint_solves, r.history.len(), "one adjoint per iterate");
        } else {
            // More-Thuente asks the gradient at its trial points too
            assert!(r.adjoint_solves <= r.forward_solves);
        }
        assert!(r.forward_solves >= r.history.len());
        // forward solves == distinct points requested: no point was solved twice, although
        // argmin asked for the cost and the gradient of every iterate in separate calls
        assert_eq!(r.forward_solves, r.distinct_points);
        assert!(r.cache_hits >= r.history.len(), "{} hits", r.cache_hits);
        // the same holds for an evaluator driven by hand
        let mut ev = Evaluator::new(&p).unwrap();
        for h in &r.history {
            ev.cost_and_gradient(&h.params).unwrap();
            ev.cost_and_gradient(&h.params).unwrap();
        }
        assert_eq!(ev.counts().forward, r.history.len());
        assert_eq!(ev.counts().adjoint, r.history.len());
    }
}

/// Bounds shall hold at every iterate and the result shall report the bound it sits on,
/// with the projected BFGS and with L-BFGS-B.
#[test]
fn bounds_are_respected_and_reported() {
    let p = problem(&exact_record());
    for method in [Method::Bfgs, Method::Lbfgsb { memory: 5 }] {
        let mut cfg = IdentifyConfig::new(vec![
            ParamSpec::free("E", 10000.0, 5000.0, 15000.0),
            ParamSpec::fixed("nu", 0.3),
            ParamSpec::free("eta", 50000.0, 1000.0, 1e6),
        ]);
        cfg.method = method;
        cfg.identifiability = false;
        let mut seen = Vec::new();
        let r = identify(&p, &cfg, &mut |h| seen.push(h.params.clone())).unwrap();
        println!(
            "{method:?}: {:?} {} after {} it",
            r.c, r.stop_reason, r.iterations
        );
        for c in &seen {
            assert!((5000.0..=15000.0).contains(&c[0]), "{c:?}");
        }
        assert_eq!(r.c[0], 15000.0);
        assert!(r.params[0].at_upper && !r.params[0].at_lower);
        assert!(!r.params[2].at_upper && !r.params[2].at_lower);
        assert!(r.stop_reason.is_converged(), "{}", r.stop_reason);
    }
}

/// Bounds-normalized and linear scalings shall reach the same optimum as log scaling;
/// Levenberg-Marquardt too.
#[test]
fn other_scalings_and_levenberg_marquardt_converge() {
    let p = problem(&exact_record());
    for (scaling, method) in [
        (Scaling::Bounds, Method::Bfgs),
        (Scaling::Linear, Method::Bfgs),
        (Scaling::Log, Method::LevenbergMarquardt),
    ] {
        let s: Vec<ParamSpec> = specs(4000.0, 70000.0)
            .into_iter()
            .map(|s| s.with_scaling(scaling))
            .collect();
        let mut cfg = IdentifyConfig::new(s);
        cfg.method = method;
        cfg.stop.max_iterations = 200;
        cfg.identifiability = false;
        let r = identify(&p, &cfg, &mut |_| {}).unwrap();
        println!(
            "{scaling:?}/{method:?}: {:?} {} it, {} fwd {} adj {} sens, {}",
            r.c,
            r.iterations,
            r.forward_solves,
            r.adjoint_solves,
            r.sensitivity_solves,
            r.stop_reason
        );
        assert!(rel(r.c[0], TRUTH[0]) < 1e-4, "{scaling:?}: E = {}", r.c[0]);
        assert!(
            rel(r.c[2], TRUTH[2]) < 1e-4,
            "{scaling:?}: eta = {}",
            r.c[2]
        );
    }
}

/// A run cut short by the iteration limit shall resume from its last record, continue the
/// numbering and the counts, and converge.
#[test]
fn resume_continues_from_the_last_record() {
    let p = problem(&exact_record());
    let mut cfg = IdentifyConfig::new(specs(4000.0, 70000.0));
    cfg.identifiability = false;
    cfg.stop.max_iterations = 3;
    let first = identify(&p, &cfg, &mut |_| {}).unwrap();
    assert_eq!(first.stop_reason, StopReason::MaxIterations);
    assert!(first.ensure_converged().is_err());
    let last = first.history.last().unwrap().clone();
    assert_eq!(last.iteration, 3);
    cfg.stop.max_iterations = 100;
    let mut numbers = Vec::new();
    let second = resume(&p, &cfg, &last, &mut |h| numbers.push(h.iteration)).unwrap();
    assert_eq!(numbers[0], 3);
    assert_eq!(numbers[1], 4);
    assert!(second.forward_solves > first.forward_solves);
    assert!(second.stop_reason.is_converged(), "{}", second.stop_reason);
    assert!(rel(second.c[0], TRUTH[0]) < 1e-4);
    assert!(rel(second.c[2], TRUTH[2]) < 1e-4);
}

/// A record sampled on other times than the simulation shall be interpolated, and the
/// identification still lands near the truth (interpolation error only).
#[test]
fn a_record_on_other_times_is_interpolated() {
    let exact = exact_record();
    // a finer record (linear interpolation of the exact one at 4x the rate)
    let t: Vec<f64> = (0..=72).map(|k| 3.0 * k as f64 / 72.0).collect();
    let f: Vec<f64> = t.iter().map(|&s| exact.interpolate(s)).collect();
    let rec = ForceRecord::new(t, f).unwrap();
    let p = problem(&rec);
    for (a, b) in p.target.iter().zip(&exact.force) {
        assert!((a - b).abs() <= 1e-9 * b.abs().max(1.0));
    }
}

/// Noise shall be reproducible: seed 42, amplitude 0.1 on 100 N gives these exact values
/// (SplitMix64 is the specification, docs/theory.md §11).
#[test]
fn noise_is_reproducible_from_its_seed() {
    let f = multiplicative_noise(&[100.0, 100.0, 100.0, 0.0], 0.1, 42);
    assert_eq!(f[0], 104.83129757543645);
    assert_eq!(f[1], 93.1982078575384);
    assert_eq!(f[2], 95.57202260510277);
    assert_eq!(f[3], 0.0);
    assert_eq!(
        f,
        multiplicative_noise(&[100.0, 100.0, 100.0, 0.0], 0.1, 42)
    );
    assert_ne!(
        f,
        multiplicative_noise(&[100.0, 100.0, 100.0, 0.0], 0.1, 43)
    );
    for v in &f[..3] {
        assert!((90.0..=110.0).contains(v));
    }
}

/// Bad input shall give typed errors with clear messages before any solve.
#[test]
fn bad_input_gives_clear_errors() {
    let rec = exact_record();
    // a record that stops before the end of the history
    let short = ForceRecord::new(rec.t[..5].to_vec(), rec.force[..5].to_vec()).unwrap();
    let e = Problem::new(
        model(),
        &Maxwell,
        schedule(),
        &short,
        None,
        SolverOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, IdentifyError::RecordDoesNotCover { .. }), "{e}");
    // too few points
    let e = ForceRecord::new(vec![0.0], vec![0.0]).unwrap_err();
    assert!(e.to_string().contains("at least 2"), "{e}");
    // weights that leave fewer data than free parameters
    let n = schedule().t.len();
    let mut w = vec![0.0; n];
    w[3] = 1.0;
    let p = Problem::new(
        model(),
        &Maxwell,
        schedule(),
        &rec,
        Some(w),
        SolverOptions::default(),
    )
    .unwrap();
    let e = identify(
        &p,
        &IdentifyConfig::new(specs(4000.0, 70000.0)),
        &mut |_| {},
    )
    .unwrap_err();
    assert!(matches!(e, IdentifyError::TooFewPoints { .. }), "{e}");
    let p = problem(&rec);
    // start outside the bounds
    let e = identify(&p, &IdentifyConfig::new(specs(500.0, 70000.0)), &mut |_| {}).unwrap_err();
    assert!(matches!(e, IdentifyError::StartOutsideBounds { .. }), "{e}");
    // bounds that exclude each other
    let mut s = specs(4000.0, 70000.0);
    s[2].lower = Some(2e7);
    let e = identify(&p, &IdentifyConfig::new(s), &mut |_| {}).unwrap_err();
    assert!(matches!(e, IdentifyError::BoundsExclude { .. }), "{e}");
    // a fixed parameter without a value
    let mut s = specs(4000.0, 70000.0);
    s[1].value = None;
    let e = identify(&p, &IdentifyConfig::new(s), &mut |_| {}).unwrap_err();
    assert_eq!(e.to_string(), "parameter `nu` is fixed but has no value");
    // a nonsense option
    let mut cfg = IdentifyConfig::new(specs(4000.0, 70000.0));
    cfg.initial_step = -1.0;
    let e = identify(&p, &cfg, &mut |_| {}).unwrap_err();
    assert!(e.to_string().contains("initial_step"), "{e}");
}

/// An optimizer that stalls shall report it, keep the history so far, and
/// `ensure_converged` shall turn it into an error naming the reason.
#[test]
fn a_stalled_run_reports_and_keeps_its_history() {
    let p = problem(&exact_record());
    let mut cfg = IdentifyConfig::new(specs(4000.0, 70000.0));
    cfg.identifiability = false;
    // a first trial step of e^40 and a single trial point allowed: the line search fails
    cfg.initial_step = 40.0;
    cfg.stop.max_line_search_evaluations = 1;
    let mut seen = 0;
    let r = identify(&p, &cfg, &mut |_| seen += 1).unwrap();
    assert!(
        matches!(r.stop_reason, StopReason::Stalled(_)),
        "{}",
        r.stop_reason
    );
    assert_eq!(seen, r.history.len());
    assert!(!r.history.is_empty());
    assert_eq!(r.c, vec![4000.0, 0.3, 70000.0]);
    let e = r.ensure_converged().unwrap_err();
    assert!(e.to_string().contains("stalled"), "{e}");
    assert!(e.to_string().contains("line search"), "{e}");
}
