//! The adjoint sweep and forward sensitivities of a material with internal variables,
//! written once against its Jacobian blocks (docs/theory.md §12), the regime of every
//! Gauss point held as recorded.

use indentify_contact::Trajectory;
use indentify_laws::Material;

use crate::{Adjoint, AdjointError, Gradient, Replay, Sensitivities};

impl Adjoint<'_> {
    /// [`Adjoint::gradient`] for a material without [`Material::as_law`].
    pub(crate) fn gradient_material(
        &mut self,
        mat: &dyn Material,
        _c: &[f64],
        _traj: &Trajectory,
        _dj_df: &[f64],
    ) -> Result<Gradient, AdjointError> {
        Err(unsupported(mat, "gradient"))
    }

    /// [`Adjoint::gradient_replayed`] for a material without [`Material::as_law`].
    pub(crate) fn gradient_replayed_material(
        &mut self,
        mat: &dyn Material,
        _c: &[f64],
        _traj: &Trajectory,
        _dj_df: &[f64],
        _replay: Replay<'_, '_>,
    ) -> Result<Gradient, AdjointError> {
        Err(unsupported(mat, "checkpointed gradient"))
    }

    /// [`Adjoint::sensitivities`] for a material without [`Material::as_law`].
    pub(crate) fn sensitivities_material(
        &mut self,
        mat: &dyn Material,
        _c: &[f64],
        _traj: &Trajectory,
    ) -> Result<Sensitivities, AdjointError> {
        Err(unsupported(mat, "forward sensitivities"))
    }
}

/// The error for a combination this file does not take yet.
fn unsupported(mat: &dyn Material, what: &str) -> AdjointError {
    AdjointError::Unsupported(format!(
        "the {what} of law `{}` (internal variables) is not available in this model; \
         use finite differences (`gradient: fd`)",
        mat.name()
    ))
}
