//! The time-stepped direct problem (P): the direct solver ([`DirectSolver`]: time
//! stepping over a schedule, adaptive step cutting, checkpoints and replay) around the
//! Newton driver of one step (`newton.rs`), and the recorded trajectory that the adjoint
//! replays.
//!
//! At step i (docs/theory.md §1): local backward-Euler updates at every Gauss point give
//! `sigma_i(u_i)` and the tangent `C_i`; equilibrium `sum_g w_g B^T sigma_i = G^T lambda_i`
//! holds on the free dofs; on the active set `A_i` the contact dofs are prescribed by the
//! model's contact constraint (`constraint/`: vertical, `u_z,k = phi(r_k) - U_i`; normal,
//! `m . u` at the gap along the punch's normal; normal with Coulomb friction) and
//! `lambda_k` is the nodal reaction. The set is updated by releasing nodes with
//! `lambda_k < 0` and activating nodes with `gap_k < 0`. The force is always the vertical
//! one, `F = -sum_k f_int,z,k`. docs/solver.md describes the pieces.
//!
//! Cost (see `ConstrainedSystem`): affine laws (elasticity, Maxwell) converge in one solve
//! per active set and start each step from the stored internal force; nonlinear laws start
//! Newton from the displacement extrapolated in time while the depth keeps its rate
//! (by the polynomial of degree 1 to 3 that predicted the last step best), and solve
//! the Newton systems by CG preconditioned with an earlier factorization, to a relative
//! residual equal to Newton's own (Dembo, Eisenstat & Steihaug 1982), so that Newton stays
//! quadratic with a fraction of the factorizations.

use indentify_laws::{Material, Regime, Vec4};

use crate::ContactError;
use crate::drive::{CompliantDrive, DepthDrive, Drive, ForceDrive, Frame};
use crate::friction::Status;
use crate::history::{LoadHistory, Schedule};
use crate::model::Model;
use crate::newton::{Newton, State, StepFailure, StepSpec};
use crate::refresh::RefreshRule;
use crate::system::ConstrainedSystem;

/// Numerical options of the direct solver.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverOptions {
    /// Relative tolerance on the equilibrium residual (inf-norm over free dofs, relative
    /// to the largest internal force component).
    pub residual_tol: f64,
    /// Maximum global Newton iterations per step (counting re-solves after active-set changes).
    pub max_iterations: usize,
    /// Maximum number of successive halvings of a step before giving up.
    pub max_cuts: u32,
    /// Relative residual below which the active set is checked (and corrected) before full
    /// convergence: semi-smooth Newton on equilibrium and complementarity together. The
    /// default 1e-2 corrects a wrong set early (R2 with the degree-2 predictor: 298 Newton
    /// iterations with 1e-6, 284 with 1e-2, same solution); a step converges only with its
    /// set verified at `residual_tol`.
    pub active_set_check_tol: f64,
    /// Relative tolerance on penetration before a node is activated: times the current
    /// depth, and never less than times the width of the first element under the punch
    /// ([`Model::gap_length`]), so that near depth 0 a node just released is not
    /// re-activated by a penetration of round-off size.
    pub gap_tol: f64,
    /// Relative tolerance on tensile reactions (times the current force) before a node is released.
    pub lambda_tol: f64,
    /// Keep stresses and displacements of every step (needed by the adjoint and VTU output).
    pub record_fields: bool,
    /// With `record_fields = false`, save the solver state every this many schedule steps
    /// (0: never) so that the adjoint can replay segments instead of storing every step.
    pub checkpoint_every: usize,
}

impl Default for SolverOptions {
    fn default() -> Self {
        SolverOptions {
            residual_tol: 1e-10,
            max_iterations: 60,
            max_cuts: 8,
            active_set_check_tol: 1e-2,
            gap_tol: 1e-10,
            lambda_tol: 1e-10,
            record_fields: true,
            checkpoint_every: 0,
        }
    }
}

/// What the solver records at each converged step.
#[derive(Clone, Debug, PartialEq)]
pub struct StepRecord {
    /// End time of the step (s).
    pub t: f64,
    /// Step length (s).
    pub dt: f64,
    /// Punch depth `U_i` (mm).
    pub depth: f64,
    /// Punch force `F_i = sum_k lambda_k` (N, full circle).
    pub force: f64,
    /// Contact radius: radius of the outermost active node (mm), 0 without contact.
    pub contact_radius: f64,
    /// Active candidates (indices into [`Model::candidates`]), increasing.
    pub active: Vec<u32>,
    /// Nodal reactions `lambda_k` of the active candidates (N), same order as `active`.
    pub lambda: Vec<f64>,
    /// Coulomb friction: the stick/slip status of the active candidates, same order as
    /// `active` (0 sticks, +-1 slips along +-t; [`crate::friction`]); empty without
    /// friction.
    pub slip: Vec<Status>,
    /// Global Newton iterations (linear solves) of this step.
    pub iterations: u32,
    /// Active-set changes during this step.
    pub active_set_changes: u32,
    /// `true` for steps ending on a time of the schedule, `false` for sub-steps (of a cut,
    /// or the schedule's own, [`Schedule::with_substeps`]).
    pub on_schedule: bool,
    /// Index of the schedule time this step ends at (or heads to, for a sub-step).
    pub schedule_index: usize,
}

/// Fields of one converged step, kept when [`SolverOptions::record_fields`] is set.
#[derive(Clone, PartialEq)]
pub struct StepFields {
    /// Displacements, all dofs (mm).
    pub u: Vec<f64>,
    /// Converged stress at every Gauss point (MPa, Mandel).
    pub sigma: Vec<Vec4>,
    /// Internal variables of a material that has them, point-major
    /// (`alpha[q * n .. (q + 1) * n]` at Gauss point `q`, `n` =
    /// [`Material::n_internal`]); empty for a stress-only law.
    pub alpha: Vec<f64>,
    /// The branch of the local residual each Gauss point's update took (held by the
    /// adjoint, docs/theory.md §12); empty for a stress-only law.
    pub regime: Vec<Regime>,
}

impl std::fmt::Debug for StepFields {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "StepFields {{ {} dofs, {} Gauss points }}",
            self.u.len(),
            self.sigma.len()
        )
    }
}

/// The recorded forward run: one record per converged step (sub-steps included), the
/// fields of the initial state (index 0) and of every step (`fields[i + 1]` for `steps[i]`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    /// Step records in time order.
    pub steps: Vec<StepRecord>,
    /// Fields: initial state then one per step (empty unless recorded).
    pub fields: Vec<StepFields>,
    /// Saved states every [`SolverOptions::checkpoint_every`] schedule steps (empty when 0).
    pub checkpoints: Vec<Checkpoint>,
    /// Parameters of the run.
    pub params: Vec<f64>,
    /// Wall-clock split of the run.
    pub timing: Timing,
}

impl Trajectory {
    /// The records ending on schedule times, in order (sub-steps of cut steps left out).
    pub fn schedule_steps(&self) -> impl Iterator<Item = &StepRecord> {
        self.steps.iter().filter(|s| s.on_schedule)
    }

    /// Force at each schedule time, starting with 0 for the initial state.
    pub fn forces(&self) -> Vec<f64> {
        std::iter::once(0.0)
            .chain(self.schedule_steps().map(|s| s.force))
            .collect()
    }

    /// Bytes held by the recorded fields and records (an estimate of the memory the
    /// adjoint's replay needs).
    pub fn recorded_bytes(&self) -> usize {
        let f: usize = self
            .fields
            .iter()
            .map(|f| 8 * f.u.len() + 32 * f.sigma.len() + 8 * f.alpha.len() + f.regime.len())
            .sum();
        let s: usize = self
            .steps
            .iter()
            .map(|s| std::mem::size_of::<StepRecord>() + 12 * s.active.len())
            .sum();
        let c: usize = self.checkpoints.iter().map(Checkpoint::bytes).sum();
        f + s + c
    }

    /// Total global iterations over all steps.
    pub fn total_iterations(&self) -> u64 {
        self.steps.iter().map(|s| s.iterations as u64).sum()
    }
}

/// Wall-clock time split of a run (s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timing {
    /// Local updates and internal forces.
    pub local: f64,
    /// Tangent assembly.
    pub assembly: f64,
    /// Numeric factorizations.
    pub factorization: f64,
    /// Triangular solves.
    pub solve: f64,
    /// Whole run.
    pub total: f64,
    /// Number of numeric factorizations.
    pub factorizations: usize,
    /// Conjugate-gradient iterations of the inexact solves (nonlinear laws: Newton
    /// iterations reuse an earlier factorization as preconditioner).
    pub cg_iterations: usize,
    /// Preconditioned CG solves (the inexact Newton solves that did not factorize first).
    pub pcg_solves: usize,
    /// Preconditioned CG solves that did not converge within their cap and factorized
    /// instead (fallbacks).
    pub pcg_fallbacks: usize,
    /// Gauss-point passes (evaluations of an iterate: one per Newton pass, and one per
    /// shortened iterate the line search tried).
    pub passes: usize,
    /// Shortened iterates the line search tried (docs/solver.md, "The line search").
    pub halvings: usize,
}

impl std::fmt::Display for Timing {
    /// `F factorizations, C CG iterations in S PCG solves (B fell back), P passes (H
    /// halvings); local .. ms, assembly .. ms, factorization .. ms, solve .. ms, total
    /// .. ms`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} factorizations, {} CG iterations in {} PCG solves ({} fell back), {} passes \
             ({} halvings); local {:.1} ms, assembly {:.1} ms, factorization {:.1} ms, solve \
             {:.1} ms, total {:.1} ms",
            self.factorizations,
            self.cg_iterations,
            self.pcg_solves,
            self.pcg_fallbacks,
            self.passes,
            self.halvings,
            1e3 * self.local,
            1e3 * self.assembly,
            1e3 * self.factorization,
            1e3 * self.solve,
            1e3 * self.total
        )
    }
}

/// A saved solver state at a schedule time, from which [`DirectSolver::replay`] recomputes
/// the following steps exactly (checkpointing bounds the memory of the adjoint's replay).
#[derive(Clone, PartialEq)]
pub struct Checkpoint {
    /// Schedule index of the saved state.
    pub schedule_index: usize,
    /// Number of trajectory steps (sub-steps included) before this state.
    pub steps_done: usize,
    /// The checkpointed run's cadence ([`SolverOptions::checkpoint_every`]): the run
    /// forgot what its Newton driver carries across steps at every checkpoint, and a
    /// replay forgets it at the same schedule indices (it also crosses the later ones).
    every: usize,
    state: State,
}

impl Checkpoint {
    /// Bytes held by the saved state.
    pub fn bytes(&self) -> usize {
        self.state.bytes()
    }
}

impl std::fmt::Debug for Checkpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Checkpoint {{ schedule_index: {}, steps_done: {} }}",
            self.schedule_index, self.steps_done
        )
    }
}

/// What a run tells the watch it runs under ([`DirectSolver::watched`]) after each
/// converged step: whether to stop there. A caller that needs only part of a run (an
/// optimizer's trial whose cost has already passed the value at which it is rejected)
/// ends it between steps this way, without a failing step and its cuts.
pub trait StepWatch {
    /// Called with the record of every converged step (sub-steps included), in time
    /// order; `true` ends the run after this step with [`ContactError::Stopped`].
    fn stop_after(&mut self, step: &StepRecord) -> bool;
}

/// The watch of the runs inside [`DirectSolver::watched`].
struct Watch<'m>(Box<dyn StepWatch + Send + 'm>);

impl std::fmt::Debug for Watch<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Watch")
    }
}

/// The direct solver on one model (borrowed once, at construction): time stepping with
/// step cutting, checkpoints and replay around the Newton driver of one step
/// (`newton.rs`), which keeps the symbolic factorization and the work space, so that
/// repeated runs (an optimizer's iterations) allocate and analyse nothing new.
#[derive(Debug)]
pub struct DirectSolver<'m> {
    model: &'m Model,
    newton: Newton<'m>,
    /// The watch of the runs inside [`DirectSolver::watched`] (none outside).
    watch: Option<Watch<'m>>,
}

impl<'m> DirectSolver<'m> {
    /// The constrained tangent system of the last step solved (see
    /// [`ConstrainedSystem::matrix`]).
    pub fn system(&self) -> &ConstrainedSystem {
        &self.newton.system
    }

    /// The constrained tangent system itself: [`crate::RecordedContact::exchange_factor`]
    /// exchanges its factorization with an adjoint's.
    pub(crate) fn system_mut(&mut self) -> &mut ConstrainedSystem {
        &mut self.newton.system
    }

    /// A solver for `model`, which it keeps for every run: analyses the model's pattern
    /// once.
    ///
    /// # Errors
    /// [`ContactError::Fe`] if the symbolic factorization fails.
    pub fn new(model: &'m Model) -> Result<DirectSolver<'m>, ContactError> {
        Ok(DirectSolver {
            model,
            newton: Newton::new(model)?,
            watch: None,
        })
    }

    /// Calls `run` (one or more runs or replays of this solver) under `watch`: after each
    /// converged step the watch may stop the run, which then ends with
    /// [`ContactError::Stopped`]. The steps a watched run takes are those of the same run
    /// without the watch, bit for bit, up to where it stops. Runs after this call (and
    /// before it) are not watched.
    pub fn watched<R>(
        &mut self,
        watch: Box<dyn StepWatch + Send + 'm>,
        run: impl FnOnce(&mut Self) -> R,
    ) -> R {
        let outer = self.watch.replace(Watch(watch));
        let r = run(self);
        self.watch = outer;
        r
    }

    /// Sets the rule that decides when a nonlinear law's inexact Newton solves refresh
    /// their factor (`refresh.rs`; [`RefreshRule::Auto`] by default).
    pub fn set_refresh_rule(&mut self, rule: RefreshRule) {
        self.newton.system.set_refresh_rule(rule);
    }

    /// Keeps (or stops keeping) a log of every preconditioned CG solve from now on
    /// ([`ConstrainedSystem::pcg_log`], through [`DirectSolver::system`]).
    pub fn keep_pcg_log(&mut self, keep: bool) {
        self.newton.system.keep_pcg_log(keep);
    }

    /// The model this solver runs.
    pub fn model(&self) -> &'m Model {
        self.model
    }

    /// The relative equilibrium residual of every Newton pass of the last step attempted
    /// (the last step of a run: its convergence history, for rate checks), each with the
    /// number of active-set changes made before that pass.
    pub fn last_residuals(&self) -> &[(f64, u32)] {
        &self.newton.residuals
    }

    /// Runs the whole schedule for parameters `c` of the material `mat` (a stress-only
    /// [`indentify_laws::Law`] as [`indentify_laws::LawMaterial`]: today's paths and bits).
    ///
    /// # Errors
    /// [`ContactError::Parameters`] for inadmissible parameters;
    /// [`ContactError::StepFailed`] when a step fails even after `max_cuts` halvings, carrying
    /// the trajectory up to the last converged step.
    pub fn run(
        &mut self,
        law: &dyn Material,
        c: &[f64],
        schedule: &Schedule,
        opts: &SolverOptions,
    ) -> Result<Trajectory, ContactError> {
        check_material(self.model, law, c)?;
        let model = self.model;
        let mut traj = Trajectory {
            params: c.to_vec(),
            ..Default::default()
        };
        let state = State::initial(model, law, schedule.t[0], schedule.depth[0]);
        let run = Run {
            law,
            c,
            schedule,
            drive: &DepthDrive(schedule),
            opts,
            guess: None,
        };
        let stretch = Stretch {
            j0: 0,
            j1: schedule.t.len() - 1,
            record: opts.record_fields,
            every: opts.checkpoint_every,
            checkpoints: true,
        };
        self.advance(&run, state, &stretch, &mut traj)?;
        Ok(traj)
    }

    /// Runs the schedule as [`DirectSolver::run`] does, but starts each step's Newton
    /// iterations of a nonlinear law from the increment `guess` (a converged trajectory of
    /// the same schedule at other parameters, with its fields recorded) took over the same
    /// step, instead of the time extrapolation: near the guess's parameters that increment
    /// is within `O(dc)` of the solution, where the extrapolation is within `O(dt^p)`.
    /// Steps the guess does not have (a step cut in either run) fall back to the
    /// extrapolation. The result is the same solution to the solver's tolerance
    /// ([`SolverOptions::residual_tol`]), not the same bits. Affine laws (one solve from
    /// anywhere), runs with checkpoints (a replay must repeat the run bit for bit) and a
    /// guess without fields run exactly as [`DirectSolver::run`].
    ///
    /// # Errors
    /// As [`DirectSolver::run`].
    pub fn run_warm(
        &mut self,
        law: &dyn Material,
        c: &[f64],
        schedule: &Schedule,
        opts: &SolverOptions,
        guess: &Trajectory,
    ) -> Result<Trajectory, ContactError> {
        let usable = opts.record_fields
            && opts.checkpoint_every == 0
            && guess.fields.len() == guess.steps.len() + 1
            && guess.fields[0].u.len() == self.model.disc.n_dofs();
        if !usable {
            return self.run(law, c, schedule, opts);
        }
        check_material(self.model, law, c)?;
        let mut traj = Trajectory {
            params: c.to_vec(),
            ..Default::default()
        };
        let state = State::initial(self.model, law, schedule.t[0], schedule.depth[0]);
        let run = Run {
            law,
            c,
            schedule,
            drive: &DepthDrive(schedule),
            opts,
            guess: Some(guess),
        };
        let stretch = Stretch {
            j0: 0,
            j1: schedule.t.len() - 1,
            record: true,
            every: 0,
            checkpoints: false,
        };
        self.advance(&run, state, &stretch, &mut traj)?;
        Ok(traj)
    }

    /// Runs a history whose segments prescribe the depth or the force
    /// ([`LoadHistory`]): under load control the depth of each step is an unknown solved
    /// with the force equation (docs/theory.md §13); the trajectory records the depths
    /// reached and the forces carried. A history of depth segments only runs as
    /// [`DirectSolver::run`] does on its schedule (the same bits).
    ///
    /// # Errors
    /// As [`DirectSolver::run`]; a load-controlled step whose force cannot be carried
    /// fails with the reason ([`ContactError::StepFailed`]). Checkpoints
    /// ([`SolverOptions::checkpoint_every`]) are replayed by
    /// [`DirectSolver::replay_history`].
    pub fn run_history(
        &mut self,
        law: &dyn Material,
        c: &[f64],
        history: &LoadHistory,
        opts: &SolverOptions,
    ) -> Result<Trajectory, ContactError> {
        if !history.is_load_controlled() {
            return self.run(law, c, &history.schedule, opts);
        }
        check_material(self.model, law, c)?;
        let schedule = &history.schedule;
        let mut traj = Trajectory {
            params: c.to_vec(),
            ..Default::default()
        };
        let state = State::initial(self.model, law, schedule.t[0], 0.0);
        let run = Run {
            law,
            c,
            schedule,
            drive: &ForceDrive(history),
            opts,
            guess: None,
        };
        let stretch = Stretch {
            j0: 0,
            j1: schedule.t.len() - 1,
            record: opts.record_fields,
            every: opts.checkpoint_every,
            checkpoints: true,
        };
        self.advance(&run, state, &stretch, &mut traj)?;
        Ok(traj)
    }

    /// Runs a schedule of machine depths through the instrument's frame ([`Frame`]):
    /// the recorded depth is `h + Cf F + vd (t - t0) + h0`, so each step solves
    /// `h + Cf F(h) = H(t)` with `H(t) = depth(t) - vd (t - t0) - h0` prescribed (the
    /// frame's spring in series with the contact, a bordered update on the same
    /// factorization, docs/theory.md §13.7). The trajectory records the punch depths `h`
    /// and the forces. With `Cf = 0` every step prescribes `H(t)` as [`DirectSolver::run`]
    /// does (its bits when `vd = h0 = 0`).
    ///
    /// # Errors
    /// As [`DirectSolver::run`]; [`ContactError::Input`] for a negative or non-finite
    /// compliance or a non-finite drift or offset.
    pub fn run_compliant(
        &mut self,
        law: &dyn Material,
        c: &[f64],
        schedule: &Schedule,
        frame: &Frame,
        opts: &SolverOptions,
    ) -> Result<Trajectory, ContactError> {
        check_frame(frame)?;
        check_material(self.model, law, c)?;
        let mut traj = Trajectory {
            params: c.to_vec(),
            ..Default::default()
        };
        let t0 = schedule.t[0];
        let state = State::initial(self.model, law, t0, frame.prescribed(schedule, t0));
        let run = Run {
            law,
            c,
            schedule,
            drive: &CompliantDrive {
                schedule,
                frame: *frame,
            },
            opts,
            guess: None,
        };
        let stretch = Stretch {
            j0: 0,
            j1: schedule.t.len() - 1,
            record: opts.record_fields,
            every: opts.checkpoint_every,
            checkpoints: true,
        };
        self.advance(&run, state, &stretch, &mut traj)?;
        Ok(traj)
    }

    /// Replays a run of [`DirectSolver::run_compliant`] from `checkpoint` up to schedule
    /// index `j_end` as [`DirectSolver::replay`] does (the same drive: the same bits).
    ///
    /// # Errors
    /// As [`DirectSolver::replay`].
    #[allow(clippy::too_many_arguments)]
    pub fn replay_compliant(
        &mut self,
        law: &dyn Material,
        c: &[f64],
        schedule: &Schedule,
        frame: &Frame,
        opts: &SolverOptions,
        checkpoint: &Checkpoint,
        j_end: usize,
    ) -> Result<Trajectory, ContactError> {
        check_frame(frame)?;
        let drive = CompliantDrive {
            schedule,
            frame: *frame,
        };
        self.replay_with(law, c, (schedule, &drive), opts, checkpoint, j_end)
    }

    /// Replays the run from `checkpoint` up to schedule index `j_end`, recording fields:
    /// the returned trajectory's `fields[0]` is the checkpoint's state and its steps are
    /// those of the original run from `checkpoint.steps_done` on, bit for bit: the
    /// computation is deterministic, and the replay forgets the preconditioner's factor
    /// and what else the Newton driver carries across steps at the run's checkpoints, as
    /// the run did (also at those it crosses), so the steps read the checkpoint's state
    /// alone.
    ///
    /// # Errors
    /// As [`DirectSolver::run`]; also [`ContactError::Input`] if `j_end` is before the
    /// checkpoint or beyond the schedule.
    pub fn replay(
        &mut self,
        law: &dyn Material,
        c: &[f64],
        schedule: &Schedule,
        opts: &SolverOptions,
        checkpoint: &Checkpoint,
        j_end: usize,
    ) -> Result<Trajectory, ContactError> {
        let drive = DepthDrive(schedule);
        self.replay_with(law, c, (schedule, &drive), opts, checkpoint, j_end)
    }

    /// Replays a run of [`DirectSolver::run_history`] from `checkpoint` up to schedule
    /// index `j_end` as [`DirectSolver::replay`] does a depth-controlled run: its
    /// load-controlled segments driven by their force again (the checkpoint holds the
    /// state the drive reads: depth, force and past increments), so the replayed steps
    /// are the run's, bit for bit.
    ///
    /// # Errors
    /// As [`DirectSolver::replay`].
    pub fn replay_history(
        &mut self,
        law: &dyn Material,
        c: &[f64],
        history: &LoadHistory,
        opts: &SolverOptions,
        checkpoint: &Checkpoint,
        j_end: usize,
    ) -> Result<Trajectory, ContactError> {
        if !history.is_load_controlled() {
            return self.replay(law, c, &history.schedule, opts, checkpoint, j_end);
        }
        let drive = ForceDrive(history);
        self.replay_with(law, c, (&history.schedule, &drive), opts, checkpoint, j_end)
    }

    /// [`DirectSolver::replay`] with the run's drive.
    fn replay_with(
        &mut self,
        law: &dyn Material,
        c: &[f64],
        (schedule, drive): (&Schedule, &dyn Drive),
        opts: &SolverOptions,
        checkpoint: &Checkpoint,
        j_end: usize,
    ) -> Result<Trajectory, ContactError> {
        if j_end < checkpoint.schedule_index || j_end >= schedule.t.len() {
            return Err(ContactError::Input {
                field: "replay.j_end",
                value: j_end.to_string(),
                allowed: format!(
                    "a schedule index in [{}, {}]",
                    checkpoint.schedule_index,
                    schedule.t.len() - 1
                ),
            });
        }
        let mut traj = Trajectory {
            params: c.to_vec(),
            ..Default::default()
        };
        let state = checkpoint.state.clone();
        let run = Run {
            law,
            c,
            schedule,
            drive,
            opts,
            guess: None,
        };
        let stretch = Stretch {
            j0: checkpoint.schedule_index,
            j1: j_end,
            record: true,
            every: checkpoint.every,
            checkpoints: false,
        };
        self.advance(&run, state, &stretch, &mut traj)?;
        Ok(traj)
    }

    /// Steps from `state` (at schedule index `stretch.j0`) to schedule index
    /// `stretch.j1`, appending to `traj`; stores fields when `stretch.record`, and a
    /// checkpoint every `stretch.every` schedule steps. A failed step is cut (halved, or
    /// by the local update's suggested factor) up to `max_cuts` times.
    fn advance(
        &mut self,
        run: &Run<'_>,
        mut state: State,
        stretch: &Stretch,
        traj: &mut Trajectory,
    ) -> Result<(), ContactError> {
        let Stretch {
            j0,
            j1,
            record,
            every,
            checkpoints,
        } = *stretch;
        let (schedule, opts) = (run.schedule, run.opts);
        let start = std::time::Instant::now();
        if record {
            traj.fields.push(StepFields {
                u: state.u.clone(),
                sigma: state.sigma.clone(),
                alpha: state.internal.alpha.clone(),
                regime: state.internal.regime.clone(),
            });
        }
        let counters = self.counters();
        self.newton.system.begin_run(run.law.as_law().is_some());
        for j in j0 + 1..=j1 {
            if j == j0 + 1 || (every > 0 && (j - 1 - j0) % every == 0) {
                // a run, and every stretch a replay may start from, begins with a fresh
                // factorization, in the run and in a replay that crosses the stretch's
                // start alike: the replay then repeats its steps bit for bit
                self.newton.forget_carried();
            }
            if every > 0 && (j - 1 - j0) % every == 0 {
                if checkpoints {
                    traj.checkpoints.push(Checkpoint {
                        schedule_index: j - 1,
                        steps_done: traj.steps.len(),
                        every,
                        state: state.clone(),
                    });
                }
            }
            // targets still to reach, last first (the step's sub-steps, then t[j]); a failed
            // step pushes an intermediate time
            let mut targets: Vec<(f64, u32)> = schedule
                .step_targets(j)
                .into_iter()
                .rev()
                .map(|t| (t, 0u32))
                .collect();
            while let Some(&(t1, level)) = targets.last() {
                let (depth, load) = run.drive.step(t1, &state);
                let spec = StepSpec {
                    mat: run.law,
                    c: run.c,
                    opts,
                    state: &state,
                    t1,
                    depth,
                    load,
                    guess: run
                        .guess
                        .and_then(|g| guessed_step(g, schedule, state.t, t1)),
                };
                match self.newton.step(&spec, &mut traj.timing) {
                    Ok((rec_state, mut rec)) => {
                        targets.pop();
                        rec.on_schedule = targets.is_empty();
                        rec.schedule_index = j;
                        tracing::debug!(
                            step = j,
                            t = rec.t,
                            depth_mm = rec.depth,
                            force_n = rec.force,
                            active = rec.active.len(),
                            iterations = rec.iterations,
                            "step converged"
                        );
                        state = rec_state;
                        if record {
                            traj.fields.push(StepFields {
                                u: state.u.clone(),
                                sigma: state.sigma.clone(),
                                alpha: state.internal.alpha.clone(),
                                regime: state.internal.regime.clone(),
                            });
                        }
                        traj.steps.push(rec);
                        let stop = match (self.watch.as_mut(), traj.steps.last()) {
                            (Some(w), Some(rec)) => w.0.stop_after(rec),
                            _ => false,
                        };
                        if stop {
                            self.account(traj, start, counters);
                            return Err(ContactError::Stopped {
                                step: j,
                                t: t1,
                                steps: traj.steps.len(),
                                newton_iterations: traj.total_iterations(),
                                factorizations: traj.timing.factorizations,
                            });
                        }
                    }
                    Err(fail) => {
                        // a failed step may have assembled non-finite tangents
                        self.newton.system.forget_assembly();
                        if level >= opts.max_cuts || matches!(fail, StepFailure::Geometry(_)) {
                            traj.timing.total += start.elapsed().as_secs_f64();
                            return Err(ContactError::StepFailed {
                                step: j,
                                t: t1,
                                cuts: level,
                                reason: fail.to_string(),
                                partial: Box::new(std::mem::take(traj)),
                            });
                        }
                        let factor = match fail {
                            StepFailure::Local { factor, .. } => factor.clamp(0.1, 0.5),
                            _ => 0.5,
                        };
                        let tm = state.t + factor * (t1 - state.t);
                        tracing::debug!(
                            step = j,
                            from = state.t,
                            to = t1,
                            retry_to = tm,
                            cut = level + 1,
                            "step cut: {fail}"
                        );
                        targets.push((tm, level + 1));
                        // the remaining part keeps its level so repeated failures keep cutting
                        let n = targets.len();
                        targets[n - 2].1 = level + 1;
                    }
                }
            }
        }
        self.account(traj, start, counters);
        Ok(())
    }

    /// The system's counters at the start of a stretch ([`DirectSolver::account`]).
    fn counters(&self) -> Counters {
        let s = &self.newton.system;
        Counters {
            factorizations: s.factorizations(),
            cg: s.pcg_iterations,
            solves: s.pcg_solves,
            fallbacks: s.pcg_fallbacks,
            seconds: s.seconds,
        }
    }

    /// Adds what the system did since `c` and the wall time since `start` to the
    /// trajectory's timing.
    fn account(&self, traj: &mut Trajectory, start: std::time::Instant, c: Counters) {
        let s = &self.newton.system;
        traj.timing.factorizations += s.factorizations() - c.factorizations;
        traj.timing.cg_iterations += s.pcg_iterations - c.cg;
        traj.timing.pcg_solves += s.pcg_solves - c.solves;
        traj.timing.pcg_fallbacks += s.pcg_fallbacks - c.fallbacks;
        traj.timing.assembly += s.seconds[0] - c.seconds[0];
        traj.timing.factorization += s.seconds[1] - c.seconds[1];
        traj.timing.solve += s.seconds[2] - c.seconds[2];
        traj.timing.total += start.elapsed().as_secs_f64();
    }
}

/// The system's counters at the start of a stretch of steps.
#[derive(Clone, Copy)]
struct Counters {
    factorizations: usize,
    cg: usize,
    solves: usize,
    fallbacks: usize,
    seconds: [f64; 3],
}

/// A run's fixed inputs: the law and its parameters, the schedule's times and the drive
/// that sets the punch depth at each, the options.
struct Run<'a> {
    law: &'a dyn Material,
    c: &'a [f64],
    schedule: &'a Schedule,
    drive: &'a dyn Drive,
    opts: &'a SolverOptions,
    /// A converged trajectory of the same schedule (other parameters) whose increments
    /// start the nonlinear law's Newton iterations ([`DirectSolver::run_warm`]).
    guess: Option<&'a Trajectory>,
}

/// The stretch of the schedule one call of [`DirectSolver::advance`] covers: from
/// schedule index `j0` to `j1`, recording fields when `record`; every `every` schedule
/// steps (0: never) the Newton driver forgets what it carries across steps, and saves a
/// checkpoint there when `checkpoints` (a replay forgets where the run saved one).
#[derive(Clone, Copy)]
struct Stretch {
    j0: usize,
    j1: usize,
    record: bool,
    every: usize,
    checkpoints: bool,
}

/// The displacements before and after the step of `guess` from `t0` to `t1` (the same
/// times to the bit), if it has that step.
fn guessed_step<'g>(
    guess: &'g Trajectory,
    schedule: &Schedule,
    t0: f64,
    t1: f64,
) -> Option<(&'g [f64], &'g [f64])> {
    let k = guess.steps.partition_point(|s| s.t < t1);
    let step = guess.steps.get(k)?;
    let start = match k {
        0 => schedule.t[0],
        _ => guess.steps[k - 1].t,
    };
    (step.t == t1 && start == t0).then(|| {
        (
            guess.fields[k].u.as_slice(),
            guess.fields[k + 1].u.as_slice(),
        )
    })
}

/// The checks of a run's material: its parameters.
///
/// # Errors
/// [`ContactError::Parameters`] for inadmissible parameters.
fn check_material(_model: &Model, mat: &dyn Material, c: &[f64]) -> Result<(), ContactError> {
    mat.check_params(c)?;
    Ok(())
}

/// The checks of a frame: `Cf >= 0` and finite, `vd` and `h0` finite.
///
/// # Errors
/// [`ContactError::Input`] naming the field.
fn check_frame(frame: &Frame) -> Result<(), ContactError> {
    let fields = [
        (
            "frame.compliance",
            frame.compliance,
            "a finite compliance Cf >= 0 (mm/N)",
        ),
        ("frame.drift", frame.drift, "a finite drift rate (mm/s)"),
        ("frame.offset", frame.offset, "a finite depth offset (mm)"),
    ];
    for (k, (field, value, allowed)) in fields.into_iter().enumerate() {
        if !value.is_finite() || (k == 0 && value < 0.0) {
            return Err(ContactError::Input {
                field,
                value: value.to_string(),
                allowed: allowed.into(),
            });
        }
    }
    Ok(())
}

/// Nodal pressures of a step: `lambda_k / int N_k 2 pi r dr` at the active candidates (MPa),
/// as `(r, p)` pairs sorted by r.
pub fn nodal_pressures(model: &Model, rec: &StepRecord) -> Vec<(f64, f64)> {
    rec.active
        .iter()
        .zip(&rec.lambda)
        .map(|(&k, &l)| {
            (
                model.candidate_r(k as usize),
                l / model.candidate_area[k as usize],
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use crate::newton::extrapolation_weights;
    use crate::{ContactKind, DirectSolver, Model, Punch, Schedule, Segment, SolverOptions};
    use indentify_laws::{Elastic, LawMaterial};
    use indentify_mesh::CylinderMesher;

    /// Newton iterations and residuals of the last step of an elastic ramp to 0.05 mm
    /// under a sphere (R = 0.5 mm) with normal contact, on a 2 x 2 mm cylinder.
    fn sphere_last_step(no_curvature: bool) -> Vec<f64> {
        let mesh = CylinderMesher {
            radius: 2.0,
            height: 2.0,
            nr: 12,
            nz: 12,
            grading_r: 1.3,
            grading_z: 1.3,
        }
        .build()
        .unwrap();
        let model =
            Model::with_contact(mesh, Punch::Sphere { radius: 0.5 }, ContactKind::Normal).unwrap();
        let sched = Schedule::from_segments(&[Segment {
            duration: 1.0,
            depth: 0.05,
            steps: 10,
        }])
        .unwrap();
        let opts = SolverOptions {
            residual_tol: 1e-13,
            ..Default::default()
        };
        crate::model::test_hooks::NO_CURVATURE.with(|c| c.set(no_curvature));
        let mut solver = DirectSolver::new(&model).unwrap();
        let run = solver.run(&LawMaterial(&Elastic), &[20000.0, 0.3], &sched, &opts);
        crate::model::test_hooks::NO_CURVATURE.with(|c| c.set(false));
        run.unwrap();
        solver.last_residuals().iter().map(|r| r.0).collect()
    }

    /// The curvature stiffness makes Newton quadratic on a sphere; without it the same
    /// step converges linearly (each residual a roughly constant fraction of the last),
    /// in more iterations.
    #[test]
    fn curvature_stiffness_makes_newton_quadratic() {
        let with = sphere_last_step(false);
        let without = sphere_last_step(true);
        println!("with curvature stiffness: {with:?}\nwithout: {without:?}");
        assert!(without.len() > with.len() + 1, "{with:?} {without:?}");
        // without: linear contraction between 1e-3 and 1e-11 (no pair squares)
        let pairs: Vec<f64> = without
            .windows(2)
            .filter(|w| w[0] < 1e-3 && w[1] > 1e-11)
            .map(|w| w[1] / w[0])
            .collect();
        assert!(pairs.len() >= 3, "{without:?}");
        for w in without.windows(2).filter(|w| w[0] < 1e-3 && w[1] > 1e-11) {
            assert!(w[1] > 10.0 * w[0] * w[0], "{:e} -> {:e}", w[0], w[1]);
        }
    }

    /// The extrapolation of degree p is exact for polynomials of degree p and misses
    /// degree p + 1, with unequal steps (a cut step among full ones).
    #[test]
    fn extrapolation_is_exact_for_polynomials_of_its_degree() {
        let times = [0.1, 0.3, 0.55, 0.675, 0.925];
        let (t_next, t) = (times[4], &times[..4]);
        let h = [t[3] - t[2], t[2] - t[1], t[1] - t[0]];
        let dt = t_next - t[3];
        for order in 1..=3 {
            let w = extrapolation_weights(dt, h, order);
            for degree in 0..=order + 1 {
                let u = |x: f64| {
                    (0..=degree)
                        .map(|k| (1.0 + k as f64) * x.powi(k as i32))
                        .sum::<f64>()
                };
                let du = [u(t[3]) - u(t[2]), u(t[2]) - u(t[1]), u(t[1]) - u(t[0])];
                let got = w[0] * du[0] + w[1] * du[1] + w[2] * du[2];
                let err = (got - (u(t_next) - u(t[3]))).abs();
                if degree <= order {
                    assert!(err < 1e-13, "order {order}, degree {degree}: {err:e}");
                } else {
                    assert!(err > 1e-3, "order {order} fits degree {degree}: {err:e}");
                }
            }
            // only the steps the degree uses carry weight
            assert!(w[order..].iter().all(|&x| x == 0.0), "{w:?}");
        }
    }
}
