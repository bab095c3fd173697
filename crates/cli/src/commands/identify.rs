//! `indentify identify`: maps its arguments onto `indentify_study::identify`, shows the
//! iterations (log lines and a progress bar) and prints the table of the result.
//!
//! With no configuration, the embedded default runs: R1 (`examples/r1-maxwell.ron`), its
//! curve simulated at the truth `(E, nu, eta) = (20000, 0.3, 30000)` as the "experimental"
//! data, and `(E, eta)` identified from the paper's first start `(4000, 70000)`, nu fixed.

use std::path::PathBuf;

use anyhow::{Result, bail};
use indentify_study::config::{MethodName, Overrides, fixed_item, name_value};
use indentify_study::discretization::Discretization;
use indentify_study::explore::StartsOptions;
use indentify_study::format::{sig, table};
use indentify_study::identify::{self, IdentifyOptions, IdentifyOutcome, Observer, RunInfo};
use indentify_study::{
    ConfigSource, Identifiability, IterationRecord, Observable, ProfileSettings,
};

use crate::print;

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

    /// The optimizer (overrides identify.method): bfgs, lbfgs, lbfgsb or lm.
    #[arg(long, value_parser = parse_method)]
    pub method: Option<MethodName>,

    /// Identify exactly these parameters (comma-separated); the others are held.
    #[arg(long, value_name = "NAMES", value_delimiter = ',', num_args = 1)]
    pub free: Option<Vec<String>>,

    /// Hold these parameters (comma-separated, repeatable): `nu` at its law value, `nu=0.3`
    /// at a given one.
    #[arg(long, value_name = "NAME[=VALUE]", value_delimiter = ',')]
    pub fixed: Vec<String>,

    /// Start of a free parameter (comma-separated, repeatable), e.g. `--start E=4000,eta=7e4`;
    /// `--start closed-form`: the parameters a closed form covers (`E`; Maxwell's `E` and
    /// `eta`) from the pre-fit of the curve's loading and hold (Sneddon, Hertz, the flat
    /// punch, Lee and Radok), corrected by one forward run (docs/analysis.md).
    #[arg(long, value_name = "NAME=VALUE", value_delimiter = ',')]
    pub start: Vec<String>,

    /// Iteration limit (overrides identify.stop.max_iterations).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = super::parse_usize)]
    pub max_iter: Option<usize>,

    /// Continue from the last line of DIR/history.csv (quasi-Newton curvature restarts).
    #[arg(long, conflicts_with = "force")]
    pub resume: bool,

    /// Replace the report of another run in DIR (by default a folder holding another
    /// run's history.csv is refused).
    #[arg(long)]
    pub force: bool,

    /// Bound the memory: record no fields, save the solver state every N schedule steps and
    /// replay the segments for each gradient (same result to round-off; Levenberg-Marquardt
    /// and the final identifiability summary still record one run in full).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub checkpoint: Option<u32>,

    /// Threads solving the tests of a joint fit (`tests: [...]`) in parallel; default: all
    /// cores. The result is bit-identical for any number.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub jobs: Option<u32>,

    /// Without --checkpoint, checkpoint automatically when recording every step's fields
    /// would take more than this many MB.
    #[arg(long, value_name = "MB", default_value_t = 1024)]
    pub memory_budget: usize,

    /// Synthesized data only: multiplicative noise F (1 + a xi), xi uniform in [-1, 1].
    #[arg(
        long,
        value_name = "A",
        conflicts_with = "data",
        allow_negative_numbers = true
    )]
    pub noise: Option<f64>,

    /// Seed of the noise generator and of the multi-start's Latin hypercube (SplitMix64;
    /// default 1). Needs --noise or --starts.
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = super::parse_count)]
    pub seed: Option<u64>,

    /// Multi-start: N starts drawn by Latin-hypercube sampling of the scaled box of the
    /// free parameters (ln c for log-scaled ones; finite bounds needed), run in parallel on
    /// all cores, end points within 0.01 in every scaled variable clustered into one
    /// minimum; the best is reported, the distinct minima are listed (console, report.md,
    /// result.json `multistart`). N in [1, 10000].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=10000), conflicts_with = "resume")]
    pub starts: Option<u32>,

    /// Profile-likelihood 95% intervals of every free parameter after the fit: each
    /// parameter held at values stepping away from the optimum (half a Gauss-Newton std.
    /// dev. per step, at most 8 per side), the others re-fitted from the neighbouring point;
    /// the interval is where 2 (J - J*) / s_k^2 <= 3.841 with s_k^2 on the scale of the
    /// std. dev.'s noise model (2 J* / (n - p) under `noise: Residual`). Chains of
    /// different parameters and sides run in parallel. Console, report.md, result.json
    /// `profiles`, figures profile_{name}.svg/png.
    #[arg(long)]
    pub profiles: bool,

    /// Skip the discretization error (by default the forward problem is re-run at the
    /// optimum on a 2x refined mesh with halved time steps, and the force change and the
    /// parameter shift it implies are reported beside the standard deviations).
    #[arg(long)]
    pub no_refine: bool,

    /// Override a scalar of the configuration by its dotted path (repeatable), e.g.
    /// `--set specimen.nr=10 --set identify.params.E.start=5000`.
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    pub sets: Vec<String>,
}

fn parse_method(text: &str) -> Result<MethodName, String> {
    MethodName::parse(text).map_err(|e| e.to_string())
}

/// Log lines and the progress bar of a run.
struct Console {
    progress: Option<crate::log::Progress>,
    names: Vec<&'static str>,
    free: Vec<usize>,
    header_done: bool,
    /// The unit of J (N^2; mm^2 under load control).
    cost_unit: &'static str,
}

impl Observer for Console {
    fn started(&mut self, info: &RunInfo) {
        self.names = info.names.clone();
        self.free = (0..info.free.len()).filter(|&k| info.free[k]).collect();
        self.cost_unit = info.cost_unit;
        let free: Vec<&str> = self.free.iter().map(|&k| info.names[k]).collect();
        tracing::info!(
            "indentify identify {}\n  law {}, identifying {} ({}), method {}{}\n  data: {}\n  \
             report directory `{}`",
            info.config,
            info.law,
            free.join(", "),
            if info.held.is_empty() {
                "nothing held".to_string()
            } else {
                format!("held: {}", info.held.join(", "))
            },
            info.method,
            match info.resumed_at {
                Some(r) => format!(", resumed at iteration {r}"),
                None => String::new(),
            },
            info.data,
            info.out
                .as_ref()
                .map_or("-".into(), |p| p.display().to_string())
        );
        self.progress = Some(crate::log::Progress::new(
            "identify",
            info.max_iterations as u64,
            "iterations",
        ));
    }

    fn iteration(&mut self, r: &IterationRecord) {
        if let Some(p) = &self.progress {
            p.set(
                r.iteration as u64,
                format!(
                    "J {:.4e} {}, {} forward / {} adjoint solves",
                    r.cost, self.cost_unit, r.forward_solves, r.adjoint_solves
                ),
            );
        }
        if !self.header_done {
            let mut cols = vec![
                format!("{:>4}", "iter"),
                format!("{:<13}", format!("J ({})", self.cost_unit)),
            ];
            cols.push(format!("{:<10}", "|grad|"));
            cols.extend(self.free.iter().map(|&k| format!("{:<14}", self.names[k])));
            cols.push("fwd/adj  s".into());
            tracing::info!("  {}", cols.join(" "));
            self.header_done = true;
        }
        let mut cols = vec![
            format!("{:>4}", r.iteration),
            format!("{:<13.6e}", r.cost),
            format!("{:<10.3e}", r.grad_norm),
        ];
        cols.extend(
            self.free
                .iter()
                .map(|&k| format!("{:<14}", sig(r.params[k], 9))),
        );
        cols.push(format!(
            "{}/{}  {:.1}",
            r.forward_solves, r.adjoint_solves, r.seconds
        ));
        tracing::info!("  {}", cols.join(" "));
    }
}

/// The study's options from the command line.
///
/// # Errors
/// A malformed `--fixed` or `--start` item.
pub fn options(args: &Args) -> Result<IdentifyOptions> {
    if args.seed.is_some() && args.noise.is_none() && args.starts.is_none() {
        bail!("--seed needs --noise or --starts (it seeds the noise and the multi-start's starts)");
    }
    Ok(IdentifyOptions {
        config: args
            .config
            .clone()
            .map_or(ConfigSource::Default, ConfigSource::Path),
        sets: args.sets.clone(),
        data: args.data.clone(),
        out: Some(args.out.clone()),
        overrides: Overrides {
            free: args.free.clone(),
            fixed: args
                .fixed
                .iter()
                .map(|f| fixed_item(f))
                .collect::<Result<_>>()?,
            starts: args
                .start
                .iter()
                .filter(|s| s.as_str() != "closed-form")
                .map(|s| name_value("--start", s))
                .collect::<Result<_>>()?,
            method: args.method,
            max_iterations: args.max_iter,
            noise: None,
            bfgs_start: None,
        },
        resume: args.resume,
        force: args.force,
        noise: args.noise.map(|a| (a, args.seed.unwrap_or(1))),
        figures: true,
        cancel: crate::interrupt::cancel_on_ctrl_c(),
        checkpoint: args.checkpoint.map(|n| n as usize),
        memory_budget: args.memory_budget.saturating_mul(1 << 20),
        refine: !args.no_refine,
        starts: args
            .starts
            .map(|n| StartsOptions::new(n as usize, args.seed.unwrap_or(1))),
        profiles: args.profiles.then(ProfileSettings::default),
        jobs: args.jobs.map(|n| n as usize),
        closed_form_start: args.start.iter().any(|s| s == "closed-form"),
    })
}

/// Exit status of a run that met a convergence criterion where the data leave some free
/// parameters undetermined (a stall and the iteration limit exit with 1, an interruption
/// with 130).
pub const EXIT_UNDETERMINED: i32 = 3;

/// Runs the identification, writes the report and prints the table.
///
/// # Errors
/// Invalid input (before any solve and any file written), an unwritable or occupied
/// report directory, and a run that does not converge (after the report is written).
pub fn run(args: &Args) -> Result<()> {
    let opts = options(args)?;
    let mut console = Console {
        progress: None,
        names: Vec::new(),
        free: Vec::new(),
        header_done: false,
        cost_unit: "N^2",
    };
    let outcome = identify::run(&opts, &mut console);
    drop(console.progress.take());
    let o = outcome?;
    print::print_text(&summary(&o))?;
    if let Some(m) = &o.multistart {
        print::print_text(&m.table())?;
    }
    if let Some(p) = &o.profiles {
        print::print_text(&indentify_study::explore::profiles_table(p))?;
    }
    let r = &o.result;
    if !o.converged() {
        let files = o.files.as_ref();
        let (result, history) = files.map_or((String::new(), String::new()), |f| {
            (
                f.result.display().to_string(),
                f.history.display().to_string(),
            )
        });
        if let indentify_study::StopReason::Undetermined { met, params } = &r.stop_reason {
            // the exit status of an undetermined stop (3), distinct from the iteration
            // limit's and a stall's (1)
            eprintln!(
                "error: the identification of `{}` stopped ({met}) at a point where the data \
                 do not determine {}. What to do: {}. The result is in `{result}` and the \
                 history in `{history}`.",
                o.config,
                params.join("; "),
                indentify_study::StopReason::UNDETERMINED_ADVICE
            );
            std::process::exit(EXIT_UNDETERMINED);
        }
        if r.stop_reason == indentify_study::StopReason::Interrupted {
            tracing::warn!(
                "interrupted after iteration {}: the result so far is in `{result}` and the \
                 history in `{history}` (continue with --resume)",
                r.iterations
            );
            std::process::exit(130);
        }
        bail!(
            "the identification of `{}` did not converge: {} after {} iterations (J = {:.4e} \
             N^2); the result so far is in `{result}` and the history in `{history}` (continue \
             with --resume, or change the start, bounds or method)",
            o.config,
            r.stop_reason,
            r.iterations,
            r.cost,
        );
    }
    if opts.cancel.is_raised() {
        // converged, then interrupted during the discretization check (skipped, said above)
        tracing::warn!(
            "interrupted after the fit: the report is written without the discretization check"
        );
        std::process::exit(130);
    }
    Ok(())
}

/// The table of the result and the lines under it.
pub fn summary(o: &IdentifyOutcome) -> String {
    let mut text = parameter_table(o);
    if let Some(c) = &o.start {
        text.push_str(&format!("  {}\n", c.summary()));
    }
    text.push_str(&fit_lines(o));
    if let Some(i) = &o.result.identifiability {
        text.push_str(&identifiability_lines(i, o.fit.observable));
    }
    if let Some(d) = &o.discretization {
        text.push_str(&discretization_lines(o, d));
    }
    if let Some(f) = &o.files {
        let reports = f.report.as_ref().map_or(String::new(), |(md, json, figs)| {
            format!(
                "{} and {}, {} figures as SVG and PNG; ",
                md.display(),
                json.display(),
                figs.len() / 2
            )
        });
        text.push_str(&format!(
            "  report: {reports}result {}, history {}, fit {}; total wall time {:.1} s\n",
            f.result.display(),
            f.history.display(),
            f.fit.display(),
            o.wall_seconds
        ));
    }
    text
}

/// The first line and the parameter table: start, final value, truth, deviation and
/// discretization shift per parameter.
fn parameter_table(o: &IdentifyOutcome) -> String {
    let result = &o.result;
    let mut rows = vec![
        ["parameter", "unit", "start", "final"]
            .map(String::from)
            .to_vec(),
    ];
    if o.truth.is_some() {
        rows[0].extend(["truth".to_string(), "rel. error".to_string()]);
    }
    let disc = o.discretization.as_ref();
    let id = result.identifiability.as_ref();
    if id.is_some() {
        rows[0].push("std. dev.".to_string());
    }
    if disc.is_some() {
        rows[0].push("disc. shift".to_string());
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
        if let Some(truth) = &o.truth {
            row.push(truth[k].to_string());
            row.push(if p.free {
                format!("{:.1e}", ((p.value - truth[k]) / truth[k]).abs())
            } else {
                String::new()
            });
        }
        let undetermined = id.is_some_and(|i| i.is_undetermined(p.name));
        if id.is_some() {
            // an undetermined parameter never shows a number for its deviation
            row.push(if undetermined {
                "undetermined".to_string()
            } else {
                o.std_dev(p.name).map_or(String::new(), |s| sig(s, 3))
            });
        }
        if let Some(d) = disc {
            row.push(match (p.free, d.shift[k]) {
                (false, _) => String::new(),
                (true, Some(s)) => format!(
                    "{}{}",
                    sig(s, 3),
                    if o.std_dev(p.name).is_some_and(|sd| s.abs() > sd) {
                        " (> std. dev.)"
                    } else {
                        ""
                    }
                ),
                (true, None) => "undetermined".to_string(),
            });
        }
        rows.push(row);
    }
    format!(
        "identified {} parameters ({}, {}: {})\n{}",
        o.law,
        result.method.name(),
        o.headline_status(),
        result.stop_reason,
        table(&rows, "  ")
    )
}

/// The cost, the counts and the fit quality (each test's too in a joint fit).
fn fit_lines(o: &IdentifyOutcome) -> String {
    let result = &o.result;
    let mut text = String::new();
    // under load control the depth is fitted: J on the depth residuals (mm^2)
    let depth = o.fit.observable == indentify_study::Observable::Depth;
    let mixed = o.tests.iter().any(|t| t.fit.observable != o.fit.observable);
    let (what, unit, y) = if depth {
        ("depth", "mm", "h")
    } else {
        ("force", "N", "F")
    };
    if depth && !mixed {
        text.push_str("  load control: the force is prescribed, the depth fitted\n");
    }
    text.push_str(&format!(
        "  J = {:.4e} {} (start {:.4e}), {} iterations, {} forward and {} adjoint solves, {:.1} s\n",
        result.cost,
        if mixed {
            "(weighted: force and depth tests)".to_string()
        } else {
            format!("{unit}^2")
        },
        result.initial_cost,
        result.iterations,
        result.forward_solves,
        result.adjoint_solves,
        result.seconds
    ));
    if let Some(q) = &o.quality {
        text.push_str(&format!(
            "  fit{}: R^2 = {:.6}, RMS {what} residual {:.4e} {unit} = {:.3}% of {y}_max, \
             largest residual {:.4e} {unit} ({} points)\n",
            if o.tests.is_empty() {
                String::new()
            } else {
                format!(" of the {} tests together", o.tests.len())
            },
            q.r2,
            q.rms,
            100.0 * q.rms_rel,
            q.max_abs,
            q.n
        ));
    }
    for t in &o.tests {
        let q = t
            .quality
            .as_ref()
            .map_or("no fit quality".to_string(), |q| {
                format!(
                    "R^2 = {:.6}, RMS {:.3}% of {}_max ({} points)",
                    q.r2,
                    100.0 * q.rms_rel,
                    t.fit.observable.symbol(),
                    q.n
                )
            });
        text.push_str(&format!(
            "    {}: {q}; weight {:.4e}{}, w J = {:.4e}\n",
            t.name,
            t.weight,
            if t.default_weight {
                format!(" (1/(n {}_max^2))", t.fit.observable.symbol())
            } else {
                String::new()
            },
            t.cost
        ));
    }
    if let Some(b) = &o.oliver_pharr {
        text.push_str(&indentify_study::op_beside::lines(b));
    }
    // model adequacy and the caveats of the headline (indentify_study::adequacy)
    text.push_str(&o.adequacy_lines());
    text
}

/// The identifiability summary and the undetermined parameters.
fn identifiability_lines(i: &Identifiability, observable: Observable) -> String {
    let mut text = String::new();
    text.push_str(&format!("  {}\n", identifiability_line(i, observable)));
    if let Some(w) = i.weakest_direction() {
        text.push_str(&format!("  weakest direction: {w}\n"));
    }
    if !i.undetermined.is_empty() {
        let list: Vec<String> = i
            .undetermined
            .iter()
            .zip(&i.reasons)
            .map(|(n, why)| format!("{n}: {why}"))
            .collect();
        text.push_str(&format!(
            "  UNDETERMINED by these data: {}\n  what to do: {}\n",
            list.join("; "),
            indentify_study::StopReason::UNDETERMINED_ADVICE
        ));
        if let Some(t) = i.intervals_text() {
            text.push_str(&format!("  intervals: {t}\n"));
        }
    }
    text
}

/// The discretization error: the refined run's force change (each test's in a joint fit)
/// and the parameter shift.
fn discretization_lines(o: &IdentifyOutcome, d: &Discretization) -> String {
    let result = &o.result;
    let mut text = String::new();
    let rel: Vec<String> = result
        .params
        .iter()
        .zip(&d.relative_shift)
        .filter(|(p, _)| p.free)
        .map(|(p, r)| match r {
            Some(r) => format!("{} {:+.2e}", p.name, r),
            None => format!("{} undetermined", p.name),
        })
        .collect();
    if d.tests.len() > 1 {
        // a joint fit: every test refined, one line each, then the joint shift
        text.push_str(&format!(
            "  discretization: each test's mesh refined 2x and steps halved; relative \
             parameter shift of the joint fit {}; {:.1} s (--no-refine skips it)\n",
            rel.join(", "),
            d.seconds
        ));
        for t in &d.tests {
            text.push_str(&format!(
                "    {}: {} -> {} elements, {} -> {} steps: force change RMS {:.3}% of \
                 F_max (largest {:.3e} N)\n",
                t.name,
                t.elements.0,
                t.elements.1,
                t.n_steps.0,
                t.n_steps.1,
                100.0 * t.rms_rel,
                t.max_abs
            ));
        }
    } else {
        text.push_str(&format!(
            "  discretization: mesh refined 2x ({} -> {} elements), steps halved ({} -> \
             {}): force change RMS {:.3}% of F_max (largest {:.3e} N); relative parameter \
             shift {}; {:.1} s (--no-refine skips it)\n",
            d.elements.0,
            d.elements.1,
            d.n_steps.0,
            d.n_steps.1,
            100.0 * d.rms_rel,
            d.max_abs,
            rel.join(", "),
            d.seconds
        ));
    }
    text
}

/// `identifiability: relative std. dev. E 1e-9, eta 2e-9; correlation E-eta -0.87;
/// singular values 1.2e3, 4.5e1; condition number 1.105e1` (undetermined parameters show
/// no deviation and no correlation; a condition number beyond 1e16 shows as `singular`).
fn identifiability_line(i: &Identifiability, observable: Observable) -> String {
    let sd: Vec<String> = i
        .names
        .iter()
        .zip(&i.rel_std_dev)
        .map(|(n, s)| {
            if i.is_undetermined(n) || !s.is_finite() {
                format!("{n} undetermined")
            } else {
                format!("{n} {s:.1e}")
            }
        })
        .collect();
    let mut corr = Vec::new();
    for a in 0..i.names.len() {
        for b in a + 1..i.names.len() {
            let c = i.correlation[a][b];
            if [a, b].iter().any(|&k| i.is_undetermined(i.names[k])) || !c.is_finite() {
                continue;
            }
            corr.push(format!("{}-{} {:.3}", i.names[a], i.names[b], c));
        }
    }
    let mut s = format!("identifiability: relative std. dev. {}", sd.join(", "));
    if !corr.is_empty() {
        s.push_str(&format!("; correlation {}", corr.join(", ")));
    }
    let sv: Vec<String> = i
        .singular_values
        .iter()
        .map(|v| format!("{v:.2e}"))
        .collect();
    s.push_str(&format!(
        "; singular values of S {}; condition number {}",
        sv.join(", "),
        i.condition_text()
    ));
    if i.noise != indentify_study::NoiseModel::Residual {
        s.push_str(&format!(
            "; deviations assume {}",
            match observable {
                Observable::Depth => i.noise.describe_observed(i.noise_level, "h", "mm"),
                Observable::Force => i.noise.describe(i.noise_level),
            }
        ));
    }
    s
}
