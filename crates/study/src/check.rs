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
use indentify_identify::{ForceRecord, Problem};
use serde::Serialize;

use crate::data;
use crate::error::{Classify, ErrorKind, Result};
use crate::format::{Named, assignments};
use crate::identify::prepare;
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

/// Runs the check. A failed comparison is not an error: [`CheckReport::passed`] says so.
///
/// # Errors
/// Invalid inputs (a step or tolerance out of range, a check point outside the law's
/// admissible range), a failing solve.
pub fn run(args: &CheckOptions) -> Result<CheckReport> {
    let config_error = |msg: String| Err(crate::Error::msg(ErrorKind::Config, msg));
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
    let cfg = args.config.load(&args.sets)?;
    if cfg.tests.is_some() && args.test.is_none() {
        return run_joint(args, cfg, &name);
    }
    let cfg = cfg
        .one_test(args.test, "gradient-check", &name)
        .kind(ErrorKind::Config)?;
    let (law, truth) = cfg.law.build().kind(ErrorKind::Config)?;
    let names = param_names(law);
    let infos = law.params();
    let prepared = prepare(&cfg, &name)?;
    let (schedule, model) = (prepared.schedule, prepared.model);
    let opts = SolverOptions {
        residual_tol: cfg.solver.residual_tol.min(CHECK_RESIDUAL_TOL),
        ..cfg.solver.options(true)
    };
    let fd_opts = SolverOptions {
        record_fields: false,
        ..opts.clone()
    };

    // data and check point
    let (record, data_name, point, synthesized) = match &args.data {
        Some(path) => {
            let curve = data::read_curve(path).kind(ErrorKind::Data)?;
            let (t0, t1) = (schedule.t[0], schedule.t[schedule.t.len() - 1]);
            curve.check_covers(t0, t1, &name).kind(ErrorKind::Data)?;
            (
                curve.record().kind(ErrorKind::Data)?,
                curve.name.clone(),
                truth.clone(),
                false,
            )
        }
        None => {
            let mut solver = DirectSolver::new(&model).kind(ErrorKind::Solver)?;
            let traj = forward(&mut solver, law, &truth, &schedule, &fd_opts, &name)
                .kind(ErrorKind::Solver)?;
            let record = ForceRecord::new(schedule.t.clone(), traj.forces())
                .context("cannot use the simulated curve as data")
                .kind(ErrorKind::Data)?;
            let point: Vec<f64> = names
                .iter()
                .zip(&truth)
                .map(|(n, v)| {
                    let factor = if *n == "nu" {
                        NU_PERTURBATION
                    } else {
                        PERTURBATION
                    };
                    round_significant(v * factor)
                })
                .collect();
            law.check_params(&point)
                .map_err(|e| {
                    anyhow!(
                        "the check point (configuration x {PERTURBATION}, nu x \
                         {NU_PERTURBATION}) is not admissible: {e}; give --data or other law \
                         values"
                    )
                })
                .kind(ErrorKind::Config)?;
            let data = format!(
                "synthesized from `{name}` at {}",
                assignments(&names, &truth)
            );
            (record, data, point, true)
        }
    };
    ensure_differentiable(law, &point, "no gradient check").kind(ErrorKind::Config)?;
    for (k, info) in infos.iter().enumerate() {
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
    let problem = Problem::new(model, law, schedule, &record, None, opts.clone())
        .with_context(|| format!("cannot compare `{data_name}` with `{name}`"))
        .kind(ErrorKind::Data)?;
    let model = &problem.model();
    let mut solver = DirectSolver::new(model).kind(ErrorKind::Solver)?;

    // adjoint and sensitivities at the check point
    let start = Instant::now();
    let traj = forward(&mut solver, law, &point, problem.schedule(), &opts, &name)
        .kind(ErrorKind::Solver)?;
    let forward_seconds = start.elapsed().as_secs_f64();
    let j = problem.cost_of(&traj.forces());
    let rho = problem.dj_df(&traj);
    let mut adjoint = Adjoint::new(model).kind(ErrorKind::Solver)?;
    let grad = adjoint
        .gradient(law, &point, &traj, &rho)
        .context("the adjoint sweep failed")
        .kind(ErrorKind::Solver)?;
    let sens = adjoint
        .sensitivities(law, &point, &traj)
        .context("the forward sensitivities failed")
        .kind(ErrorKind::Solver)?;
    let jt_rho = sens.transpose_mul(&rho);
    // with friction, the differences are meaningful only where no status flips
    let statuses = |t: &indentify_contact::Trajectory| -> Vec<(Vec<u32>, Vec<i8>)> {
        t.steps
            .iter()
            .map(|s| (s.active.clone(), s.slip.clone()))
            .collect()
    };
    let base_statuses = (model.contact.friction() > 0.0).then(|| statuses(&traj));
    let flipped = std::cell::Cell::new(false);
    drop(traj);

    // finite differences of the forward solver's own cost
    let fd_start = Instant::now();
    let mut solves = 0usize;
    let mut cost = |c: &[f64]| -> Result<f64> {
        solves += 1;
        let t = forward(&mut solver, law, c, problem.schedule(), &fd_opts, &name)
            .kind(ErrorKind::Solver)?;
        if base_statuses.as_ref().is_some_and(|b| *b != statuses(&t)) {
            flipped.set(true);
        }
        Ok(problem.cost_of(&t.forces()))
    };
    let mut checks = Vec::new();
    for (k, info) in infos.iter().enumerate() {
        flipped.set(false);
        let fd = central_difference(&mut cost, &point, k, args.rel_step)?;
        let statuses_held = base_statuses.as_ref().map(|_| !flipped.get());
        let rows = if args.scan {
            Some(scan(&mut cost, &point, k, grad.dj_dc[k], &SCAN_STEPS)?)
        } else {
            None
        };
        let (a, s) = (grad.dj_dc[k], jt_rho[k]);
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

    Ok(CheckReport {
        law: law.name(),
        config: name.clone(),
        data: if synthesized {
            "synthesized".into()
        } else {
            data_name.clone()
        },
        truth: synthesized.then(|| Named::new(names.iter().copied().zip(truth.clone()))),
        params: Named::new(names.iter().copied().zip(point.iter().copied())),
        j,
        rel_step: args.rel_step,
        tol: args.tol,
        sensitivity_tol: SENSITIVITY_TOL,
        residual_tol: opts.residual_tol,
        checks,
        passed,
        forward_seconds,
        adjoint_seconds: grad.seconds,
        sensitivity_seconds: sens.seconds,
        fd_seconds,
        fd_forward_solves: solves,
        schedule_times: problem.schedule().t.len(),
        data_name,
        synthesized,
        failures,
    })
}

/// The check of a joint configuration (`tests: [...]`, no `--test`): the gradient of the
/// joint cost `J = sum_k w_k J_k` (the tests' adjoint gradients summed in test order by
/// the [`Evaluator`], tests solved in parallel) against central differences of the joint
/// cost over every test's whole history and against the stacked sensitivities
/// `sum_i w_i (F_i - F_i^exp) dF_i/dc`. Tests without a record are synthesized at the law
/// values; when every test is synthesized the check point is perturbed as for one test,
/// else it is the law values.
fn run_joint(
    args: &CheckOptions,
    mut cfg: crate::config::Config,
    name: &str,
) -> Result<CheckReport> {
    use indentify_identify::Evaluator;
    if args.data.is_some() {
        return Err(crate::Error::msg(
            ErrorKind::Config,
            format!(
                "--data replaces the record of a one-test configuration, and `{name}` is a \
                 joint configuration: give each test's record in tests[K].data, or check one \
                 test with --test K"
            ),
        ));
    }
    let (law, truth) = cfg.law.build().kind(ErrorKind::Config)?;
    let names = param_names(law);
    let infos = law.params();
    // tight forward solves for the differences (the data are synthesized with them too)
    cfg.solver.residual_tol = cfg.solver.residual_tol.min(CHECK_RESIDUAL_TOL);
    let opts = crate::identify::IdentifyOptions::new(args.config.clone());
    let (problem, tests, _) = crate::identify::joint_problem(&opts, &cfg, name, law, &truth)?;
    let synthesized = tests.iter().all(|(_, d, ..)| d.truth.is_some());
    let point: Vec<f64> = if synthesized {
        names
            .iter()
            .zip(&truth)
            .map(|(n, v)| {
                let f = if *n == "nu" {
                    NU_PERTURBATION
                } else {
                    PERTURBATION
                };
                round_significant(v * f)
            })
            .collect()
    } else {
        truth.clone()
    };
    law.check_params(&point)
        .map_err(|e| anyhow!("the check point is not admissible: {e}"))
        .kind(ErrorKind::Config)?;
    ensure_differentiable(law, &point, "no gradient check").kind(ErrorKind::Config)?;
    let mut eval = Evaluator::new(&problem).kind(ErrorKind::Solver)?;
    let start = Instant::now();
    let forces = eval.forces(&point).kind(ErrorKind::Solver)?;
    let forward_seconds = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let (j, grad) = eval.cost_and_gradient(&point).kind(ErrorKind::Solver)?;
    let adjoint_seconds = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let jac = eval.jacobian(&point).kind(ErrorKind::Solver)?;
    let sensitivity_seconds = start.elapsed().as_secs_f64();
    let rho: Vec<f64> = forces
        .iter()
        .zip(&problem.target)
        .zip(&problem.weights)
        .map(|((f, t), w)| w * (f - t))
        .collect();
    let fd_start = Instant::now();
    let mut solves = 0usize;
    let mut cost = |c: &[f64]| -> Result<f64> {
        solves += 1;
        eval.cost(c).kind(ErrorKind::Solver)
    };
    let mut checks = Vec::new();
    for (k, info) in infos.iter().enumerate() {
        let fd = central_difference(&mut cost, &point, k, args.rel_step)?;
        let rows = if args.scan {
            Some(scan(&mut cost, &point, k, grad[k], &SCAN_STEPS)?)
        } else {
            None
        };
        let s: f64 = jac.iter().zip(&rho).map(|(row, r)| r * row[k]).sum();
        let a = grad[k];
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
            passed: rd_fd <= args.tol && rd_s <= SENSITIVITY_TOL && a.is_finite(),
            scan: rows.map(|r| {
                r.iter()
                    .map(|r| ScanRow {
                        rel_step: r.h_rel,
                        fd: r.fd,
                        rel_diff: r.rel_diff,
                    })
                    .collect()
            }),
            statuses_held: None,
        });
    }
    let fd_seconds = fd_start.elapsed().as_secs_f64();
    let passed = checks.iter().all(|c| c.passed);
    let failures: Vec<String> = checks
        .iter()
        .filter(|c| !c.passed)
        .map(|c| {
            format!(
                "{}: adjoint vs central FD {:.1e} (--tol {:.0e}), adjoint vs sensitivities {:.1e} \
                 (limit {SENSITIVITY_TOL:.0e})",
                c.name, c.rel_diff_fd, args.tol, c.rel_diff_sensitivity
            )
        })
        .collect();
    let describe = tests
        .iter()
        .map(|(label, d, ..)| format!("{label}: {}", d.describe))
        .collect::<Vec<_>>()
        .join("; ");
    let data_name = format!(
        "the joint cost sum_k w_k J_k of {} tests ({describe})",
        tests.len()
    );
    Ok(CheckReport {
        law: law.name(),
        config: name.to_string(),
        data: if synthesized {
            "synthesized".into()
        } else {
            data_name.clone()
        },
        truth: synthesized.then(|| Named::new(names.iter().copied().zip(truth.clone()))),
        params: Named::new(names.iter().copied().zip(point.iter().copied())),
        j,
        rel_step: args.rel_step,
        tol: args.tol,
        sensitivity_tol: SENSITIVITY_TOL,
        residual_tol: cfg.solver.residual_tol,
        checks,
        passed,
        forward_seconds,
        adjoint_seconds,
        sensitivity_seconds,
        fd_seconds,
        fd_forward_solves: solves,
        schedule_times: problem.n_data(),
        data_name,
        synthesized,
        failures,
    })
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
