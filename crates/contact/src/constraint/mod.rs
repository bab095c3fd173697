//! The contact constraints of the direct problem, one piece per kind behind one
//! interface ([`Constraint`]): vertical contact ([`vertical`]), frictionless normal contact
//! ([`frictionless`]) and normal contact with Coulomb friction ([`coulomb`]). The Newton
//! driver (`newton.rs`) calls a constraint at fixed points of every pass and never asks
//! which kind it serves (docs/solver.md):
//!
//! 1. step start: [`Constraint::predict`] activates the candidates the new depth makes
//!    penetrate;
//! 2. each pass, after the Gauss-point evaluation: [`Constraint::update`] (gaps, closest
//!    points), [`Constraint::constrained_equations`] and [`Constraint::residual`] (the
//!    equations the constraint replaces, and its own rows' residual),
//!    [`Constraint::targets_met`] (the prescribed values reached);
//! 3. the complementarity check, once equilibrium is loosely met: [`Constraint::lambda`],
//!    [`Constraint::gap`] and [`Constraint::holds_under_tension`] for the contact set,
//!    [`Constraint::check_status`] for a second partition (stick/slip);
//! 4. a converged step: [`Constraint::accept`], [`Constraint::record`],
//!    [`Constraint::stick_points`];
//! 5. each solve: [`Constraint::impose`] (the node frames of the constrained system) and
//!    [`Constraint::prescribe`] (the prescribed increments of the constrained dofs).
//!
//! The adjoint sweep and the forward sensitivities (`crates/adjoint`) transpose or
//! differentiate each converged step with the same piece, through [`RecordedContact`]:
//!
//! 6. a recorded step: [`Constraint::recorded_frames`] (the frames its system is
//!    transposed with); the adjoint: [`Constraint::force_cotangent`] (how the cost's
//!    `dJ/dF_i` enters), [`Constraint::adjoint_rhs`] (its part of the right-hand side and
//!    the adjoint's values on the constrained dofs), [`Constraint::adjoint_carry`] (what
//!    a step passes to the one before it: friction's sticking ties); the sensitivities:
//!    [`Constraint::sensitivity_ties`] (prescribed values of a step that depend on the
//!    previous step's displacement variation).
//!
//! A new kind of contact is a new file implementing [`Constraint`] (forward and adjoint
//! together) and one line in [`for_model`].

mod recorded;

pub(crate) mod coulomb;
pub(crate) mod frictionless;
pub(crate) mod vertical;

pub(crate) use recorded::Tie;
pub use recorded::{ForceCotangent, RecordedContact, StepTangent};

use crate::StepRecord;
use crate::friction::Status;
use crate::model::Model;
use crate::newton::StepFailure;
use crate::normal::ContactKind;
use crate::system::{ConstrainedSystem, NodeFrame};

/// The contact set of a state: which candidates are active, and with Coulomb friction
/// the stick/slip status of every candidate (meaningful for the active ones; empty
/// without friction).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ContactSet {
    /// `active[k]`: candidate `k` is in contact.
    pub active: Vec<bool>,
    /// Coulomb friction: the status of every candidate (0 sticks, +-1 slips).
    pub slip: Vec<Status>,
}

impl ContactSet {
    /// No candidate in contact (every status sticking under friction).
    pub(crate) fn initial(model: &Model) -> ContactSet {
        let nc = model.candidates.len();
        ContactSet {
            active: vec![false; nc],
            slip: if model.contact.friction() > 0.0 {
                vec![0; nc]
            } else {
                Vec::new()
            },
        }
    }

    /// Puts candidate `k` in contact: a node entering contact starts sticking.
    pub(crate) fn activate(&mut self, k: usize) {
        self.active[k] = true;
        if !self.slip.is_empty() {
            self.slip[k] = 0;
        }
    }

    /// Releases an active candidate `k` or activates an inactive one.
    pub(crate) fn toggle(&mut self, k: usize) {
        if self.active[k] {
            self.active[k] = false;
        } else {
            self.activate(k);
        }
    }

    /// The active candidates, increasing.
    pub(crate) fn active(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.active.len()).filter(|&k| self.active[k])
    }
}

/// The Newton iterate as a constraint sees it: displacement and internal force (all dofs),
/// the punch depth, and the stick points of the step's initial state (Coulomb friction;
/// empty otherwise).
#[derive(Clone, Copy)]
pub(crate) struct Iterate<'a> {
    /// Displacement (mm).
    pub u: &'a [f64],
    /// Internal force `sum_g w_g B^T sigma_g` (N).
    pub f_int: &'a [f64],
    /// Punch depth (mm).
    pub depth: f64,
    /// The arc coordinate of every candidate's closest point at the step's initial state.
    pub xi: &'a [f64],
}

impl Iterate<'_> {
    /// The internal force `(f_r, f_z)` on candidate `k`'s node.
    pub(crate) fn node_force(&self, model: &Model, k: usize) -> [f64; 2] {
        let n = model.candidates[k];
        [self.f_int[2 * n], self.f_int[2 * n + 1]]
    }
}

/// The tolerances of the complementarity check: on tensile reactions (N), on
/// penetration (mm), and the force that scales violations (N, > 0).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tolerances {
    /// Reactions below `-lambda` are tensile.
    pub lambda: f64,
    /// Gaps below `-gap` penetrate.
    pub gap: f64,
    /// `|F|` (never 0), the scale of a reaction's violation.
    pub force: f64,
}

/// A status change proposed by [`Constraint::check_status`]: the candidate, its new
/// status and how far the old one is violated (relative).
pub(crate) type StatusFlip = (usize, Status, f64);

/// One kind of contact constraint on the punch candidates (see the module's
/// documentation for when the Newton driver calls each method). Implementors hold the
/// model and their per-pass scratch (closest points, frames).
pub(crate) trait Constraint: std::fmt::Debug + Send + Sync {
    /// Activates the inactive candidates that the depth `depth` makes penetrate, with
    /// their displacement `u` extrapolated by `ratio` times the last increment `du`.
    fn predict(&self, set: &mut ContactSet, u: &[f64], du: &[f64], ratio: f64, depth: f64);

    /// Evaluates the constraint at the iterate (gaps, closest points).
    fn update(&mut self, set: &ContactSet, it: &Iterate<'_>);

    /// Marks the equations whose equilibrium row this constraint replaces for the
    /// active candidates (`constrained` is all false on entry).
    fn constrained_equations(&self, set: &ContactSet, constrained: &mut [bool]);

    /// The largest residual of the constraint's own rows among the replaced equations
    /// (normal contact: the tangential equations of the active nodes), N; 0 without.
    fn residual(&self, set: &ContactSet, it: &Iterate<'_>) -> f64;

    /// Whether every active candidate meets its prescribed values (to round-off).
    fn targets_met(&self, set: &ContactSet, it: &Iterate<'_>) -> bool;

    /// The reaction `lambda_k` (N, > 0 in compression) of candidate `k`.
    fn lambda(&self, k: usize, it: &Iterate<'_>) -> f64;

    /// The gap of candidate `k` (mm, < 0 penetrating).
    fn gap(&self, k: usize, it: &Iterate<'_>) -> f64;

    /// Whether an active candidate keeps contact under tension until a second partition
    /// changes first (a sticking node turns to slip before it is released).
    fn holds_under_tension(&self, _set: &ContactSet, _k: usize) -> bool {
        false
    }

    /// Proposes the status changes of a second partition of the active candidates (Coulomb
    /// friction's stick/slip), checked once the contact set holds.
    fn check_status(
        &self,
        _set: &ContactSet,
        _it: &Iterate<'_>,
        _tol: &Tolerances,
        _flips: &mut Vec<StatusFlip>,
    ) {
    }

    /// Accepts the converged iterate, or fails the run when it has no meaning (a node in
    /// normal contact beyond the end of the punch surface).
    ///
    /// # Errors
    /// [`StepFailure::Geometry`].
    fn accept(&self, _set: &ContactSet, _it: &Iterate<'_>) -> Result<(), StepFailure> {
        Ok(())
    }

    /// Completes the record of a converged step (`rec` holds the vertical reactions, the
    /// force and the reference contact radius).
    fn record(&self, _set: &ContactSet, _it: &Iterate<'_>, _rec: &mut StepRecord) {}

    /// The stick points of the converged iterate for the next step (Coulomb friction:
    /// every candidate's arc coordinate; empty otherwise).
    fn stick_points(&self) -> Vec<f64> {
        Vec::new()
    }

    /// Imposes the constraint on `system` for a solve (after `set_active`): the frames of
    /// the active nodes under normal contact.
    fn impose(&mut self, set: &ContactSet, it: &Iterate<'_>, system: &mut ConstrainedSystem);

    /// The prescribed increments of the constrained equations into `xbar` (zero
    /// elsewhere on entry).
    fn prescribe(&self, set: &ContactSet, it: &Iterate<'_>, xbar: &mut [f64]);

    /// Whether [`Constraint::recorded_frames`] needs the step's internal force.
    fn frames_need_force(&self) -> bool {
        false
    }

    /// The frames of the active nodes of a converged recorded step `rec` at its
    /// displacement `u` (all dofs), with its internal force `f_int` (all dofs; given when
    /// [`Constraint::frames_need_force`]), into the caller's `frames` (cleared first; its
    /// capacity kept from step to step, so no allocation per step): the system the
    /// adjoint and the sensitivities transpose. Empty for vertical contact.
    ///
    /// # Errors
    /// A message when the record does not fit the constraint (friction: an active node
    /// without a frame, or a stick/slip status missing).
    fn recorded_frames(
        &self,
        rec: &StepRecord,
        u: &[f64],
        f_int: Option<&[f64]>,
        frames: &mut Vec<NodeFrame>,
    ) -> Result<(), String>;

    /// How the cost's `dJ/dF_i` enters the adjoint of a step ([`ForceCotangent`]).
    fn force_cotangent(&self) -> ForceCotangent {
        ForceCotangent::Prescribed
    }

    /// The constraint's part of the adjoint of the recorded step `step` with the cost's
    /// `rho = dJ/dF_i`: adds its terms to the right-hand side `g` (equations, holding the
    /// body's `sum_g w B^T (C S - I) mu_{i+1}` on entry) and writes the adjoint's values
    /// on the constrained equations into `v_p` (zero on entry; with
    /// [`ForceCotangent::Shifted`] it must stay zero).
    fn adjoint_rhs(&mut self, step: &Step<'_>, rho: f64, g: &mut [f64], v_p: &mut [f64]);

    /// After the transposed solve of the step: `stick` holds, per frame, the cotangent of
    /// a sticking node's prescribed tangential value; the constraint keeps what the step
    /// passes to the one before it (its [`Constraint::adjoint_rhs`] adds it there).
    fn adjoint_carry(&mut self, _step: &Step<'_>, _stick: &[f64]) {}

    /// Load control (docs/theory.md §13): what the load carried into the step `step`
    /// by the later steps (friction's sticking ties, [`Constraint::adjoint_carry`]; read
    /// before [`Constraint::adjoint_rhs`] consumes it) makes of a unit increment of the
    /// step's depth with everything before the step held: the load against the step's
    /// depth column `col` (equations), plus its direct dependence on the depth through the
    /// tied nodes' position relative to the punch, `x + U e_z`. 0 without such a load.
    fn adjoint_depth(&self, _step: &Step<'_>, _col: &[f64]) -> f64 {
        0.0
    }

    /// Whether [`Constraint::adjoint_carry`] left a load for the step before (the sweep
    /// may skip a step only without one).
    fn adjoint_pending(&self) -> bool {
        false
    }

    /// Drops what an earlier sweep carried (start of a sweep).
    fn adjoint_reset(&mut self) {}

    /// Whether a step's prescribed values depend on the previous step's motion (the
    /// sensitivities then keep each parameter's displacement variation).
    fn ties_steps(&self) -> bool {
        false
    }

    /// The forward sensitivities of step `step`: the prescribed values of its constrained
    /// equations that depend on the previous step `prev` (record and displacement), as
    /// [`Tie`]s on the previous displacement variation (none without friction).
    fn sensitivity_ties(
        &self,
        _step: &Step<'_>,
        _prev: Option<(&StepRecord, &[f64])>,
        _ties: &mut Vec<Tie>,
    ) {
    }
}

/// A converged recorded step as the constraint's adjoint reads it: its record, its
/// displacement (all dofs) and the frames [`Constraint::recorded_frames`] gave it.
#[derive(Clone, Copy)]
pub(crate) struct Step<'a> {
    /// The step's record.
    pub rec: &'a StepRecord,
    /// The converged displacement (all dofs, mm).
    pub u: &'a [f64],
    /// The frames of its active nodes (same order as `rec.active` under friction).
    pub frames: &'a [NodeFrame],
}

/// The constraint of `model`'s contact kind.
pub(crate) fn for_model(model: &Model) -> Box<dyn Constraint + '_> {
    match model.contact {
        ContactKind::Vertical => Box::new(vertical::Vertical::new(model)),
        ContactKind::Normal => Box::new(frictionless::Frictionless::new(model)),
        ContactKind::NormalFriction { friction } => {
            Box::new(coulomb::Coulomb::new(model, friction))
        }
    }
}
