//! `indentify check`: validates a configuration (with its `--set` overrides) without
//! solving, and prints it resolved as an annotated configuration; a joint configuration's
//! tests are each prepared and summarized.

use std::io::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result};

use indentify_study::ConfigSource;
use indentify_study::config::Config;
use indentify_study::identify::prepare;
use indentify_study::templates::annotated;

/// Arguments of `indentify check`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Configuration file (RON).
    pub config: PathBuf,

    /// Override a scalar of the configuration by its dotted path (repeatable), as for
    /// `simulate`.
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    pub sets: Vec<String>,
}

/// Validates the configuration (every test of a joint one), prints a summary to standard
/// error, per test, and the resolved configuration (annotated RON, every default written
/// out) to standard output.
///
/// # Errors
/// An invalid configuration or a closed standard output.
pub fn run(args: &Args) -> Result<()> {
    let name = args.config.display().to_string();
    let cfg = ConfigSource::Path(args.config.clone()).load(&args.sets)?;
    let tests = cfg.one_test_configs(&name)?;
    let mut summaries = Vec::with_capacity(tests.len());
    for (test_name, test) in &tests {
        summaries.push(summary(test_name, test)?);
    }
    let mut header = vec![format!("Resolved from `{name}` by `indentify check`.")];
    if !args.sets.is_empty() {
        header.push(format!("Overrides: --set {}", args.sets.join(" --set ")));
    }
    std::io::stdout()
        .lock()
        .write_all(annotated(&cfg, &header).as_bytes())
        .context("cannot write to standard output")?;
    for lines in summaries {
        for line in lines {
            tracing::info!("{line}");
        }
    }
    Ok(())
}

/// Prepares one test (mesh, model, schedule, record) and describes it.
fn summary(name: &str, cfg: &Config) -> Result<Vec<String>> {
    let prepared = prepare(cfg, name)?;
    let schedule = &prepared.schedule;
    let mut lines = vec![format!(
        "{name}: valid; law {}, punch {}, mesh: {}, {} steps{} over {} s",
        cfg.law.name(),
        cfg.punch.describe(),
        prepared.mesher.describe(),
        schedule.n_steps(),
        schedule
            .substeps_summary()
            .map_or(String::new(), |s| format!(
                " ({s}: {} solver steps)",
                schedule.n_solver_steps()
            )),
        indentify_study::format::sig(schedule.t.last().copied().unwrap_or(0.0), 6)
            .parse::<f64>()
            .unwrap_or(0.0)
    )];
    lines.push(format!(
        "  model: {}{}",
        cfg.describe_model(),
        if cfg.is_measured() {
            " (measured data: unless stated, normal contact and finite strain)"
        } else {
            ""
        }
    ));
    if let Some(m) = &prepared.measured {
        lines.push(format!("  data: {}", m.summary()));
    }
    if prepared.rim != indentify_study::Rim::Smooth {
        lines.push(format!("  rim: {}", prepared.rim.describe()));
    }
    Ok(lines)
}
