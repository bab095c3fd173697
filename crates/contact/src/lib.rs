//! Frictionless contact of a rigid axisymmetric punch and the time-stepped direct problem
//! (P) of indentify: punch profiles ([`Punch`]), depth histories ([`Schedule`]), the
//! model ([`Model`]) and solver ([`DirectSolver`]) whose run is a recorded [`Trajectory`].
//!
//! Units: mm, N (full circle), MPa, s. The punch is driven by its depth `U(t)` (positive
//! into the body, which lies below z = 0). This crate owns time stepping; it knows
//! nothing of adjoints, costs or optimizers.

mod body;
mod constraint;
pub mod direct;
mod drive;
pub mod friction;
pub mod history;
pub mod kinematics;
pub mod model;
mod newton;
pub mod normal;
pub mod pdotp;
pub mod punch;
pub mod refresh;
pub mod system;

pub use constraint::{ForceCotangent, RecordedContact, StepTangent};
pub use direct::{
    Checkpoint, DirectSolver, SolverOptions, StepFields, StepRecord, StepWatch, Timing, Trajectory,
    nodal_pressures,
};
pub use drive::Frame;
pub use history::{
    HistorySegment, LoadHistory, MAX_SUBSTEPS, Schedule, Segment, Target, trapezoid,
};
pub use kinematics::Kinematics;
pub use model::Model;
pub use normal::ContactKind;
pub use pdotp::{Leg, PdotP, SegmentSpec};
pub use punch::Punch;
pub use refresh::{PcgEvent, RefreshRule};
pub use system::{ConstrainedSystem, NodeFrame};

/// Errors of the direct problem.
#[derive(Debug, thiserror::Error)]
pub enum ContactError {
    /// An input outside its admissible range.
    #[error("`{field}` = {value} is not allowed: expected {allowed}")]
    Input {
        /// Dotted config path of the field.
        field: &'static str,
        /// Offending value, as text.
        value: String,
        /// What is allowed.
        allowed: String,
    },
    /// Inadmissible law parameters.
    #[error(transparent)]
    Parameters(#[from] indentify_laws::LawError),
    /// A linear-algebra failure outside of a step (symbolic analysis).
    #[error(transparent)]
    Fe(#[from] indentify_fe::FeError),
    /// A step failed even after cutting it `cuts` times; `partial` holds the converged steps.
    #[error("step {step} (t = {t} s) failed after {cuts} step cuts: {reason}")]
    StepFailed {
        /// Schedule index of the step.
        step: usize,
        /// Target time of the failing (sub-)step (s).
        t: f64,
        /// Number of halvings tried.
        cuts: u32,
        /// Why the last attempt failed.
        reason: String,
        /// The trajectory up to the last converged step.
        partial: Box<Trajectory>,
    },
    /// The run's watch ([`direct::StepWatch`]) stopped it after a converged step.
    #[error("the run was stopped by its watch after step {step} (t = {t} s, {steps} steps run)")]
    Stopped {
        /// Schedule index of the step the run stopped after (the one it was heading to,
        /// for a sub-step).
        step: usize,
        /// End time of that step (s).
        t: f64,
        /// Converged steps run (sub-steps included).
        steps: usize,
        /// Newton iterations of the steps run.
        newton_iterations: u64,
        /// Numeric factorizations of the steps run.
        factorizations: usize,
    },
}
