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

use common::FrictionCase;

/// The finite-strain adjoint with friction shall differentiate an elastic cost (cone
/// mu = 0.1, sphere mu = 0.2).
#[test]
fn elastic_finite_with_friction() {
    common::friction_law_check(FrictionCase::Elastic, common::finite_model_with_friction, 6);
}

/// The finite-strain adjoint with friction shall differentiate a Maxwell cost (cone
/// mu = 0.2, sphere mu = 0.1).
#[test]
fn maxwell_finite_with_friction() {
    common::friction_law_check(FrictionCase::Maxwell, common::finite_model_with_friction, 6);
}

/// The finite-strain adjoint with friction shall differentiate a Norton-Hoff cost with
/// yield (sY > 0; cone mu = 0.1, sphere mu = 0.2).
#[test]
fn norton_hoff_with_yield_finite_with_friction() {
    common::friction_law_check(
        FrictionCase::NortonHoffYield,
        common::finite_model_with_friction,
        6,
    );
}

/// The finite-strain adjoint with friction shall differentiate a Norton-Hoff cost without
/// yield (sY = 0; cone and sphere, mu = 0.2).
#[test]
fn norton_hoff_without_yield_finite_with_friction() {
    common::friction_law_check(
        FrictionCase::NortonHoffNoYield,
        common::finite_model_with_friction,
        6,
    );
}
