//! The direct and adjoint solves as the commands run them: failures of the libraries turned
//! into messages that name the configuration and what to change.

use anyhow::{Result, anyhow};
use indentify_contact::{ContactError, DirectSolver, Schedule, SolverOptions, Trajectory};
use indentify_laws::{LawError, Material};

/// Fails unless the law is differentiable at `params` (Norton-Hoff needs `m > 1`), with a
/// message naming the `law.` field: a gradient there would be meaningless, never NaN.
///
/// # Errors
/// The law's [`LawError::NotDifferentiable`] as `law.m = 1 ...: why`.
pub fn ensure_differentiable(law: &dyn Material, params: &[f64], what: &str) -> Result<()> {
    match law.check_differentiable(params) {
        Ok(()) => Ok(()),
        Err(LawError::NotDifferentiable {
            law: name,
            name: param,
            value,
            why,
        }) => Err(anyhow!(
            "{what}: law.{param} = {value} is not a point where the {name} cost is \
             differentiable: {why} (choose another value, e.g. with --set law.{param}=...)"
        )),
        Err(e) => Err(e.into()),
    }
}

/// Runs the direct problem; a step that fails even after cutting becomes an error naming
/// the configuration, the parameters, the step and the solver options to change.
///
/// # Errors
/// The solver's error, with context.
pub fn forward(
    solver: &mut DirectSolver,
    law: &dyn Material,
    params: &[f64],
    schedule: &Schedule,
    opts: &SolverOptions,
    config: &str,
) -> Result<Trajectory> {
    solver
        .run(law, params, schedule, opts)
        .map_err(|e| match e {
            ContactError::StepFailed {
                step,
                t,
                cuts,
                reason,
                ..
            } => anyhow!(
                "the direct problem of `{config}` at {} failed at step {step} (t = {t} s) after \
                 {cuts} step cuts: {reason} (try smaller steps in `history.segments` or a larger \
                 `solver.max_cuts`)",
                crate::format::assignments(
                    &law.params().iter().map(|i| i.name).collect::<Vec<_>>(),
                    params
                )
            ),
            other => anyhow!(other).context(format!("cannot simulate `{config}`")),
        })
}

/// The law's parameter names, in its order.
pub fn param_names(law: &dyn Material) -> Vec<&'static str> {
    law.params().iter().map(|i| i.name).collect()
}
