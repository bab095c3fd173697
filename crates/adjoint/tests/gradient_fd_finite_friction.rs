//! Adjoint gradients and forward sensitivities under finite strain with Coulomb friction
//! (`Kinematics::Finite` with `ContactKind::NormalFriction`: the step operators
//! `G_i = P B_L(u_i)` and the consistent tangent composed with the friction frames,
//! sticking nodes tied to the previous step, slipping rows unsymmetric) against central
//! finite differences of the whole-history cost, over load-hold-unload histories with the
//! contact zone growing and shrinking and both sticking and slipping node-steps (counted
//! and asserted), for elastic, Maxwell and Norton-Hoff (sY = 0 and > 0), cone and sphere,
//! mu = 0.1 and 0.2.
//!
//! The finite-difference rule is friction's (`common::friction_history_check`): the +-h
//! runs must keep every step's contact set and stick/slip statuses of the base run.
//! Mesh: 4 x 4 mm cylinder, 8 x 8 Q8 graded 1.45 towards axis and top (as
//! `gradient_fd_finite.rs`); 0 -> 0.1 mm -> hold -> 0.02 mm, 1 s and 6 steps per segment:
//! strains under the tip of order 0.3.

mod common;

use common::Outcome;
use indentify_contact::{ContactKind, Kinematics, Model, Punch};
use indentify_laws::{Elastic, Law, Maxwell, NortonHoff};
use indentify_mesh::CylinderMesher;

fn model(punch: Punch, mu: f64) -> Model {
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
    let kind = ContactKind::normal_with_friction(mu).unwrap();
    Model::with_contact(mesh, punch, kind)
        .unwrap()
        .with_kinematics(Kinematics::Finite)
        .unwrap()
}

fn cone() -> Punch {
    Punch::Cone {
        half_angle_deg: 68.0,
    }
}

fn sphere() -> Punch {
    Punch::Sphere { radius: 1.0 }
}

/// The whole-history check with friction, 6 steps per segment.
fn check_gradient(
    punch: Punch,
    mu: f64,
    law: &dyn Law,
    truth: &[f64],
    c: &[f64],
    checked: usize,
) -> Outcome {
    common::friction_history_check(&model(punch, mu), law, truth, c, checked, 6)
}

/// The finite-strain adjoint with friction shall differentiate an elastic cost (cone
/// mu = 0.1, sphere mu = 0.2).
#[test]
fn elastic_finite_with_friction() {
    let mut all = Outcome::default();
    let (t, c) = ([20000.0, 0.3], [17000.0, 0.27]);
    for (punch, mu) in [(cone(), 0.1), (sphere(), 0.2)] {
        all.add(check_gradient(punch, mu, &Elastic, &t, &c, 2));
    }
    all.assert_stick_and_slip();
}

/// The finite-strain adjoint with friction shall differentiate a Maxwell cost (cone
/// mu = 0.2, sphere mu = 0.1).
#[test]
fn maxwell_finite_with_friction() {
    let mut all = Outcome::default();
    let (t, c) = ([20000.0, 0.3, 30000.0], [15000.0, 0.28, 45000.0]);
    for (punch, mu) in [(cone(), 0.2), (sphere(), 0.1)] {
        all.add(check_gradient(punch, mu, &Maxwell, &t, &c, 3));
    }
    all.assert_stick_and_slip();
}

/// The finite-strain adjoint with friction shall differentiate a Norton-Hoff cost with
/// yield (sY > 0; cone mu = 0.1, sphere mu = 0.2).
#[test]
fn norton_hoff_with_yield_finite_with_friction() {
    let mut all = Outcome::default();
    let t = [1e5, 0.3, 1500.0, 5.0, 500.0];
    let c = [1.2e5, 0.31, 1300.0, 4.0, 420.0];
    for (punch, mu) in [(cone(), 0.1), (sphere(), 0.2)] {
        all.add(check_gradient(punch, mu, &NortonHoff, &t, &c, 5));
    }
    all.assert_stick_and_slip();
}

/// The finite-strain adjoint with friction shall differentiate a Norton-Hoff cost without
/// yield (sY = 0; cone and sphere, mu = 0.2).
#[test]
fn norton_hoff_without_yield_finite_with_friction() {
    let mut all = Outcome::default();
    let t = [1e5, 0.3, 1500.0, 5.0, 0.0];
    let c = [1.2e5, 0.31, 1300.0, 4.0, 0.0];
    for (punch, mu) in [(cone(), 0.2), (sphere(), 0.2)] {
        all.add(check_gradient(punch, mu, &NortonHoff, &t, &c, 4));
    }
    all.assert_stick_and_slip();
}
