//! What moves the punch: the drive of a run, its third piece beside the body's kinematics
//! (`body.rs`) and the contact constraint (`constraint/`), chosen once per run by the
//! direct solver. [`DepthDrive`] prescribes the depth history `U(t)` of a [`Schedule`]
//! (the force is measured); [`ForceDrive`] follows a [`LoadHistory`] whose segments
//! prescribe the depth or the force `P(t)`: in a load-controlled step the depth is one
//! more unknown with the scalar equation `sum_k lambda_k = P`, solved by the Newton
//! driver's bordered update on the same factorization (`newton.rs`, `Newton::border`;
//! docs/theory.md §13). The constraints never read the drive: they take the iterate's
//! depth (`constraint::Iterate::depth`), so a depth that changes between Newton
//! iterations needs no change in them (docs/solver.md).

use crate::history::{LoadHistory, Schedule, Target};
use crate::newton::State;

/// What a load-controlled step prescribes: the punch force at its end (N). (The time
/// extrapolation of nonlinear laws keys on the step's force rate, `newton.rs`.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Load {
    pub force: f64,
}

/// The drive of a run: what sets the punch of each step.
pub(crate) trait Drive: Sync {
    /// For the step from `state` to the time `t1` (s): the punch depth (mm) Newton starts
    /// from (prescribed under depth control), and the prescribed force under load control.
    fn step(&self, t1: f64, state: &State) -> (f64, Option<Load>);
}

/// The punch driven by the depth history of a schedule (the paper's problem (P)).
#[derive(Clone, Copy, Debug)]
pub(crate) struct DepthDrive<'a>(pub &'a Schedule);

impl Drive for DepthDrive<'_> {
    fn step(&self, t1: f64, _state: &State) -> (f64, Option<Load>) {
        (self.0.depth_at(t1), None)
    }
}

/// The punch driven by a history whose segments prescribe the depth or the force. Each
/// step moves linearly from its state towards its segment's end target (the force of
/// the state for a load-controlled segment, the depth for a depth-controlled one), so a
/// segment starts from wherever the previous one ended, and cut steps and sub-steps
/// follow the same straight line in time.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ForceDrive<'a>(pub &'a LoadHistory);

impl Drive for ForceDrive<'_> {
    fn step(&self, t1: f64, state: &State) -> (f64, Option<Load>) {
        let (t_end, target) = self.0.segment_at(t1);
        let f = (t1 - state.t) / (t_end - state.t);
        match target {
            Target::Depth(d) if f >= 1.0 => (d, None),
            Target::Depth(d) => (state.depth + f * (d - state.depth), None),
            Target::Force(p) => {
                let force = if f >= 1.0 {
                    p
                } else {
                    state.force + f * (p - state.force)
                };
                // Newton starts from the depth extrapolated linearly from the last step
                // (a nonlinear law's Newton driver replaces it by the displacement's own
                // time extrapolation, `newton.rs`)
                let last = &state.past[0];
                let depth = if last.dt > 0.0 {
                    state.depth + (t1 - state.t) / last.dt * last.depth
                } else {
                    state.depth
                };
                (depth, Some(Load { force }))
            }
        }
    }
}
