//! Adjoint gradients and forward sensitivities under finite strain
//! (`Kinematics::Finite`: total-Lagrangian Q8, laws in Hencky strain, normal contact)
//! against central finite differences, over whole load-hold-unload histories with the
//! contact zone growing and shrinking, for elastic, Maxwell and Norton-Hoff (sY = 0 and
//! > 0), cone and sphere.
//!
//! References: central differences of the direct solver's own whole-history cost
//! (independent of the adjoint code), and the forward-sensitivity Jacobian `J^T rho` (the
//! same step operators, not transposed). Mesh: 4 x 4 mm cylinder, 8 x 8 Q8 graded 1.45
//! towards axis and top; trapezoid 0 -> 0.1 mm -> hold -> 0, 6 steps per segment: strains
//! under the tip of order 0.3, where finite and small strain differ by 5-40%.

mod common;

use indentify_adjoint::Adjoint;
use indentify_contact::{DirectSolver, Punch, Schedule, SolverOptions, trapezoid};
use indentify_laws::{Elastic, Law, Maxwell, NortonHoff};
use indentify_testkit::{cone68 as cone, sphere1 as sphere};

/// Adjoint vs central differences (1e-6), vs `J^T rho` (1e-10), and the checkpointed
/// adjoint vs the recorded one (1e-10) (`common::whole_history_check`, 6 steps per
/// segment). Returns the worst relative differences (fd, sensitivities).
fn check_gradient(
    punch: Punch,
    law: &dyn Law,
    truth: &[f64],
    c: &[f64],
    checked: usize,
) -> (f64, f64) {
    common::whole_history_check(
        &common::finite_model(punch),
        law,
        truth,
        c,
        checked,
        6,
        1e-10,
    )
}

/// The finite-strain adjoint shall differentiate an elastic cost (cone and sphere).
#[test]
fn elastic_cone_and_sphere() {
    for punch in [cone(), sphere()] {
        check_gradient(punch, &Elastic, &[20000.0, 0.3], &[17000.0, 0.27], 2);
    }
}

/// The finite-strain adjoint shall differentiate a Maxwell cost (cone and sphere).
#[test]
fn maxwell_cone_and_sphere() {
    for punch in [cone(), sphere()] {
        check_gradient(
            punch,
            &Maxwell,
            &[20000.0, 0.3, 30000.0],
            &[15000.0, 0.28, 45000.0],
            3,
        );
    }
}

/// The finite-strain adjoint shall differentiate a Norton-Hoff cost with yield (sY > 0),
/// cone and sphere.
#[test]
fn norton_hoff_with_yield_cone_and_sphere() {
    for punch in [cone(), sphere()] {
        check_gradient(
            punch,
            &NortonHoff,
            &[1e5, 0.3, 1500.0, 5.0, 500.0],
            &[1.2e5, 0.31, 1300.0, 4.0, 420.0],
            5,
        );
    }
}

/// The finite-strain adjoint shall differentiate a Norton-Hoff cost without yield
/// (sY = 0), cone and sphere.
#[test]
fn norton_hoff_without_yield_cone_and_sphere() {
    for punch in [cone(), sphere()] {
        check_gradient(
            punch,
            &NortonHoff,
            &[1e5, 0.3, 1500.0, 5.0, 0.0],
            &[1.2e5, 0.31, 1300.0, 4.0, 0.0],
            4,
        );
    }
}

/// Stress scaling under finite strain: multiplying every stress-like parameter (E and eta
/// for Maxwell; E, K and sY for Norton-Hoff) by a factor multiplies `T`, hence
/// `S = P(C) T` and every force, by it at fixed displacements and active sets, so the
/// sensitivities shall satisfy `sum_k c_k dF_i/dc_k = F_i` at every step to round-off.
#[test]
fn stress_scaling_identity_under_finite_strain() {
    let cases: [(&dyn Law, Vec<f64>, Vec<usize>); 2] = [
        (&Maxwell, vec![20000.0, 0.3, 30000.0], vec![0, 2]),
        (
            &NortonHoff,
            vec![1e5, 0.3, 1500.0, 5.0, 500.0],
            vec![0, 2, 4],
        ),
    ];
    for punch in [cone(), sphere()] {
        let model = common::finite_model(punch);
        let sched = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 6)).unwrap();
        let opts = SolverOptions {
            residual_tol: 1e-12,
            ..Default::default()
        };
        for (law, c, stress_like) in &cases {
            let traj = DirectSolver::new(&model)
                .unwrap()
                .run(&indentify_laws::LawMaterial(*law), c, &sched, &opts)
                .unwrap();
            let sens = Adjoint::new(&model)
                .unwrap()
                .sensitivities(&indentify_laws::LawMaterial(*law), c, &traj)
                .unwrap();
            let fmax = traj.steps.iter().map(|s| s.force.abs()).fold(0.0, f64::max);
            let mut worst: f64 = 0.0;
            for (rec, row) in traj.steps.iter().zip(&sens.df_dc) {
                let lhs: f64 = stress_like.iter().map(|&k| c[k] * row[k]).sum();
                worst = worst.max((lhs - rec.force).abs() / fmax);
            }
            println!(
                "{}: max |sum c_k dF/dc_k - F| / F_max = {worst:.2e}",
                law.name()
            );
            assert!(worst < 1e-9, "{}: {worst}", law.name());
        }
    }
}
