//! Adjoint gradients of indentation costs (elastic, Maxwell) against central finite
//! differences and forward sensitivities, contact on, over a load-hold-unload history.
//!
//! Reference: central differences of the direct solver's own cost (independent of the
//! adjoint code), and the forward-sensitivity Jacobian (an independent derivation).
//! Mesh: 4 x 4 mm cylinder, 10 x 10 Q8 graded 1.45 towards axis and top; cone 68 deg;
//! trapezoid 0 -> 0.1 mm -> hold -> 0, 8 steps per segment (contact grows, holds, is lost).

use indentify_adjoint::Adjoint;
use indentify_adjoint::check::{central_difference, relative_difference};
use indentify_contact::{DirectSolver, Model, Punch, Schedule, SolverOptions, trapezoid};
use indentify_laws::{Elastic, Law, Maxwell, NortonHoff};
use indentify_testkit::cylinder;

fn model() -> Model {
    let mesh = cylinder(4.0, 10, 1.45);
    Model::new(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
    )
    .unwrap()
}

/// Checks adjoint vs central differences (1e-6) and vs J^T rho (1e-10) for every parameter.
fn check_gradient(law: &dyn Law, truth: &[f64], c: &[f64], steps: usize) {
    let model = model();
    let sched = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, steps)).unwrap();
    let opts = SolverOptions {
        residual_tol: 1e-12,
        ..Default::default()
    };
    let mut solver = DirectSolver::new(&model).unwrap();
    // data and cost live on the schedule's times; sub-steps of cut steps have rho = 0
    let data: Vec<f64> = solver
        .run(&indentify_laws::LawMaterial(law), truth, &sched, &opts)
        .unwrap()
        .forces();
    let mut cost = |p: &[f64]| -> Result<f64, String> {
        let t = solver
            .run(&indentify_laws::LawMaterial(law), p, &sched, &opts)
            .map_err(|e| e.to_string())?;
        Ok(0.5
            * t.forces()
                .iter()
                .zip(&data)
                .map(|(f, d)| (f - d).powi(2))
                .sum::<f64>())
    };
    let fd: Vec<f64> = (0..c.len())
        .map(|k| central_difference(&mut cost, c, k, 1e-5).unwrap())
        .collect();
    let mut solver = DirectSolver::new(&model).unwrap();
    let traj = solver
        .run(&indentify_laws::LawMaterial(law), c, &sched, &opts)
        .unwrap();
    let rho: Vec<f64> = traj
        .steps
        .iter()
        .map(|s| {
            if s.on_schedule {
                s.force - data[s.schedule_index]
            } else {
                0.0
            }
        })
        .collect();
    let mut adj = Adjoint::new(&model).unwrap();
    let g = adj
        .gradient(&indentify_laws::LawMaterial(law), c, &traj, &rho)
        .unwrap();
    let sens = adj
        .sensitivities(&indentify_laws::LawMaterial(law), c, &traj)
        .unwrap();
    let jt = sens.transpose_mul(&rho);
    for k in 0..c.len() {
        let name = law.params()[k].name;
        println!(
            "{name}: adjoint={:.12e} fd={:.12e} sens={:.12e}",
            g.dj_dc[k], fd[k], jt[k]
        );
        assert!(relative_difference(g.dj_dc[k], fd[k]) < 1e-6, "{name}");
        assert!(relative_difference(g.dj_dc[k], jt[k]) < 1e-10, "{name}");
    }
}

/// The adjoint shall give dJ/dE and dJ/dnu of an elastic indentation cost to 1e-6 of
/// central differences, and equal J^T rho from the forward sensitivities to 1e-10.
#[test]
fn elastic_gradient_matches_finite_differences_and_sensitivities() {
    check_gradient(&Elastic, &[20000.0, 0.3], &[17000.0, 0.27], 8);
}

/// The adjoint shall differentiate a Maxwell (history-dependent) indentation cost in E, nu
/// and eta over load, hold and unload with contact on.
#[test]
fn maxwell_gradient_matches_finite_differences_and_sensitivities() {
    check_gradient(
        &Maxwell,
        &[20000.0, 0.3, 30000.0],
        &[15000.0, 0.28, 45000.0],
        8,
    );
}

/// The adjoint shall differentiate a Norton-Hoff (nonlinear, with yield) indentation cost
/// in all five parameters, with plastic flow during loading and hold.
#[test]
fn norton_hoff_gradient_matches_finite_differences_and_sensitivities() {
    check_gradient(
        &NortonHoff,
        &[1e5, 0.3, 1500.0, 5.0, 500.0],
        &[1.2e5, 0.31, 1300.0, 4.0, 420.0],
        8,
    );
}
