//! Schedules whose steps are solved in sub-steps (`Schedule::with_substeps`, what
//! `data.substeps` of a measured record sets): the forward solve equals the run over a
//! schedule with the sub-steps' times inserted as points, the cost sees the schedule's
//! points only, and the adjoint (which transposes the sub-steps as it transposes the
//! sub-steps of a cut step) stays exact: against central differences of the direct
//! solver's own cost, against `J^T rho`, and replayed from checkpoints.
//!
//! Model: finite strain, frictionless normal contact (what measured data default to),
//! Norton-Hoff with yield, cone and sphere; 4 x 4 mm cylinder, 8 x 8 Q8 graded 1.45;
//! trapezoid 0 -> 0.1 mm -> hold -> 0 in 4 steps per segment, sub-steps 1 to 3 per step.

mod common;

use indentify_contact::{DirectSolver, Punch, Schedule, SolverOptions, trapezoid};
use indentify_laws::NortonHoff;

/// The trapezoid's 12 steps with uneven sub-steps (more in the loading, none in places).
fn schedule() -> Schedule {
    Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 4))
        .unwrap()
        .with_substeps(vec![3, 2, 2, 1, 2, 1, 1, 3, 1, 2, 2, 1])
        .unwrap()
}

/// The schedule with every sub-step's end inserted as a point (no sub-steps), and where
/// the original points are in it.
fn inserted(s: &Schedule) -> (Schedule, Vec<usize>) {
    let (mut t, mut d, mut at) = (vec![s.t[0]], vec![s.depth[0]], vec![0]);
    for j in 1..=s.n_steps() {
        for tk in s.step_targets(j) {
            t.push(tk);
            d.push(s.depth_at(tk));
        }
        at.push(t.len() - 1);
    }
    (Schedule::from_record(&t, &d).unwrap(), at)
}

fn opts() -> SolverOptions {
    SolverOptions {
        residual_tol: 1e-12,
        ..Default::default()
    }
}

/// Sub-steps are the inserted points' run: the same forces at the schedule's points
/// (1e-9), as many recorded steps, the schedule's points marked on them.
#[test]
fn substeps_solve_the_schedule_with_the_points_inserted() {
    let law = NortonHoff;
    let c = [1e5, 0.3, 1500.0, 5.0, 500.0];
    for punch in [
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        Punch::Sphere { radius: 1.0 },
    ] {
        let m = common::finite_model(punch);
        let s = schedule();
        let (fine, at) = inserted(&s);
        let mut solver = DirectSolver::new(&m).unwrap();
        let traj = solver
            .run(&indentify_laws::LawMaterial(&law), &c, &s, &opts())
            .unwrap();
        let reference = solver
            .run(&indentify_laws::LawMaterial(&law), &c, &fine, &opts())
            .unwrap();
        // one recorded step per sub-step (and per cut, the same in both runs)
        assert!(traj.steps.len() >= s.n_solver_steps());
        assert_eq!(traj.steps.len(), reference.steps.len());
        assert_eq!(s.n_solver_steps(), fine.n_steps());
        assert_eq!(traj.schedule_steps().count(), s.n_steps());
        let (f, f_ref) = (traj.forces(), reference.forces());
        assert_eq!(f.len(), s.t.len());
        let f_max = f.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        for (j, &i) in at.iter().enumerate() {
            assert!(
                (f[j] - f_ref[i]).abs() <= 1e-9 * f_max,
                "point {j}: {} vs {} with the points inserted",
                f[j],
                f_ref[i]
            );
        }
        // and they are not the forces without sub-steps (the test can tell)
        let plain = Schedule {
            substeps: Vec::new(),
            ..s.clone()
        };
        let f_plain = solver
            .run(&indentify_laws::LawMaterial(&law), &c, &plain, &opts())
            .unwrap()
            .forces();
        let moved = f
            .iter()
            .zip(&f_plain)
            .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        assert!(moved > 1e-4 * f_max, "sub-steps changed nothing: {moved}");
    }
}

/// The adjoint through sub-steps: vs central differences of the cost at the schedule's
/// points (1e-6), vs `J^T rho` (1e-10), recorded vs replayed from checkpoints (1e-10)
/// (`common::whole_history_check_on`).
#[test]
fn the_adjoint_through_substeps_matches_finite_differences() {
    let law = NortonHoff;
    let truth = [1e5, 0.3, 1500.0, 5.0, 500.0];
    let c = [1.2e5, 0.31, 1300.0, 4.0, 420.0];
    for punch in [
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        Punch::Sphere { radius: 1.0 },
    ] {
        let m = common::finite_model(punch);
        let (fd, sens) =
            common::whole_history_check_on(&m, &law, &truth, &c, 5, &schedule(), 1e-10);
        println!("worst relative differences: fd {fd:.1e}, sensitivities {sens:.1e}");
    }
}
