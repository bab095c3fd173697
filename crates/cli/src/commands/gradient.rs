//! `indentify gradient`: the least-squares misfit `J` between a configuration's simulated
//! force and a measured curve, and its exact gradient `dJ/dc` by the discrete adjoint, with
//! the wall time of the forward run and of the adjoint sweep.
//!
//! `J = 1/2 sum_i (F_i - F_i^exp)^2` over the schedule times `t_i` of the configuration
//! (index 0, the stress-free start, included; every weight 1), `F^exp` being the data
//! interpolated linearly at `t_i` (the cost of `indentify_identify::Problem`).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indentify_adjoint::{Adjoint, Gradient};
use indentify_contact::DirectSolver;
use indentify_identify::Problem;
use serde::Serialize;

use crate::config;
use crate::data;
use crate::report::{self, Named, gradient_unit, table};
use crate::solve::{ensure_differentiable, forward, param_names};

/// Arguments of `indentify gradient`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Configuration file (RON): specimen, punch, law and its parameters (the point where
    /// the gradient is taken), depth history.
    pub config: PathBuf,

    /// The measured curve: CSV with a header naming at least the columns `t` (s) and `F` (N),
    /// e.g. the `t,h,F,a` file of `indentify simulate`; it must cover the simulated history.
    /// Optional for a configuration with a `data` section (then it replaces `data.file`,
    /// read with the section's format and preprocessing).
    #[arg(long, value_name = "CURVE.csv")]
    pub data: Option<PathBuf>,

    /// Print one JSON object instead of the text report.
    #[arg(long)]
    pub json: bool,

    /// Bound the memory: record no fields, save the solver state every N schedule steps, and
    /// replay each segment during the adjoint sweep (same gradient to round-off).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub checkpoint: Option<u32>,

    /// Override a scalar of the configuration by its dotted path (repeatable), e.g.
    /// `--set law.eta=25000 --set specimen.nr=10`.
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    pub sets: Vec<String>,
}

/// The JSON report.
#[derive(Debug, Serialize)]
struct JsonReport {
    law: &'static str,
    config: String,
    data: String,
    params: Named<f64>,
    units: Named<&'static str>,
    #[serde(rename = "J")]
    j: f64,
    gradient: Named<f64>,
    forward_seconds: f64,
    adjoint_seconds: f64,
    adjoint_to_forward: f64,
    steps: usize,
    schedule_times: usize,
    factorizations: usize,
    forward_factorizations: usize,
    recorded_bytes: usize,
    checkpoint_every: Option<u32>,
}

/// Computes and prints `J` and `dJ/dc`.
///
/// # Errors
/// An invalid configuration or data file, data that do not cover the simulated history, a
/// law not differentiable at the configured parameters, a failing forward run, or a
/// non-finite gradient.
pub fn run(args: &Args) -> Result<()> {
    let name = args.config.display().to_string();
    let cfg = config::load(&args.config, &args.sets)?;
    let (law, params) = cfg.law.build()?;
    ensure_differentiable(law, &params, &format!("no gradient for `{name}`"))?;
    let mut cfg = cfg;
    if let (Some(d), Some(path)) = (&mut cfg.data, &args.data) {
        d.file = crate::commands::identify::absolute(path);
    }
    let prepared = cfg.prepare(&name)?;
    let curve = match (&prepared.measured, &args.data) {
        // the measured record: its preprocessed force at its own times (the schedule's)
        (Some(m), _) => data::Curve {
            name: m.path.display().to_string(),
            t: m.record.t.clone(),
            h: Some(m.record.h.clone()),
            f: m.record.f.clone(),
        },
        (None, Some(path)) => data::read_curve(path)?,
        (None, None) => bail!(
            "no data for `{name}`: give --data CURVE.csv, or a `data` section in the \
             configuration"
        ),
    };
    let schedule = prepared.schedule;
    let (t0, t1) = (schedule.t[0], schedule.t[schedule.t.len() - 1]);
    curve.check_covers(t0, t1, &name)?;
    let mut opts = cfg.solver.options(true);
    if let Some(n) = args.checkpoint {
        opts.record_fields = false;
        opts.checkpoint_every = n as usize;
    }
    let problem = Problem::new(
        prepared.model,
        law,
        schedule,
        &curve.record()?,
        None,
        opts.clone(),
    )
    .with_context(|| format!("cannot compare `{}` with `{name}`", curve.name))?;
    let model = &problem.model;

    let mut solver = DirectSolver::new(model)?;
    let start = Instant::now();
    let traj = forward(
        &mut solver,
        model,
        law,
        &params,
        &problem.schedule,
        &opts,
        &name,
    )?;
    let forward_seconds = start.elapsed().as_secs_f64();
    let j = problem.cost_of(&traj.forces());
    let rho = problem.dj_df(&traj);
    let mut adjoint = Adjoint::new(model)?;
    let grad: Gradient = if args.checkpoint.is_some() {
        adjoint.gradient_replayed(
            model,
            law,
            &params,
            &traj,
            &rho,
            &mut solver,
            &problem.schedule,
            &opts,
        )
    } else {
        adjoint.gradient(model, law, &params, &traj, &rho)
    }
    .with_context(|| format!("the adjoint sweep of `{name}` failed"))?;
    let names = param_names(law);
    if let Some(k) = grad.dj_dc.iter().position(|g| !g.is_finite()) {
        bail!(
            "the adjoint gave dJ/d{} = {} at {}: no finite gradient there",
            names[k],
            grad.dj_dc[k],
            report::assignments(&names, &params)
        );
    }
    let full_bytes = (traj.steps.len() + 1) * (8 * model.disc.n_dofs() + 32 * model.disc.n_qp());
    let n_times = problem.schedule.t.len();
    let ratio = grad.seconds / forward_seconds.max(1e-12);

    if args.json {
        let infos = law.params();
        return report::print_json(&JsonReport {
            law: law.name(),
            config: name,
            data: curve.name.clone(),
            params: Named::new(names.iter().copied().zip(params.iter().copied())),
            units: Named::new(infos.iter().map(|i| (i.name, i.unit))),
            j,
            gradient: Named::new(names.iter().copied().zip(grad.dj_dc.iter().copied())),
            forward_seconds,
            adjoint_seconds: grad.seconds,
            adjoint_to_forward: ratio,
            steps: traj.steps.len(),
            schedule_times: n_times,
            factorizations: grad.factorizations,
            forward_factorizations: traj.timing.factorizations,
            recorded_bytes: traj.recorded_bytes(),
            checkpoint_every: args.checkpoint,
        });
    }

    let mut rows = vec![vec![
        "parameter".to_string(),
        "unit".into(),
        "value".into(),
        "dJ/dc".into(),
        "unit of dJ/dc".into(),
    ]];
    for ((info, v), g) in law.params().iter().zip(&params).zip(&grad.dj_dc) {
        rows.push(vec![
            info.name.into(),
            info.unit.into(),
            v.to_string(),
            format!("{g:.10e}"),
            gradient_unit(info.unit),
        ]);
    }
    let sub_steps = traj.steps.len() + 1 - n_times;
    let memory = match args.checkpoint {
        Some(n) => format!(
            "recorded {} (states every {n} schedule steps; storing every step would take {}); \
             the adjoint time includes replaying the segments",
            report::bytes(traj.recorded_bytes()),
            report::bytes(full_bytes)
        ),
        None => format!(
            "recorded {} (the fields of every step; --checkpoint N bounds it)",
            report::bytes(traj.recorded_bytes())
        ),
    };
    let sets: String = args.sets.iter().map(|s| format!(" --set {s}")).collect();
    let text = format!(
        "indentify gradient {name} --data {data}{sets}\n  \
         law {law_name}, {steps} steps ({sub_steps} sub-step{plural} from cuts), data `{data}` \
         ({rows_n} rows, t in [{a}, {b}] s)\n  \
         J = 1/2 sum_i (F_i - F_exp,i)^2 over the {n_times} schedule times (weights 1) = {j:.10e} N^2\n\n\
         {table}\n\n  \
         forward {forward_seconds:.3} s ({fwd_fact} factorizations), adjoint sweep {adj:.3} s \
         ({adj_fact} factorizations): adjoint / forward = {ratio:.2}\n  \
         {memory}\n",
        data = curve.name,
        plural = if sub_steps == 1 { "" } else { "s" },
        law_name = law.name(),
        steps = traj.steps.len(),
        rows_n = curve.t.len(),
        a = curve.span().0,
        b = curve.span().1,
        table = table(&rows, "  ").trim_end(),
        fwd_fact = traj.timing.factorizations,
        adj = grad.seconds,
        adj_fact = grad.factorizations,
    );
    report::print_text(&text)
}
