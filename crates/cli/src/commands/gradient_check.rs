//! `indentify gradient-check`: prints the comparison of `indentify_study::check` (the
//! adjoint gradient against central finite differences and the forward sensitivities) and
//! fails when a tolerance is exceeded.

use std::path::PathBuf;

use anyhow::{Result, bail};
use indentify_study::ConfigSource;
use indentify_study::check::{
    self, CheckOptions, NU_PERTURBATION, PERTURBATION, SCAN_STEPS, SENSITIVITY_TOL,
};
use indentify_study::format::{assignments, table};

use crate::print;

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

    /// The test (from 1) of a joint configuration (`tests: [...]`) to work on.
    #[arg(long, value_name = "K")]
    pub test: Option<usize>,
}

/// Runs the check, prints the comparison, and fails if a tolerance is exceeded.
///
/// # Errors
/// Invalid inputs, a failing solve, or a difference above `--tol` (adjoint vs FD) or above
/// [`SENSITIVITY_TOL`] (adjoint vs sensitivities); the report is printed first.
pub fn run(args: &Args) -> Result<()> {
    let r = check::run(&CheckOptions {
        config: ConfigSource::Path(args.config.clone()),
        sets: args.sets.clone(),
        test: args.test,
        data: args.data.clone(),
        rel_step: args.rel_step,
        tol: args.tol,
        scan: args.scan,
    })?;
    let name = r.config.clone();
    let names: Vec<&str> = r.checks.iter().map(|c| c.name).collect();
    let (j, synthesized, data_name, checks, passed, failures) = (
        r.j,
        r.synthesized,
        &r.data_name,
        &r.checks,
        r.passed,
        &r.failures,
    );
    let point: Vec<f64> = r.params.0.iter().map(|(_, v)| *v).collect();
    if args.json {
        print::print_json(&r)?;
    } else {
        let mut text = format!(
            "indentify gradient-check {name}\n  law {}; data {data_name}\n",
            r.law
        );
        if synthesized {
            text.push_str(&format!(
                "  check point {} (every parameter x {PERTURBATION}, nu x {NU_PERTURBATION})\n",
                assignments(&names, &point)
            ));
        } else {
            text.push_str(&format!(
                "  check point {} (the configuration's law)\n",
                assignments(&names, &point)
            ));
        }
        text.push_str(&format!(
            "  J = {j:.6e} N^2 over {} schedule times; central differences with h = {:e} |c_k|; \
             forward solves to residual_tol = {:e}\n\n",
            r.schedule_times, args.rel_step, r.residual_tol
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
        for c in checks {
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
                for c in checks {
                    let r = c.scan.as_ref().map_or(f64::NAN, |s| s[i].rel_diff);
                    row.push(format!("{r:.1e}"));
                }
                rows.push(row);
            }
            text.push_str(&table(&rows, "  "));
        }
        text.push_str(&format!(
            "\n  forward {:.3} s, adjoint {:.3} s, sensitivities {:.3} s, {} forward solves \
             for the differences {:.3} s\n",
            r.forward_seconds,
            r.adjoint_seconds,
            r.sensitivity_seconds,
            r.fd_forward_solves,
            r.fd_seconds
        ));
        if passed {
            text.push_str(&format!(
                "  passed: adjoint vs central FD <= {:.0e} (--tol), adjoint vs sensitivities <= \
                 {SENSITIVITY_TOL:.0e}\n",
                args.tol
            ));
        }
        print::print_text(&text)?;
    }
    if !passed {
        bail!(
            "gradient check of `{name}` failed:\n{}",
            failures.join("\n")
        );
    }
    Ok(())
}
