//! `indentify identify`: identification of law parameters from a force curve — the
//! least-squares misfit minimized with its adjoint gradient by `indentify_identify` — with
//! a report directory (`result.json`, `history.csv` written as iterations complete,
//! `fit.csv`) and a short table.
//!
//! With no configuration, the embedded default runs: R1 (`examples/r1-maxwell.ron`), its
//! curve simulated at the truth `(E, nu, eta) = (20000, 0.3, 30000)` as the "experimental"
//! data, and `(E, eta)` identified from the paper's first start `(4000, 70000)`, nu fixed.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use indentify_contact::{DirectSolver, SolverOptions};
use indentify_identify::{
    ForceRecord, Identifiability, IdentifyResult, IterationRecord, Problem, identify,
    multiplicative_noise, resume,
};
use serde::Serialize;

use crate::config::{self, IdentifySection, MethodName, Overrides, fixed_item, name_value};
use crate::data;
use crate::history::HistoryWriter;
use crate::report::{self, Named, sig, table};
use crate::solve::{ensure_differentiable, forward, param_names};

/// The default problem of `indentify identify` without arguments.
pub const DEFAULT_CONFIG: &str = include_str!("../../../../examples/r1-maxwell.ron");
/// Its name in messages.
pub const DEFAULT_NAME: &str = "examples/r1-maxwell.ron (embedded default)";

/// Arguments of `indentify identify`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Configuration file (RON) with an optional `identify` section; without it, the
    /// embedded R1 default (examples/r1-maxwell.ron).
    pub config: Option<PathBuf>,

    /// The measured curve (CSV with columns `t` (s) and `F` (N), e.g. from `indentify
    /// simulate`); without it, the configuration's own curve at its `law` values (the truth).
    #[arg(long, value_name = "CURVE.csv")]
    pub data: Option<PathBuf>,

    /// Report directory: result.json, history.csv, fit.csv.
    #[arg(long, value_name = "DIR", default_value = "out")]
    pub out: PathBuf,

    /// The optimizer (overrides identify.method).
    #[arg(long, value_enum)]
    pub method: Option<MethodName>,

    /// Identify exactly these parameters (comma-separated); the others are held.
    #[arg(long, value_name = "NAMES", value_delimiter = ',', num_args = 1)]
    pub free: Option<Vec<String>>,

    /// Hold these parameters (comma-separated, repeatable): `nu` at its law value, `nu=0.3`
    /// at a given one.
    #[arg(long, value_name = "NAME[=VALUE]", value_delimiter = ',')]
    pub fixed: Vec<String>,

    /// Start of a free parameter (comma-separated, repeatable), e.g. `--start E=4000,eta=7e4`.
    #[arg(long, value_name = "NAME=VALUE", value_delimiter = ',')]
    pub start: Vec<String>,

    /// Iteration limit (overrides identify.stop.max_iterations).
    #[arg(long, value_name = "N")]
    pub max_iter: Option<usize>,

    /// Continue from the last line of DIR/history.csv (quasi-Newton curvature restarts).
    #[arg(long)]
    pub resume: bool,

    /// Synthesized data only: multiplicative noise F (1 + a xi), xi uniform in [-1, 1].
    #[arg(long, value_name = "A", conflicts_with = "data")]
    pub noise: Option<f64>,

    /// Seed of the noise generator (SplitMix64).
    #[arg(long, value_name = "N", default_value_t = 1, requires = "noise")]
    pub seed: u64,

    /// Override a scalar of the configuration by its dotted path (repeatable), e.g.
    /// `--set specimen.nr=10 --set identify.params.E.start=5000`.
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    pub sets: Vec<String>,
}

/// One parameter in result.json.
#[derive(Debug, Serialize)]
struct ParamJson {
    name: &'static str,
    unit: &'static str,
    free: bool,
    start: f64,
    value: f64,
    lower: f64,
    upper: f64,
    bound_hit: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    truth: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    rel_error: Option<f64>,
}

/// The identifiability summary in result.json.
#[derive(Debug, Serialize)]
struct IdentifiabilityJson {
    names: Vec<&'static str>,
    n_data: usize,
    sigma2: f64,
    std_dev: Named<f64>,
    rel_std_dev: Named<f64>,
    correlation: Vec<Vec<f64>>,
    condition_number: f64,
    unidentifiable: Vec<&'static str>,
}

impl From<&Identifiability> for IdentifiabilityJson {
    fn from(i: &Identifiability) -> Self {
        IdentifiabilityJson {
            names: i.names.clone(),
            n_data: i.n_data,
            sigma2: i.sigma2,
            std_dev: Named::new(i.names.iter().copied().zip(i.std_dev.clone())),
            rel_std_dev: Named::new(i.names.iter().copied().zip(i.rel_std_dev.clone())),
            correlation: i.correlation.clone(),
            condition_number: i.condition_number,
            unidentifiable: i.unidentifiable.clone(),
        }
    }
}

/// result.json.
#[derive(Debug, Serialize)]
struct ResultJson {
    law: &'static str,
    config: String,
    data: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    noise: Option<NoiseJson>,
    method: &'static str,
    parameters: Vec<ParamJson>,
    #[serde(rename = "J")]
    j: f64,
    #[serde(rename = "J_start")]
    j_start: f64,
    #[serde(rename = "J_ref")]
    j_ref: f64,
    iterations: usize,
    forward_solves: usize,
    adjoint_solves: usize,
    sensitivity_solves: usize,
    stop_reason: String,
    converged: bool,
    seconds: f64,
    resumed: bool,
    identifiability: Option<IdentifiabilityJson>,
    history: String,
    fit: String,
}

/// Noise of synthesized data.
#[derive(Debug, Serialize)]
struct NoiseJson {
    amplitude: f64,
    seed: u64,
}

/// Where the data come from.
struct Data {
    record: ForceRecord,
    /// For messages and result.json.
    describe: String,
    /// The law values that generated them, if synthesized.
    truth: Option<Vec<f64>>,
}

/// Runs the identification and writes the report.
///
/// # Errors
/// Invalid configuration, settings or data (before any solve); a start that cannot be
/// solved or differentiated; an unwritable report directory; and a run that does not
/// converge (after the report and the history are written).
pub fn run(args: &Args) -> Result<()> {
    let wall = Instant::now();
    let (cfg, name) = match &args.config {
        Some(p) => (config::load(p, &args.sets)?, p.display().to_string()),
        None => (
            config::load_str(DEFAULT_CONFIG, DEFAULT_NAME, &args.sets)?,
            DEFAULT_NAME.to_string(),
        ),
    };
    let (law, law_values) = cfg.law.build()?;
    let names = param_names(law);
    let overrides = Overrides {
        free: args.free.clone(),
        fixed: args
            .fixed
            .iter()
            .map(|f| fixed_item(f))
            .collect::<Result<_>>()?,
        starts: args
            .start
            .iter()
            .map(|s| name_value("--start", s))
            .collect::<Result<_>>()?,
        method: args.method,
        max_iterations: args.max_iter,
    };
    let id_cfg = IdentifySection::resolve(cfg.identify.as_ref(), &cfg.law, &overrides)
        .with_context(|| format!("invalid identification settings for `{name}`"))?;
    let start: Vec<f64> = id_cfg
        .params
        .iter()
        .map(|p| p.value.unwrap_or(0.0))
        .collect();
    ensure_differentiable(law, &start, "cannot identify from this start")?;
    if let Some(a) = args.noise {
        if !(0.0..1.0).contains(&a) {
            bail!("--noise {a} is not allowed: expected an amplitude in [0, 1) (0.1 = +-10%)");
        }
    }

    // the report directory, before any solve
    let out = &args.out;
    std::fs::create_dir_all(out)
        .with_context(|| format!("cannot create the report directory `{}`", out.display()))?;
    let (history_path, result_path, fit_path) = (
        out.join("history.csv"),
        out.join("result.json"),
        out.join("fit.csv"),
    );
    let (mut history, resume_from) = if args.resume {
        let (w, last) = HistoryWriter::resume(&history_path, &names)?;
        (w, Some(last))
    } else {
        (HistoryWriter::create(&history_path, &names)?, None)
    };
    for p in [&result_path, &fit_path] {
        std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(p)
            .with_context(|| format!("cannot write `{}`", p.display()))?;
    }

    let mut cfg = cfg;
    if cfg.data.is_some() && args.noise.is_some() {
        bail!(
            "--noise perturbs synthesized data only, and `{name}` fits a measured record \
             (its `data` section)"
        );
    }
    if let (Some(d), Some(path)) = (&mut cfg.data, &args.data) {
        // --data replaces the configuration's record, read with its preprocessing
        d.file = absolute(path);
    }
    let prepared = cfg.prepare(&name)?;
    let (schedule, model) = (prepared.schedule, prepared.model);
    let opts = cfg.solver.options(false);
    let data = match (&prepared.measured, &args.data) {
        (Some(m), _) => Data {
            record: ForceRecord::new(m.record.t.clone(), m.record.f.clone())
                .with_context(|| format!("cannot use `{}` as data", m.path.display()))?,
            describe: format!(
                "`{}` ({}{}), {} samples, {} points after preprocessing ({})",
                m.path.display(),
                m.raw.meta.format.name(),
                m.raw
                    .meta
                    .test_name
                    .as_ref()
                    .map_or(String::new(), |t| format!(", test {t}")),
                m.raw.t.len(),
                m.record.t.len(),
                if m.applied.is_empty() {
                    "none applied".to_string()
                } else {
                    m.applied
                        .iter()
                        .map(|a| a.step.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                }
            ),
            truth: None,
        },
        (None, Some(path)) => {
            let curve = data::read_curve(path)?;
            let (t0, t1) = (schedule.t[0], schedule.t[schedule.t.len() - 1]);
            curve.check_covers(t0, t1, &name)?;
            Data {
                record: curve.record()?,
                describe: curve.name.clone(),
                truth: None,
            }
        }
        (None, None) => {
            let mut solver = DirectSolver::new(&model)?;
            let traj = forward(
                &mut solver,
                &model,
                law,
                &law_values,
                &schedule,
                &opts,
                &name,
            )?;
            let mut forces = traj.forces();
            let mut describe = format!(
                "synthesized: the curve of `{name}` at {}",
                report::assignments(&names, &law_values)
            );
            if let Some(a) = args.noise {
                forces = multiplicative_noise(&forces, a, args.seed);
                describe.push_str(&format!(
                    ", noise F (1 + {a} xi), xi uniform in [-1, 1], seed {}",
                    args.seed
                ));
            } else {
                describe.push_str(" (exact)");
            }
            Data {
                record: ForceRecord::new(schedule.t.clone(), forces)
                    .context("cannot use the simulated curve as data")?,
                describe,
                truth: Some(law_values.clone()),
            }
        }
    };
    let problem = Problem::new(model, law, schedule, &data.record, None, opts.clone())
        .with_context(|| format!("cannot compare the data with `{name}`"))?;

    // the run, with the history written line by line
    let free: Vec<&str> = id_cfg
        .params
        .iter()
        .filter(|p| p.free)
        .map(|p| p.name.as_str())
        .collect();
    let held: Vec<String> = id_cfg
        .params
        .iter()
        .filter(|p| !p.free)
        .map(|p| format!("{} = {}", p.name, p.value.unwrap_or(f64::NAN)))
        .collect();
    tracing::info!(
        "indentify identify {name}\n  law {}, identifying {} ({}), method {}{}\n  data: {}\n  \
             report directory `{}`",
        law.name(),
        free.join(", "),
        if held.is_empty() {
            "nothing held".to_string()
        } else {
            format!("held: {}", held.join(", "))
        },
        id_cfg.method.name(),
        match &resume_from {
            Some(r) => format!(", resumed at iteration {}", r.iteration),
            None => String::new(),
        },
        data.describe,
        out.display()
    );
    let free_idx: Vec<usize> = id_cfg
        .params
        .iter()
        .enumerate()
        .filter(|(_, p)| p.free)
        .map(|(k, _)| k)
        .collect();
    let progress =
        crate::log::Progress::new("identify", id_cfg.stop.max_iterations as u64, "iterations");
    let mut header_done = false;
    let mut write_error: Option<anyhow::Error> = None;
    let mut observer = |r: &IterationRecord| {
        if write_error.is_some() {
            return;
        }
        progress.set(
            r.iteration as u64,
            format!(
                "J {:.4e} N^2, {} forward / {} adjoint solves",
                r.cost, r.forward_solves, r.adjoint_solves
            ),
        );
        match history.record(r) {
            Ok(true) => {
                if !header_done {
                    let mut cols = vec![format!("{:>4}", "iter"), format!("{:<13}", "J (N^2)")];
                    cols.push(format!("{:<10}", "|grad|"));
                    cols.extend(free_idx.iter().map(|&k| format!("{:<14}", names[k])));
                    cols.push("fwd/adj  s".into());
                    tracing::info!("  {}", cols.join(" "));
                    header_done = true;
                }
                let mut cols = vec![
                    format!("{:>4}", r.iteration),
                    format!("{:<13.6e}", r.cost),
                    format!("{:<10.3e}", r.grad_norm),
                ];
                cols.extend(
                    free_idx
                        .iter()
                        .map(|&k| format!("{:<14}", sig(r.params[k], 9))),
                );
                cols.push(format!(
                    "{}/{}  {:.1}",
                    r.forward_solves, r.adjoint_solves, r.seconds
                ));
                tracing::info!("  {}", cols.join(" "));
            }
            Ok(_) => {}
            Err(e) => write_error = Some(e),
        }
    };
    let outcome = match &resume_from {
        Some(last) => resume(&problem, &id_cfg, last, &mut observer),
        None => identify(&problem, &id_cfg, &mut observer),
    };
    drop(progress);
    if let Some(e) = write_error {
        return Err(e);
    }
    let result = outcome.map_err(|e| {
        let kept = if history.lines > 0 {
            format!(
                "; the history so far ({} lines) is in `{}`",
                history.lines,
                history_path.display()
            )
        } else {
            String::new()
        };
        anyhow!(e).context(format!("the identification of `{name}` failed{kept}"))
    })?;

    // fit.csv: the data, the start's and the final curves at the schedule times
    let start_params: Vec<f64> = result.params.iter().map(|p| p.start).collect();
    let mut solver = DirectSolver::new(&problem.model)?;
    let mut curve_at = |c: &[f64]| -> Result<Vec<f64>> {
        Ok(forward(
            &mut solver,
            &problem.model,
            law,
            c,
            &problem.schedule,
            &SolverOptions {
                record_fields: false,
                ..opts.clone()
            },
            &name,
        )?
        .forces())
    };
    let f_start = curve_at(&start_params)?;
    let f_final = curve_at(&result.c)?;
    write_fit(&fit_path, &problem, &f_start, &f_final)?;
    let history_records = crate::history::read_all(&history_path, names.len());
    let (file, test) = match &prepared.measured {
        Some(m) => (
            m.path.display().to_string(),
            m.raw.meta.test_name.clone().unwrap_or_default(),
        ),
        None => (data.describe.clone(), String::new()),
    };
    // result.json first: a report or figure that cannot be made must not lose the result
    write_result(
        &result_path,
        &result,
        &name,
        &data,
        args,
        resume_from.is_some(),
        &history_path,
        &fit_path,
    )?;
    let written = crate::figures::write(
        out,
        &result,
        &crate::figures::Inputs {
            title: format!("Identification of {} parameters: {name}", law.name()),
            file,
            test,
            measured: prepared.measured.as_ref(),
            t: &problem.schedule.t,
            h: &problem.schedule.depth,
            f_data: &problem.target,
            f_start: &f_start,
            f_final: &f_final,
            history: &history_records,
        },
    )
    .map_err(|e| {
        tracing::warn!(
            "warning: no report.md, report.json or figures: {e:#} (result.json, history.csv \
             and fit.csv are written)"
        );
    })
    .ok();

    // the table
    let mut rows = vec![
        ["parameter", "unit", "start", "final"]
            .map(String::from)
            .to_vec(),
    ];
    if data.truth.is_some() {
        rows[0].extend(["truth".to_string(), "rel. error".to_string()]);
    }
    for (k, p) in result.params.iter().enumerate() {
        let mut row = vec![p.name.to_string(), p.unit.to_string(), p.start.to_string()];
        row.push(if p.free {
            let bound = if p.at_lower {
                " (at lower bound)"
            } else if p.at_upper {
                " (at upper bound)"
            } else {
                ""
            };
            format!("{}{bound}", sig(p.value, 9))
        } else {
            format!("{} (held)", p.value)
        });
        if let Some(truth) = &data.truth {
            row.push(truth[k].to_string());
            row.push(if p.free {
                format!("{:.1e}", ((p.value - truth[k]) / truth[k]).abs())
            } else {
                String::new()
            });
        }
        rows.push(row);
    }
    let mut text = format!(
        "identified {} parameters ({}, {}: {})\n{}",
        law.name(),
        result.method.name(),
        if result.stop_reason.is_converged() {
            "converged"
        } else {
            "NOT converged"
        },
        result.stop_reason,
        table(&rows, "  ")
    );
    text.push_str(&format!(
        "  J = {:.4e} N^2 (start {:.4e}), {} iterations, {} forward and {} adjoint solves, {:.1} s\n",
        result.cost,
        result.initial_cost,
        result.iterations,
        result.forward_solves,
        result.adjoint_solves,
        result.seconds
    ));
    if let Some(w) = &written {
        text.push_str(&format!(
            "  fit: R^2 = {:.6}, RMS force residual {:.4e} N = {:.3}% of F_max, largest \
             residual {:.4e} N ({} points)\n",
            w.fit.r2,
            w.fit.rms,
            100.0 * w.fit.rms_rel,
            w.fit.max_abs,
            w.fit.n
        ));
    }
    if let Some(i) = &result.identifiability {
        text.push_str(&format!("  {}\n", identifiability_line(i)));
    }
    let reports = written.as_ref().map_or(String::new(), |w| {
        format!(
            "{} and {}, {} figures as SVG and PNG; ",
            w.markdown.display(),
            w.json.display(),
            w.figures.len() / 2
        )
    });
    text.push_str(&format!(
        "  report: {reports}result {}, history {}, fit {}; total wall time {:.1} s\n",
        result_path.display(),
        history_path.display(),
        fit_path.display(),
        wall.elapsed().as_secs_f64()
    ));
    report::print_text(&text)?;
    if !result.stop_reason.is_converged() {
        bail!(
            "the identification of `{name}` did not converge: {} after {} iterations (J = {:.4e} \
             N^2); the result so far is in `{}` and the history in `{}` (continue with --resume, \
             or change the start, bounds or method)",
            result.stop_reason,
            result.iterations,
            result.cost,
            result_path.display(),
            history_path.display()
        );
    }
    Ok(())
}

/// `path` made absolute against the working directory (the configuration's folder does
/// not apply to a path given on the command line).
pub fn absolute(path: &Path) -> String {
    std::env::current_dir()
        .map_or_else(|_| path.to_path_buf(), |d| d.join(path))
        .display()
        .to_string()
}

/// `relative std. dev. E 1e-9, eta 2e-9; correlation E-eta -0.87; condition number 12`.
fn identifiability_line(i: &Identifiability) -> String {
    let sd: Vec<String> = i
        .names
        .iter()
        .zip(&i.rel_std_dev)
        .filter(|(n, _)| !i.unidentifiable.contains(n))
        .map(|(n, s)| format!("{n} {s:.1e}"))
        .collect();
    let mut corr = Vec::new();
    for a in 0..i.names.len() {
        for b in a + 1..i.names.len() {
            if [a, b]
                .iter()
                .any(|&k| i.unidentifiable.contains(&i.names[k]))
            {
                continue;
            }
            corr.push(format!(
                "{}-{} {:.3}",
                i.names[a], i.names[b], i.correlation[a][b]
            ));
        }
    }
    let mut s = format!("identifiability: relative std. dev. {}", sd.join(", "));
    if !corr.is_empty() {
        s.push_str(&format!("; correlation {}", corr.join(", ")));
    }
    if !i.unidentifiable.is_empty() {
        s.push_str(&format!(
            "; NOT identifiable from these data (no effect on the force): {} (hold them, or \
             narrow their bounds)",
            i.unidentifiable.join(", ")
        ));
    }
    s.push_str(&format!("; condition number {:.3e}", i.condition_number));
    s
}

/// Writes fit.csv: `t,h,F_data,F_start,F_final` at the schedule times.
fn write_fit(path: &Path, problem: &Problem, f_start: &[f64], f_final: &[f64]) -> Result<()> {
    let mut text = String::from("t,h,F_data,F_start,F_final\n");
    let s = &problem.schedule;
    for i in 0..s.t.len() {
        let at = |f: &[f64]| f.get(i).copied().unwrap_or(f64::NAN);
        text.push_str(&format!(
            "{},{},{},{},{}\n",
            s.t[i],
            s.depth[i],
            problem.target[i],
            at(f_start),
            at(f_final)
        ));
    }
    std::fs::write(path, text).with_context(|| format!("cannot write `{}`", path.display()))
}

/// Writes result.json.
#[allow(clippy::too_many_arguments)]
fn write_result(
    path: &Path,
    r: &IdentifyResult,
    config: &str,
    data: &Data,
    args: &Args,
    resumed: bool,
    history: &Path,
    fit: &Path,
) -> Result<()> {
    let parameters = r
        .params
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let truth = data.truth.as_ref().map(|t| t[k]);
            ParamJson {
                name: p.name,
                unit: p.unit,
                free: p.free,
                start: p.start,
                value: p.value,
                lower: p.lower,
                upper: p.upper,
                bound_hit: if p.at_lower {
                    Some("lower")
                } else if p.at_upper {
                    Some("upper")
                } else {
                    None
                },
                truth,
                rel_error: truth.filter(|_| p.free).map(|t| ((p.value - t) / t).abs()),
            }
        })
        .collect();
    let json = ResultJson {
        law: r.law,
        config: config.to_string(),
        data: data.describe.clone(),
        noise: args
            .noise
            .filter(|_| data.truth.is_some())
            .map(|amplitude| NoiseJson {
                amplitude,
                seed: args.seed,
            }),
        method: r.method.name(),
        parameters,
        j: r.cost,
        j_start: r.initial_cost,
        j_ref: r.reference_cost,
        iterations: r.iterations,
        forward_solves: r.forward_solves,
        adjoint_solves: r.adjoint_solves,
        sensitivity_solves: r.sensitivity_solves,
        stop_reason: r.stop_reason.to_string(),
        converged: r.stop_reason.is_converged(),
        seconds: r.seconds,
        resumed,
        identifiability: r.identifiability.as_ref().map(IdentifiabilityJson::from),
        history: history.display().to_string(),
        fit: fit.display().to_string(),
    };
    let text = serde_json::to_string_pretty(&json).context("cannot represent the result")?;
    std::fs::write(path, text + "\n").with_context(|| format!("cannot write `{}`", path.display()))
}
