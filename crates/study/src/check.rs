//! The gradient check: the adjoint gradient of the misfit against central finite
//! differences of the forward solver's own cost and against the forward sensitivities
//! (`J^T rho`), per parameter, over the whole loading history with contact on.
//!
//! Without `--data`, the data are the configuration's own curve (simulated at its law
//! parameters, the "truth") and the check point is the truth with every parameter
//! multiplied by [`PERTURBATION`], except `nu`, multiplied by [`NU_PERTURBATION`]: the
//! misfit is then non-zero and every component of the gradient is exercised (values rounded
//! to 12 significant digits, so that `1e5 x 1.1` prints as `110000`). With `--data`, the
//! check point is the configuration's law parameters.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, anyhow};
use indentify_adjoint::Adjoint;
use indentify_adjoint::check::{central_difference, relative_difference, scan};
use indentify_contact::{DirectSolver, SolverOptions};
use indentify_identify::{Evaluator, ForceRecord, Problem};
use indentify_laws::Material;
use rayon::prelude::*;
use serde::Serialize;
use std::sync::Arc;

use crate::config::Config;
use crate::data;
use crate::error::{Classify, ErrorKind, Result};
use crate::format::{Named, assignments};
use crate::identify::prepare_driven;
use crate::solve::{ensure_differentiable, forward, param_names};
use crate::source::ConfigSource;

/// Factor applied to every parameter but `nu` to get the check point from the truth.
pub const PERTURBATION: f64 = 1.1;
/// Factor applied to `nu` (`0.3 -> 0.291`; `1.1` would push a near-incompressible `nu`
/// out of its range).
pub const NU_PERTURBATION: f64 = 0.97;
/// Largest admissible relative difference between the adjoint and `J^T rho`: two exact
/// derivations of the same discrete derivative, equal to round-off.
pub const SENSITIVITY_TOL: f64 = 1e-8;
/// Relative FD steps of `--scan`.
pub const SCAN_STEPS: [f64; 8] = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9];
/// The forward solves of the check converge to at least this relative residual, so that
/// the noise of the finite differences (residual / step) stays below `--tol`.
pub const CHECK_RESIDUAL_TOL: f64 = 1e-12;

/// What to check.
#[derive(Clone, Debug)]
pub struct CheckOptions {
    /// The configuration.
    pub config: ConfigSource,
    /// `dotted.path=value` overrides.
    pub sets: Vec<String>,
    /// Compare with this curve at the configuration's law parameters; without it, data
    /// are synthesized and the point perturbed ([`PERTURBATION`]).
    pub data: Option<PathBuf>,
    /// Relative step of the central differences: `h = rel_step |c_k|`.
    pub rel_step: f64,
    /// Largest admissible relative difference between the adjoint and central differences.
    pub tol: f64,
    /// Also difference at relative steps [`SCAN_STEPS`].
    pub scan: bool,
    /// The test (from 1) of a joint configuration (`tests: [...]`) to work on; required
    /// for one, refused for a one-test configuration.
    pub test: Option<usize>,
}

impl CheckOptions {
    /// The default check (relative step 1e-5, tolerance 1e-6, no scan) of `config`.
    pub fn new(config: ConfigSource) -> CheckOptions {
        CheckOptions {
            config,
            sets: Vec::new(),
            data: None,
            rel_step: 1e-5,
            tol: 1e-6,
            scan: false,
            test: None,
        }
    }
}

/// One row of the FD scan.
#[derive(Clone, Debug, Serialize)]
pub struct ScanRow {
    /// Relative step.
    pub rel_step: f64,
    /// Central difference.
    pub fd: f64,
    /// Its relative difference to the adjoint.
    pub rel_diff: f64,
}

/// One parameter's comparison.
#[derive(Clone, Debug, Serialize)]
pub struct ParamCheck {
    /// Parameter name.
    pub name: &'static str,
    /// Its unit.
    pub unit: &'static str,
    /// The check point's value.
    pub value: f64,
    /// Adjoint `dJ/dc`.
    pub adjoint: f64,
    /// Central difference.
    pub fd: f64,
    /// `J^T rho` from the forward sensitivities.
    pub sensitivity: f64,
    /// Relative difference adjoint vs FD.
    pub rel_diff_fd: f64,
    /// Relative difference adjoint vs sensitivities.
    pub rel_diff_sensitivity: f64,
    /// Both within their tolerances.
    pub passed: bool,
    /// The scan, if asked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scan: Option<Vec<ScanRow>>,
    /// Coulomb friction only: whether the +h and -h runs kept the check point's contact
    /// set and stick/slip status at every step (where a status flips the cost is not
    /// differentiable and the comparison is not meaningful: the check then fails).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub statuses_held: Option<bool>,
}

/// The check's outcome (serialized as the JSON report of `indentify gradient-check`).
#[derive(Clone, Debug, Serialize)]
pub struct CheckReport {
    /// The law's name.
    pub law: &'static str,
    /// The configuration's name.
    pub config: String,
    /// `synthesized`, or the data's name.
    pub data: String,
    /// The law values that synthesized the data.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth: Option<Named<f64>>,
    /// The check point.
    pub params: Named<f64>,
    /// The misfit at the check point (N^2).
    #[serde(rename = "J")]
    pub j: f64,
    /// Relative FD step.
    pub rel_step: f64,
    /// Tolerance adjoint vs FD.
    pub tol: f64,
    /// Tolerance adjoint vs sensitivities.
    pub sensitivity_tol: f64,
    /// Forward residual tolerance used.
    pub residual_tol: f64,
    /// One comparison per parameter.
    pub checks: Vec<ParamCheck>,
    /// Every comparison passed.
    pub passed: bool,
    /// Wall times (s).
    pub forward_seconds: f64,
    /// Adjoint sweep (s).
    pub adjoint_seconds: f64,
    /// Sensitivities (s).
    pub sensitivity_seconds: f64,
    /// Finite differences (s).
    pub fd_seconds: f64,
    /// Forward solves of the differences.
    pub fd_forward_solves: usize,
    /// Schedule times.
    #[serde(skip)]
    pub schedule_times: usize,
    /// The data's name, also when synthesized.
    #[serde(skip)]
    pub data_name: String,
    /// Whether the data were synthesized.
    #[serde(skip)]
    pub synthesized: bool,
    /// The failures, one line each.
    #[serde(skip)]
    pub failures: Vec<String>,
}

/// Runs the check of a configuration's cost: the one test's, or with a joint configuration
/// (`tests: [...]`, no `--test`) the joint cost `J = sum_k w_k J_k` over every test's whole
/// history, each test's adjoint gradient and sensitivities summed in test order (the
/// tests solved in parallel). A failed comparison is not an error:
/// [`CheckReport::passed`] says so.
///
/// # Errors
/// Invalid inputs (a step or tolerance out of range, a check point outside the law's
/// admissible range, `--data` with a joint configuration), a failing solve.
pub fn run(args: &CheckOptions) -> Result<CheckReport> {
    if !(args.rel_step > 0.0 && args.rel_step < 1.0) {
        return config_error(format!(
            "--rel-step {} is not allowed: expected a relative step in (0, 1), e.g. 1e-5",
            args.rel_step
        ));
    }
    if !(args.tol > 0.0 && args.tol.is_finite()) {
        return config_error(format!(
            "--tol {} is not allowed: expected a tolerance > 0",
            args.tol
        ));
    }
    let name = args.config.name();
    let mut cfg = args.config.load(&args.sets)?;
    if args.test.is_some() {
        cfg = cfg
            .one_test(args.test, "gradient-check", &name)
            .kind(ErrorKind::Config)?;
    }
    if cfg.tests.is_some() && args.data.is_some() {
        return config_error(format!(
            "--data replaces the record of a one-test configuration, and `{name}` is a joint \
             configuration: give each test's record in tests[K].data, or check one test with \
             --test K"
        ));
    }
    let (law, truth) = cfg.law.build().kind(ErrorKind::Config)?;
    // the instrument's parameters (Cf, vd, h0) that the `identify` section names, checked
    // with the law's (load control; the check point holds them at 0)
    let (law, truth) = crate::instrument::with_instrument(&cfg, law, truth, &Default::default());
    let law = &law;
    // tight forward solves for the differences (and the synthesized data)
    cfg.solver.residual_tol = cfg.solver.residual_tol.min(CHECK_RESIDUAL_TOL);
    let opts = cfg.solver.options(true);
    let set_up = set_up(args, &cfg, &name, law, &truth)?;
    let point = check_point(args, law, &truth, set_up.synthesized)?;
    let SetUp {
        problem,
        run_names,
        data_name,
        synthesized,
    } = set_up;
    // each solver borrows its test's model, which lives in the problem
    let mut solvers: Vec<DirectSolver> = problem
        .tests
        .iter()
        .map(|t| DirectSolver::new(&t.model))
        .collect::<std::result::Result<_, _>>()
        .kind(ErrorKind::Solver)?;
    let at = at_point(&problem, &mut solvers, &point, &opts, &run_names)?;
    let fd_start = Instant::now();
    let (checks, solves) = compare(args, &problem, &mut solvers, &point, &at, &opts, &run_names)?;
    let fd_seconds = fd_start.elapsed().as_secs_f64();
    let passed = checks.iter().all(|c| c.passed);
    let failures: Vec<String> = checks
        .iter()
        .filter(|c| !c.passed)
        .map(|c| {
            let flip = if c.statuses_held == Some(false) {
                "; a contact or stick/slip status flips under +-h (the cost is not \
                 differentiable across it: the difference is not meaningful; try a smaller \
                 --rel-step)"
            } else {
                ""
            };
            format!(
                "{}: adjoint vs central FD {:.1e} (--tol {:.0e}), adjoint vs sensitivities {:.1e} \
                 (limit {SENSITIVITY_TOL:.0e}){flip}",
                c.name, c.rel_diff_fd, args.tol, c.rel_diff_sensitivity
            )
        })
        .collect();
    let names = param_names(&**law);
    Ok(CheckReport {
        law: law.name(),
        config: name,
        data: if synthesized {
            "synthesized".into()
        } else {
            data_name.clone()
        },
        truth: synthesized.then(|| Named::new(names.iter().copied().zip(truth.clone()))),
        params: Named::new(names.iter().copied().zip(point.iter().copied())),
        j: at.j,
        rel_step: args.rel_step,
        tol: args.tol,
        sensitivity_tol: SENSITIVITY_TOL,
        residual_tol: opts.residual_tol,
        checks,
        passed,
        forward_seconds: at.forward_seconds,
        adjoint_seconds: at.adjoint_seconds,
        sensitivity_seconds: at.sensitivity_seconds,
        fd_seconds,
        fd_forward_solves: solves,
        schedule_times: problem.tests.iter().map(|t| t.schedule.t.len()).sum(),
        data_name,
        synthesized,
        failures,
    })
}

/// A [`ErrorKind::Config`] error.
fn config_error<T>(msg: String) -> Result<T> {
    Err(crate::Error::msg(ErrorKind::Config, msg))
}

/// The tests of a check, set up: the problem, a direct solver per test, the data.
struct SetUp {
    problem: Problem,
    /// Each test's name in messages (`config [label]` in a joint configuration).
    run_names: Vec<String>,
    data_name: String,
    synthesized: bool,
}

/// Every test of `cfg` (the configuration itself without `tests`) prepared, its data read
/// (`--data`, one test only) or synthesized at `truth`, and weighted (1 for a one-test
/// configuration, else its `weight` or the default `1 / (n F_max^2)`).
fn set_up(
    args: &CheckOptions,
    cfg: &Config,
    name: &str,
    law: &Arc<dyn Material>,
    truth: &[f64],
) -> Result<SetUp> {
    let opts = cfg.solver.options(true);
    let fd_opts = SolverOptions {
        record_fields: false,
        ..opts.clone()
    };
    let names = param_names(&**law);
    let mut tests = Vec::with_capacity(cfg.n_tests());
    let mut run_names = Vec::with_capacity(cfg.n_tests());
    let mut data_name = String::new();
    for k in 0..cfg.n_tests() {
        let (sub, run_name, what) = match &cfg.tests {
            Some(_) => (
                cfg.test_config(k)
                    .with_context(|| format!("in tests[{k}] of `{name}`"))
                    .kind(ErrorKind::Config)?,
                format!("{name} [{}]", cfg.test_name(k)),
                format!("tests[{k}] of `{name}`"),
            ),
            None => (cfg.clone(), name.to_string(), format!("`{name}`")),
        };
        // under load control (force segments, `data.drive: Force`) the depth is the
        // observable: the data's `h`, or the truth's depths
        let (prepared, load) = prepare_driven(&sub, &run_name)?;
        let (schedule, model) = (prepared.schedule, prepared.model);
        let record = match &args.data {
            Some(path) => {
                let curve = data::read_curve(path).kind(ErrorKind::Data)?;
                let (t0, t1) = (schedule.t[0], schedule.t[schedule.t.len() - 1]);
                curve.check_covers(t0, t1, name).kind(ErrorKind::Data)?;
                data_name = curve.name.clone();
                match (&load, &curve.h) {
                    (None, _) => curve.record().kind(ErrorKind::Data)?,
                    (Some(_), Some(h)) => ForceRecord::new(curve.t.clone(), h.clone())
                        .with_context(|| format!("invalid depths in `{}`", curve.name))
                        .kind(ErrorKind::Data)?,
                    (Some(_), None) => {
                        return Err(crate::Error::msg(
                            ErrorKind::Data,
                            format!(
                                "the data `{}` have no depth column `h`: under load control \
                                 the depth is the observable of {what}",
                                curve.name
                            ),
                        ));
                    }
                }
            }
            None => {
                let mut solver = DirectSolver::new(&model).kind(ErrorKind::Solver)?;
                let traj = run_test(
                    &mut solver,
                    &**law,
                    truth,
                    &schedule,
                    load.as_ref(),
                    &fd_opts,
                    &run_name,
                )
                .with_context(|| format!("cannot simulate `{run_name}`"))
                .kind(ErrorKind::Solver)?;
                let observed = match load {
                    Some(_) => depths(&traj),
                    None => traj.forces(),
                };
                ForceRecord::new(schedule.t.clone(), observed)
                    .context("cannot use the simulated curve as data")
                    .kind(ErrorKind::Data)?
            }
        };
        let compare = || match &args.data {
            Some(_) => format!("cannot compare `{data_name}` with {what}"),
            None => format!("cannot compare the data with {what}"),
        };
        let weight = match cfg.tests.as_ref().map(|t| t[k].weight) {
            None => 1.0,
            Some(Some(w)) => w,
            Some(None) => indentify_identify::Test::default_weight(&schedule, &record)
                .with_context(compare)
                .kind(ErrorKind::Data)?,
        };
        let test = match load {
            Some(h) => {
                indentify_identify::Test::new_load(model, h, &record, None, opts.clone(), weight)
            }
            None => {
                indentify_identify::Test::new(model, schedule, &record, None, opts.clone(), weight)
            }
        }
        .with_context(compare)
        .kind(ErrorKind::Data)?;
        tests.push(test);
        run_names.push(run_name);
    }
    let synthesized = args.data.is_none();
    if synthesized {
        data_name = format!(
            "synthesized from `{name}` at {}",
            assignments(&names, truth)
        );
        if cfg.tests.is_some() {
            data_name = format!(
                "the joint cost sum_k w_k J_k of {} tests, each {data_name}",
                tests.len()
            );
        }
    }
    let problem = crate::instrument::problem(cfg, name, law, tests, &Default::default())?;
    Ok(SetUp {
        problem,
        run_names,
        data_name,
        synthesized,
    })
}

/// The check point: with synthesized data the truth perturbed ([`PERTURBATION`],
/// [`NU_PERTURBATION`]), else the truth; refused where the law is not differentiable or a
/// difference stencil leaves a parameter's range.
fn check_point(
    args: &CheckOptions,
    law: &Arc<dyn Material>,
    truth: &[f64],
    synthesized: bool,
) -> Result<Vec<f64>> {
    let names = param_names(&**law);
    let point: Vec<f64> = if synthesized {
        names
            .iter()
            .zip(truth)
            .map(|(n, v)| {
                let factor = if *n == "nu" {
                    NU_PERTURBATION
                } else {
                    PERTURBATION
                };
                // an instrument parameter (0 at the truth) at its nominal scale, so that
                // the stencil stays admissible (Cf >= 0) and its terms are exercised
                match indentify_identify::Instrument::nominal_scale(n) {
                    Some(s) if *v == 0.0 => s,
                    _ => round_significant(v * factor),
                }
            })
            .collect()
    } else {
        truth.to_vec()
    };
    if synthesized {
        law.check_params(&point)
            .map_err(|e| {
                anyhow!(
                    "the check point (configuration x {PERTURBATION}, nu x {NU_PERTURBATION}) \
                     is not admissible: {e}; give --data or other law values"
                )
            })
            .kind(ErrorKind::Config)?;
    }
    ensure_differentiable(&**law, &point, "no gradient check").kind(ErrorKind::Config)?;
    for (k, info) in law.params().iter().enumerate() {
        let h = if point[k] == 0.0 {
            args.rel_step
        } else {
            args.rel_step * point[k].abs()
        };
        let steps_inside = [point[k] - h, point[k] + h].iter().all(|&v| {
            let mut c = point.clone();
            c[k] = v;
            law.check_params(&c).is_ok() && law.check_differentiable(&c).is_ok()
        });
        if !steps_inside {
            return config_error(format!(
                "cannot difference `{}` at {}: the stencil {} +- {h} leaves its admissible \
                 range {} (choose a check point inside, e.g. with --set law.{}=...)",
                info.name,
                point[k],
                point[k],
                info.range_text(),
                info.name
            ));
        }
    }
    Ok(point)
}

/// The contact set and stick/slip statuses of every step (with friction, the differences
/// are meaningful only where none flips).
type Statuses = Vec<(Vec<u32>, Vec<i8>)>;

fn statuses(t: &indentify_contact::Trajectory) -> Statuses {
    t.steps
        .iter()
        .map(|s| (s.active.clone(), s.slip.clone()))
        .collect()
}

/// `f` over the tests with their solvers: inline for one test, in parallel (results in
/// test order) for several.
fn each_test<R: Send>(
    problem: &Problem,
    solvers: &mut [DirectSolver<'_>],
    f: impl Fn(usize, &indentify_identify::Test, &mut DirectSolver<'_>) -> Result<R> + Sync + Send,
) -> Result<Vec<R>> {
    if let [solver] = solvers {
        return Ok(vec![f(0, &problem.tests[0], solver)?]);
    }
    problem.install(|| {
        solvers
            .par_iter_mut()
            .zip(&problem.tests)
            .enumerate()
            .map(|(k, (solver, test))| f(k, test, solver))
            .collect()
    })
}

/// The cost, gradients and statuses at the check point.
struct AtPoint {
    j: f64,
    /// The adjoint gradient, the tests' summed in test order.
    gradient: Vec<f64>,
    /// `J^T rho` from the forward sensitivities, over every test's steps in order.
    jt_rho: Vec<f64>,
    /// Each test's statuses, with friction.
    statuses: Vec<Option<Statuses>>,
    forward_seconds: f64,
    adjoint_seconds: f64,
    sensitivity_seconds: f64,
}

/// Each test's forward run, adjoint gradient and forward sensitivities at `point`.
fn at_point(
    problem: &Problem,
    solvers: &mut [DirectSolver<'_>],
    point: &[f64],
    opts: &SolverOptions,
    names: &[String],
) -> Result<AtPoint> {
    if problem.has_instrument() {
        return at_point_evaluated(problem, point);
    }
    let law = &problem.law;
    let start = Instant::now();
    let runs = each_test(problem, solvers, |k, test, solver| {
        let model = &test.model;
        let traj = run_test(
            solver,
            &**law,
            point,
            &test.schedule,
            test.load.as_ref(),
            opts,
            &names[k],
        )
        .with_context(|| format!("cannot simulate `{}`", names[k]))
        .kind(ErrorKind::Solver)?;
        let forward_done = start.elapsed().as_secs_f64();
        let rho = test.dj_df(&traj);
        let mut adjoint = Adjoint::new(model).kind(ErrorKind::Solver)?;
        let (grad, sens) = match &test.load {
            // load control: rho is dJ/dh, the rows dh/dc (docs/theory.md §13)
            Some(h) => {
                let zero = vec![0.0; rho.len()];
                let grad = adjoint
                    .gradient_load(&**law, point, &traj, h, &rho, &zero)
                    .context("the adjoint sweep failed")
                    .kind(ErrorKind::Solver)?;
                let s = adjoint
                    .sensitivities_load(&**law, point, &traj, h)
                    .context("the forward sensitivities failed")
                    .kind(ErrorKind::Solver)?;
                (grad, (s.dh_dc, s.seconds))
            }
            None => {
                let grad = adjoint
                    .gradient(&**law, point, &traj, &rho)
                    .context("the adjoint sweep failed")
                    .kind(ErrorKind::Solver)?;
                let s = adjoint
                    .sensitivities(&**law, point, &traj)
                    .context("the forward sensitivities failed")
                    .kind(ErrorKind::Solver)?;
                (grad, (s.df_dc, s.seconds))
            }
        };
        let held = (model.contact.friction() > 0.0).then(|| statuses(&traj));
        Ok((test.observables(&traj), rho, grad, sens, held, forward_done))
    })?;
    let mut forces = Vec::with_capacity(problem.target.len());
    let mut gradient: Option<Vec<f64>> = None;
    let mut jt_rho = vec![0.0; law.params().len()];
    let mut at = AtPoint {
        j: 0.0,
        gradient: Vec::new(),
        jt_rho: Vec::new(),
        statuses: Vec::with_capacity(runs.len()),
        forward_seconds: 0.0,
        adjoint_seconds: 0.0,
        sensitivity_seconds: 0.0,
    };
    for (f, rho, grad, sens, held, forward_done) in runs {
        forces.extend(f);
        match gradient.as_mut() {
            None => gradient = Some(grad.dj_dc),
            Some(g) => g.iter_mut().zip(&grad.dj_dc).for_each(|(a, b)| *a += b),
        }
        for (row, r) in sens.0.iter().zip(&rho) {
            for (gk, d) in jt_rho.iter_mut().zip(row) {
                *gk += r * d;
            }
        }
        at.statuses.push(held);
        at.forward_seconds = at.forward_seconds.max(forward_done);
        at.adjoint_seconds += grad.seconds;
        at.sensitivity_seconds += sens.1;
    }
    at.j = problem.cost_of(&forces);
    at.gradient = gradient.unwrap_or_default();
    at.jt_rho = jt_rho;
    Ok(at)
}

/// A fresh evaluator of `problem` (under load control each forward run starts cold).
fn evaluator(problem: &Problem) -> Result<Evaluator<'_>> {
    Evaluator::new(problem).map_err(solver_error)
}

/// An identification error as a solver error.
fn solver_error(e: indentify_identify::IdentifyError) -> crate::Error {
    crate::Error::new(ErrorKind::Solver, anyhow!(e))
}

/// [`at_point`] for a problem with instrument parameters, through the identification's
/// evaluator (the cost the fit minimizes, its adjoint gradient with the instrument's
/// terms, the sensitivity rows with the instrument's columns: docs/theory.md §13.6).
fn at_point_evaluated(problem: &Problem, point: &[f64]) -> Result<AtPoint> {
    let mut ev = evaluator(problem)?;
    let start = Instant::now();
    ev.cost(point).map_err(solver_error)?;
    let forward_seconds = start.elapsed().as_secs_f64();
    let (j, gradient) = ev.cost_and_gradient(point).map_err(solver_error)?;
    let adjoint_seconds = start.elapsed().as_secs_f64() - forward_seconds;
    let observed = ev.forces(point).map_err(solver_error)?;
    let jac = ev.jacobian(point).map_err(solver_error)?;
    let sensitivity_seconds = start.elapsed().as_secs_f64() - forward_seconds - adjoint_seconds;
    // with friction, each test's contact sets and stick/slip statuses, which the +-h runs
    // of the differences must hold
    let mut held = Vec::with_capacity(problem.tests.len());
    for (k, test) in problem.tests.iter().enumerate() {
        held.push(if test.model.contact.friction() > 0.0 {
            Some(statuses(ev.trajectory_of(k, point).map_err(solver_error)?))
        } else {
            None
        });
    }
    let mut jt_rho = vec![0.0; point.len()];
    for ((row, h), (d, w)) in jac
        .iter()
        .zip(&observed)
        .zip(problem.target.iter().zip(&problem.weights))
    {
        for (g, r) in jt_rho.iter_mut().zip(row) {
            *g += w * (h - d) * r;
        }
    }
    Ok(AtPoint {
        j,
        gradient,
        jt_rho,
        statuses: held,
        forward_seconds,
        adjoint_seconds,
        sensitivity_seconds,
    })
}

/// Central differences of the cost (every test's forward run at `c +- h e_k`) against the
/// adjoint and the sensitivities, per parameter; the forward solves they took.
fn compare(
    args: &CheckOptions,
    problem: &Problem,
    solvers: &mut [DirectSolver<'_>],
    point: &[f64],
    at: &AtPoint,
    opts: &SolverOptions,
    names: &[String],
) -> Result<(Vec<ParamCheck>, usize)> {
    let law = &problem.law;
    let fd_opts = SolverOptions {
        record_fields: false,
        ..opts.clone()
    };
    let friction = at.statuses.iter().any(Option::is_some);
    let flipped = std::cell::Cell::new(false);
    let mut solves = 0usize;
    let mut cost = |c: &[f64]| -> Result<f64> {
        solves += problem.tests.len();
        if problem.has_instrument() {
            let mut ev = evaluator(problem)?;
            let j = ev.cost(c).map_err(solver_error)?;
            // with friction, whether every test's run held the check point's statuses
            for (k, held) in at.statuses.iter().enumerate() {
                if let Some(b) = held
                    && *b != statuses(ev.trajectory_of(k, c).map_err(solver_error)?)
                {
                    flipped.set(true);
                }
            }
            return Ok(j);
        }
        let runs = each_test(problem, solvers, |k, test, solver| {
            let t = run_test(
                solver,
                &**law,
                c,
                &test.schedule,
                test.load.as_ref(),
                &fd_opts,
                &names[k],
            )
            .with_context(|| format!("cannot simulate `{}`", names[k]))
            .kind(ErrorKind::Solver)?;
            let kept = at.statuses[k].as_ref().is_none_or(|b| *b == statuses(&t));
            Ok((test.observables(&t), kept))
        })?;
        let mut forces = Vec::with_capacity(problem.target.len());
        for (f, kept) in runs {
            forces.extend(f);
            if !kept {
                flipped.set(true);
            }
        }
        Ok(problem.cost_of(&forces))
    };
    let mut checks = Vec::new();
    for (k, info) in law.params().iter().enumerate() {
        flipped.set(false);
        let fd = central_difference(&mut cost, point, k, args.rel_step)?;
        let statuses_held = friction.then(|| !flipped.get());
        let rows = if args.scan {
            Some(scan(&mut cost, point, k, at.gradient[k], &SCAN_STEPS)?)
        } else {
            None
        };
        let (a, s) = (at.gradient[k], at.jt_rho[k]);
        let (rd_fd, rd_s) = (relative_difference(a, fd), relative_difference(a, s));
        checks.push(ParamCheck {
            name: info.name,
            unit: info.unit,
            value: point[k],
            adjoint: a,
            fd,
            sensitivity: s,
            rel_diff_fd: rd_fd,
            rel_diff_sensitivity: rd_s,
            passed: rd_fd <= args.tol
                && rd_s <= SENSITIVITY_TOL
                && a.is_finite()
                && statuses_held != Some(false),
            scan: rows.map(|r| {
                r.iter()
                    .map(|r| ScanRow {
                        rel_step: r.h_rel,
                        fd: r.fd,
                        rel_diff: r.rel_diff,
                    })
                    .collect()
            }),
            statuses_held,
        });
    }
    Ok((checks, solves))
}

/// A test's forward run: by its depth schedule, or under load control by its history.
fn run_test(
    solver: &mut DirectSolver<'_>,
    law: &dyn Material,
    c: &[f64],
    schedule: &indentify_contact::Schedule,
    load: Option<&indentify_contact::LoadHistory>,
    opts: &SolverOptions,
    name: &str,
) -> anyhow::Result<indentify_contact::Trajectory> {
    match load {
        Some(h) => Ok(solver.run_history(law, c, h, opts)?),
        None => forward(solver, law, c, schedule, opts, name),
    }
}

/// The depths at the schedule times (index 0: the initial state, 0).
fn depths(traj: &indentify_contact::Trajectory) -> Vec<f64> {
    std::iter::once(0.0)
        .chain(traj.schedule_steps().map(|s| s.depth))
        .collect()
}

/// `v` rounded to 12 significant digits.
fn round_significant(v: f64) -> f64 {
    format!("{v:.11e}").parse().unwrap_or(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_points_print_without_float_noise() {
        assert_eq!(round_significant(1e5 * PERTURBATION).to_string(), "110000");
        assert_eq!(
            round_significant(0.3 * NU_PERTURBATION).to_string(),
            "0.291"
        );
        assert_eq!(round_significant(0.0), 0.0);
    }
}
