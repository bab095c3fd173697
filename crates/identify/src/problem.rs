//! The identification problem (a law and one or more tests: model, schedule, target
//! forces, weights) and the [`Evaluator`]: the cost `J = sum_k J_k`, its adjoint gradient
//! and the sensitivity Jacobian at a parameter point, with a one-point cache keyed on the
//! exact parameter bits so that one forward solve and at most one adjoint sweep per test
//! serve every request at that point; the tests of a joint problem are solved in parallel
//! (rayon) and combined in test order.

use std::collections::HashSet;
use std::sync::Arc;
use std::time::Instant;

use indentify_adjoint::{Adjoint, LoadReplay, Replay};
use indentify_contact::{
    ContactError, DirectSolver, LoadHistory, Model, Schedule, SolverOptions, StepRecord, StepWatch,
    Target, Trajectory,
};
use indentify_laws::{Law, LawMaterial, Material};

use crate::IdentifyError;
use crate::data::ForceRecord;
use crate::instrument::{Applied, Instrument, Instrumented};
use crate::tasks::{self, Follow, Todo};

/// What a [`Problem`] takes as its law: a material shared by the tests' solvers. A
/// stress-only [`Law`] becomes a [`LawMaterial`] (the solver dispatches it to the `Law`
/// fast paths through [`Material::as_law`], so its bits are today's); a registry material
/// (`Box<dyn Material>`, `Arc<dyn Material>`) is taken as is.
pub trait IntoMaterial {
    /// The shared material.
    fn into_material(self) -> Arc<dyn Material>;
}

impl IntoMaterial for &'static dyn Law {
    fn into_material(self) -> Arc<dyn Material> {
        Arc::new(LawMaterial(self))
    }
}

impl<L: Law> IntoMaterial for &'static L {
    fn into_material(self) -> Arc<dyn Material> {
        Arc::new(LawMaterial(self))
    }
}

impl IntoMaterial for Arc<dyn Material> {
    fn into_material(self) -> Arc<dyn Material> {
        self
    }
}

impl IntoMaterial for Box<dyn Material> {
    fn into_material(self) -> Arc<dyn Material> {
        Arc::from(self)
    }
}

/// One test of an identification: the direct problem (model, depth schedule, solver
/// options) and the data it is compared with, weighted.
///
/// Its cost (docs/theory.md §6, paper eq. 16) is
/// `J_k(c) = 1/2 sum_{i=0..I} w_i (F_i(c) - F_i^exp)^2` over the schedule times `t_i`
/// (index 0 is the stress-free initial state, `F_0 = 0`); `F^exp` is the record
/// interpolated at `t_i`; `w_i` = the point weight times the test's [`Test::weight`].
#[derive(Debug)]
pub struct Test {
    /// The direct problem's model (mesh, punch, ...).
    pub model: Model,
    /// Depth history driving the simulation (the measured `U^exp(t)`).
    pub schedule: Schedule,
    /// Options of the direct solver (fields are always recorded: the adjoint needs them).
    pub solver_options: SolverOptions,
    /// `F_i^exp` at the schedule times (N), `schedule.t.len()` entries.
    pub target: Vec<f64>,
    /// Weights `w_i >= 0` (the test weight included), `schedule.t.len()` entries.
    pub weights: Vec<f64>,
    /// The test's weight `w_k > 0` in the joint cost (1 for a single test).
    pub weight: f64,
    /// Load control ([`Test::new_load`]): the history prescribing the force (its
    /// `schedule` is [`Test::schedule`]); the observable is then the punch depth, and
    /// `target` holds the measured depths `h_exp` (mm), the cost
    /// `J_k = 1/2 sum w_i (h_i - h_exp,i)^2` (docs/theory.md §13). `None`: depth control,
    /// the observable is the force.
    pub load: Option<LoadHistory>,
}

impl Test {
    /// Builds a test; `record` is interpolated onto the schedule's times; the point
    /// `weights` default to 1 (one per schedule time, index 0 included) and are multiplied
    /// by the test's `weight`.
    ///
    /// # Errors
    /// [`IdentifyError::RecordDoesNotCover`] when the record does not span the schedule;
    /// [`IdentifyError::InvalidWeights`] for a wrong length, a negative or non-finite
    /// weight, all weights zero, or a test weight that is not finite and > 0.
    pub fn new(
        model: Model,
        schedule: Schedule,
        record: &ForceRecord,
        weights: Option<Vec<f64>>,
        solver_options: SolverOptions,
        weight: f64,
    ) -> Result<Test, IdentifyError> {
        if !(weight.is_finite() && weight > 0.0) {
            return Err(IdentifyError::InvalidWeights {
                why: format!(
                    "the test weight {weight} is not allowed: expected a finite value > 0"
                ),
            });
        }
        let target = record.at_times(&schedule.t)?;
        let n = schedule.t.len();
        let weights = weights.unwrap_or_else(|| vec![1.0; n]);
        if weights.len() != n {
            return Err(IdentifyError::InvalidWeights {
                why: format!(
                    "{} weights for {n} schedule times (one per time, the initial state included)",
                    weights.len()
                ),
            });
        }
        if let Some(i) = weights.iter().position(|w| !(w.is_finite() && *w >= 0.0)) {
            return Err(IdentifyError::InvalidWeights {
                why: format!("weight {i} = {} is not a finite value >= 0", weights[i]),
            });
        }
        if weights.iter().all(|&w| w == 0.0) {
            return Err(IdentifyError::InvalidWeights {
                why: "all weights are zero".into(),
            });
        }
        let weights = if weight == 1.0 {
            weights
        } else {
            weights.iter().map(|w| w * weight).collect()
        };
        // with checkpoints, the states are saved every `checkpoint_every` steps and the
        // gradient replays the segments (bounded memory); otherwise every step's fields
        let solver_options = SolverOptions {
            record_fields: solver_options.checkpoint_every == 0,
            ..solver_options
        };
        Ok(Test {
            model,
            schedule,
            solver_options,
            target,
            weights,
            weight,
            load: None,
        })
    }

    /// Builds a load-controlled test: `history` prescribes the force (and the depth on its
    /// depth-controlled segments), `depths` is the measured depth record (s, mm; read
    /// through [`ForceRecord`], whose values are then depths), interpolated onto the
    /// history's times; the observable is the depth. Weights as in [`Test::new`]. The
    /// solver records every step's fields, or with checkpoints
    /// ([`SolverOptions::checkpoint_every`]) saves states the bordered adjoint replays
    /// (`Adjoint::gradient_load_replayed`).
    ///
    /// # Errors
    /// As [`Test::new`].
    pub fn new_load(
        model: Model,
        history: LoadHistory,
        depths: &ForceRecord,
        weights: Option<Vec<f64>>,
        solver_options: SolverOptions,
        weight: f64,
    ) -> Result<Test, IdentifyError> {
        let mut t = Test::new(
            model,
            history.schedule.clone(),
            depths,
            weights,
            solver_options,
            weight,
        )?;
        t.load = Some(history);
        Ok(t)
    }

    /// The observables of a trajectory at the schedule times (index 0 = the initial state,
    /// 0): the forces under depth control, the depths under load control.
    pub fn observables(&self, traj: &Trajectory) -> Vec<f64> {
        if self.load.is_some() {
            std::iter::once(0.0)
                .chain(traj.schedule_steps().map(|s| s.depth))
                .collect()
        } else {
            traj.forces()
        }
    }

    /// The default weight of a test in a joint fit, `1 / (n F_max^2)` with `n` the number
    /// of its data points (schedule times with a non-zero point weight) and `F_max` the
    /// largest `|F^exp|` among them: each test then contributes about equally to `J`
    /// whatever its number of points and its force scale (`J_k / w_k` is of the order of
    /// `n F_max^2` times the squared relative misfit). 1 for a record of zero force.
    ///
    /// `record` is interpolated onto `schedule` as in [`Test::new`].
    ///
    /// # Errors
    /// [`IdentifyError::RecordDoesNotCover`] when the record does not span the schedule.
    pub fn default_weight(schedule: &Schedule, record: &ForceRecord) -> Result<f64, IdentifyError> {
        let target = record.at_times(&schedule.t)?;
        let f_max = target.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
        let n = target.len();
        Ok(if f_max > 0.0 && n > 0 {
            1.0 / (n as f64 * f_max * f_max)
        } else {
            1.0
        })
    }

    /// `J_k` of forces at the schedule times.
    pub fn cost_of(&self, forces: &[f64]) -> f64 {
        weighted_half_squares(forces, &self.target, &self.weights)
    }

    /// `dJ/dF` per trajectory step: `w_j (F_i - F_j^exp)` for a step ending on schedule
    /// time j, 0 for the sub-steps of a cut step (the cost does not see them). Under load
    /// control ([`Test::load`]) the derivative with respect to the observable, the depth:
    /// `w_j (h_i - h_j^exp)`.
    pub fn dj_df(&self, traj: &Trajectory) -> Vec<f64> {
        let load = self.load.is_some();
        traj.steps
            .iter()
            .map(|s| {
                if s.on_schedule {
                    let j = s.schedule_index;
                    let y = if load { s.depth } else { s.force };
                    self.weights[j] * (y - self.target[j])
                } else {
                    0.0
                }
            })
            .collect()
    }
}

/// Everything fixed during an identification: the law whose parameters are identified and
/// one or more tests ([`Test`]) sharing them.
///
/// The cost (docs/theory.md §6, paper eq. 16) is `J(c) = sum_k J_k(c)`, the sum of the tests'
/// weighted least-squares misfits. The data of all tests are laid end to end, test after
/// test, in [`Problem::target`] and [`Problem::weights`] (and the forces and Jacobian rows
/// of [`Evaluator`]): `J = 1/2 sum_i w_i (F_i - F_i^exp)^2` over that concatenation, so
/// the optimizers, Levenberg-Marquardt's stacked residuals and the identifiability see one
/// long record. A single test ([`Problem::new`]) has weight 1 and is exactly the
/// one-curve problem.
#[derive(Debug)]
pub struct Problem {
    /// The material whose parameters are identified (a stress-only law as
    /// [`LawMaterial`], or a law with internal variables from the registry).
    pub law: Arc<dyn Material>,
    /// The tests, in order (at least one).
    pub tests: Vec<Test>,
    /// The observed values of every test, laid end to end: `F_i^exp` (N), or `h_exp,i`
    /// (mm) for a load-controlled test ([`Test::load`]).
    pub target: Vec<f64>,
    /// The weights `w_i` (test weights included), laid end to end.
    pub weights: Vec<f64>,
    /// The pool the tests are solved on ([`Problem::set_threads`]); `None`: the current
    /// rayon pool (by default the global one, all cores).
    pool: Option<Arc<rayon::ThreadPool>>,
    /// Whether an [`Evaluator`] starts each forward run's Newton iterations from the best
    /// point's trajectory ([`Problem::set_warm_start`]).
    warm_start: bool,
    /// The material the solvers run: [`Problem::law`] itself, or the law inside the
    /// [`Instrumented`] of [`Problem::joint_instrumented`] (run at `c[..n_law]`).
    material: Arc<dyn Material>,
    /// The instrument's parameters and what they add to the observables.
    applied: Option<Applied>,
}

impl Problem {
    /// Builds a one-test problem; `record` is interpolated onto the schedule's times;
    /// `weights` default to 1 (one per schedule time, index 0 included).
    ///
    /// # Errors
    /// [`IdentifyError::RecordDoesNotCover`] when the record does not span the schedule;
    /// [`IdentifyError::InvalidWeights`] for a wrong length, a negative or non-finite
    /// weight, or all weights zero.
    pub fn new(
        model: Model,
        law: impl IntoMaterial,
        schedule: Schedule,
        record: &ForceRecord,
        weights: Option<Vec<f64>>,
        solver_options: SolverOptions,
    ) -> Result<Problem, IdentifyError> {
        let test = Test::new(model, schedule, record, weights, solver_options, 1.0)?;
        Problem::joint(law, vec![test])
    }

    /// A joint problem: `tests` share the parameters of `law`; `J = sum_k J_k`.
    ///
    /// # Errors
    /// [`IdentifyError::InvalidSpec`] (field `tests`) for an empty list.
    pub fn joint(law: impl IntoMaterial, tests: Vec<Test>) -> Result<Problem, IdentifyError> {
        let law = law.into_material();
        if tests.is_empty() {
            return Err(IdentifyError::InvalidSpec {
                name: "tests".into(),
                why: "the list of tests is empty: expected at least one test".into(),
            });
        }
        let target = tests
            .iter()
            .flat_map(|t| t.target.iter().copied())
            .collect();
        let weights = tests
            .iter()
            .flat_map(|t| t.weights.iter().copied())
            .collect();
        Ok(Problem {
            material: law.clone(),
            law,
            tests,
            target,
            weights,
            pool: None,
            warm_start: true,
            applied: None,
        })
    }

    /// A joint problem whose parameters are the law's followed by those of `instrument`
    /// (docs/theory.md §13.6): `Cf`, `vd`, then `h0` (one test) or `h0[1]`, `h0[2]`, ...
    /// (one per test). [`Problem::law`] is then the [`Instrumented`] law, so every
    /// parameter list ([`crate::Parameterization`], results, identifiability) shows them;
    /// the evaluator runs the law at `c[..n_law]` and adds `Cf F_i + vd (t_i - t_0) + h0_k`
    /// to test `k`'s depths, their derivatives to its gradient and sensitivity rows. An
    /// empty instrument is [`Problem::joint`].
    ///
    /// A depth-controlled test (its force the observable) runs through the frame's
    /// spring instead (docs/theory.md §13.7, `DirectSolver::run_compliant`): its recorded
    /// depth is the machine's, `h + Cf F + vd (t - t0) + h0_k`.
    ///
    /// # Errors
    /// As [`Problem::joint`].
    pub fn joint_instrumented(
        law: impl IntoMaterial,
        instrument: Instrument,
        tests: Vec<Test>,
    ) -> Result<Problem, IdentifyError> {
        let inner = law.into_material();
        if instrument.is_empty() {
            return Problem::joint(inner, tests);
        }
        let n = tests.len();
        let wrapped = Instrumented::new(inner.clone(), instrument, n);
        let applied = wrapped.applied();
        let mut p = Problem::joint(Arc::new(wrapped) as Arc<dyn Material>, tests)?;
        p.material = inner;
        p.applied = Some(applied);
        Ok(p)
    }

    /// The material the solvers run (the law without the instrument's parameters; see
    /// [`Problem::law_part`]).
    pub fn material(&self) -> &Arc<dyn Material> {
        &self.material
    }

    /// The law's part of a full parameter vector (all of it without an instrument).
    pub fn law_part<'c>(&self, c: &'c [f64]) -> &'c [f64] {
        match &self.applied {
            Some(a) => &c[..a.n_law.min(c.len())],
            None => c,
        }
    }

    /// What the data observe: the force (every test depth-controlled), the depth (every
    /// test load-controlled) or both (a joint fit of mixed drives).
    pub fn observed(&self) -> crate::identifiability::Observed {
        use crate::identifiability::Observed;
        let load = self.tests.iter().filter(|t| t.load.is_some()).count();
        match load {
            0 => Observed::Force,
            n if n == self.tests.len() => Observed::Depth,
            _ => Observed::ForceAndDepth,
        }
    }

    /// Whether the problem carries instrument parameters ([`Problem::joint_instrumented`]).
    pub fn has_instrument(&self) -> bool {
        self.applied.is_some()
    }

    /// Test `k`'s observables at `c` from its trajectory `traj` (a run of
    /// [`Problem::material`] at [`Problem::law_part`]): [`Test::observables`] plus the
    /// instrument's terms.
    pub fn observables_of(&self, k: usize, c: &[f64], traj: &Trajectory) -> Vec<f64> {
        let t = &self.tests[k];
        let mut obs = t.observables(traj);
        if let Some(a) = &self.applied {
            a.observe(k, t, c, traj, &mut obs);
        }
        obs
    }

    /// Solves the tests on a pool of `threads` threads of its own (instead of the current
    /// rayon pool). The results do not depend on it, only the time.
    ///
    /// # Errors
    /// [`IdentifyError::InvalidOption`] (`jobs`) for 0 threads or a pool that cannot be
    /// built.
    pub fn set_threads(&mut self, threads: usize) -> Result<(), IdentifyError> {
        if threads == 0 {
            return Err(IdentifyError::InvalidOption {
                field: "jobs",
                value: "0".into(),
                allowed: "a number of threads >= 1",
            });
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| IdentifyError::InvalidOption {
                field: "jobs",
                value: format!("{threads} ({e})"),
                allowed: "a number of threads the system can start",
            })?;
        self.pool = Some(Arc::new(pool));
        Ok(())
    }

    /// Whether the [`Evaluator`]s of this problem start a forward run's Newton iterations,
    /// step by step, from the increments of the lowest-cost point's converged trajectory
    /// (`DirectSolver::run_warm`) instead of the time extrapolation (default: on). The
    /// results agree with cold runs to the solver's tolerance, not bit for bit, and depend
    /// on the sequence of points evaluated (never on the thread count): off, every forward
    /// run starts cold and a point's forces are the same bits whatever came before.
    pub fn set_warm_start(&mut self, on: bool) {
        self.warm_start = on;
    }

    /// Runs `f` on the problem's pool ([`Problem::set_threads`]), or on the current rayon
    /// pool without one: for work over the tests done outside the [`Evaluator`] (the
    /// refined runs of the discretization error).
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        match &self.pool {
            Some(p) => p.install(f),
            None => f(),
        }
    }

    /// The first test's model (the only one of a one-test problem).
    pub fn model(&self) -> &Model {
        &self.tests[0].model
    }

    /// The first test's schedule (the only one of a one-test problem).
    pub fn schedule(&self) -> &Schedule {
        &self.tests[0].schedule
    }

    /// The first test's solver options (the only ones of a one-test problem).
    pub fn solver_options(&self) -> &SolverOptions {
        &self.tests[0].solver_options
    }

    /// The range of test `k`'s rows in the concatenated data.
    pub fn rows_of(&self, k: usize) -> std::ops::Range<usize> {
        let start: usize = self.tests[..k].iter().map(|t| t.target.len()).sum();
        start..start + self.tests[k].target.len()
    }

    /// Number of data points that count (non-zero weight), all tests.
    pub fn n_data(&self) -> usize {
        self.weights.iter().filter(|&&w| w > 0.0).count()
    }

    /// `J_ref = 1/2 sum w_i (F_i^exp)^2`: the cost of predicting zero force, the scale that
    /// the optimizers divide `J` by (so `sqrt(2 J / J_ref)` is a relative RMS misfit).
    pub fn reference_cost(&self) -> f64 {
        let j: f64 = 0.5
            * self
                .weights
                .iter()
                .zip(&self.target)
                .map(|(w, f)| w * f * f)
                .sum::<f64>();
        if j > 0.0 { j } else { 1.0 }
    }

    /// `J` of forces at the schedule times (all tests laid end to end).
    pub fn cost_of(&self, forces: &[f64]) -> f64 {
        weighted_half_squares(forces, &self.target, &self.weights)
    }

    /// `dJ/dF` per trajectory step of the first test (the only one of a one-test
    /// problem); [`Test::dj_df`] for the others.
    pub fn dj_df(&self, traj: &Trajectory) -> Vec<f64> {
        self.tests[0].dj_df(traj)
    }
}

/// `1/2 sum_i w_i (F_i - F_exp,i)^2`: the cost of one test and of a joint problem.
fn weighted_half_squares(forces: &[f64], target: &[f64], weights: &[f64]) -> f64 {
    0.5 * forces
        .iter()
        .zip(target)
        .zip(weights)
        .map(|((f, d), w)| w * (f - d).powi(2))
        .sum::<f64>()
}

/// Counters of the expensive operations an [`Evaluator`] performed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Forward (direct problem) solves, failed ones included.
    pub forward: usize,
    /// Forward solves that failed, or points the law does not admit (the cost is then
    /// `+inf`).
    pub forward_failed: usize,
    /// Newton iterations (linear solves) of the forward solves that converged or were
    /// stopped by their cost bound ([`Counts::stopped`]), summed over the steps they ran.
    pub newton_iterations: u64,
    /// Numeric factorizations of the forward solves that converged or were stopped by
    /// their cost bound.
    pub factorizations: usize,
    /// Adjoint sweeps asked for (one per test and gradient request not in the cache,
    /// whether the sweep ran then or had been computed ahead: [`Counts::prefetched`]).
    pub adjoint: usize,
    /// Forward-sensitivity (Jacobian) computations asked for (as [`Counts::adjoint`]).
    pub sensitivities: usize,
    /// Requests answered from the cache.
    pub cache_hits: usize,
    /// Distinct parameter points requested (forward solves can only exceed this when the
    /// optimizer comes back to a point it left: the cache holds one point).
    pub distinct_points: usize,
    /// Forward solves stopped between steps because the test's partial cost had reached
    /// the bound of [`Evaluator::cost_below`] (counted in [`Counts::forward`] too).
    pub stopped: usize,
    /// Schedule steps the forward solves ran (the completed ones' and the stopped ones'
    /// up to where they stopped; failed solves left out).
    pub schedule_steps: u64,
    /// Schedule steps the stopped forward solves did not run.
    pub steps_skipped: u64,
    /// Adjoint sweeps or sensitivity passes computed ahead of a request on a core that
    /// would otherwise have waited ([`Evaluator::set_prefetch`]); unlike the other counts
    /// this one depends on timing, and those of points the optimizer leaves are wasted.
    pub prefetched: usize,
}

/// What an [`Evaluator`] may compute ahead of a request, on cores that the forward runs of
/// a joint problem leave idle (fewer tests left than cores while the last forwards run):
/// the follow-up an optimizer usually asks for next at the point whose cost it just asked
/// for. A follow-up only starts when it is expected (from the previous evaluation's
/// timings, with a 10% margin) to end before the last running forward does, so that it
/// should not delay the request that was made (it can when that estimate is wrong: an
/// evaluation waits for every task it started); it never changes a result (bit-identical
/// with or without).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Prefetch {
    /// Compute nothing ahead (the default).
    #[default]
    None,
    /// The tests' adjoint sweeps (gradient methods: the gradient follows an accepted
    /// line-search point).
    Gradient,
    /// The tests' forward sensitivities (Levenberg-Marquardt: the Jacobian follows an
    /// accepted trial point).
    Jacobian,
}

/// The follow-up of a test's forward run in one evaluation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Gradient,
    Jacobian,
}

/// What the cache holds of one test at the last parameter point.
#[derive(Debug, Default)]
struct TestEntry {
    forces: Option<Vec<f64>>,
    traj: Option<Trajectory>,
    /// The forward run was stopped at this schedule index by its cost bound
    /// ([`CostWatch`]).
    stopped: Option<usize>,
    /// The stopped run's Newton iterations and factorizations.
    stopped_work: (u64, usize),
    /// Why the forward run failed (taken when the evaluation is assembled).
    forward_error: Option<ContactError>,
    gradient: Option<Vec<f64>>,
    jacobian: Option<Vec<Vec<f64>>>,
    /// Why the adjoint sweep failed (taken by the request).
    gradient_error: Option<IdentifyError>,
    /// Why the sensitivities failed (taken by the request).
    jacobian_error: Option<IdentifyError>,
}

impl TestEntry {
    fn has(&self, kind: Kind) -> bool {
        match kind {
            Kind::Gradient => self.gradient.is_some(),
            Kind::Jacobian => self.jacobian.is_some(),
        }
    }
}

/// What the cache holds for the last parameter point.
#[derive(Debug)]
struct Entry {
    key: Vec<u64>,
    cost: f64,
    /// A test's forward run was stopped by the bound of [`Evaluator::cost_below`]: the
    /// cost is only known to be at least the bound, and no request but a bounded cost's
    /// at a bound as high may use the entry.
    stopped: Option<f64>,
    /// Every test's forces end to end (`None` when a forward solve failed).
    forces: Option<Vec<f64>>,
    tests: Vec<TestEntry>,
    gradient: Option<Vec<f64>>,
    jacobian: Option<Vec<Vec<f64>>>,
}

/// The forward and adjoint workspaces of one test, and how long its last forward run,
/// adjoint sweep and sensitivity pass took (for the scheduling of [`Prefetch`]).
#[derive(Debug)]
pub(crate) struct Work<'p> {
    pub(crate) solver: DirectSolver<'p>,
    pub(crate) adjoint: Adjoint<'p>,
    seconds: [Option<f64>; 3],
    /// The lowest-cost point's trajectory, the warm start of the next forward runs
    /// ([`Problem::set_warm_start`]).
    warm: Option<Trajectory>,
    /// The parameters whose sensitivities the Jacobian forms
    /// ([`Evaluator::set_jacobian_columns`]; `None`: all).
    columns: Option<Vec<usize>>,
}

/// The cost/gradient oracle of one [`Problem`]: owns each test's forward and adjoint
/// workspaces and caches the last point (its trajectories, `J`, `dJ/dc`, `dF/dc`).
///
/// A request at the same point (the same bits of every parameter) is served from the
/// cache, so a line search's cost call, the optimizer's gradient call after it and a
/// report's force call cost one forward solve and one adjoint sweep per test in total.
/// Each request at a new point replaces the entry.
///
/// The tests of a joint problem are solved in parallel on the current rayon pool: each
/// test's forward run is a task and its adjoint sweep or sensitivities another, started
/// when that forward ends (forwards first), so that with fewer cores than tests the
/// follow-ups fill the cores the last forwards leave idle ([`Prefetch`] does the same for
/// a follow-up not yet asked for). Costs, gradients and Jacobian rows are combined in
/// test order, never in completion order, so every result is bit-identical whatever the
/// number of threads and the timing.
#[derive(Debug)]
pub struct Evaluator<'p> {
    problem: &'p Problem,
    work: Vec<Work<'p>>,
    entry: Option<Entry>,
    counts: Counts,
    best: Option<(f64, Vec<f64>)>,
    start: Instant,
    seen: HashSet<Vec<u64>>,
    prefetch: Prefetch,
}

fn key_of(c: &[f64]) -> Vec<u64> {
    c.iter().map(|v| v.to_bits()).collect()
}

/// The watch of a forward run bounded by [`Evaluator::cost_below`]: the test's cost
/// `J_k = 1/2 sum_i w_i (y_i - y_exp,i)^2` summed over the schedule times reached so far,
/// in the order and with the operations of [`Problem::cost_of`] (row 0, the initial state's
/// `y = 0`, first). Its terms are `>= 0` and rounded addition and multiplication by a
/// positive number are monotone, so the partial value never exceeds the whole run's
/// `J_k`, nor that the joint `J` of all tests: once it reaches the bound the run is
/// stopped, its cost at least the bound whatever the remaining steps give.
struct CostWatch<'p> {
    target: &'p [f64],
    weights: &'p [f64],
    /// Load control: the observable is the depth.
    load: bool,
    bound: f64,
    /// `sum w_i (y_i - y_exp,i)^2` over the rows so far.
    sum: f64,
    /// The next row (schedule time).
    row: usize,
}

impl<'p> CostWatch<'p> {
    fn new(t: &'p Test, bound: f64) -> CostWatch<'p> {
        let mut w = CostWatch {
            target: &t.target,
            weights: &t.weights,
            load: t.load.is_some(),
            bound,
            sum: 0.0,
            row: 0,
        };
        w.add(0.0);
        w
    }

    /// Adds the next row's observable `y`; true once `J_k` so far reaches the bound (or
    /// is NaN: the whole run's would be too, and NaN is rejected as the bound is).
    fn add(&mut self, y: f64) -> bool {
        let (Some(w), Some(d)) = (self.weights.get(self.row), self.target.get(self.row)) else {
            return false;
        };
        self.row += 1;
        self.sum += w * (y - d).powi(2);
        !(0.5 * self.sum < self.bound)
    }
}

impl StepWatch for CostWatch<'_> {
    fn stop_after(&mut self, step: &StepRecord) -> bool {
        step.on_schedule && self.add(if self.load { step.depth } else { step.force })
    }
}

/// Test `k`'s forward run at `c` into its cache entry; false when it failed or was
/// stopped by the cost `bound` ([`CostWatch`]; not for an instrumented problem, whose
/// observables the instrument's frame changes).
fn forward_task<'p>(
    p: &'p Problem,
    c: &[f64],
    k: usize,
    w: &mut Work<'p>,
    te: &mut TestEntry,
    bound: Option<f64>,
) -> bool {
    let t = &p.tests[k];
    let (law, cl) = (&*p.material, p.law_part(c));
    let warm = &w.warm;
    let run = |solver: &mut DirectSolver<'p>| match (&t.load, warm) {
        (Some(h), _) => solver.run_history(law, cl, h, &t.solver_options),
        // depth control through the instrument's frame (docs/theory.md §13.7)
        (None, _) if p.applied.is_some() => {
            let frame = p
                .applied
                .as_ref()
                .map(|a| a.frame(k, c))
                .unwrap_or_default();
            solver.run_compliant(law, cl, &t.schedule, &frame, &t.solver_options)
        }
        (None, Some(g)) if p.warm_start => {
            solver.run_warm(law, cl, &t.schedule, &t.solver_options, g)
        }
        (None, _) => solver.run(law, cl, &t.schedule, &t.solver_options),
    };
    let run = match bound.filter(|_| p.applied.is_none()) {
        Some(b) => w.solver.watched(Box::new(CostWatch::new(t, b)), run),
        None => run(&mut w.solver),
    };
    match run {
        Ok(traj) => {
            te.forces = Some(p.observables_of(k, c, &traj));
            te.traj = Some(traj);
            true
        }
        Err(ContactError::Stopped {
            step,
            newton_iterations,
            factorizations,
            ..
        }) => {
            te.stopped = Some(step);
            te.stopped_work = (newton_iterations, factorizations);
            false
        }
        Err(e) => {
            te.forward_error = Some(e);
            false
        }
    }
}

/// `traj` if it holds every step's fields, else the run `run` makes with the fields
/// recorded and no checkpoints (kept in `slot`): the forward sensitivities need them all.
pub(crate) fn in_full<'a>(
    traj: &'a Trajectory,
    opts: &SolverOptions,
    c: &[f64],
    slot: &'a mut Option<Trajectory>,
    run: impl FnOnce(&SolverOptions) -> Result<Trajectory, ContactError>,
) -> Result<&'a Trajectory, IdentifyError> {
    if traj.fields.len() == traj.steps.len() + 1 {
        return Ok(traj);
    }
    let opts = SolverOptions {
        record_fields: true,
        checkpoint_every: 0,
        ..opts.clone()
    };
    let full = run(&opts).map_err(|source| IdentifyError::Forward {
        params: c.to_vec(),
        source,
    })?;
    Ok(slot.insert(full))
}

/// Test `k`'s adjoint gradient at `c` from its cached trajectory.
fn gradient_task(
    p: &Problem,
    c: &[f64],
    k: usize,
    w: &mut Work,
    te: &TestEntry,
) -> Result<Vec<f64>, IdentifyError> {
    let t = &p.tests[k];
    let Some(traj) = te.traj.as_ref() else {
        return Err(IdentifyError::Optimizer("trajectory missing".into()));
    };
    // the sweep starts from the forward's factor where its key is the same (a linear
    // law's last tangent and capacitance columns; checked, never a stale one)
    w.adjoint.take_factor(&mut w.solver);
    match (&p.applied, &t.load) {
        (Some(a), Some(h)) => return instrumented_gradient(p, a, c, k, w, te, h),
        (Some(a), None) => return crate::instrument::compliant_gradient(p, a, c, k, w, traj),
        _ => {}
    }
    let rho = t.dj_df(traj);
    let g = if let Some(h) = &t.load {
        let zero = vec![0.0; rho.len()];
        w.adjoint.gradient_load_replayed(
            &*p.law,
            c,
            traj,
            h,
            &rho,
            &zero,
            LoadReplay {
                solver: &mut w.solver,
                opts: &t.solver_options,
            },
        )
    } else if t.solver_options.checkpoint_every > 0 {
        w.adjoint.gradient_replayed(
            &*p.law,
            c,
            traj,
            &rho,
            Replay {
                solver: &mut w.solver,
                schedule: &t.schedule,
                opts: &t.solver_options,
            },
        )
    } else {
        w.adjoint.gradient(&*p.law, c, traj, &rho)
    }
    .map_err(|source| IdentifyError::Adjoint {
        params: c.to_vec(),
        source,
    })?;
    Ok(g.dj_dc)
}

/// Test `k`'s adjoint gradient with the instrument (load control, checked by
/// [`Problem::joint_instrumented`]): the law's part by the bordered adjoint with
/// `dJ/dh_i = r_i` and `dJ/dF_i = Cf r_i` (read at depth-controlled steps), `r_i =
/// w_i (h_meas,i - h_exp,i)`; the instrument's entries in closed form ([`Applied`]).
fn instrumented_gradient(
    p: &Problem,
    a: &Applied,
    c: &[f64],
    k: usize,
    w: &mut Work,
    te: &TestEntry,
    history: &LoadHistory,
) -> Result<Vec<f64>, IdentifyError> {
    let t = &p.tests[k];
    let (Some(traj), Some(obs)) = (te.traj.as_ref(), te.forces.as_ref()) else {
        return Err(IdentifyError::Optimizer("trajectory missing".into()));
    };
    let r: Vec<f64> = obs
        .iter()
        .zip(&t.target)
        .zip(&t.weights)
        .map(|((h, d), w)| w * (h - d))
        .collect();
    let rho: Vec<f64> = traj
        .steps
        .iter()
        .map(|s| {
            if s.on_schedule {
                r[s.schedule_index]
            } else {
                0.0
            }
        })
        .collect();
    let cf = a.compliance(c);
    let mut rho_f: Vec<f64> = rho.iter().map(|v| cf * v).collect();
    if cf != 0.0 {
        fold_interpolated_forces(traj, history, &mut rho_f);
    }
    let g = w
        .adjoint
        .gradient_load_replayed(
            &*p.material,
            p.law_part(c),
            traj,
            history,
            &rho,
            &rho_f,
            LoadReplay {
                solver: &mut w.solver,
                opts: &t.solver_options,
            },
        )
        .map_err(|source| IdentifyError::Adjoint {
            params: c.to_vec(),
            source,
        })?;
    let mut full = vec![0.0; c.len()];
    full[..g.dj_dc.len()].copy_from_slice(&g.dj_dc);
    a.gradient(k, t, traj, &r, &mut full);
    Ok(full)
}

/// Moves `dJ/dF_i` of the load-controlled steps whose prescribed force depends on the
/// parameters onto the depth-controlled step it depends on (the adjoint reads `dJ/dF` at
/// depth-controlled steps only). A load-controlled segment that follows a depth-controlled
/// step `a` prescribes the straight line from its computed force `F_a(c)` to the target
/// `p` (contact's `ForceDrive`): `F_i = F_a + (t_i - t_a) / (t_end - t_a) (p - F_a)`, so
/// `dF_i/dc = (1 - (t_i - t_a) / (t_end - t_a)) dF_a/dc`; later segments start from their
/// predecessor's target and do not depend on `c`.
fn fold_interpolated_forces(traj: &Trajectory, history: &LoadHistory, dj_df: &mut [f64]) {
    // the last depth-controlled step before the current load-controlled segment, if the
    // segment began right after it: (its index, its time, the segment's end time)
    let mut anchor: Option<(usize, f64, f64)> = None;
    let mut prev: Option<(usize, f64, bool)> = None; // (index, time, load-controlled)
    for (i, s) in traj.steps.iter().enumerate() {
        let (t_end, target) = history.segment_at(s.t);
        let load = matches!(target, Target::Force(_));
        if load {
            let same_segment = anchor.is_some_and(|(_, _, e)| e == t_end);
            if !same_segment {
                anchor = match prev {
                    Some((a, t_a, false)) => Some((a, t_a, t_end)),
                    _ => None,
                };
            }
            if let Some((a, t_a, e)) = anchor {
                let w = 1.0 - (s.t - t_a) / (e - t_a);
                dj_df[a] += w * dj_df[i];
            }
            dj_df[i] = 0.0;
        } else {
            anchor = None;
        }
        prev = Some((i, s.t, load));
    }
}

/// Test `k`'s Jacobian rows (`dF/dc` at its schedule times) at `c` by forward
/// sensitivities from its cached trajectory.
fn jacobian_task(
    p: &Problem,
    c: &[f64],
    k: usize,
    w: &mut Work,
    te: &TestEntry,
) -> Result<Vec<Vec<f64>>, IdentifyError> {
    let t = &p.tests[k];
    let Some(traj) = te.traj.as_ref() else {
        return Err(IdentifyError::Optimizer("trajectory missing".into()));
    };
    // as the gradient, from the forward's factor where its key is the same
    w.adjoint.take_factor(&mut w.solver);
    // the forward sensitivities need every step's fields: a checkpointed trajectory is
    // recorded again in full for them (the memory of one unbounded run)
    if let (Some(a), None) = (&p.applied, &t.load) {
        return crate::instrument::compliant_jacobian(p, a, c, k, w, traj);
    }
    if let Some(h) = &t.load {
        let cl = p.law_part(c);
        let mut slot = None;
        let traj = in_full(traj, &t.solver_options, c, &mut slot, |o| {
            w.solver.run_history(&*p.material, cl, h, o)
        })?;
        let sens = w
            .adjoint
            .sensitivities_load(&*p.material, cl, traj, h)
            .map_err(|source| IdentifyError::Adjoint {
                params: c.to_vec(),
                source,
            })?;
        let mut jac = vec![vec![0.0; c.len()]; t.schedule.t.len()];
        // the measured depth's law columns: dh/dc + Cf dF/dc (the force's are non-zero on
        // depth-controlled steps only)
        let cf = p.applied.as_ref().map_or(0.0, |a| a.compliance(c));
        for ((s, dh), df) in traj.steps.iter().zip(&sens.dh_dc).zip(&sens.df_dc) {
            if s.on_schedule {
                let row = &mut jac[s.schedule_index];
                for (r, (a, b)) in row.iter_mut().zip(dh.iter().zip(df)) {
                    *r = if cf != 0.0 { a + cf * b } else { *a };
                }
            }
        }
        if let Some(a) = &p.applied {
            a.jacobian(k, t, traj, &mut jac);
        }
        return Ok(jac);
    }
    let mut slot = None;
    let traj = in_full(traj, &t.solver_options, c, &mut slot, |o| {
        w.solver.run(&*p.law, c, &t.schedule, o)
    })?;
    let sens = match &w.columns {
        Some(cols) => w.adjoint.sensitivities_of(&*p.law, c, traj, cols),
        None => w.adjoint.sensitivities(&*p.law, c, traj),
    }
    .map_err(|source| IdentifyError::Adjoint {
        params: c.to_vec(),
        source,
    })?;
    let mut jac = vec![vec![0.0; c.len()]; t.schedule.t.len()];
    for (s, row) in traj.steps.iter().zip(&sens.df_dc) {
        if s.on_schedule {
            jac[s.schedule_index].clone_from(row);
        }
    }
    Ok(jac)
}

/// Runs the forward runs (`forward`) and follow-ups of `kind` of every test through the
/// task scheduler; `needed`: the follow-ups are asked for, otherwise speculative.
/// Returns how many speculative follow-ups ran.
#[allow(clippy::too_many_arguments)]
fn run_tests<'p>(
    p: &'p Problem,
    c: &[f64],
    work: &mut [Work<'p>],
    entries: &mut [TestEntry],
    forward: bool,
    kind: Option<Kind>,
    needed: bool,
    bound: Option<f64>,
) -> usize {
    let slot = |k: Kind| match k {
        Kind::Gradient => 1,
        Kind::Jacobian => 2,
    };
    let todo: Vec<Todo> = work
        .iter()
        .zip(entries.iter())
        .map(|(w, te)| Todo {
            forward,
            follow: match kind {
                Some(k) if !te.has(k) && needed => Follow::Needed,
                Some(k) if !te.has(k) => Follow::Speculative,
                _ => Follow::None,
            },
            expected: (w.seconds[0], kind.and_then(|k| w.seconds[slot(k)])),
        })
        .collect();
    let mut slots: Vec<(&mut Work, &mut TestEntry)> =
        work.iter_mut().zip(entries.iter_mut()).collect();
    let done = tasks::run(
        p.pool.as_deref(),
        &mut slots,
        &todo,
        |k, (w, te)| forward_task(p, c, k, w, te, bound),
        |k, (w, te)| match kind {
            Some(Kind::Gradient) => match gradient_task(p, c, k, w, te) {
                Ok(g) => te.gradient = Some(g),
                Err(e) => te.gradient_error = Some(e),
            },
            Some(Kind::Jacobian) => match jacobian_task(p, c, k, w, te) {
                Ok(j) => te.jacobian = Some(j),
                Err(e) => te.jacobian_error = Some(e),
            },
            None => {}
        },
    );
    let mut speculated = 0;
    for (((w, d), t), te) in work.iter_mut().zip(&done).zip(&todo).zip(entries.iter()) {
        // a stopped run's time says nothing of a whole run's
        if let (Some(s), None) = (d.forward, te.stopped) {
            w.seconds[0] = Some(s);
        }
        if let (Some(s), Some(k)) = (d.follow, kind) {
            w.seconds[slot(k)] = Some(s);
            if t.follow == Follow::Speculative {
                speculated += 1;
            }
        }
    }
    speculated
}

impl<'p> Evaluator<'p> {
    /// Workspaces for `problem` (one symbolic analysis each for the forward and the
    /// adjoint of every test).
    ///
    /// # Errors
    /// [`IdentifyError::Forward`] / [`IdentifyError::Adjoint`] if the analysis fails.
    pub fn new(problem: &'p Problem) -> Result<Evaluator<'p>, IdentifyError> {
        let mut work = Vec::with_capacity(problem.tests.len());
        for t in &problem.tests {
            let solver = DirectSolver::new(&t.model).map_err(|source| IdentifyError::Forward {
                params: vec![],
                source,
            })?;
            let adjoint = Adjoint::new(&t.model).map_err(|source| IdentifyError::Adjoint {
                params: vec![],
                source,
            })?;
            work.push(Work {
                solver,
                adjoint,
                seconds: [None; 3],
                warm: None,
                columns: None,
            });
        }
        Ok(Evaluator {
            problem,
            work,
            entry: None,
            counts: Counts::default(),
            best: None,
            start: Instant::now(),
            seen: HashSet::new(),
            prefetch: Prefetch::None,
        })
    }

    /// What to compute ahead of a request on cores left idle ([`Prefetch`]; the
    /// optimizers of [`crate::optimize`] set it for their method).
    pub fn set_prefetch(&mut self, prefetch: Prefetch) {
        self.prefetch = prefetch;
    }

    /// Restricts the Jacobian ([`Evaluator::jacobian`]) of depth-controlled tests to the
    /// parameters `columns` (indices in law order; `None`: all): the other parameters'
    /// sensitivity systems are never solved and their columns are zero. The columns
    /// formed are the same bits as the full Jacobian's. An identification passes its free
    /// parameters (the fixed ones' columns serve nothing there). A cached Jacobian formed
    /// with other columns is dropped. Load-controlled tests form every column.
    pub fn set_jacobian_columns(&mut self, columns: Option<Vec<usize>>) {
        if self.work.first().is_some_and(|w| w.columns == columns) {
            return;
        }
        for w in &mut self.work {
            w.columns.clone_from(&columns);
        }
        if let Some(e) = self.entry.as_mut() {
            e.jacobian = None;
            for t in &mut e.tests {
                t.jacobian = None;
                t.jacobian_error = None;
            }
        }
    }

    /// The problem.
    pub fn problem(&self) -> &'p Problem {
        self.problem
    }

    /// Counters so far (a forward solve, adjoint sweep or sensitivity pass of a joint
    /// problem counts once per test).
    pub fn counts(&self) -> Counts {
        self.counts
    }

    /// Seconds since this evaluator was created.
    pub fn elapsed(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// The lowest finite cost seen so far and its parameters.
    pub fn best(&self) -> Option<(f64, &[f64])> {
        self.best.as_ref().map(|(j, c)| (*j, c.as_slice()))
    }

    /// Makes sure the cache holds point `c` with its trajectories (one forward solve per
    /// test unless already there), and, with `want`, every test's follow-up of that kind
    /// (scheduled together with the forwards). A failed forward solve caches `J = +inf`.
    ///
    /// With a `bound` (a cost request of [`Evaluator::cost_below`]) each test's forward run
    /// stops once its partial cost reaches it ([`CostWatch`]); the entry is then marked
    /// stopped.
    fn ensure(
        &mut self,
        c: &[f64],
        need_traj: bool,
        want: Option<Kind>,
        bound: Option<f64>,
    ) -> Result<&mut Entry, IdentifyError> {
        let key = key_of(c);
        if self.seen.insert(key.clone()) {
            self.counts.distinct_points += 1;
        }
        let p = self.problem;
        let hit = self.entry.as_ref().is_some_and(|e| {
            e.key == key
                && (!need_traj || e.forces.is_some())
                // a stopped entry answers a bounded cost at a bound no higher only
                && e.stopped.is_none_or(|b0| bound.is_some_and(|b| b <= b0))
        });
        if hit {
            self.counts.cache_hits += 1;
            if let (Some(kind), Some(e)) = (want, self.entry.as_mut())
                && e.forces.is_some()
                && e.tests.iter().any(|t| !t.has(kind))
            {
                run_tests(p, c, &mut self.work, &mut e.tests, false, want, true, None);
            }
        } else {
            let n = p.tests.len();
            self.counts.forward += n;
            let old = self.entry.take();
            if p.warm_start {
                self.keep_warm(old);
            }
            let mut tests: Vec<TestEntry> = (0..n).map(|_| TestEntry::default()).collect();
            let (kind, needed) = match (want, self.prefetch) {
                (Some(k), _) => (Some(k), true),
                (None, Prefetch::Gradient) => (Some(Kind::Gradient), false),
                (None, Prefetch::Jacobian) => (Some(Kind::Jacobian), false),
                (None, Prefetch::None) => (None, false),
            };
            self.counts.prefetched +=
                run_tests(p, c, &mut self.work, &mut tests, true, kind, needed, bound);
            for t in tests.iter().filter_map(|te| te.traj.as_ref()) {
                self.counts.newton_iterations += t.total_iterations();
                self.counts.factorizations += t.timing.factorizations;
            }
            let mut stopped = false;
            for (t, te) in p.tests.iter().zip(&tests) {
                let n = t.schedule.t.len().saturating_sub(1) as u64;
                if let Some(j) = te.stopped {
                    stopped = true;
                    self.counts.stopped += 1;
                    self.counts.newton_iterations += te.stopped_work.0;
                    self.counts.factorizations += te.stopped_work.1;
                    self.counts.schedule_steps += j as u64;
                    self.counts.steps_skipped += n.saturating_sub(j as u64);
                } else if te.traj.is_some() {
                    self.counts.schedule_steps += n;
                }
            }
            let mut failed = None;
            let mut error = None;
            for (k, te) in tests.iter_mut().enumerate() {
                if let Some(source) = te.forward_error.take() {
                    // a step that failed, or a point the law does not admit (a box face
                    // on an open end of its range, `sum g_i >= 1` of a Prony law): the
                    // cost there is +inf, so a line search or a trial step backs off
                    let step_failed = matches!(
                        source,
                        ContactError::StepFailed { .. } | ContactError::Parameters(_)
                    );
                    if step_failed {
                        self.counts.forward_failed += 1;
                    }
                    if step_failed && !need_traj {
                        failed.get_or_insert(k);
                    } else if error.is_none() {
                        error = Some(source);
                    }
                }
            }
            if let Some(source) = error {
                return Err(IdentifyError::Forward {
                    params: c.to_vec(),
                    source,
                });
            }
            let entry = if failed.is_some() {
                Entry {
                    key,
                    cost: f64::INFINITY,
                    stopped: None,
                    forces: None,
                    tests,
                    gradient: None,
                    jacobian: None,
                }
            } else if let (true, Some(b)) = (stopped, bound) {
                // at least the bound: never the lowest cost, never a warm start
                Entry {
                    key,
                    cost: f64::INFINITY,
                    stopped: Some(b),
                    forces: None,
                    tests,
                    gradient: None,
                    jacobian: None,
                }
            } else {
                let forces: Vec<f64> = tests
                    .iter()
                    .flat_map(|e| e.forces.iter().flatten().copied())
                    .collect();
                let cost = p.cost_of(&forces);
                if cost.is_finite() && self.best.as_ref().is_none_or(|(b, _)| cost < *b) {
                    self.best = Some((cost, c.to_vec()));
                }
                Entry {
                    key,
                    cost,
                    stopped: None,
                    forces: Some(forces),
                    tests,
                    gradient: None,
                    jacobian: None,
                }
            };
            self.entry = Some(entry);
        }
        match self.entry.as_mut() {
            Some(e) => Ok(e),
            None => Err(IdentifyError::Optimizer("cache entry vanished".into())),
        }
    }

    /// Keeps the trajectories of `old`, the entry being replaced, as the warm start of
    /// the next forward runs when it is the lowest-cost point so far (a point a
    /// Levenberg-Marquardt iteration or a line search accepted); the previous warm start
    /// stays otherwise.
    fn keep_warm(&mut self, old: Option<Entry>) {
        let Some(old) = old else { return };
        let best = self
            .best
            .as_ref()
            .is_some_and(|(_, c)| key_of(c) == old.key);
        if best && old.forces.is_some() {
            for (w, te) in self.work.iter_mut().zip(old.tests) {
                if let Some(mut t) = te.traj {
                    // only the displacements serve (n_steps x n_dofs values)
                    for f in &mut t.fields {
                        f.sigma = Vec::new();
                        f.alpha = Vec::new();
                        f.regime = Vec::new();
                    }
                    t.checkpoints = Vec::new();
                    w.warm = Some(t);
                }
            }
        }
    }

    /// The cache entry [`Evaluator::ensure`] just made or found.
    fn entry_mut(&mut self) -> Result<&mut Entry, IdentifyError> {
        self.entry
            .as_mut()
            .ok_or_else(|| IdentifyError::Optimizer("cache entry vanished".into()))
    }

    /// Counts a request of `kind` at `c` (one adjoint sweep or sensitivity pass per test)
    /// unless the cache already holds its combined result.
    fn count_request(&mut self, c: &[f64], kind: Kind) {
        let cached = self.entry.as_ref().is_some_and(|e| {
            e.key == key_of(c)
                && match kind {
                    Kind::Gradient => e.gradient.is_some(),
                    Kind::Jacobian => e.jacobian.is_some(),
                }
        });
        if !cached {
            let n = self.problem.tests.len();
            match kind {
                Kind::Gradient => self.counts.adjoint += n,
                Kind::Jacobian => self.counts.sensitivities += n,
            }
        }
    }

    /// `J(c)`; `+inf` when the direct problem of a test fails even after step cutting (so
    /// that a line search backs off).
    ///
    /// # Errors
    /// [`IdentifyError::Forward`] for inadmissible parameters.
    pub fn cost(&mut self, c: &[f64]) -> Result<f64, IdentifyError> {
        Ok(self.ensure(c, false, None, None)?.cost)
    }

    /// `J(c)` when it is below `bound`, else possibly only that it is not: `Some(J)` as
    /// [`Evaluator::cost`] gives it (bit for bit; `+inf` for a failed run), or `None`
    /// when `J(c) >= bound` was established before the forward runs ended (a caller that
    /// rejects any point whose cost is at least `bound`, as a Levenberg-Marquardt trial,
    /// saves their remaining steps). Each test's run stops between steps once its own
    /// partial cost reaches the bound: the other tests' costs are `>= 0`, so the joint one
    /// is then at least the bound too, and what stops does not depend on the number of
    /// threads. The bound used is raised to the lowest cost seen so far, so that a stopped
    /// point could never have been the lowest one (nor the warm start of later runs). A
    /// problem with an instrument ([`Problem::joint_instrumented`]) runs in full.
    ///
    /// # Errors
    /// As [`Evaluator::cost`].
    pub fn cost_below(&mut self, c: &[f64], bound: f64) -> Result<Option<f64>, IdentifyError> {
        let bound = match &self.best {
            Some((b, _)) => bound.max(*b),
            None => bound,
        };
        let e = self.ensure(c, false, None, Some(bound))?;
        Ok(e.stopped.is_none().then_some(e.cost))
    }

    /// Forces `F_i(c)` at the schedule times (index 0 = initial state), every test's laid
    /// end to end in test order ([`Problem::rows_of`]); a load-controlled test's rows are
    /// its depths `h_i(c)` (mm), its observable ([`Test::observables`]).
    ///
    /// # Errors
    /// [`IdentifyError::Forward`] when the direct problem fails.
    pub fn forces(&mut self, c: &[f64]) -> Result<Vec<f64>, IdentifyError> {
        let e = self.ensure(c, true, None, None)?;
        Ok(e.forces.clone().unwrap_or_default())
    }

    /// The recorded trajectory of the first test at `c` (the only one of a one-test
    /// problem); [`Evaluator::trajectory_of`] for the others.
    ///
    /// # Errors
    /// [`IdentifyError::Forward`] when the direct problem fails.
    pub fn trajectory(&mut self, c: &[f64]) -> Result<&Trajectory, IdentifyError> {
        self.trajectory_of(0, c)
    }

    /// The recorded trajectory of test `k` at `c`.
    ///
    /// # Errors
    /// [`IdentifyError::Forward`] when the direct problem fails;
    /// [`IdentifyError::InvalidSpec`] for a test index out of range.
    pub fn trajectory_of(&mut self, k: usize, c: &[f64]) -> Result<&Trajectory, IdentifyError> {
        let n = self.problem.tests.len();
        if k >= n {
            return Err(IdentifyError::InvalidSpec {
                name: "test".into(),
                why: format!("test index {k} is out of range: the problem has {n} tests"),
            });
        }
        let e = self.ensure(c, true, None, None)?;
        e.tests[k]
            .traj
            .as_ref()
            .ok_or_else(|| IdentifyError::Optimizer("trajectory missing".into()))
    }

    /// `J(c)` and the full physical gradient `dJ/dc` (law order) by the adjoint: the sum of
    /// the tests' adjoint gradients, in test order.
    ///
    /// # Errors
    /// [`IdentifyError::Forward`] when the direct problem fails, [`IdentifyError::Adjoint`]
    /// when the adjoint does (e.g. Norton-Hoff with `m <= 1`).
    pub fn cost_and_gradient(&mut self, c: &[f64]) -> Result<(f64, Vec<f64>), IdentifyError> {
        // hit or miss, `ensure` counts it; a gradient already there is a second hit
        self.ensure(c, true, Some(Kind::Gradient), None)?;
        // counted once the forward runs succeeded (a failed forward sweeps nothing)
        self.count_request(c, Kind::Gradient);
        let e = self.entry_mut()?;
        if let Some(g) = &e.gradient {
            return Ok((e.cost, g.clone()));
        }
        // summed in test order (bit-identical for any number of threads)
        let mut total: Option<Vec<f64>> = None;
        for te in &mut e.tests {
            if let Some(err) = te.gradient_error.take() {
                return Err(err);
            }
            let Some(g) = &te.gradient else {
                return Err(IdentifyError::Optimizer("gradient missing".into()));
            };
            match total.as_mut() {
                None => total = Some(g.clone()),
                Some(t) => t.iter_mut().zip(g).for_each(|(a, b)| *a += b),
            }
        }
        let g = total.unwrap_or_default();
        e.gradient = Some(g.clone());
        Ok((e.cost, g))
    }

    /// The Jacobian `dF_i/dc_k` at the schedule times (row 0 of each test, its initial
    /// state, is 0), all law parameters, by forward sensitivities; the tests' rows laid end
    /// to end in test order ([`Problem::rows_of`]); a load-controlled test's rows are
    /// `dh_i/dc_k` (the bordered sensitivities, docs/theory.md §13).
    ///
    /// # Errors
    /// As [`Evaluator::cost_and_gradient`].
    pub fn jacobian(&mut self, c: &[f64]) -> Result<Vec<Vec<f64>>, IdentifyError> {
        let p = self.problem;
        self.ensure(c, true, Some(Kind::Jacobian), None)?;
        self.count_request(c, Kind::Jacobian);
        let e = self.entry_mut()?;
        if let Some(j) = &e.jacobian {
            return Ok(j.clone());
        }
        let mut jac = Vec::with_capacity(p.target.len());
        for te in &mut e.tests {
            if let Some(err) = te.jacobian_error.take() {
                return Err(err);
            }
            let Some(j) = &te.jacobian else {
                return Err(IdentifyError::Optimizer("Jacobian missing".into()));
            };
            jac.extend(j.iter().cloned());
        }
        e.jacobian = Some(jac.clone());
        Ok(jac)
    }
}
