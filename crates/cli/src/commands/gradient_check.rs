//! `indentify gradient-check`: the adjoint gradient of the misfit against central finite
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

use anyhow::{Context, Result, anyhow, bail};
use indentify_adjoint::Adjoint;
use indentify_adjoint::check::{central_difference, relative_difference, scan};
use indentify_contact::{DirectSolver, SolverOptions};
use indentify_identify::{ForceRecord, Problem};
use serde::Serialize;

use crate::config;
use crate::data;
use crate::report::{self, Named, table};
use crate::solve::{ensure_differentiable, forward, param_names};

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

/// Arguments of `indentify gradient-check`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Configuration file (RON).
    pub config: PathBuf,

    /// Compare with this curve (CSV with columns `t` and `F`) at the configuration's law
    /// parameters; without it, data are synthesized (see the command's help).
    #[arg(long, value_name = "CURVE.csv")]
    pub data: Option<PathBuf>,

    /// Relative step of the central differences: `h = rel_step |c_k|`.
    #[arg(long, value_name = "H", default_value_t = 1e-5)]
    pub rel_step: f64,

    /// Largest admissible relative difference between the adjoint and central differences.
    #[arg(long, value_name = "TOL", default_value_t = 1e-6)]
    pub tol: f64,

    /// Also print the finite differences at relative steps 1e-2 ... 1e-9 per parameter (the
    /// truncation / round-off V; 16 forward solves per parameter).
    #[arg(long)]
    pub scan: bool,

    /// Print one JSON object instead of the text report.
    #[arg(long)]
    pub json: bool,

    /// Override a scalar of the configuration by its dotted path (repeatable).
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    pub sets: Vec<String>,
}

/// One row of the FD scan.
#[derive(Debug, Serialize)]
struct ScanJson {
    rel_step: f64,
    fd: f64,
    rel_diff: f64,
}

/// One parameter's comparison.
#[derive(Debug, Serialize)]
struct CheckJson {
    name: &'static str,
    unit: &'static str,
    value: f64,
    adjoint: f64,
    fd: f64,
    sensitivity: f64,
    rel_diff_fd: f64,
    rel_diff_sensitivity: f64,
    passed: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    scan: Option<Vec<ScanJson>>,
}

/// The JSON report.
#[derive(Debug, Serialize)]
struct JsonReport {
    law: &'static str,
    config: String,
    data: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    truth: Option<Named<f64>>,
    params: Named<f64>,
    #[serde(rename = "J")]
    j: f64,
    rel_step: f64,
    tol: f64,
    sensitivity_tol: f64,
    residual_tol: f64,
    checks: Vec<CheckJson>,
    passed: bool,
    forward_seconds: f64,
    adjoint_seconds: f64,
    sensitivity_seconds: f64,
    fd_seconds: f64,
    fd_forward_solves: usize,
}

/// Runs the check, prints the comparison, and fails if a tolerance is exceeded.
///
/// # Errors
/// Invalid inputs, a failing solve, or a difference above `--tol` (adjoint vs FD) or above
/// [`SENSITIVITY_TOL`] (adjoint vs sensitivities); the report is printed first.
pub fn run(args: &Args) -> Result<()> {
    if !(args.rel_step > 0.0 && args.rel_step < 1.0) {
        bail!(
            "--rel-step {} is not allowed: expected a relative step in (0, 1), e.g. 1e-5",
            args.rel_step
        );
    }
    if !(args.tol > 0.0 && args.tol.is_finite()) {
        bail!(
            "--tol {} is not allowed: expected a tolerance > 0",
            args.tol
        );
    }
    let name = args.config.display().to_string();
    let cfg = config::load(&args.config, &args.sets)?;
    let (law, truth) = cfg.law.build()?;
    let names = param_names(law);
    let infos = law.params();
    let prepared = cfg.prepare(&name)?;
    let (schedule, model) = (prepared.schedule, prepared.model);
    let opts = SolverOptions {
        residual_tol: cfg.solver.residual_tol.min(CHECK_RESIDUAL_TOL),
        ..cfg.solver.options(true)
    };
    let fd_opts = SolverOptions {
        record_fields: false,
        ..opts.clone()
    };
    let mut solver = DirectSolver::new(&model)?;

    // data and check point
    let (record, data_name, point, synthesized) = match &args.data {
        Some(path) => {
            let curve = data::read_curve(path)?;
            let (t0, t1) = (schedule.t[0], schedule.t[schedule.t.len() - 1]);
            curve.check_covers(t0, t1, &name)?;
            (curve.record()?, curve.name.clone(), truth.clone(), false)
        }
        None => {
            let traj = forward(&mut solver, &model, law, &truth, &schedule, &fd_opts, &name)?;
            let record = ForceRecord::new(schedule.t.clone(), traj.forces())
                .context("cannot use the simulated curve as data")?;
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
            law.check_params(&point).map_err(|e| {
                anyhow!(
                    "the check point (configuration x {PERTURBATION}, nu x {NU_PERTURBATION}) \
                     is not admissible: {e}; give --data or other law values"
                )
            })?;
            let data = format!(
                "synthesized from `{name}` at {}",
                report::assignments(&names, &truth)
            );
            (record, data, point, true)
        }
    };
    ensure_differentiable(law, &point, "no gradient check")?;
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
            bail!(
                "cannot difference `{}` at {}: the stencil {} +- {h} leaves its admissible \
                 range {} (choose a check point inside, e.g. with --set law.{}=...)",
                info.name,
                point[k],
                point[k],
                info.range_text(),
                info.name
            );
        }
    }
    let problem = Problem::new(model, law, schedule, &record, None, opts.clone())
        .with_context(|| format!("cannot compare `{data_name}` with `{name}`"))?;
    let model = &problem.model;

    // adjoint and sensitivities at the check point
    let start = Instant::now();
    let traj = forward(
        &mut solver,
        model,
        law,
        &point,
        &problem.schedule,
        &opts,
        &name,
    )?;
    let forward_seconds = start.elapsed().as_secs_f64();
    let j = problem.cost_of(&traj.forces());
    let rho = problem.dj_df(&traj);
    let mut adjoint = Adjoint::new(model)?;
    let grad = adjoint
        .gradient(model, law, &point, &traj, &rho)
        .context("the adjoint sweep failed")?;
    let sens = adjoint
        .sensitivities(model, law, &point, &traj)
        .context("the forward sensitivities failed")?;
    let jt_rho = sens.transpose_mul(&rho);
    drop(traj);

    // finite differences of the forward solver's own cost
    let fd_start = Instant::now();
    let mut solves = 0usize;
    let mut cost = |c: &[f64]| -> Result<f64> {
        solves += 1;
        let t = forward(
            &mut solver,
            model,
            law,
            c,
            &problem.schedule,
            &fd_opts,
            &name,
        )?;
        Ok(problem.cost_of(&t.forces()))
    };
    let mut checks = Vec::new();
    for (k, info) in infos.iter().enumerate() {
        let fd = central_difference(&mut cost, &point, k, args.rel_step)?;
        let rows = if args.scan {
            Some(scan(&mut cost, &point, k, grad.dj_dc[k], &SCAN_STEPS)?)
        } else {
            None
        };
        let (a, s) = (grad.dj_dc[k], jt_rho[k]);
        let (rd_fd, rd_s) = (relative_difference(a, fd), relative_difference(a, s));
        checks.push(CheckJson {
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
                    .map(|r| ScanJson {
                        rel_step: r.h_rel,
                        fd: r.fd,
                        rel_diff: r.rel_diff,
                    })
                    .collect()
            }),
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

    if args.json {
        report::print_json(&JsonReport {
            law: law.name(),
            config: name.clone(),
            data: if synthesized {
                "synthesized".into()
            } else {
                data_name
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
        })?;
    } else {
        let mut text = format!(
            "indentify gradient-check {name}\n  law {}; data {data_name}\n",
            law.name()
        );
        if synthesized {
            text.push_str(&format!(
                "  check point {} (every parameter x {PERTURBATION}, nu x {NU_PERTURBATION})\n",
                report::assignments(&names, &point)
            ));
        } else {
            text.push_str(&format!(
                "  check point {} (the configuration's law)\n",
                report::assignments(&names, &point)
            ));
        }
        text.push_str(&format!(
            "  J = {j:.6e} N^2 over {} schedule times; central differences with h = {:e} |c_k|; \
             forward solves to residual_tol = {:e}\n\n",
            problem.schedule.t.len(),
            args.rel_step,
            opts.residual_tol
        ));
        let mut rows = vec![
            [
                "parameter",
                "unit",
                "adjoint dJ/dc",
                "central FD",
                "rel. diff",
                "sensitivities J^T rho",
                "rel. diff",
            ]
            .map(String::from)
            .to_vec(),
        ];
        for c in &checks {
            rows.push(vec![
                c.name.into(),
                c.unit.into(),
                format!("{:.10e}", c.adjoint),
                format!("{:.10e}", c.fd),
                format!("{:.1e}", c.rel_diff_fd),
                format!("{:.10e}", c.sensitivity),
                format!("{:.1e}", c.rel_diff_sensitivity),
            ]);
        }
        text.push_str(&table(&rows, "  "));
        if args.scan {
            text.push_str(
                "\n  relative difference of central FD to the adjoint, by relative step:\n",
            );
            let mut rows = vec![
                std::iter::once("h / |c|".to_string())
                    .chain(names.iter().map(|n| n.to_string()))
                    .collect::<Vec<_>>(),
            ];
            for (i, h) in SCAN_STEPS.iter().enumerate() {
                let mut row = vec![format!("{h:.0e}")];
                for c in &checks {
                    let r = c.scan.as_ref().map_or(f64::NAN, |s| s[i].rel_diff);
                    row.push(format!("{r:.1e}"));
                }
                rows.push(row);
            }
            text.push_str(&table(&rows, "  "));
        }
        text.push_str(&format!(
            "\n  forward {forward_seconds:.3} s, adjoint {:.3} s, sensitivities {:.3} s, \
             {solves} forward solves for the differences {fd_seconds:.3} s\n",
            grad.seconds, sens.seconds
        ));
        if passed {
            text.push_str(&format!(
                "  passed: adjoint vs central FD <= {:.0e} (--tol), adjoint vs sensitivities <= \
                 {SENSITIVITY_TOL:.0e}\n",
                args.tol
            ));
        }
        report::print_text(&text)?;
    }
    if !passed {
        bail!(
            "gradient check of `{name}` failed:\n{}",
            failures.join("\n")
        );
    }
    Ok(())
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
