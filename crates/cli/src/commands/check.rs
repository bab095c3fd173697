//! `indentify check`: validates a configuration (with its `--set` overrides) without
//! solving, and prints it resolved as an annotated configuration.

use std::io::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result};

use indentify_study::ConfigSource;
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

/// Validates the configuration, prints a summary to standard error and the resolved
/// configuration (annotated RON, every default written out) to standard output.
///
/// # Errors
/// An invalid configuration or a closed standard output.
pub fn run(args: &Args) -> Result<()> {
    let name = args.config.display().to_string();
    let cfg = ConfigSource::Path(args.config.clone()).load(&args.sets)?;
    let prepared = prepare(&cfg, &name)?;
    let schedule = &prepared.schedule;
    let mut header = vec![format!("Resolved from `{name}` by `indentify check`.")];
    if !args.sets.is_empty() {
        header.push(format!("Overrides: --set {}", args.sets.join(" --set ")));
    }
    std::io::stdout()
        .lock()
        .write_all(annotated(&cfg, &header).as_bytes())
        .context("cannot write to standard output")?;
    tracing::info!(
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
    );
    tracing::info!(
        "  model: {}{}",
        cfg.describe_model(),
        if cfg.is_measured() {
            " (measured data: unless stated, normal contact and finite strain)"
        } else {
            ""
        }
    );
    if let Some(m) = &prepared.measured {
        tracing::info!("  data: {}", m.summary());
    }
    if prepared.rim != indentify_contact::punch::Rim::Smooth {
        tracing::info!("  rim: {}", prepared.rim.describe());
    }
    Ok(())
}
