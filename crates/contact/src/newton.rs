//! The Newton driver of one time step: global Newton on equilibrium with a primal-dual
//! active set (semi-smooth Newton on equilibrium and complementarity together), the
//! pieces it calls at fixed points — the body's Gauss-point passes under the model's
//! kinematics (`body.rs`), the contact constraint of the model's kind
//! (`constraint/`), the constrained linear system (`system.rs`) — and the state carried
//! from step to step. The punch depth of the step comes from the drive (`drive.rs`);
//! the time stepping, step cutting and checkpoints are the direct solver's
//! (`direct.rs`). docs/solver.md describes the split.
//!
//! A pass evaluates the iterate once (stresses, internal force), measures the residual
//! on the equations the constraint does not replace plus the constraint's own rows, and
//! either checks the contact set (once equilibrium is loosely met), accepts the step, or
//! solves: tangent, constraints, prescribed increments, an inexact linear solve (forcing
//! term = the relative residual).

use indentify_fe::dofs::NO_EQ;
use indentify_fe::{FeError, QP_PER_ELEMENT};
use indentify_laws::{Material, Regime, Vec4};

use crate::body::{Body, Internal, PassOutputs, StepLaw};
use crate::constraint::{self, Constraint, ContactSet, Iterate, StatusFlip, Tolerances};
use crate::direct::{SolverOptions, StepRecord, Timing};
use crate::drive::Load;
use crate::kinematics::{self, FiniteFailure, Kinematics};
use crate::model::Model;
use crate::normal::ContactKind;
use crate::system::ConstrainedSystem;

/// A step failure the driver reacts to by cutting the step.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum StepFailure {
    Local {
        qp: usize,
        reason: String,
        factor: f64,
    },
    Newton {
        residual: f64,
    },
    /// Depth control: the residual norm has not gone below its best (with the contact set
    /// unchanged) for [`STALLED_ITERATIONS`] iterations: the iteration diverges.
    Stalled {
        residual: f64,
        iterations: u32,
    },
    Cycling {
        changes: u32,
    },
    Linear(String),
    /// A node in normal contact beyond the end of the punch surface: not cured by cutting.
    Geometry(String),
    /// Load control: the prescribed force cannot be carried (no positive contact
    /// stiffness, or a depth beyond the specimen), with the reason.
    Load(String),
    /// Finite strain: an element inverted (`det F <= 0`) at Gauss point `qp`.
    Inverted {
        qp: usize,
        det: f64,
        depth: f64,
    },
}

impl std::fmt::Display for StepFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StepFailure::Local { qp, reason, .. } => {
                write!(
                    f,
                    "local update failed at Gauss point {qp} (element {}): {reason}",
                    qp / QP_PER_ELEMENT
                )
            }
            StepFailure::Newton { residual } => write!(
                f,
                "global Newton did not converge (relative residual {residual:.3e})"
            ),
            StepFailure::Stalled {
                residual,
                iterations,
            } => write!(
                f,
                "global Newton diverged: no iterate below its best residual for \
                 {STALLED_ITERATIONS} iterations, at iteration {iterations} (relative residual \
                 {residual:.3e})"
            ),
            StepFailure::Cycling { changes } => {
                write!(f, "active set cycling after {changes} changes")
            }
            StepFailure::Linear(m) => write!(f, "linear solve failed: {m}"),
            StepFailure::Geometry(m) | StepFailure::Load(m) => write!(f, "{m}"),
            StepFailure::Inverted { qp, det, depth } => write!(
                f,
                "element {} is inverted (det F = {det:.3e} at its Gauss point {}) at the \
                 depth {depth} mm: the mesh cannot follow the deformation under the punch; \
                 refine it there (specimen nr and nz, or elements_in_contact) or reduce \
                 the maximum depth",
                qp / QP_PER_ELEMENT,
                qp % QP_PER_ELEMENT
            ),
        }
    }
}

/// The state carried from step to step.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct State {
    pub(crate) t: f64,
    /// Largest internal-force component seen in converged steps: the residual's scale
    /// when the current forces vanish (full unloading).
    pub(crate) f_scale: f64,
    pub(crate) u: Vec<f64>,
    pub(crate) sigma: Vec<Vec4>,
    /// Internal variables of every Gauss point (empty for a stress-only law).
    pub(crate) internal: Internal,
    /// Internal force `sum_g w_g B^T sigma_g` of the converged state, all dofs (N).
    pub(crate) f_int: Vec<f64>,
    /// The contact set (and stick/slip statuses) of the state.
    pub(crate) set: ContactSet,
    /// The last three steps' displacement increments (all dofs), lengths and depth rates,
    /// the latest first (a zero length: no such step).
    pub(crate) past: [Increment; 3],
    /// The degree (1 to 3) of the time extrapolation that predicted the last step best.
    pub(crate) order: usize,
    /// Punch depth of the state (mm).
    pub(crate) depth: f64,
    /// Punch force of the state (N): the sum of the active candidates' vertical reactions.
    pub(crate) force: f64,
    /// The contact stiffness `dF/dU` (N/mm) of the last bordered solve of the step that
    /// reached the state under a prescribed force (0 otherwise): the drive's restart after
    /// the trigger reads the force-depth exponent from it (`drive.rs`).
    pub(crate) stiffness: f64,
    /// Coulomb friction (empty without): the arc coordinate of every candidate's closest
    /// point at this state (the stick points of the next step).
    pub(crate) xi: Vec<f64>,
}

/// One past step of a [`State`] (`du` empty where it is never read).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Increment {
    pub(crate) du: Vec<f64>,
    pub(crate) dt: f64,
    pub(crate) rate: f64,
    /// The step's depth increment (mm).
    pub(crate) depth: f64,
    /// Whether the step prescribed the force (`rate` then is its force rate, N/s).
    pub(crate) load: bool,
}

impl State {
    /// The undeformed state at time `t0` and depth `depth0`, nothing in contact.
    pub(crate) fn initial(model: &Model, mat: &dyn Material, t0: f64, depth0: f64) -> State {
        let nc = model.candidates.len();
        State {
            t: t0,
            f_scale: 0.0,
            u: vec![0.0; model.disc.n_dofs()],
            sigma: vec![Vec4::ZERO; model.disc.n_qp()],
            internal: Internal::initial(mat, model.disc.n_qp()),
            f_int: vec![0.0; model.disc.n_dofs()],
            set: ContactSet::initial(model),
            // steps of zero length: only the latest increment is ever read (times 0)
            past: std::array::from_fn(|k| Increment {
                du: if k == 0 {
                    vec![0.0; model.disc.n_dofs()]
                } else {
                    Vec::new()
                },
                dt: 0.0,
                rate: 0.0,
                depth: 0.0,
                load: false,
            }),
            order: 1,
            depth: depth0,
            force: 0.0,
            stiffness: 0.0,
            xi: if model.contact.friction() > 0.0 {
                let u0 = vec![0.0; model.disc.n_dofs()];
                (0..nc).map(|k| model.project(k, &u0, depth0).s).collect()
            } else {
                Vec::new()
            },
        }
    }

    /// Bytes held by the state (a checkpoint's memory).
    pub(crate) fn bytes(&self) -> usize {
        // u and f_int per dof, the past increments kept; stress per Gauss point; active flag
        // and more per candidate
        16 * self.u.len()
            + 8 * self.past.iter().map(|p| p.du.len()).sum::<usize>()
            + 32 * self.sigma.len()
            + 8 * self.internal.alpha.len()
            + self.internal.regime.len()
            + 17 * self.set.active.len()
            + 9 * self.xi.len()
    }
}

/// A step to solve: the law and its parameters, the options, the converged state it
/// starts from, its end time, the punch depth Newton starts from and, under load
/// control, the prescribed force (both from the drive, `drive.rs`).
pub(crate) struct StepSpec<'a> {
    pub mat: &'a dyn Material,
    pub c: &'a [f64],
    pub opts: &'a SolverOptions,
    pub state: &'a State,
    pub t1: f64,
    pub depth: f64,
    pub load: Option<Load>,
    /// The displacements before and after the same step of an earlier converged run at
    /// other parameters: their difference starts a nonlinear law's Newton iterations
    /// instead of the time extrapolation (`DirectSolver::run_warm`).
    pub guess: Option<(&'a [f64], &'a [f64])>,
}

/// The time extrapolation of a nonlinear law's first iterate: the polynomial of degree 1
/// to 3 through the last states, while the depth keeps its rate (within a segment).
struct Extrapolation {
    /// The highest degree the segment's past steps allow (0: no extrapolation).
    degrees: usize,
    /// The weights of the increments for each degree ([`extrapolation_weights`]).
    weights: [[f64; 3]; 3],
}

impl Extrapolation {
    /// For a step of length `dt` at the depth rate `rate` from `state` (under load
    /// control, `load`, the force rate); `affine` laws converge in one solve from
    /// anywhere and keep their cheap first pass (no extrapolation). The past steps of
    /// the same drive count while their rate is the step's: the depth rate to round-off
    /// (a segment of the schedule), the force rate within [`LOAD_RATE_CHANGE`] (a force
    /// history prescribed point by point, a record's, changes its rate a little at
    /// every step and still moves smoothly; a ramp's end does not).
    fn new(state: &State, dt: f64, rate: f64, affine: bool, load: bool, n: usize) -> Extrapolation {
        let last = &state.past[0];
        let tol = if load { LOAD_RATE_CHANGE } else { 1e-9 };
        let same = |a: f64, b: f64, b_load: bool| {
            b_load == load && (a - b).abs() <= tol * a.abs().max(b.abs())
        };
        // the highest degree the segment's past steps allow (0: no extrapolation; 1 for a
        // step more than twice the last one, after a cut, where the higher degrees' weights
        // grow like (dt / h_1)^degree)
        let degrees = if affine {
            0
        } else {
            let kept = state
                .past
                .iter()
                .take_while(|p| p.dt > 0.0 && p.du.len() == n && same(rate, p.rate, p.load))
                .count();
            // under load control the drive starts the depth from its last increment,
            // linear in time (`drive.rs`): where the force rate changed too much for the
            // polynomial, the displacement still follows its last increment (degree 1),
            // so that the first iterate is one state of the same linear motion rather than
            // the last state with the punch moved alone (a coarse mesh's force history
            // changes its rate by up to 5x from step to step as nodes touch down; R2's
            // rate-independent laws: 221-244 Newton iterations and 56-63 factorizations
            // with it against 270-316 and 83-212 without, the line search on)
            let kept = if load && kept == 0 && last.load && last.dt > 0.0 && last.du.len() == n {
                1
            } else {
                kept
            };
            if dt > 2.0 * last.dt {
                kept.min(1)
            } else {
                kept
            }
        };
        let h = state.past.each_ref().map(|p| p.dt);
        let weights: [[f64; 3]; 3] = std::array::from_fn(|k| extrapolation_weights(dt, h, k + 1));
        Extrapolation { degrees, weights }
    }

    /// At the first step of a configured segment (`restart`, [`Load::restart`]): the last
    /// step's increment times `q`, degree 1, in place of the time polynomial (affine laws
    /// keep none).
    fn restarted(self, state: &State, q: f64, affine: bool, n: usize) -> Extrapolation {
        let last = &state.past[0];
        if affine || !(last.dt > 0.0 && last.du.len() == n) {
            return self;
        }
        let mut weights = self.weights;
        weights[0] = [q, 0.0, 0.0];
        Extrapolation {
            degrees: 1,
            weights,
        }
    }

    /// The increment predicted by degree `d` at dof `i` (reads the `d` latest steps only).
    fn predict(&self, past: &[Increment; 3], d: usize, i: usize) -> f64 {
        let w = &self.weights[d - 1];
        (0..d).map(|k| w[k] * past[k].du[i]).sum()
    }

    /// Adds the predicted increment of the state's best degree to `u`.
    fn apply(&self, state: &State, u: &mut [f64]) {
        if self.degrees > 0 {
            let d = state.order.min(self.degrees);
            for (i, x) in u.iter_mut().enumerate() {
                *x += self.predict(&state.past, d, i);
            }
        }
    }

    /// The depth (mm) the state's best degree predicts for the step (`None` without
    /// extrapolation).
    fn depth(&self, state: &State) -> Option<f64> {
        if self.degrees == 0 {
            return None;
        }
        let d = state.order.min(self.degrees);
        let w = &self.weights[d - 1];
        Some(state.depth + (0..d).map(|k| w[k] * state.past[k].depth).sum::<f64>())
    }

    /// Hindsight: the degree that would have predicted the increment `du` best.
    fn best_order(&self, state: &State, du: &[f64]) -> usize {
        let degrees = self.degrees;
        let mut err = [0.0f64; 3];
        if degrees > 1 {
            for (i, &d) in du.iter().enumerate() {
                for (k, e) in err.iter_mut().enumerate().take(degrees) {
                    *e += (d - self.predict(&state.past, k + 1, i)).powi(2);
                }
            }
        }
        (1..=degrees.max(1))
            .min_by(|&a, &b| err[a - 1].total_cmp(&err[b - 1]))
            .unwrap_or(1)
    }
}

/// The iterate of a step and its bookkeeping.
struct Iteration {
    u: Vec<f64>,
    /// The punch depth of the iterate (mm): the step's under depth control, an unknown
    /// under load control.
    depth: f64,
    sigma: Vec<Vec4>,
    internal: Internal,
    set: ContactSet,
    /// The contact sets tried so far (cycling detection).
    seen: Vec<ContactSet>,
    changes: u32,
    iterations: u32,
    /// After a repeated set: change one node at a time.
    single_change: bool,
}

/// The residual of a pass: the largest free component (N), the largest internal-force
/// component (N) and the relative residual.
#[derive(Clone, Copy)]
struct Residual {
    res: f64,
    fmax: f64,
    rel: f64,
    /// The Euclidean norm of the bordered residual (N): the free equations, the
    /// constraint's largest row and, under load control, the force equation.
    norm: f64,
}

/// Iterations without a residual norm below the best one of the same contact set after
/// which a depth-controlled step is given up as diverging and cut. The whole test suite
/// and the examples measured (docs/solver.md, "Diverging iterations cut early"): every
/// converged depth-controlled step went at most 12 iterations without a new best, and
/// the attempts that ran to `max_iterations` (60) mostly had their best before the 10th
/// iteration, their norm growing after it.
pub(crate) const STALLED_ITERATIONS: u32 = 20;

/// The best residual norm of the current contact set and the iteration it was reached,
/// for [`STALLED_ITERATIONS`].
#[derive(Clone, Copy, Debug)]
struct Stall {
    best: f64,
    at: u32,
    changes: u32,
}

impl Default for Stall {
    fn default() -> Self {
        Stall {
            best: f64::INFINITY,
            at: 0,
            changes: u32::MAX,
        }
    }
}

impl Stall {
    /// Records the iterate's residual and says whether the iteration has stalled: the
    /// first iterate (before a solve, where the prescribed increments are not applied
    /// yet) and a change of the contact set start the count again.
    fn stalled(&mut self, r: &Residual, it: &Iteration) -> bool {
        if it.iterations <= 1 || it.changes != self.changes || r.norm < self.best {
            *self = Stall {
                best: r.norm,
                at: it.iterations,
                changes: it.changes,
            };
        }
        it.iterations - self.at >= STALLED_ITERATIONS
    }
}

/// What the complementarity check of a pass found.
enum Check {
    /// The sets hold and equilibrium has converged: the step is done.
    Converged,
    /// The sets changed (or hold without converged equilibrium): solve again.
    Continue,
}

/// How much the force rate of a load-controlled step may differ from that of an earlier
/// step (relative to the larger) for the time extrapolation to reach back to it.
const LOAD_RATE_CHANGE: f64 = 0.5;

/// The Newton driver's pieces and work space on one model.
#[derive(Debug)]
pub(crate) struct Newton<'m> {
    model: &'m Model,
    pub(crate) system: ConstrainedSystem,
    body: Body,
    constraint: Box<dyn Constraint + 'm>,
    /// Work space of the equation-sized vectors: right-hand side and prescribed values.
    rhs: Vec<f64>,
    aux: Vec<f64>,
    /// Marks of the equations the constraint replaces (work space).
    constrained: Vec<bool>,
    /// Relative residual of every pass of the last step attempted, with the active-set
    /// changes made before it.
    pub(crate) residuals: Vec<(f64, u32)>,
    /// Status changes proposed by the constraint (work space).
    flips: Vec<StatusFlip>,
    /// Load control's work space (equation-sized): the active candidates' vertical
    /// equations `v`, `K v`, and the depth column of the bordered system.
    v: Vec<f64>,
    kv: Vec<f64>,
    col: Vec<f64>,
    /// The depth column's solve `w` of the last load-controlled Newton iterate (the start
    /// of the next column's CG, in the same step or the next one), and whether it is
    /// set: carried across steps like the preconditioner's factor and forgotten with it
    /// ([`Newton::forget_carried`]), so that a replay from a checkpoint repeats the run.
    w_prev: Vec<f64>,
    w_ok: bool,
    /// The depth increment `dU` (mm) of the last bordered update: with `self.col` the
    /// depth's part of the update in `self.rhs` (the line search's to shorten).
    d_depth: f64,
    /// The contact stiffness `s` of the last bordered update (N/mm; 0 before one).
    stiffness: f64,
    /// The line search's evaluated iterate kept aside while a shorter one is tried
    /// (under a prescribed force, [`Newton::backtrack`]).
    kept: Kept,
}

/// An evaluated iterate kept aside by the line search: its displacement and depth, its
/// stresses and internal variables, and the body's pass outputs (swapped, not copied).
#[derive(Debug, Default)]
struct Kept {
    u: Vec<f64>,
    depth: f64,
    sigma: Vec<Vec4>,
    internal: Internal,
    pass: PassOutputs,
}

impl<'m> Newton<'m> {
    /// The driver on `model`: analyses its pattern once.
    ///
    /// # Errors
    /// [`FeError`] if the symbolic factorization fails.
    pub(crate) fn new(model: &'m Model) -> Result<Newton<'m>, FeError> {
        let n = model.dofs.n_eq;
        Ok(Newton {
            model,
            system: ConstrainedSystem::new(model)?,
            body: Body::new(model),
            constraint: constraint::for_model(model),
            rhs: vec![0.0; n],
            aux: vec![0.0; n],
            constrained: vec![false; n],
            residuals: Vec::new(),
            flips: Vec::new(),
            v: Vec::new(),
            kv: Vec::new(),
            col: Vec::new(),
            w_prev: Vec::new(),
            w_ok: false,
            d_depth: 0.0,
            stiffness: 0.0,
            kept: Kept::default(),
        })
    }

    /// Forgets what one step hands the next besides its state: the preconditioner's
    /// factor and refresh history ([`ConstrainedSystem::forget_preconditioner`]) and the
    /// last depth column (the start of the next column's CG). A run, and every stretch
    /// a replay may start from, begins with it: what follows then depends on the state
    /// alone. (The first solve after it factorizes, and a direct solve does not read the
    /// carried column: forgetting the column is a safeguard, should that change.)
    pub(crate) fn forget_carried(&mut self) {
        self.system.forget_preconditioner();
        self.w_ok = false;
    }

    /// Solves one step: from `spec.state` to `spec.t1` at the depth `spec.depth`.
    ///
    /// # Errors
    /// A [`StepFailure`] the caller answers by cutting the step.
    pub(crate) fn step(
        &mut self,
        spec: &StepSpec<'_>,
        timing: &mut Timing,
    ) -> Result<(State, StepRecord), StepFailure> {
        let state = spec.state;
        let dt = spec.t1 - state.t;
        self.system.begin_step(spec.load.is_some());
        self.stiffness = 0.0;
        let mut it = Iteration {
            u: state.u.clone(),
            depth: spec.depth,
            sigma: state.sigma.clone(),
            internal: state.internal.clone(),
            set: state.set.clone(),
            seen: Vec::new(),
            changes: 0,
            iterations: 0,
            single_change: false,
        };
        // predictor: activate nodes that the new depth makes penetrate, with the surface
        // displacement extrapolated from the last increment (at the start of a configured
        // segment, scaled as the drive scaled the depth)
        let last = &state.past[0];
        let restart = spec.load.and_then(|l| l.restart);
        let force_prescribed = spec.load.is_some_and(|l| l.is_force());
        let ratio = match restart {
            Some(q) => q,
            None if last.dt > 0.0 => dt / last.dt,
            None => 0.0,
        };
        // under a prescribed force (not at a restart) the nodes are activated at a depth no
        // deeper than the run's mean depth rate over its last load-controlled steps
        // gives: a coarse contact's depth increments alternate as nodes touch down (R2's
        // reference mesh: 3.3e-3 to 1.0e-2 mm per step), and a node activated by an
        // overshooting guess costs more than one that joins at the set check (Newton
        // stalls against it under the line search: the 13th Pdot/P step 17 iterations
        // against 10, docs/validation-load-control.md §12)
        let pdepth = if restart.is_none() && force_prescribed && last.dt > 0.0 {
            let (sum, n) = state
                .past
                .iter()
                .take_while(|p| p.dt > 0.0 && p.load)
                .fold((0.0, 0usize), |(s, n), p| (s + p.depth / p.dt, n + 1));
            if n > 0 {
                spec.depth.min(state.depth + sum / n as f64 * dt)
            } else {
                spec.depth
            }
        } else {
            spec.depth
        };
        self.constraint
            .predict(&mut it.set, &it.u, &last.du, ratio, pdepth);
        // a force prescribed out of contact needs the trigger; the frame's spring
        // (a compliant depth drive) carries the step from anywhere
        let triggered = force_prescribed && !it.set.active.contains(&true);
        if triggered {
            // load control out of contact: the trigger moves the punch to where its first
            // candidate touches (a hair beyond), where the contact stiffness is positive
            it.depth = touch_depth(self.model, &it.u) + 1e-9 * self.model.gap_length();
            self.constraint
                .predict(&mut it.set, &it.u, &last.du, ratio, it.depth);
        }
        let as_law = spec.mat.as_law();
        let affine = self
            .body
            .begin_step(self.model, as_law, spec.c, state, dt)?;
        let law = StepLaw {
            mat: spec.mat,
            law: as_law,
            c: spec.c,
            state,
            dt,
            affine,
        };
        // a nonlinear law starts Newton from the displacement extrapolated in time, while
        // the depth keeps its rate (within a segment): by the polynomial of degree 1 to 3
        // through the last states that predicted the last step best (in R2's settled creep
        // and relaxation the higher degrees predict 5-15 times closer: a Newton iteration
        // fewer per step). Affine laws converge in one solve from anywhere and keep their
        // cheap first pass.
        let rate = match spec.load {
            // the spring's prescribed depth keys the extrapolation as a depth rate does
            Some(Load {
                spring: Some(spring),
                ..
            }) => spring.rate,
            // a hold's force change is the last step's residual: zero
            Some(load) if dt > 0.0 => {
                let df = load.force - state.force;
                if df.abs() <= 1e-6 * load.force.abs() {
                    0.0
                } else {
                    df / dt
                }
            }
            None if dt > 0.0 => (spec.depth - state.depth) / dt,
            _ => 0.0,
        };
        let mut extra = Extrapolation::new(
            state,
            dt,
            rate,
            law.affine.is_some(),
            force_prescribed,
            it.u.len(),
        );
        if let Some(q) = restart {
            extra = extra.restarted(state, q, law.affine.is_some(), it.u.len());
        }
        match spec.guess {
            Some((u0, u1)) if law.affine.is_none() => {
                for ((x, a), b) in it.u.iter_mut().zip(u0).zip(u1) {
                    *x += b - a;
                }
            }
            _ => {
                extra.apply(state, &mut it.u);
                if spec.load.is_some() && !triggered {
                    // under load control the depth is an unknown: it starts from the same
                    // polynomial as the displacement, so that the first iterate is one
                    // state of the extrapolated motion (the drive's linear guess left a
                    // depth inconsistent with it: R2 took 38% more iterations)
                    if let Some(d) = extra.depth(state) {
                        it.depth = d;
                    }
                }
            }
        }
        it.seen.push(it.set.clone());
        self.residuals.clear();
        let mut last: Option<(Residual, u32)> = None;
        // from the trigger, penetrating nodes join as the depth moves down until the
        // first complementarity check, which then owns the set (`join_penetrating`)
        // (vertical contact only: on a finite-strain sphere under normal contact,
        // `gradient_load_material`'s J2 case, the joined first step changed which later
        // steps were cut, and one finite-difference run cut once more than its base)
        let mut joining = triggered && self.model.contact == ContactKind::Vertical;
        let mut stall = Stall::default();
        loop {
            // every pass evaluates the current iterate once, then checks or solves
            let mut r = self.evaluate(spec, &law, &mut it, timing)?;
            if let Some(prev) = last {
                r = self.backtrack(spec, &law, &mut it, timing, r, prev)?;
            }
            last = Some((r, it.changes));
            if it.iterations > 0 {
                let view = iterate(&self.body.f_int, spec, &it);
                let targets_met = self.constraint.targets_met(&it.set, &view);
                let converged = r.rel <= spec.opts.residual_tol || r.res == 0.0;
                // complementarity is checked once equilibrium for the current set is loosely
                // met (semi-smooth Newton): a wrong set is corrected without a full solve
                if targets_met && (converged || r.rel <= spec.opts.active_set_check_tol) {
                    joining = false;
                    if let Check::Converged = self.check_sets(spec, &mut it, converged)? {
                        if let Some(load) = spec.load {
                            self.depth_within_specimen(it.depth, load.target(it.depth))?;
                        }
                        return Ok(self.finish(spec, &law, it, r, rate, &extra));
                    }
                }
            }
            if it.iterations as usize >= spec.opts.max_iterations {
                return Err(StepFailure::Newton { residual: r.rel });
            }
            if spec.load.is_none() && stall.stalled(&r, &it) {
                return Err(StepFailure::Stalled {
                    residual: r.rel,
                    iterations: it.iterations,
                });
            }
            it.iterations += 1;
            self.solve(spec, &law, &mut it, r, timing)?;
            if joining && self.d_depth > 0.0 {
                self.join_penetrating(spec, &mut it);
            }
        }
    }

    /// Backtracking for a material whose residual switches branches (a point of the
    /// iterate in [`Regime::Elastic`] or [`Regime::Plastic`]): when a Newton update raised
    /// the merit above that of the iterate before (`prev.0`, with the contact set of
    /// `prev.1` unchanged), the update is halved, up to four times, while that lowers it.
    /// A rate-independent law's points switch between the elastic and plastic branches of
    /// their residual, where the consistent tangent jumps: a full step across the switch
    /// can overshoot into a cycle the iteration never leaves (R2's mesh and history: 60
    /// iterations at a relative residual of 1, then a step cut). Under depth control the
    /// update halved is the free equations' part (the constrained equations keep their
    /// prescribed values); under load control and through the frame's spring it is the
    /// bordered update, the displacement and the depth together ([`Newton::shorten`]).
    /// The merit is the relative residual under depth control (`r.rel`, the largest
    /// component over the largest internal force), and under load control the Euclidean
    /// norm of the bordered residual in N (`r.norm`: equilibrium, the constraint's rows
    /// and the force equation, [`Newton::evaluate`]); docs/solver.md, "The line search".
    /// Under depth control and the frame's spring, smooth materials and the laws' paths
    /// (`as_law`) are left as they are (their bits unchanged); under a prescribed force
    /// every law's update that raised the merit is shortened: Norton-Hoff's first iterate
    /// of a Pdot/P step where a third node had just touched down sat 9 increments deep,
    /// and its updates raised the norm 15x, then cycled until the step was cut
    /// (docs/validation-load-control.md §12). Every update that lowered the merit is
    /// left as it is. Returns the residual of the iterate kept.
    ///
    /// # Errors
    /// A failed local update of a shortened iterate, as [`Newton::evaluate`].
    fn backtrack(
        &mut self,
        spec: &StepSpec<'_>,
        law: &StepLaw<'_>,
        it: &mut Iteration,
        timing: &mut Timing,
        r: Residual,
        prev: (Residual, u32),
    ) -> Result<Residual, StepFailure> {
        let switching = it.internal.regime.iter().any(|g| *g != Regime::Smooth);
        // the merit: the relative largest residual under depth control (its bits kept);
        // the Euclidean norm of the bordered residual in N under load control, where the
        // largest component relative to the largest internal force saturates at 1 while
        // the iterate is far off (R2's Voce: 1 cut sub-step and 114 factorizations on
        // the largest component, none and 63 on the norm)
        let merit = |r: &Residual| if spec.load.is_some() { r.norm } else { r.rel };
        let m0 = merit(&prev.0);
        // under a prescribed force every nonlinear law's diverging update is shortened
        // too (a smooth law's, Norton-Hoff's through `as_law`, included): see above
        let eligible = if spec.load.is_some_and(|l| l.is_force()) {
            true
        } else {
            switching && law.law.is_none()
        };
        if !eligible || it.changes != prev.1 || merit(&r) <= m0 {
            return Ok(r);
        }
        // under a prescribed force the evaluated iterate is kept aside while a shorter
        // one is tried, and swapped back when that one is worse: one Gauss-point pass
        // fewer per rejected halving (R2's reference mesh, trigger and Pdot/P: about
        // half of the halvings tried, docs/validation-load-control.md §12). Elsewhere
        // the iterate is moved back and evaluated again (its bits kept).
        let keep = spec.load.is_some_and(|l| l.is_force());
        let mut best = r;
        let mut f = 1.0;
        for _ in 0..4 {
            f *= 0.5;
            timing.halvings += 1;
            if keep {
                self.keep_aside(it);
            }
            self.shorten(spec, it, f);
            let r1 = self.evaluate(spec, law, it, timing)?;
            if merit(&r1) >= merit(&best) {
                // undo this halving: the longer step was better
                if keep {
                    self.take_back(it);
                    return Ok(self.measure(spec, it));
                }
                self.shorten(spec, it, -f);
                return self.evaluate(spec, law, it, timing);
            }
            best = r1;
            if merit(&best) <= m0 {
                break;
            }
        }
        Ok(best)
    }

    /// Moves the iterate back by the fraction `f` of the last Newton update (forward for
    /// a negative `f`). Under depth control: the free equations' part of the update (in
    /// `self.rhs`; the constrained equations keep their prescribed values). Under load
    /// control (and through the frame's spring) the update is bordered, `du_1 + dU du_2`
    /// with the depth moving by `dU` ([`Newton::border`]): the depth moves back by `f dU`,
    /// the free equations by `f` of their update, and the constrained equations by `f`
    /// of the depth column's part `dU du_2` only, so that they keep meeting their
    /// targets at the shortened depth (the first solve's prescribed increments, which
    /// close the gaps at the iterate's depth, stay whole).
    fn shorten(&self, spec: &StepSpec<'_>, it: &mut Iteration, f: f64) {
        let bordered = spec.load.is_some();
        for (d, &e) in self.model.dofs.eq.iter().enumerate() {
            if e == NO_EQ {
                continue;
            }
            let e = e as usize;
            if !self.constrained[e] {
                it.u[d] -= f * self.rhs[e];
            } else if bordered {
                it.u[d] -= f * (self.d_depth * self.col[e]);
            }
        }
        if bordered {
            it.depth -= f * self.d_depth;
        }
    }

    /// A load-controlled step from the trigger whose update moved the punch down: the
    /// inactive candidates the iterate's depth makes penetrate join the contact set at
    /// once. From the trigger a single node carries the force, and its small stiffness
    /// throws the depth far beyond the contact that then forms, where the set check only
    /// comes once equilibrium is loosely met (a 40 x 40 mesh: 12 updates growing the
    /// depth threefold each up to 0.62 mm for a step whose depth is 3.3e-3 mm, then 66
    /// nodes in contact and 23 more iterations releasing two at a time); joined as the
    /// depth moves, the contact's stiffness stops the depth near its solution. Only until
    /// the step's first complementarity check: joining after it could undo its releases
    /// into a cycle of sets.
    fn join_penetrating(&mut self, spec: &StepSpec<'_>, it: &mut Iteration) {
        let before = it.set.active().count();
        self.constraint
            .predict(&mut it.set, &it.u, &spec.state.past[0].du, 0.0, it.depth);
        if it.set.active().count() != before {
            it.changes += 1;
        }
    }

    /// Evaluates the iterate (stresses, internal force, the constraint's gaps) and its
    /// residual on the equations the constraint does not replace, plus the constraint's
    /// own rows, relative to the largest internal force (or the largest seen in converged
    /// steps when the forces vanish); records it in `self.residuals`.
    fn evaluate(
        &mut self,
        spec: &StepSpec<'_>,
        law: &StepLaw<'_>,
        it: &mut Iteration,
        timing: &mut Timing,
    ) -> Result<Residual, StepFailure> {
        let model = self.model;
        timing.passes += 1;
        let tl = std::time::Instant::now();
        self.body
            .evaluate(model, law, &it.u, &mut it.sigma, &mut it.internal)
            .map_err(|f| match f {
                StepFailure::Inverted { qp, det, .. } => StepFailure::Inverted {
                    qp,
                    det,
                    depth: it.depth,
                },
                other => other,
            })?;
        timing.local += tl.elapsed().as_secs_f64();
        Ok(self.measure(spec, it))
    }

    /// Keeps the evaluated iterate `it` aside ([`Kept`]): its displacement and depth
    /// copied, its stresses, internal variables and the body's pass outputs swapped out
    /// (the next evaluation overwrites the buffers swapped in).
    fn keep_aside(&mut self, it: &mut Iteration) {
        let k = &mut self.kept;
        k.u.clone_from(&it.u);
        k.depth = it.depth;
        if k.sigma.len() != it.sigma.len() {
            k.sigma.clone_from(&it.sigma);
        }
        if k.internal.alpha.len() != it.internal.alpha.len()
            || k.internal.regime.len() != it.internal.regime.len()
        {
            k.internal.clone_from(&it.internal);
        }
        std::mem::swap(&mut it.sigma, &mut k.sigma);
        std::mem::swap(&mut it.internal, &mut k.internal);
        self.body.swap_pass(&mut k.pass);
    }

    /// Returns to the iterate kept aside by [`Newton::keep_aside`], as it was evaluated.
    fn take_back(&mut self, it: &mut Iteration) {
        let k = &mut self.kept;
        std::mem::swap(&mut it.u, &mut k.u);
        it.depth = k.depth;
        std::mem::swap(&mut it.sigma, &mut k.sigma);
        std::mem::swap(&mut it.internal, &mut k.internal);
        self.body.swap_pass(&mut k.pass);
    }

    /// The rest of [`Newton::evaluate`] after the Gauss-point pass: the constraint's gaps
    /// and the residual, recorded in `self.residuals`.
    fn measure(&mut self, spec: &StepSpec<'_>, it: &Iteration) -> Residual {
        let model = self.model;
        let view = iterate(&self.body.f_int, spec, it);
        self.constraint.update(&it.set, &view);
        // residual on free, unconstrained equations (normal contact: the tangential
        // component at the active nodes)
        self.constrained.fill(false);
        self.constraint
            .constrained_equations(&it.set, &mut self.constrained);
        let mut res: f64 = 0.0;
        let mut fmax: f64 = 0.0;
        let mut sq = 0.0;
        for (d, &e) in model.dofs.eq.iter().enumerate() {
            if e != NO_EQ {
                fmax = fmax.max(self.body.f_int[d].abs());
                if !self.constrained[e as usize] {
                    res = res.max(self.body.f_int[d].abs());
                    sq += self.body.f_int[d] * self.body.f_int[d];
                }
            }
        }
        let rc = self.constraint.residual(&it.set, &view);
        sq += rc * rc;
        res = res.max(rc);
        if let Some(load) = spec.load {
            // the drive's row: the punch force meets the prescribed one
            // (through the frame's spring: the force the spring carries at this depth,
            // less its rounding floor, `Load::floor`)
            let target = load.target(it.depth);
            let off = (punch_force(model, &it.set, view.f_int) - target).abs();
            let off = (off - load.floor(it.depth)).max(0.0);
            sq += off * off;
            res = res.max(off);
        }
        let scale = fmax.max(spec.state.f_scale);
        let rel = if scale > 0.0 { res / scale } else { res };
        self.residuals.push((rel, it.changes));
        Residual {
            res,
            fmax,
            rel,
            norm: sq.sqrt(),
        }
    }

    /// The complementarity check of a pass: tensile reactions and penetrating gaps change
    /// the contact set (all of them, or after a repeated set the worst one only), and once
    /// the set holds the constraint's second partition (stick/slip) may change.
    ///
    /// # Errors
    /// [`StepFailure::Cycling`] when a set repeats while changing one node at a time;
    /// the constraint's [`Constraint::accept`] failure.
    fn check_sets(
        &mut self,
        spec: &StepSpec<'_>,
        it: &mut Iteration,
        converged: bool,
    ) -> Result<Check, StepFailure> {
        let model = self.model;
        let view = iterate(&self.body.f_int, spec, it);
        let depth = it.depth;
        let force = punch_force(model, &it.set, view.f_int);
        let tol = Tolerances {
            lambda: spec.opts.lambda_tol * force.abs().max(1e-300),
            gap: spec.opts.gap_tol * depth.abs().max(model.gap_length()),
            force: force.abs().max(1e-300),
        };
        let mut worst: Option<(usize, f64)> = None;
        let mut violations = Vec::new();
        for k in 0..it.set.active.len() {
            let v = if it.set.active[k] {
                let lam = self.constraint.lambda(k, &view);
                if lam < -tol.lambda && !self.constraint.holds_under_tension(&it.set, k) {
                    -lam / tol.force
                } else {
                    0.0
                }
            } else {
                let g = self.constraint.gap(k, &view);
                if g < -tol.gap {
                    -g / depth.abs().max(1e-12)
                } else {
                    0.0
                }
            };
            if v > 0.0 {
                violations.push(k);
                if worst.is_none_or(|(_, w)| v > w) {
                    worst = Some((k, v));
                }
            }
        }
        // the second partition (stick/slip), checked once the contact set holds
        self.flips.clear();
        if violations.is_empty() {
            self.constraint
                .check_status(&it.set, &view, &tol, &mut self.flips);
        }
        if violations.is_empty() && self.flips.is_empty() && converged {
            self.constraint.accept(&it.set, &view)?;
            return Ok(Check::Converged);
        }
        if !violations.is_empty() {
            if it.single_change {
                it.set.toggle(worst.map_or(0, |w| w.0));
            } else {
                for k in violations {
                    it.set.toggle(k);
                }
            }
        } else if !self.flips.is_empty() {
            if it.single_change {
                let flip = self
                    .flips
                    .iter()
                    .copied()
                    .max_by(|a, b| a.2.total_cmp(&b.2));
                if let Some((k, st, _)) = flip {
                    it.set.slip[k] = st;
                }
            } else {
                for &(k, st, _) in &self.flips {
                    it.set.slip[k] = st;
                }
            }
        } else {
            return Ok(Check::Continue);
        }
        it.changes += 1;
        if it.seen.contains(&it.set) {
            if it.single_change {
                return Err(StepFailure::Cycling {
                    changes: it.changes,
                });
            }
            it.single_change = true;
        }
        it.seen.push(it.set.clone());
        Ok(Check::Continue)
    }

    /// The converged step: its record, and the next state with the increment's history
    /// for the extrapolation.
    fn finish(
        &self,
        spec: &StepSpec<'_>,
        law: &StepLaw<'_>,
        it: Iteration,
        r: Residual,
        rate: f64,
        extra: &Extrapolation,
    ) -> (State, StepRecord) {
        let model = self.model;
        let state = spec.state;
        let dt = spec.t1 - state.t;
        let view = iterate(&self.body.f_int, spec, &it);
        let mut rec = record(
            model,
            &it.set,
            view.f_int,
            [spec.t1, dt, it.depth],
            [it.iterations, it.changes],
        );
        self.constraint.record(&it.set, &view, &mut rec);
        let f_scale = state.f_scale.max(r.fmax);
        let du: Vec<f64> = it.u.iter().zip(&state.u).map(|(a, b)| a - b).collect();
        let order = extra.best_order(state, &du);
        // the older increments serve the extrapolation of nonlinear laws only
        let older = |p: &Increment| Increment {
            du: if law.affine.is_none() {
                p.du.clone()
            } else {
                Vec::new()
            },
            ..*p
        };
        let (p0, p1) = (older(&state.past[0]), older(&state.past[1]));
        let force = rec.force;
        let ddepth = it.depth - state.depth;
        let next = State {
            t: spec.t1,
            f_scale,
            u: it.u,
            sigma: it.sigma,
            internal: it.internal,
            f_int: self.body.f_int.clone(),
            set: it.set,
            past: [
                Increment {
                    du,
                    dt,
                    rate,
                    depth: ddepth,
                    load: spec.load.is_some_and(|l| l.is_force()),
                },
                p0,
                p1,
            ],
            order,
            depth: it.depth,
            force,
            stiffness: if spec.load.is_some_and(|l| l.is_force()) {
                self.stiffness
            } else {
                0.0
            },
            xi: self.constraint.stick_points(),
        };
        (next, rec)
    }

    /// One Newton solve: the tangent, the constraints and their prescribed increments, an
    /// inexact solve to the forcing term `eta = |R|` (relative), and the update of the
    /// iterate.
    ///
    /// # Errors
    /// [`StepFailure::Linear`] when the factorization or the solve fails or the iterate
    /// is no longer finite.
    fn solve(
        &mut self,
        spec: &StepSpec<'_>,
        law: &StepLaw<'_>,
        it: &mut Iteration,
        r: Residual,
        timing: &mut Timing,
    ) -> Result<(), StepFailure> {
        let model = self.model;
        let depth = it.depth;
        // the element tangents of this iterate (finite strain) are formed only now that a
        // solve needs them (a converged pass returned before)
        timing.local += self
            .body
            .set_tangent(model, law, &it.sigma, &mut self.system);
        self.system.set_active(model, &it.set.active);
        let view = iterate(&self.body.f_int, spec, it);
        self.constraint.impose(&it.set, &view, &mut self.system);
        // reusable tangents factorize (or reuse) exactly; others prepare inexact solves
        self.system
            .prepare_inexact(model)
            .map_err(|e: FeError| StepFailure::Linear(e.to_string()))
            .map_err(|f| distortion(model, f, &it.u, depth))?;
        // right-hand side: -R on free equations, prescribed increments on active ones
        self.aux.fill(0.0);
        self.constraint.prescribe(&it.set, &view, &mut self.aux);
        for (d, &e) in model.dofs.eq.iter().enumerate() {
            if e != NO_EQ {
                self.rhs[e as usize] = -self.body.f_int[d];
            }
        }
        // forcing term eta = |R| (relative): inexact Newton stays quadratic
        // (Dembo, Eisenstat & Steihaug 1982); near convergence no tighter than
        // what brings the residual a decade below the tolerance (no oversolving)
        let rel = r.rel;
        let eta = rel
            .max(0.1 * spec.opts.residual_tol / rel.max(1e-300))
            .clamp(1e-12, 0.1);
        // load control in the capacitance mode: the step and the depth column in one
        let fused = match spec.load {
            Some(load) => self.border_capacitance(it, load, spec.state.depth)?,
            None => false,
        };
        if !fused {
            self.system
                .solve_inexact(model, &mut self.rhs, &self.aux, eta)
                .map_err(|e: FeError| StepFailure::Linear(e.to_string()))
                .map_err(|f| distortion(model, f, &it.u, depth))?;
            if let Some(load) = spec.load {
                self.border(it, load, spec.state.depth, eta)?;
            }
        }
        for (d, &e) in model.dofs.eq.iter().enumerate() {
            if e != NO_EQ {
                it.u[d] += self.rhs[e as usize];
            }
        }
        if it.u.iter().any(|v| !v.is_finite()) {
            return Err(StepFailure::Linear("non-finite displacement".into()));
        }
        Ok(())
    }
}

impl Newton<'_> {
    /// Load control's bordered update (docs/theory.md §13): the first solve left
    /// `du_1` in `self.rhs` (`K du_1 = -R` with the constraint's increments); the depth
    /// column `du_2 = w - v` comes from one more solve with the same factorization,
    /// `K w = K v` with the constrained equations held (`v`: 1 on the active candidates'
    /// vertical equations: the constraints see the punch depth as a vertical translation
    /// of their nodes), and the force row `F + g . du = P` with `g . du = -(K v) . du`
    /// (the linearized sum of the vertical reactions) gives the depth increment
    /// `dU = (P - F - g . du_1) / s` over the Schur complement `s = g . du_2 = v . K v -
    /// (K v) . w`, the contact stiffness `dF/dU`. Leaves `du_1 + dU du_2` in `self.rhs`
    /// and moves the iterate's depth by `dU`, limited to three times its distance from
    /// the step's start depth `start` (or a tenth of the first element's width).
    ///
    /// Through the frame's spring (a compliant depth drive, `drive.rs`) the row is
    /// `F + g . du = (H - U - dU) / Cf`: the same update with `P` the spring's force at
    /// the iterate's depth and `s + 1 / Cf` for `s` (docs/theory.md §13.7). The spring
    /// keeps it positive out of contact (`s = 0`: the depth moves to `H`), and no limit
    /// applies.
    ///
    /// # Errors
    /// [`StepFailure::Load`] when `s` is not positive (no contact, or none that carries
    /// load) or the depth leaves the specimen; [`StepFailure::Linear`] from the solve.
    fn border(
        &mut self,
        it: &mut Iteration,
        load: Load,
        start: f64,
        eta: f64,
    ) -> Result<(), StepFailure> {
        let model = self.model;
        self.border_space();
        if !load.is_force() && it.set.active().next().is_none() {
            // the spring alone: out of contact the depth column and `s` vanish
            self.col.fill(0.0);
            let du = load.target(it.depth) / load.stiffness();
            it.depth += du;
            self.d_depth = du;
            return Ok(());
        }
        self.v.fill(0.0);
        for k in it.set.active() {
            if let Some(e) = model.dofs.equation(2 * model.candidates[k] + 1) {
                self.v[e] = 1.0;
            }
        }
        // `K v`: the sum of the active vertical equations' columns of `K` (a handful of
        // entries, not a product over the whole matrix)
        self.kv.fill(0.0);
        let values = self.system.k_values();
        for k in it.set.active() {
            if let Some(e) = model.dofs.equation(2 * model.candidates[k] + 1) {
                let kv = &mut self.kv;
                kv[e] += values[model.pattern.diag[e]];
                model
                    .pattern
                    .for_each_off_diagonal(e, |i, p| kv[i] += values[p]);
            }
        }
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let vkv = dot(&self.v, &self.kv);
        // the depth column `du_2 = w - v` into `self.col`: from the capacitance mode's
        // stored columns when it holds the system (an affine law under vertical contact:
        // no solve), else by one more solve
        let s = match self.system.depth_column_capacitance(&self.v, &mut self.col) {
            Some(s) => s,
            None => {
                self.col.copy_from_slice(&self.kv);
                // the first solve's prescribed increments are spent: the depth column
                // holds its constrained equations at zero. Under vertical contact `s` is
                // the column's energy `du_2 . K du_2` (the reactions of a unit settlement:
                // stationary, so its error is second order in the solve's, and a sum
                // without cancellation): the column is solved to Newton's forcing term,
                // at most 1e-2 (R2, load_vs_depth: Newton iterations 255 at the forcing
                // term, 236 at 1e-2, 221 at 1e-4 but 96 factorizations against 31,
                // since CG then falls back to one; 1e-9 before). Otherwise
                // `s = v . K v - (K v) . w` is a difference of two close numbers: the
                // column is solved tighter.
                let energy = !self.system.has_frames();
                let tol = if energy { eta.min(1e-2) } else { eta.min(1e-9) };
                self.aux.fill(0.0);
                // CG starts from the last iterate's column (the tangent moves little
                // between iterates; R2's load and hold under Norton-Hoff with the refresh
                // of `refresh.rs`: 651 CG iterations and 228 Newton iterations against 975
                // and 236 from the preconditioner's solution), also after a set change,
                // whose newly held equations the solve sets to zero (R2's reference mesh,
                // trigger and Pdot/P: 352 CG iterations against 365), and at a step's
                // first iterate from the last step's column (the same mesh: 21
                // factorizations, 303 CG iterations and 120 Newton iterations against 25,
                // 335 and 123 from the preconditioner's solution; the column's CG counts
                // in the refresh policy, `refresh.rs`)
                if self.w_ok {
                    self.system.solve_inexact_from(
                        model,
                        &mut self.col,
                        &self.aux,
                        tol,
                        &self.w_prev,
                    )
                } else {
                    self.system
                        .solve_inexact(model, &mut self.col, &self.aux, tol)
                }
                .map_err(|e: FeError| StepFailure::Linear(e.to_string()))?;
                self.w_prev.copy_from_slice(&self.col);
                self.w_ok = true;
                let s = vkv - dot(&self.kv, &self.col);
                // the energy `du_2 . K du_2` of the solved column: `K du_2 = -r` on the
                // free equations (`r` the residual CG left) and its reactions sum to `-s`
                // on the constrained ones, so `du_2 . K du_2 = s - w . r` (`w` zero on
                // the constrained equations): the same number without a product over the
                // whole matrix (0 after a direct solve, exact to round-off)
                let e = s - self.system.last_residual_dot(&self.col);
                for (c, v) in self.col.iter_mut().zip(&self.v) {
                    *c -= v;
                }
                if energy { e } else { s }
            }
        };
        let g_du1 = -dot(&self.kv, &self.rhs);
        let f = punch_force(model, &it.set, &self.body.f_int);
        let border = Border {
            load,
            depth: it.depth,
            start,
            force: f,
            gap: model.gap_length(),
            n_active: it.set.active().count(),
        };
        self.stiffness = s;
        let du = border.depth_increment(g_du1, s, vkv)?;
        for (x, c) in self.rhs.iter_mut().zip(&self.col) {
            *x += du * c;
        }
        it.depth += du;
        self.d_depth = du;
        Ok(())
    }

    /// The bordered update in the capacitance mode ([`ConstrainedSystem::solve_bordered`]:
    /// one solve and one set of column updates for the step and the depth column, `g .
    /// du_1` from the step's multipliers, no product `K v`), in place of the step's solve
    /// and [`Newton::border`]; the same update to round-off. Returns `false` (nothing
    /// changed) where that mode does not hold the system (then the step solves as
    /// before).
    ///
    /// # Errors
    /// As [`Newton::border`].
    fn border_capacitance(
        &mut self,
        it: &mut Iteration,
        load: Load,
        start: f64,
    ) -> Result<bool, StepFailure> {
        let model = self.model;
        if it.set.active().next().is_none() {
            return Ok(false);
        }
        self.border_space();
        self.v.fill(0.0);
        for k in it.set.active() {
            if let Some(e) = model.dofs.equation(2 * model.candidates[k] + 1) {
                self.v[e] = 1.0;
            }
        }
        let border = Border {
            load,
            depth: it.depth,
            start,
            force: punch_force(model, &it.set, &self.body.f_int),
            gap: model.gap_length(),
            n_active: it.set.active().count(),
        };
        let mut stiffness = 0.0;
        let solved = self.system.solve_bordered(
            model,
            &self.v,
            &mut self.rhs,
            &self.aux,
            |g_du1, s, vkv| {
                stiffness = s;
                border.depth_increment(g_du1, s, vkv)
            },
        );
        if solved.is_some() {
            self.stiffness = stiffness;
        }
        let du = match solved {
            None => return Ok(false),
            Some(du) => du?,
        };
        // the depth column on the constrained equations (the line search's to shorten):
        // -1 on the active candidates' vertical equations, 0 on the others
        for (c, v) in self.col.iter_mut().zip(&self.v) {
            *c = -v;
        }
        it.depth += du;
        self.d_depth = du;
        Ok(true)
    }

    /// Load control's work space, sized to the equations.
    fn border_space(&mut self) {
        let n = self.model.dofs.n_eq;
        if self.v.len() != n {
            self.v = vec![0.0; n];
            self.kv = vec![0.0; n];
            self.col = vec![0.0; n];
            self.w_prev = vec![0.0; n];
            self.w_ok = false;
        }
    }

    /// A converged load-controlled depth must lie within the specimen.
    ///
    /// # Errors
    /// [`StepFailure::Load`] beyond half the specimen's height.
    fn depth_within_specimen(&self, depth: f64, force: f64) -> Result<(), StepFailure> {
        let height = -self
            .model
            .mesh
            .nodes
            .iter()
            .map(|x| x[1])
            .fold(0.0, f64::min);
        if !(depth.abs() < 0.5 * height) {
            return Err(StepFailure::Load(format!(
                "load control: the force {force} N drives the punch to the depth {depth} mm, \
                 beyond half the specimen's height ({height} mm): the contact cannot carry \
                 it (a larger specimen, or a smaller force)"
            )));
        }
        Ok(())
    }
}

/// The depth (mm) at which the punch touches the first candidate of the body deformed
/// by `u`: the smallest `phi(r_k) - u_z,k` (the vertical gap closes there).
/// What the bordered update's force row needs of the iterate besides `g . du_1` and the
/// contact stiffness `s` ([`Newton::border`], [`Newton::border_capacitance`]).
struct Border {
    load: Load,
    /// The iterate's depth and the step's start depth (mm).
    depth: f64,
    start: f64,
    /// The punch force of the iterate (N).
    force: f64,
    /// The first element's width (mm).
    gap: f64,
    n_active: usize,
}

impl Border {
    /// The depth increment `dU` from the force row `F + g . du_1 + s dU = P` (through
    /// the frame's spring: `s + 1 / Cf` for `s`, `P` the spring's force), limited under
    /// a prescribed force to three times the depth's distance from the step's start (or
    /// a tenth of the first element's width): from a trigger, a single node's small
    /// stiffness would throw the punch far beyond the contact that then forms.
    ///
    /// # Errors
    /// [`StepFailure::Load`] when the stiffness is not positive (`s` against `1e-12 v . K
    /// v` under a prescribed force).
    fn depth_increment(&self, g_du1: f64, s: f64, vkv: f64) -> Result<f64, StepFailure> {
        let (load, f, n_active) = (self.load, self.force, self.n_active);
        let force = load.target(self.depth);
        if !load.is_force() {
            let total = s + load.stiffness();
            if !(total.is_finite() && total > 0.0) {
                return Err(StepFailure::Load(format!(
                    "compliant depth control: the contact and frame stiffness dF/dU + 1/Cf \
                     = {total:.3e} N/mm is not positive at the depth {} mm with {n_active} \
                     nodes in contact",
                    self.depth
                )));
            }
            return Ok((force - f - g_du1) / total);
        }
        if !(s.is_finite() && s > 1e-12 * vkv.abs()) {
            return Err(StepFailure::Load(format!(
                "load control: the contact stiffness dF/dU = {s:.3e} N/mm is not positive \
                 at the depth {} mm with {n_active} nodes in contact: the force {force} N \
                 cannot be prescribed there (no contact that carries load); end the \
                 segment in depth control",
                self.depth
            )));
        }
        let cap = (2.0 * (self.depth - self.start).abs()).max(0.1 * self.gap);
        Ok(((force - f - g_du1) / s).clamp(-cap, cap))
    }
}

fn touch_depth(model: &Model, u: &[f64]) -> f64 {
    (0..model.candidates.len())
        .map(|k| model.candidate_profile[k] - u[2 * model.candidates[k] + 1])
        .fold(f64::INFINITY, f64::min)
}

/// The constraint's view of the iterate `it` of step `spec` with the internal force
/// `f_int`.
fn iterate<'a>(f_int: &'a [f64], spec: &StepSpec<'a>, it: &'a Iteration) -> Iterate<'a> {
    Iterate {
        u: &it.u,
        f_int,
        depth: it.depth,
        xi: &spec.state.xi,
    }
}

/// The punch force `F = -sum_k f_int,z,k` over the active candidates (N): always the
/// vertical one, whatever the contact direction.
fn punch_force(model: &Model, set: &ContactSet, f_int: &[f64]) -> f64 {
    set.active()
        .map(|k| -f_int[2 * model.candidates[k] + 1])
        .sum()
}

/// The record of a converged step with the vertical reactions `-f_int,z` of the active
/// candidates, their sum as the force and the reference radius of the outermost as the
/// contact radius (the constraint completes it, [`Constraint::record`]); `[t, dt, depth]`
/// and `[iterations, changes]`.
fn record(
    model: &Model,
    set: &ContactSet,
    f_int: &[f64],
    [t, dt, depth]: [f64; 3],
    [iterations, changes]: [u32; 2],
) -> StepRecord {
    let idx: Vec<u32> = set.active().map(|k| k as u32).collect();
    let lambda: Vec<f64> = idx
        .iter()
        .map(|&k| -f_int[2 * model.candidates[k as usize] + 1])
        .collect();
    StepRecord {
        t,
        dt,
        depth,
        force: lambda.iter().sum(),
        contact_radius: idx.last().map_or(0.0, |&k| model.candidate_r(k as usize)),
        active: idx,
        lambda,
        slip: Vec::new(),
        iterations,
        active_set_changes: changes,
        on_schedule: true,
        schedule_index: 0,
    }
}

/// Weights `w` of the increment `w_1 du_1 + w_2 du_2 + w_3 du_3` predicted over the next
/// step `dt` from the last increments `du_1` (latest), `du_2`, `du_3` of lengths
/// `h = [h_1, h_2, h_3]`: the polynomial of degree `order` (1 to 3) in time through the
/// last `order + 1` states, in Lagrange form with nodes `0, -h_1, -h_1 - h_2, ...` (the
/// current time at 0). Exact for a displacement polynomial of that degree, whatever the
/// step lengths; unused steps get weight 0.
pub(crate) fn extrapolation_weights(dt: f64, h: [f64; 3], order: usize) -> [f64; 3] {
    let tau = [0.0, -h[0], -h[0] - h[1], -h[0] - h[1] - h[2]];
    let lagrange: [f64; 4] = std::array::from_fn(|k| {
        if k > order {
            return 0.0;
        }
        (0..=order)
            .filter(|&j| j != k)
            .map(|j| (dt - tau[j]) / (tau[k] - tau[j]))
            .product()
    });
    // u_(n-k) = u_n - du_1 - ... - du_k, and the weights sum to 1
    [
        -(lagrange[1] + lagrange[2] + lagrange[3]),
        -(lagrange[2] + lagrange[3]),
        -lagrange[3],
    ]
}

/// Under finite strain a tangent that is no longer positive definite means extreme
/// distortion (or a loss of stability): the failure then names the most distorted element
/// of the iterate `u` at the depth `depth` and what to do.
fn distortion(model: &Model, f: StepFailure, u: &[f64], depth: f64) -> StepFailure {
    match f {
        StepFailure::Linear(m) if model.kinematics == Kinematics::Finite => {
            let (qp, det) = kinematics::smallest_det(&model.disc, u);
            StepFailure::Linear(format!(
                "{m}; under finite strain: extreme distortion at the depth {depth} mm, \
                 smallest det F = {det:.3e} in element {} (Gauss point {}): refine the mesh \
                 under the punch (specimen nr and nz, or elements_in_contact) or reduce the \
                 maximum depth",
                qp / QP_PER_ELEMENT,
                qp % QP_PER_ELEMENT
            ))
        }
        other => other,
    }
}

/// The step failure of a finite-strain evaluation at the depth `depth`.
pub(crate) fn finite_failure(f: FiniteFailure, depth: f64) -> StepFailure {
    match f {
        FiniteFailure::Inverted { qp, det } => StepFailure::Inverted { qp, det, depth },
        FiniteFailure::Local { qp, reason, factor } => StepFailure::Local { qp, reason, factor },
    }
}
