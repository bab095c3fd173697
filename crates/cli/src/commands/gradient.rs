//! `indentify gradient`: prints `J` and `dJ/dc` of `indentify_study::gradient` as a table
//! or one JSON object.

use std::path::PathBuf;

use anyhow::Result;
use indentify_study::ConfigSource;
use indentify_study::format::{Named, bytes, gradient_unit, table};
use indentify_study::gradient::{self, GradientOptions};
use serde::Serialize;

use crate::print;

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

    /// The test (from 1) of a joint configuration (`tests: [...]`) to work on.
    #[arg(long, value_name = "K")]
    pub test: Option<usize>,
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
    solver_steps: usize,
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
    let g = gradient::run(&GradientOptions {
        config: ConfigSource::Path(args.config.clone()),
        sets: args.sets.clone(),
        test: args.test,
        data: args.data.clone(),
        checkpoint: args.checkpoint.map(|n| n as usize),
    })?;
    let names = &g.names;
    let ratio = g.adjoint_seconds / g.forward_seconds.max(1e-12);
    if args.json {
        return print::print_json(&JsonReport {
            law: g.law,
            config: g.config.clone(),
            data: g.data.clone(),
            params: Named::new(names.iter().copied().zip(g.params.iter().copied())),
            units: Named::new(names.iter().copied().zip(g.units.iter().copied())),
            j: g.j,
            gradient: Named::new(names.iter().copied().zip(g.gradient.iter().copied())),
            forward_seconds: g.forward_seconds,
            adjoint_seconds: g.adjoint_seconds,
            adjoint_to_forward: ratio,
            steps: g.steps,
            schedule_times: g.schedule_times,
            solver_steps: g.solver_steps,
            factorizations: g.factorizations,
            forward_factorizations: g.forward_factorizations,
            recorded_bytes: g.recorded_bytes,
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
    for k in 0..names.len() {
        rows.push(vec![
            names[k].into(),
            g.units[k].into(),
            g.params[k].to_string(),
            format!("{:.10e}", g.gradient[k]),
            gradient_unit(g.units[k]),
        ]);
    }
    let sub_steps = g.steps.saturating_sub(g.solver_steps);
    let own = g.solver_steps + 1 - g.schedule_times;
    let own = if own > 0 {
        format!("{own} sub-steps between the schedule times (data.substeps), ")
    } else {
        String::new()
    };
    let memory = match args.checkpoint {
        Some(n) => format!(
            "recorded {} (states every {n} schedule steps; storing every step would take {}); \
             the adjoint time includes replaying the segments",
            bytes(g.recorded_bytes),
            bytes(g.full_bytes)
        ),
        None => format!(
            "recorded {} (the fields of every step; --checkpoint N bounds it)",
            bytes(g.recorded_bytes)
        ),
    };
    let sets: String = args.sets.iter().map(|s| format!(" --set {s}")).collect();
    let text = format!(
        "indentify gradient {name} --data {data}{sets}\n  \
         law {law_name}, {steps} steps ({own}{sub_steps} sub-step{plural} from cuts), data `{data}` \
         ({rows_n} rows, t in [{a}, {b}] s)\n  \
         J = 1/2 sum_i (F_i - F_exp,i)^2 over the {n_times} schedule times (weights 1) = {j:.10e} N^2\n\n\
         {table}\n\n  \
         forward {fwd:.3} s ({fwd_fact} factorization{fwd_s}), adjoint sweep {adj:.3} s \
         ({adj_fact} factorization{adj_s}): adjoint / forward = {ratio:.2}\n  \
         {memory}\n",
        name = g.config,
        data = g.data,
        plural = if sub_steps == 1 { "" } else { "s" },
        law_name = g.law,
        steps = g.steps,
        rows_n = g.data_rows,
        a = g.data_span.0,
        b = g.data_span.1,
        n_times = g.schedule_times,
        j = g.j,
        table = table(&rows, "  ").trim_end(),
        fwd = g.forward_seconds,
        fwd_fact = g.forward_factorizations,
        fwd_s = if g.forward_factorizations == 1 {
            ""
        } else {
            "s"
        },
        adj = g.adjoint_seconds,
        adj_fact = g.factorizations,
        adj_s = if g.factorizations == 1 { "" } else { "s" },
    );
    print::print_text(&text)
}
