//! Adjoint gradients and forward sensitivities with normal contact
//! (`ContactKind::Normal`: rotated dofs, curvature stiffness) against central finite
//! differences, over whole load-hold-unload histories with the contact zone growing and
//! shrinking, for elastic, Maxwell and Norton-Hoff (sY = 0 and > 0), cone and sphere.
//!
//! Reference: central differences of the direct solver's own cost (independent of the
//! adjoint code), and the forward-sensitivity Jacobian (an independent derivation).
//! Mesh: 4 x 4 mm cylinder, 10 x 10 Q8 graded 1.45 towards axis and top; trapezoid
//! 0 -> 0.1 mm -> hold -> 0, 8 steps per segment.

use indentify_adjoint::Adjoint;
use indentify_adjoint::check::{central_difference, relative_difference};
use indentify_contact::{
    ContactKind, DirectSolver, Model, Punch, Schedule, SolverOptions, trapezoid,
};
use indentify_laws::{Elastic, Law, Maxwell, NortonHoff};
use indentify_mesh::CylinderMesher;

fn model(punch: Punch) -> Model {
    let mesh = CylinderMesher {
        radius: 4.0,
        height: 4.0,
        nr: 10,
        nz: 10,
        grading_r: 1.45,
        grading_z: 1.45,
    }
    .build()
    .unwrap();
    Model::with_contact(mesh, punch, ContactKind::Normal).unwrap()
}

fn cone() -> Punch {
    Punch::Cone {
        half_angle_deg: 68.0,
    }
}

fn sphere() -> Punch {
    Punch::Sphere { radius: 1.0 }
}

/// Adjoint vs central differences (1e-6), vs J^T rho (1e-8), and the checkpointed
/// adjoint vs the recorded one (1e-10), for the first `checked` parameters (a parameter
/// on its bound, sY = 0, has no central difference).
fn check_gradient(punch: Punch, law: &dyn Law, truth: &[f64], c: &[f64], checked: usize) {
    let model = model(punch);
    let sched = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 8)).unwrap();
    let opts = SolverOptions {
        residual_tol: 1e-12,
        ..Default::default()
    };
    let mut solver = DirectSolver::new(&model).unwrap();
    let data: Vec<f64> = solver
        .run(&model, law, truth, &sched, &opts)
        .unwrap()
        .forces();
    let mut cost = |p: &[f64]| -> Result<f64, String> {
        let t = solver
            .run(&model, law, p, &sched, &opts)
            .map_err(|e| e.to_string())?;
        Ok(0.5
            * t.forces()
                .iter()
                .zip(&data)
                .map(|(f, d)| (f - d).powi(2))
                .sum::<f64>())
    };
    let fd: Vec<f64> = (0..checked)
        .map(|k| central_difference(&mut cost, c, k, 1e-5).unwrap())
        .collect();
    let mut solver = DirectSolver::new(&model).unwrap();
    let traj = solver.run(&model, law, c, &sched, &opts).unwrap();
    // the contact zone grows, holds and is lost
    let sizes: Vec<usize> = traj.steps.iter().map(|s| s.active.len()).collect();
    let most = *sizes.iter().max().unwrap();
    assert!(most >= 3 && *sizes.last().unwrap() < most, "{sizes:?}");
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
    let g = adj.gradient(&model, law, c, &traj, &rho).unwrap();
    let sens = adj.sensitivities(&model, law, c, &traj).unwrap();
    let jt = sens.transpose_mul(&rho);
    // the same gradient from a checkpointed run replayed segment by segment
    let ck_opts = SolverOptions {
        record_fields: false,
        checkpoint_every: 5,
        ..opts.clone()
    };
    let ck = solver.run(&model, law, c, &sched, &ck_opts).unwrap();
    let g_ck = adj
        .gradient_replayed(&model, law, c, &ck, &rho, &mut solver, &sched, &ck_opts)
        .unwrap();
    for k in 0..checked {
        let name = law.params()[k].name;
        println!(
            "{name}: adjoint={:.12e} fd={:.12e} sens={:.12e} | rel fd {:.1e} sens {:.1e}",
            g.dj_dc[k],
            fd[k],
            jt[k],
            relative_difference(g.dj_dc[k], fd[k]),
            relative_difference(g.dj_dc[k], jt[k])
        );
        assert!(relative_difference(g.dj_dc[k], fd[k]) < 1e-6, "{name}");
        assert!(relative_difference(g.dj_dc[k], jt[k]) < 1e-8, "{name}");
        assert!(
            relative_difference(g.dj_dc[k], g_ck.dj_dc[k]) < 1e-10,
            "{name}"
        );
    }
}

/// The adjoint shall differentiate an elastic cost with normal contact on a cone.
#[test]
fn elastic_cone() {
    check_gradient(cone(), &Elastic, &[20000.0, 0.3], &[17000.0, 0.27], 2);
}

/// The adjoint shall differentiate an elastic cost with normal contact on a sphere (the
/// curvature stiffness enters the transposed system).
#[test]
fn elastic_sphere() {
    check_gradient(sphere(), &Elastic, &[20000.0, 0.3], &[17000.0, 0.27], 2);
}

/// The adjoint shall differentiate a Maxwell cost with normal contact (cone and sphere).
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

/// The adjoint shall differentiate a Norton-Hoff cost with yield (sY > 0) with normal
/// contact (cone and sphere).
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

/// The adjoint shall differentiate a Norton-Hoff cost without yield (sY = 0) with normal
/// contact (cone and sphere).
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
