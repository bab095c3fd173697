//! Identification under load control (docs/theory.md §13): a [`Test::new_load`] prescribes
//! the force history and fits the measured depth, `J = 1/2 sum w (h_i - h_exp,i)^2`, with
//! the bordered adjoint's gradient (BFGS) and the bordered sensitivities' Jacobian (LM).
//!
//! References: the truth that generated the data. Exact data: the identified Maxwell
//! (E, eta) equal it to 1e-6 relative. Noisy data (uniform depth noise of known sigma,
//! seeded): the identified values lie within 2 standard deviations (the identifiability's
//! linearized covariance) of the truth. The adjoint gradient of the depth cost matches
//! central differences of the same cost through the `Evaluator`.
//!
//! ```text
//!      cone 68 deg, force 0 -> 60 N (1 s) -> hold (1 s) -> 24 N (1 s), 6 steps/segment
//!      4 x 4 mm cylinder, 8 x 8 Q8 graded 1.45; Maxwell E = 20000 MPa, nu = 0.3 (fixed),
//!      eta = 30000 MPa s
//! ```

mod common;

use common::{
    assert_gradient_entry, cost_difference, jt_r, load_hold_unload as history,
    maxwell_specs as specs, schedule_depths, tight_opts as opts,
};
use indentify_contact::DirectSolver;
use indentify_identify::{
    Evaluator, ForceRecord, IdentifyConfig, Method, Problem, SplitMix64, Test, identify,
};
use indentify_laws::{LawMaterial, Maxwell};
use indentify_testkit::cone_model as model;

const TRUTH: [f64; 3] = [20000.0, 0.3, 30000.0];

/// The truth's depths at the history's times (index 0: the initial state, 0).
fn exact_depths() -> (Vec<f64>, Vec<f64>) {
    let m = model();
    let h = history();
    let traj = DirectSolver::new(&m)
        .unwrap()
        .run_history(&LawMaterial(&Maxwell), &TRUTH, &h, &opts())
        .unwrap();
    let d = schedule_depths(&traj);
    (h.schedule.t.clone(), d)
}

fn problem(t: Vec<f64>, depths: Vec<f64>) -> Problem {
    let record = ForceRecord::new(t, depths).unwrap();
    let test = Test::new_load(model(), history(), &record, None, opts(), 1.0).unwrap();
    Problem::joint(&Maxwell, vec![test]).unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The depth cost's adjoint gradient through the `Evaluator` shall match central
/// differences of the `Evaluator`'s own cost, and its Jacobian (bordered sensitivities)
/// shall give the same gradient as `J^T r`.
#[test]
fn load_controlled_gradient_and_jacobian_match_differences() {
    let (t, d) = exact_depths();
    let p = problem(t, d);
    let mut ev = Evaluator::new(&p).unwrap();
    let c = [15000.0, 0.3, 45000.0];
    let (j0, g) = ev.cost_and_gradient(&c).unwrap();
    assert!(j0 > 0.0);
    let h_sim = ev.forces(&c).unwrap();
    let jac = ev.jacobian(&c).unwrap();
    for k in [0usize, 2] {
        let fd = cost_difference(&mut ev, &c, k, 1e-5 * c[k]);
        let jt = jt_r(&p, &jac, &h_sim, k);
        assert_gradient_entry("", &format!("c{k}"), g[k], fd, jt, rel);
    }
}

/// Exact load-controlled data: BFGS (adjoint) and LM (sensitivities) shall both recover
/// (E, eta) to 1e-6 relative.
#[test]
fn identify_exact_load_controlled_data() {
    let (t, d) = exact_depths();
    let p = problem(t, d);
    for method in [Method::Bfgs, Method::LevenbergMarquardt] {
        let mut cfg = IdentifyConfig::new(specs(12000.0, 60000.0));
        cfg.method = method;
        let r = identify(&p, &cfg, &mut |_| {}).unwrap();
        println!(
            "{method:?}: {:?} after {} it, J = {:.3e} (from {:.3e}), {}",
            r.c, r.iterations, r.cost, r.initial_cost, r.stop_reason
        );
        assert!(r.stop_reason.is_converged(), "{}", r.stop_reason);
        assert!(rel(r.c[0], TRUTH[0]) < 1e-6, "E = {}", r.c[0]);
        assert!(rel(r.c[2], TRUTH[2]) < 1e-6, "eta = {}", r.c[2]);
    }
}

/// Round trip: the truth's depths with seeded uniform noise (half-width 0.2 um, sigma =
/// 0.2/sqrt(3) um) fitted by LM; each identified parameter lies within 2 of the
/// identifiability's standard deviations of the truth, and the residual sigma estimate is
/// within a factor 2 of the noise's.
#[test]
fn round_trip_noisy_load_controlled_fit_within_two_sigma() {
    let (t, d) = exact_depths();
    let a = 2e-4; // mm
    let mut rng = SplitMix64::new(7);
    let noisy: Vec<f64> = d
        .iter()
        .enumerate()
        .map(|(i, h)| {
            if i == 0 {
                0.0
            } else {
                h + a * rng.next_symmetric()
            }
        })
        .collect();
    let p = problem(t, noisy);
    let mut cfg = IdentifyConfig::new(specs(12000.0, 60000.0));
    cfg.method = Method::LevenbergMarquardt;
    let r = identify(&p, &cfg, &mut |_| {}).unwrap();
    let id = r.identifiability.as_ref().unwrap();
    println!(
        "noisy fit: {:?}, {}, std dev {:?}, sigma_hat {:.3e} mm (noise sigma {:.3e})",
        r.c,
        r.stop_reason,
        id.std_dev,
        id.sigma2.sqrt(),
        a / 3f64.sqrt()
    );
    assert!(r.stop_reason.is_converged(), "{}", r.stop_reason);
    for (k, i) in [(0usize, 0usize), (2, 1)] {
        let dev = (r.c[k] - TRUTH[k]).abs();
        assert!(
            dev <= 2.0 * id.std_dev[i],
            "{}: |{} - {}| = {dev} > 2 sigma = {}",
            id.names[i],
            r.c[k],
            TRUTH[k],
            2.0 * id.std_dev[i]
        );
        assert!(dev > 0.0, "noise shall move the estimate");
    }
    let ratio = id.sigma2.sqrt() / (a / 3f64.sqrt());
    assert!((0.5..2.0).contains(&ratio), "sigma_hat / sigma = {ratio}");
}
