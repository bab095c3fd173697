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

use indentify_contact::{DirectSolver, HistorySegment, LoadHistory, Model, Punch, SolverOptions};
use indentify_identify::{
    Evaluator, ForceRecord, IdentifyConfig, Method, ParamSpec, Problem, Test, identify,
};
use indentify_laws::{Material, Prony};
use indentify_mesh::CylinderMesher;

const TRUTH: [f64; 4] = [20000.0, 0.3, 0.4, 0.5];

fn model() -> Model {
    let mesh = CylinderMesher {
        radius: 4.0,
        height: 4.0,
        nr: 8,
        nz: 8,
        grading_r: 1.45,
        grading_z: 1.45,
    }
    .build()
    .unwrap();
    Model::new(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
    )
    .unwrap()
}

fn force(duration: f64, force: f64, steps: usize) -> HistorySegment {
    HistorySegment {
        duration,
        depth: None,
        force: Some(force),
        steps,
    }
}

fn history() -> LoadHistory {
    LoadHistory::from_segments(&[
        force(1.0, 60.0, 6),
        force(1.0, 60.0, 6),
        force(1.0, 24.0, 6),
    ])
    .unwrap()
}

fn opts() -> SolverOptions {
    SolverOptions {
        residual_tol: 1e-11,
        ..SolverOptions::default()
    }
}

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
    let d: Vec<f64> = std::iter::once(0.0)
        .chain(traj.schedule_steps().map(|s| s.depth))
        .collect();
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
        let dc = 1e-5 * c[k];
        let mut cp = c;
        cp[k] += dc;
        let mut cm = c;
        cm[k] -= dc;
        let fd = (ev.cost(&cp).unwrap() - ev.cost(&cm).unwrap()) / (2.0 * dc);
        let jt_r: f64 = jac
            .iter()
            .zip(&h_sim)
            .zip(p.target.iter().zip(&p.weights))
            .map(|((row, h), (tg, w))| w * (h - tg) * row[k])
            .sum();
        println!(
            "dJ/dc{k}: adjoint {:.10e}, FD {fd:.10e}, J^T r {jt_r:.10e}",
            g[k]
        );
        assert!(rel(g[k], fd) < 1e-6, "adjoint {} vs FD {fd}", g[k]);
        assert!(rel(jt_r, g[k]) < 1e-8, "J^T r {jt_r} vs adjoint {}", g[k]);
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
