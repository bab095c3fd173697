//! What moves the punch: the drive of a run, its third piece beside the body's kinematics
//! (`body.rs`) and the contact constraint (`constraint/`). Today the punch is driven by
//! its depth ([`DepthDrive`]: the depth history `U(t)` of a [`Schedule`] prescribes the
//! depth of every step, and the force is measured). The Newton driver (`newton.rs`) reads
//! the depth of a step from the drive once, at the step's start, and hands it to the
//! constraint with every iterate (`constraint::Iterate::depth`), so a drive whose depth
//! is an unknown of the step (a prescribed force `P(t)`: the depth becomes one more
//! unknown with the scalar equation `sum_k lambda_k = P`, a bordered Newton system) is a
//! new implementation of [`Drive`] plus its row in the Newton solve, not a new branch
//! through the constraints (docs/solver.md).

use crate::history::Schedule;

/// The drive of a run: what sets the punch depth of each step.
pub(crate) trait Drive: Sync {
    /// The punch depth (mm) at which the step ending at time `t` (s) starts Newton; a
    /// depth drive prescribes it.
    fn depth_at(&self, t: f64) -> f64;
}

/// The punch driven by the depth history of a schedule (the paper's problem (P)).
#[derive(Clone, Copy, Debug)]
pub(crate) struct DepthDrive<'a>(pub &'a Schedule);

impl Drive for DepthDrive<'_> {
    fn depth_at(&self, t: f64) -> f64 {
        self.0.depth_at(t)
    }
}
