//! Newton warm started from an earlier converged trajectory (`DirectSolver::run_warm`):
//! the same solution as a cold run to the solver's tolerance, and the Newton iterations
//! it saves near the guess's parameters (R2 of docs/theory.md §11: Norton-Hoff, cone,
//! reference mesh, trapezoid 0.1 mm).
use indentify_contact::{
    DirectSolver, Model, Punch, Schedule, SolverOptions, Trajectory, trapezoid,
};
use indentify_laws::{LawMaterial, NortonHoff};
use indentify_mesh::CylinderMesher;

fn r2_model() -> Model {
    let mesh = CylinderMesher::REFERENCE.build().expect("reference mesh");
    Model::new(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
    )
    .expect("model")
}

fn max_force_gap(a: &Trajectory, b: &Trajectory) -> f64 {
    let (fa, fb) = (a.forces(), b.forces());
    assert_eq!(fa.len(), fb.len());
    fa.iter()
        .zip(&fb)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn warm_started_forward_equals_the_cold_one_to_the_solver_tolerance() {
    let model = r2_model();
    let sched = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).expect("schedule");
    let opts = SolverOptions::default();
    let mat = LawMaterial(&NortonHoff);
    let c0 = [1e5, 0.3, 1500.0, 5.0, 500.0];
    let mut solver = DirectSolver::new(&model).expect("solver");
    let guess = solver.run(&mat, &c0, &sched, &opts).expect("guess run");
    // the guess at its own parameters: the converged increments, one solve per step
    let again = solver
        .run_warm(&mat, &c0, &sched, &opts, &guess)
        .expect("warm run at the guess");
    let fmax = guess.forces().iter().copied().fold(0.0, f64::max);
    assert!(max_force_gap(&again, &guess) <= 1e-9 * fmax);
    eprintln!(
        "at the guess: cold {} Newton iterations, warm {}",
        guess.total_iterations(),
        again.total_iterations()
    );
    assert!(again.total_iterations() < guess.total_iterations());
    for rel in [1e-3, 1e-2, 1e-1] {
        let c: Vec<f64> = c0
            .iter()
            .enumerate()
            .map(|(k, v)| if k == 1 { *v } else { v * (1.0 + rel) })
            .collect();
        let cold = solver.run(&mat, &c, &sched, &opts).expect("cold run");
        let warm = solver
            .run_warm(&mat, &c, &sched, &opts, &guess)
            .expect("warm run");
        let gap = max_force_gap(&warm, &cold);
        eprintln!(
            "parameters +{rel:e}: cold {} Newton iterations, {} factorizations, {} CG; \
             warm {}, {}, {}; max |F_warm - F_cold| / F_max = {:.2e}",
            cold.total_iterations(),
            cold.timing.factorizations,
            cold.timing.cg_iterations,
            warm.total_iterations(),
            warm.timing.factorizations,
            warm.timing.cg_iterations,
            gap / fmax
        );
        // (the cold run may cut a step the warm one does not: the forces are compared at
        // the schedule's times)
        assert!(gap <= 1e-9 * fmax, "warm and cold differ by {gap} N");
        // near the guess (measured: 272 -> 162 at +1e-3, 194 at +1e-2, 234 at +1e-1)
        assert!(warm.total_iterations() < cold.total_iterations());
        // the converged displacements agree to the tolerance too
        let last = |t: &Trajectory| t.fields.last().map(|f| f.u.clone()).unwrap_or_default();
        let (uw, uc) = (last(&warm), last(&cold));
        let umax = uc.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let du = uw
            .iter()
            .zip(&uc)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        // a step the cold run cut is a different time discretization of that stretch
        // (+1e-1: 92 steps against 91; measured 8e-7 relative at the end)
        let tol = if warm.steps.len() == cold.steps.len() {
            1e-7
        } else {
            1e-5
        };
        eprintln!("  end displacements: {:.2e} relative", du / umax);
        assert!(du <= tol * umax, "displacements differ by {du} mm");
    }
}

#[test]
fn a_guess_that_cannot_be_used_runs_cold_bit_for_bit() {
    let model = r2_model();
    let sched = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 10)).expect("schedule");
    let mat = LawMaterial(&NortonHoff);
    let c = [1e5, 0.3, 1500.0, 5.0, 500.0];
    let mut solver = DirectSolver::new(&model).expect("solver");
    let opts = SolverOptions::default();
    let cold = solver.run(&mat, &c, &sched, &opts).expect("cold run");
    // a guess without fields, and a run with checkpoints (a replay must repeat it)
    let bare = Trajectory {
        steps: cold.steps.clone(),
        ..Default::default()
    };
    let warm = solver
        .run_warm(&mat, &c, &sched, &opts, &bare)
        .expect("run");
    assert_eq!(warm.forces(), cold.forces());
    let ck = SolverOptions {
        record_fields: false,
        checkpoint_every: 5,
        ..SolverOptions::default()
    };
    let a = solver.run(&mat, &c, &sched, &ck).expect("run");
    let b = solver.run_warm(&mat, &c, &sched, &ck, &cold).expect("run");
    assert_eq!(a.forces(), b.forces());
}
