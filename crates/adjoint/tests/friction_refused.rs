//! The adjoint and the sensitivities refuse a model with Coulomb friction (not
//! implemented: docs/validation-contact.md §7) with an error naming `contact.friction`,
//! instead of returning a frictionless gradient.

use indentify_adjoint::{Adjoint, AdjointError};
use indentify_contact::{
    ContactKind, DirectSolver, Model, Punch, Schedule, SolverOptions, trapezoid,
};
use indentify_laws::Elastic;
use indentify_mesh::CylinderMesher;

/// The adjoint shall refuse friction with a clear error (gradient and sensitivities).
#[test]
fn friction_is_refused_by_the_adjoint() {
    let mesh = CylinderMesher {
        radius: 2.0,
        height: 2.0,
        nr: 6,
        nz: 6,
        grading_r: 1.3,
        grading_z: 1.3,
    }
    .build()
    .unwrap();
    let kind = ContactKind::normal_with_friction(0.2).unwrap();
    let model = Model::with_contact(mesh, Punch::Sphere { radius: 0.5 }, kind).unwrap();
    let sched = Schedule::from_segments(&trapezoid(0.02, 1.0, 1.0, 1.0, 3)).unwrap();
    let c = [20000.0, 0.3];
    let traj = DirectSolver::new(&model)
        .unwrap()
        .run(&model, &Elastic, &c, &sched, &SolverOptions::default())
        .unwrap();
    let mut adj = Adjoint::new(&model).unwrap();
    let rho = vec![1.0; traj.steps.len()];
    let e = adj.gradient(&model, &Elastic, &c, &traj, &rho).unwrap_err();
    assert!(matches!(e, AdjointError::Friction(mu) if mu == 0.2), "{e}");
    assert!(e.to_string().contains("contact.friction` = 0.2"), "{e}");
    let e = adj.sensitivities(&model, &Elastic, &c, &traj).unwrap_err();
    assert!(matches!(e, AdjointError::Friction(_)), "{e}");
}
