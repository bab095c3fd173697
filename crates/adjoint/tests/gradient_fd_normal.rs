//! Adjoint gradients and forward sensitivities with normal contact
//! (`ContactKind::Normal`: rotated dofs, curvature stiffness) against central finite
//! differences, over whole load-hold-unload histories with the contact zone growing and
//! shrinking, for elastic, Maxwell and Norton-Hoff (sY = 0 and > 0), cone and sphere.
//!
//! Reference: central differences of the direct solver's own cost (independent of the
//! adjoint code), and the forward-sensitivity Jacobian (an independent derivation).
//! Mesh: 4 x 4 mm cylinder, 10 x 10 Q8 graded 1.45 towards axis and top; trapezoid
//! 0 -> 0.1 mm -> hold -> 0, 8 steps per segment.

mod common;

use indentify_contact::{ContactKind, Model, Punch};
use indentify_laws::{Elastic, Law, Maxwell, NortonHoff};
use indentify_testkit::{cone68 as cone, cylinder, sphere1 as sphere};

fn model(punch: Punch) -> Model {
    let mesh = cylinder(4.0, 10, 1.45);
    Model::with_contact(mesh, punch, ContactKind::Normal).unwrap()
}

/// Adjoint vs central differences (1e-6), vs J^T rho (1e-8), and the checkpointed
/// adjoint vs the recorded one (1e-10) (`common::whole_history_check`, 8 steps per
/// segment).
fn check_gradient(punch: Punch, law: &dyn Law, truth: &[f64], c: &[f64], checked: usize) {
    common::whole_history_check(&model(punch), law, truth, c, checked, 8, 1e-8);
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
