//! Adjoint gradients and forward sensitivities with Coulomb friction
//! (`ContactKind::NormalFriction`: sticking nodes tied to the previous step's stick
//! point, slipping rows unsymmetric) against central finite differences of the
//! whole-history cost, over load-hold-unload histories with the contact zone growing and
//! shrinking and both sticking and slipping node-steps, for elastic, Maxwell and
//! Norton-Hoff (sY = 0 and > 0), cone and sphere, mu = 0.1 and 0.2.
//!
//! The rule for finite differences with friction: the cost is differentiable only where
//! no step's contact set or stick/slip partition changes under the perturbation. Every
//! check compares each step's active set and statuses of the +h and -h runs with the base
//! run and asserts that they match (the step size is chosen among 1e-5, 1e-6, 1e-7
//! relative, the largest for which they do); a check across a status flip would not be
//! meaningful.
//!
//! Mesh: 4 x 4 mm cylinder, 10 x 10 Q8 graded 1.45 towards axis and top; 0 -> 0.1 mm ->
//! hold -> 0.02 mm, 1 s and 8 steps per segment (as `gradient_fd_normal.rs`, whose
//! unloading to 0 ends with the axis node borderline: with friction its status flips
//! under any perturbation of nu).

mod common;

use common::FrictionCase;
use indentify_contact::{ContactKind, Model, Punch};
use indentify_testkit::cylinder;

fn model(punch: Punch, mu: f64) -> Model {
    let mesh = cylinder(4.0, 10, 1.45);
    let kind = ContactKind::normal_with_friction(mu).unwrap();
    Model::with_contact(mesh, punch, kind).unwrap()
}

/// The adjoint shall differentiate an elastic cost with friction (cone mu = 0.1, sphere
/// mu = 0.2): stick points make even elasticity history dependent.
#[test]
fn elastic_with_friction() {
    common::friction_law_check(FrictionCase::Elastic, model, 8);
}

/// The adjoint shall differentiate a Maxwell cost with friction (cone mu = 0.2, sphere
/// mu = 0.1).
#[test]
fn maxwell_with_friction() {
    common::friction_law_check(FrictionCase::Maxwell, model, 8);
}

/// The adjoint shall differentiate a Norton-Hoff cost with yield (sY > 0) with friction
/// (cone mu = 0.1, sphere mu = 0.2).
#[test]
fn norton_hoff_with_yield_with_friction() {
    common::friction_law_check(FrictionCase::NortonHoffYield, model, 8);
}

/// The adjoint shall differentiate a Norton-Hoff cost without yield (sY = 0) with
/// friction (cone and sphere, mu = 0.2: with 0.1 on the sphere nearly every node slips).
#[test]
fn norton_hoff_without_yield_with_friction() {
    common::friction_law_check(FrictionCase::NortonHoffNoYield, model, 8);
}
