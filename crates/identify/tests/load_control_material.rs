//! A law with internal variables identified under load control (docs/theory.md §12-13):
//! `Problem::joint` takes a Prony solid with a load-controlled test (it was refused), the
//! depth cost's adjoint gradient through the `Evaluator` matches central differences of
//! its own cost and `J^T r` of the bordered sensitivities, and exact data are recovered.
//!
//! References: central differences; the truth that generated the data.
//!
//! ```text
//!      cone 68 deg, force 0 -> 60 N (1 s) -> hold (1 s) -> 24 N (1 s), 6 steps/segment
//!      4 x 4 mm cylinder, 8 x 8 Q8 graded 1.45; Prony E = 20000 MPa, nu = 0.3 (fixed),
//!      one term g1 = 0.4, tau1 = 0.5 s
//! ```

use std::sync::Arc;

mod common;

use common::{
    assert_gradient_entry, cost_difference, jt_r, load_hold_unload as history, schedule_depths,
    tight_opts as opts,
};
use indentify_contact::DirectSolver;
use indentify_identify::{
    Evaluator, ForceRecord, IdentifyConfig, Method, ParamSpec, Problem, Test, identify,
};
use indentify_laws::{Material, Prony};
use indentify_testkit::cone_model as model;

const TRUTH: [f64; 4] = [20000.0, 0.3, 0.4, 0.5];

fn prony() -> Arc<dyn Material> {
    Arc::new(Prony::new(1).unwrap())
}

fn problem() -> Problem {
    let m = model();
    let h = history();
    let traj = DirectSolver::new(&m)
        .unwrap()
        .run_history(&*prony(), &TRUTH, &h, &opts())
        .unwrap();
    let d = schedule_depths(&traj);
    let record = ForceRecord::new(h.schedule.t.clone(), d).unwrap();
    let test = Test::new_load(model(), history(), &record, None, opts(), 1.0).unwrap();
    Problem::joint(prony(), vec![test]).unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn prony_load_controlled_gradient_and_jacobian_match_differences() {
    let p = problem();
    let mut ev = Evaluator::new(&p).unwrap();
    let c = [17000.0, 0.3, 0.3, 0.8];
    let (j0, g) = ev.cost_and_gradient(&c).unwrap();
    assert!(j0 > 0.0);
    let h_sim = ev.forces(&c).unwrap();
    let jac = ev.jacobian(&c).unwrap();
    for k in [0usize, 2, 3] {
        let fd = cost_difference(&mut ev, &c, k, 1e-5 * c[k]);
        let jt = jt_r(&p, &jac, &h_sim, k);
        assert_gradient_entry("", &format!("c{k}"), g[k], fd, jt, rel);
    }
}

/// Exact load-controlled data: LM (bordered sensitivities) and BFGS (bordered adjoint)
/// recover (E, g1, tau1) to 1e-6 relative.
#[test]
fn identify_exact_prony_load_controlled_data() {
    let p = problem();
    for method in [Method::LevenbergMarquardt, Method::Bfgs] {
        let mut cfg = IdentifyConfig::new(vec![
            ParamSpec::free("E", 16000.0, 1000.0, 1e6),
            ParamSpec::fixed("nu", 0.3),
            ParamSpec::free("g1", 0.3, 0.01, 0.9),
            ParamSpec::free("tau1", 0.8, 0.01, 100.0),
        ]);
        cfg.method = method;
        let r = identify(&p, &cfg, &mut |_| {}).unwrap();
        println!(
            "{method:?}: {:?} after {} it, J = {:.3e} (from {:.3e}), {}",
            r.c, r.iterations, r.cost, r.initial_cost, r.stop_reason
        );
        assert!(r.stop_reason.is_converged(), "{}", r.stop_reason);
        for k in [0usize, 2, 3] {
            assert!(rel(r.c[k], TRUTH[k]) < 1e-6, "{k}: {}", r.c[k]);
        }
    }
}
