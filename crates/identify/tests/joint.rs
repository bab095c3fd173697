//! Joint fits of several tests sharing one law's parameters: the joint cost, gradient and
//! Jacobian against the separate one-test problems and against central finite
//! differences over whole histories, recovery of Maxwell's (E, eta) from two loading rates,
//! bit-identical results for 1 and 2 threads and with or without prefetching, and the
//! bad-input errors.
//!
//! Reference: the one-test problems (J = sum_k w_k J_k, dJ/dc = sum_k w_k dJ_k/dc, the
//! Jacobian rows stacked), central finite differences of J, and the truth that generated
//! the exact synthetic data.
//!
//! ```text
//!      cone 68 deg; test A: 0 -> 0.1 mm in 0.2 s, hold 1 s; test B: 0 -> 0.05 mm in 2 s, hold 1 s
//!        \   /
//!   z=0 --\-/--------------  top: contact candidates
//!        |                |  4 x 4 mm cylinder, 6 x 6 Q8 graded 1.45
//!  axis  |                |
//!        +----------------+  bottom: u_z = 0
//! ```
//! Parameters: E = 20000 MPa, nu = 0.3 (fixed), eta = 30000 MPa s.

mod common;

use common::maxwell_specs as specs;
use indentify_contact::{DirectSolver, Model, Schedule, Segment, SolverOptions};
use indentify_identify::{
    Evaluator, ForceRecord, IdentifyConfig, IdentifyError, Method, Prefetch, Problem, Test,
    identify,
};
use indentify_laws::Maxwell;
use indentify_testkit::{cone68, cylinder};

const TRUTH: [f64; 3] = [20000.0, 0.3, 30000.0];

fn model() -> Model {
    Model::new(cylinder(4.0, 6, 1.45), cone68()).unwrap()
}

fn schedule(load_time: f64, depth: f64) -> Schedule {
    Schedule::from_segments(&[
        Segment {
            duration: load_time,
            depth,
            steps: 5,
        },
        Segment {
            duration: 1.0,
            depth,
            steps: 4,
        },
    ])
    .unwrap()
}

fn schedules() -> [Schedule; 2] {
    [schedule(0.2, 0.1), schedule(2.0, 0.05)]
}

/// The exact record of the truth on `s`.
fn record(s: &Schedule) -> ForceRecord {
    let m = model();
    let f = DirectSolver::new(&m)
        .unwrap()
        .run(
            &indentify_laws::LawMaterial(&Maxwell),
            &TRUTH,
            s,
            &SolverOptions::default(),
        )
        .unwrap()
        .forces();
    ForceRecord::new(s.t.clone(), f).unwrap()
}

/// The joint problem of both tests with their default weights, and those weights.
fn joint() -> (Problem, Vec<f64>) {
    let mut tests = Vec::new();
    let mut weights = Vec::new();
    for s in schedules() {
        let r = record(&s);
        let w = Test::default_weight(&s, &r).unwrap();
        weights.push(w);
        tests.push(Test::new(model(), s, &r, None, SolverOptions::default(), w).unwrap());
    }
    (Problem::joint(&Maxwell, tests).unwrap(), weights)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

/// The joint cost, gradient, forces and Jacobian shall be the weighted sum (and the
/// stacking) of the separate tests' ones, and the default weight shall be 1/(n F_max^2).
#[test]
fn joint_problem_is_the_weighted_sum_of_its_tests() {
    let (p, w) = joint();
    let c = [15000.0, 0.3, 45000.0];
    let mut ev = Evaluator::new(&p).unwrap();
    let (j, g) = ev.cost_and_gradient(&c).unwrap();
    let f = ev.forces(&c).unwrap();
    let jac = ev.jacobian(&c).unwrap();
    assert_eq!(f.len(), p.target.len());
    assert_eq!(jac.len(), p.target.len());
    let counts = ev.counts();
    assert_eq!(
        (counts.forward, counts.adjoint, counts.sensitivities),
        (2, 2, 2)
    );
    let mut j_sum = 0.0;
    let mut g_sum = [0.0; 3];
    for (k, s) in schedules().into_iter().enumerate() {
        let r = record(&s);
        // the default weight from its definition
        let n = s.t.len() as f64;
        let f_max = r.force.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(rel(w[k], 1.0 / (n * f_max * f_max)) < 1e-12);
        let single =
            Problem::new(model(), &Maxwell, s, &r, None, SolverOptions::default()).unwrap();
        let mut e1 = Evaluator::new(&single).unwrap();
        let (jk, gk) = e1.cost_and_gradient(&c).unwrap();
        j_sum += w[k] * jk;
        for i in 0..3 {
            g_sum[i] += w[k] * gk[i];
        }
        let rows = p.rows_of(k);
        assert_eq!(&f[rows.clone()], e1.forces(&c).unwrap().as_slice());
        assert_eq!(&jac[rows], e1.jacobian(&c).unwrap().as_slice());
    }
    assert!(rel(j, j_sum) < 1e-12, "J = {j} vs {j_sum}");
    for i in [0, 2] {
        assert!(
            rel(g[i], g_sum[i]) < 1e-10,
            "g[{i}] = {} vs {}",
            g[i],
            g_sum[i]
        );
    }
}

/// The joint gradient shall match central finite differences of the joint cost over the
/// whole histories (relative step 1e-6; agreement 1e-5).
#[test]
fn joint_gradient_matches_finite_differences() {
    let (p, _) = joint();
    let c = [15000.0, 0.3, 45000.0];
    let mut ev = Evaluator::new(&p).unwrap();
    let (_, g) = ev.cost_and_gradient(&c).unwrap();
    for i in [0, 2] {
        let h = 1e-6 * c[i];
        let mut cp = c;
        let mut cm = c;
        cp[i] += h;
        cm[i] -= h;
        let fd = (ev.cost(&cp).unwrap() - ev.cost(&cm).unwrap()) / (2.0 * h);
        println!("dJ/dc[{i}]: adjoint {:.10e}, fd {fd:.10e}", g[i]);
        assert!(rel(g[i], fd) < 1e-5, "dJ/dc[{i}] = {} vs fd {fd}", g[i]);
    }
}

/// Three tests on two threads (the case the task scheduler exists for: a follow-up fills
/// the core the third forward leaves idle) shall give, with and without prefetching and
/// on 1, 2 and 3 threads, the same bits of every cost, gradient, force and Jacobian entry
/// along a line-search-like sequence of requests (cost, then gradient or Jacobian at the
/// accepted point), and the same counts of requested work; whatever was prefetched was
/// computed on an idle core only, at most once per test and point. A gradient computed
/// before the Jacobian at a point (what a prefetch does at random) changes no bit of it.
#[test]
fn scheduling_and_prefetch_never_change_a_bit() {
    let mut tests = Vec::new();
    for s in [schedule(0.2, 0.1), schedule(2.0, 0.05), schedule(0.5, 0.08)] {
        let r = record(&s);
        let w = Test::default_weight(&s, &r).unwrap();
        tests.push(Test::new(model(), s, &r, None, SolverOptions::default(), w).unwrap());
    }
    let p = Problem::joint(&Maxwell, tests).unwrap();
    let points: Vec<[f64; 3]> = (0..6)
        .map(|i| {
            [
                15000.0 + 1000.0 * i as f64,
                0.3,
                45000.0 - 2000.0 * i as f64,
            ]
        })
        .collect();
    let run_with = |threads: usize, prefetch: Prefetch, gradient_first: bool| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut ev = Evaluator::new(&p).unwrap();
            ev.set_prefetch(prefetch);
            let mut bits: Vec<u64> = Vec::new();
            for (i, c) in points.iter().enumerate() {
                bits.push(ev.cost(c).unwrap().to_bits());
                if i % 2 == 0 {
                    let (j, g) = ev.cost_and_gradient(c).unwrap();
                    bits.push(j.to_bits());
                    bits.extend(g.iter().map(|v| v.to_bits()));
                } else {
                    if gradient_first {
                        ev.cost_and_gradient(c).unwrap();
                    }
                    bits.extend(ev.forces(c).unwrap().iter().map(|v| v.to_bits()));
                    for row in ev.jacobian(c).unwrap() {
                        bits.extend(row.iter().map(|v| v.to_bits()));
                    }
                }
            }
            // a gradient and a Jacobian at a new point asked for at once (no cost first)
            let c = [21000.0, 0.3, 28000.0];
            let (j, g) = ev.cost_and_gradient(&c).unwrap();
            bits.push(j.to_bits());
            bits.extend(g.iter().map(|v| v.to_bits()));
            for row in ev.jacobian(&c).unwrap() {
                bits.extend(row.iter().map(|v| v.to_bits()));
            }
            (bits, ev.counts())
        })
    };
    let run = |threads: usize, prefetch: Prefetch| run_with(threads, prefetch, false);
    let (reference, counts) = run(1, Prefetch::None);
    // what a prefetch may do, deterministically: a gradient before the Jacobian at a point
    // (the adjoint workspace starts every computation afresh)
    assert_eq!(
        run_with(1, Prefetch::None, true).0,
        reference,
        "a gradient before the Jacobian changed it"
    );
    assert_eq!(
        (
            counts.forward,
            counts.adjoint,
            counts.sensitivities,
            counts.prefetched
        ),
        (21, 12, 12, 0)
    );
    for threads in [1, 2, 3] {
        for prefetch in [Prefetch::None, Prefetch::Gradient, Prefetch::Jacobian] {
            let (bits, n) = run(threads, prefetch);
            println!("{threads} threads, {prefetch:?}: {n:?}");
            assert_eq!(bits, reference, "{threads} threads, {prefetch:?}");
            assert_eq!(
                (n.forward, n.adjoint, n.sensitivities, n.cache_hits),
                (
                    counts.forward,
                    counts.adjoint,
                    counts.sensitivities,
                    counts.cache_hits
                ),
                "{threads} threads, {prefetch:?}"
            );
            // one thread has no idle core; a prefetch only after a cost request
            if threads == 1 || prefetch == Prefetch::None {
                assert_eq!(n.prefetched, 0);
            }
            assert!(n.prefetched <= 3 * points.len());
        }
    }
}

/// Levenberg-Marquardt and BFGS on the joint problem shall recover (E, eta) within 1e-4
/// and give bit-identical runs on 1 and 2 threads (tests combined in test order).
#[test]
fn joint_fit_recovers_truth_bit_identically_on_1_and_2_threads() {
    let (p, _) = joint();
    for method in [Method::LevenbergMarquardt, Method::Bfgs] {
        let mut cfg = IdentifyConfig::new(specs(8000.0, 90000.0));
        cfg.method = method;
        cfg.stop.max_iterations = 40;
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| identify(&p, &cfg, &mut |_| {}).unwrap())
        };
        let r1 = run(1);
        let r2 = run(2);
        println!(
            "{method:?}: {:?} after {} it, J = {:.3e}, {}",
            r1.c, r1.iterations, r1.cost, r1.stop_reason
        );
        assert!(r1.stop_reason.is_converged(), "{}", r1.stop_reason);
        assert!(rel(r1.c[0], TRUTH[0]) < 1e-4, "E = {}", r1.c[0]);
        assert!(rel(r1.c[2], TRUTH[2]) < 1e-4, "eta = {}", r1.c[2]);
        let bits = |r: &indentify_identify::IdentifyResult| {
            let mut b: Vec<u64> = r.c.iter().map(|v| v.to_bits()).collect();
            b.push(r.cost.to_bits());
            for h in &r.history {
                b.push(h.cost.to_bits());
                b.push(h.grad_norm.to_bits());
                b.extend(h.params.iter().map(|v| v.to_bits()));
            }
            b.extend(r.forces.iter().map(|v| v.to_bits()));
            if let Some(id) = &r.identifiability {
                b.extend(id.std_dev.iter().map(|v| v.to_bits()));
            }
            b
        };
        assert_eq!(r1.iterations, r2.iterations);
        assert_eq!(bits(&r1), bits(&r2), "{method:?}: 1 and 2 threads differ");
    }
}

/// BFGS started from the damped Gauss-Newton inverse Hessian (`BfgsStart::GaussNewton`)
/// shall recover (E, eta) within 1e-6 from a far start in fewer iterations than the
/// paper's `kappa I` start, and spend sensitivity solves only for its start and restarts
/// (the paper's BFGS spends none before its final summary): every iteration whose line
/// search shortened the quasi-Newton step (more than one trial point) restarts from the
/// Gauss-Newton matrix (one sensitivity solve per test). Bit-identical on 1 and 2 threads.
#[test]
fn bfgs_from_the_gauss_newton_matrix_needs_fewer_iterations() {
    use indentify_identify::BfgsStart;
    let (p, _) = joint();
    let n_tests = p.tests.len();
    let run = |start: BfgsStart, threads: usize| {
        let mut cfg = IdentifyConfig::new(specs(4000.0, 300000.0));
        cfg.method = Method::Bfgs;
        cfg.bfgs_start = start;
        cfg.identifiability = false;
        cfg.stop.max_iterations = 60;
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| identify(&p, &cfg, &mut |_| {}).unwrap())
    };
    let paper = run(BfgsStart::Scaled, 2);
    let gn = run(BfgsStart::GaussNewton, 2);
    println!(
        "scaled: {} it ({}), {:?}; Gauss-Newton: {} it ({}), {:?}, {} sensitivity solves",
        paper.iterations,
        paper.stop_reason,
        paper.c,
        gn.iterations,
        gn.stop_reason,
        gn.c,
        gn.sensitivity_solves
    );
    assert_eq!(paper.sensitivity_solves, 0);
    assert!(gn.stop_reason.is_converged(), "{}", gn.stop_reason);
    assert!(rel(gn.c[0], TRUTH[0]) < 1e-6, "E = {}", gn.c[0]);
    assert!(rel(gn.c[2], TRUTH[2]) < 1e-6, "eta = {}", gn.c[2]);
    assert!(gn.sensitivity_solves >= 1);
    // each trial point is one forward solve per test; an iteration with several was
    // shortened and must restart from the Gauss-Newton matrix of its end point
    let mut shortened = 0;
    for w in gn.history.windows(2) {
        let trials = (w[1].forward_solves - w[0].forward_solves) / n_tests;
        let restarts = (w[1].sensitivity_solves - w[0].sensitivity_solves) / n_tests;
        println!(
            "iteration {}: {trials} trial points, {restarts} Gauss-Newton restarts",
            w[1].iteration
        );
        if trials > 1 {
            shortened += 1;
            assert_eq!(restarts, 1, "iteration {}", w[1].iteration);
        }
    }
    assert!(
        shortened > 0,
        "no line search was shortened: the restart is not exercised"
    );
    assert!(
        gn.iterations < paper.iterations,
        "Gauss-Newton start {} iterations, paper's {}",
        gn.iterations,
        paper.iterations
    );
    let one = run(BfgsStart::GaussNewton, 1);
    assert_eq!(one.c, gn.c);
    assert_eq!(one.iterations, gn.iterations);
}

/// Bad input shall be refused with the field named: an empty list of tests, a test weight
/// that is not finite and > 0.
#[test]
fn bad_joint_input_is_refused() {
    let e = Problem::joint(&Maxwell, vec![]).unwrap_err();
    assert!(
        matches!(&e, IdentifyError::InvalidSpec { name, .. } if name == "tests"),
        "{e}"
    );
    assert!(e.to_string().contains("empty"), "{e}");
    let s = schedule(0.2, 0.1);
    let r = record(&s);
    for w in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = Test::new(model(), s.clone(), &r, None, SolverOptions::default(), w).unwrap_err();
        assert!(matches!(e, IdentifyError::InvalidWeights { .. }), "{e}");
        assert!(e.to_string().contains("> 0"), "{e}");
    }
    // a record that does not cover the history
    let short = ForceRecord::new(vec![0.0, 0.5], vec![0.0, 1.0]).unwrap();
    let e = Test::new(model(), s, &short, None, SolverOptions::default(), 1.0).unwrap_err();
    assert!(matches!(e, IdentifyError::RecordDoesNotCover { .. }), "{e}");
}
