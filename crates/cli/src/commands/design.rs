//! `indentify design`: maps its arguments onto `indentify_study::design` (the candidate
//! protocols of a configuration's `design` section ranked by the standard deviations they
//! would give, in parallel) and prints the table.

use std::path::PathBuf;

use anyhow::Result;
use indentify_study::ConfigSource;
use indentify_study::config::Overrides;
use indentify_study::design::{self, DesignOptions};

use crate::print;

/// Arguments of `indentify design`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Configuration file (RON) with a `design` section.
    pub config: PathBuf,

    /// Output folder: design.json, design.md.
    #[arg(long, value_name = "DIR", default_value = "out-design")]
    pub out: PathBuf,

    /// Count exactly these parameters as identified (comma-separated); the others are held.
    #[arg(long, value_name = "NAMES", value_delimiter = ',', num_args = 1)]
    pub free: Option<Vec<String>>,

    /// Threads evaluating the candidates (default: all cores).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub jobs: Option<u32>,

    /// Override a scalar of the configuration by its dotted path (repeatable).
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    pub sets: Vec<String>,
}

/// Evaluates and writes the design, prints the table.
///
/// # Errors
/// Invalid input (before any solve), a failed solve, an unwritable folder.
pub fn run(args: &Args) -> Result<()> {
    let opts = DesignOptions {
        config: ConfigSource::Path(args.config.clone()),
        sets: args.sets.clone(),
        overrides: Overrides {
            free: args.free.clone(),
            ..Overrides::default()
        },
        out: Some(args.out.clone()),
        jobs: args.jobs.map(|n| n as usize),
    };
    let d = design::run(&opts)?;
    print::print_text(&d.summary())
}
