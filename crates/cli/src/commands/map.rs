//! `indentify map`: maps its arguments onto `indentify_study::costmap` (the cost over a 2D
//! slice of two free parameters, in parallel) and prints the summary.

use std::path::PathBuf;

use anyhow::{Result, bail};
use indentify_study::ConfigSource;
use indentify_study::config::Overrides;
use indentify_study::costmap::{self, MapOptions, Through};
use indentify_study::identify::IdentifyOptions;

use crate::print;

/// Arguments of `indentify map`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Configuration file (RON); without it, the embedded R1 default.
    pub config: Option<PathBuf>,

    /// The two free parameters to map, horizontal first, e.g. `--pair K,m`.
    #[arg(
        long,
        value_name = "A,B",
        value_delimiter = ',',
        num_args = 1,
        required = true
    )]
    pub pair: Vec<String>,

    /// Points per side of the grid, in [3, 401].
    #[arg(long, value_name = "N", default_value_t = 41)]
    pub grid: usize,

    /// Half-width of the grid in the scaled variables (ln c for log-scaled parameters): one
    /// value for both or two comma-separated; default 0.5 (a factor e^0.5 = 1.65 each way).
    #[arg(
        long,
        value_name = "S[,S]",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    pub span: Vec<f64>,

    /// Centre of the slice: `fit` (identify first, with the configuration's method and start),
    /// `law` (the configuration's law values: the truth for synthesized data) or `start`.
    #[arg(long, value_name = "WHERE", default_value = "fit", value_parser = Through::parse)]
    pub through: Through,

    /// Output folder: map.csv, map.json, map.svg, map.png.
    #[arg(long, value_name = "DIR", default_value = "out-map")]
    pub out: PathBuf,

    /// The measured curve (CSV with `t` and `F`) or record replacing `data.file`; without it,
    /// the configuration's own curve at its `law` values.
    #[arg(long, value_name = "CURVE.csv")]
    pub data: Option<PathBuf>,

    /// Synthesized data only: multiplicative noise F (1 + a xi), xi uniform in [-1, 1].
    #[arg(
        long,
        value_name = "A",
        conflicts_with = "data",
        allow_negative_numbers = true
    )]
    pub noise: Option<f64>,

    /// Seed of the noise (SplitMix64).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 1,
        requires = "noise",
        allow_negative_numbers = true,
        value_parser = super::parse_count
    )]
    pub seed: u64,

    /// Identify exactly these parameters (comma-separated); the others are held.
    #[arg(long, value_name = "NAMES", value_delimiter = ',', num_args = 1)]
    pub free: Option<Vec<String>>,

    /// Threads evaluating the grid (default: all cores).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub jobs: Option<u32>,

    /// Override a scalar of the configuration by its dotted path (repeatable).
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    pub sets: Vec<String>,
}

/// Computes and writes the map, prints the summary.
///
/// # Errors
/// Invalid input (before any solve), a failed fit or centre, an unwritable folder.
pub fn run(args: &Args) -> Result<()> {
    let mut identify = IdentifyOptions::new(
        args.config
            .clone()
            .map_or(ConfigSource::Default, ConfigSource::Path),
    );
    identify.sets = args.sets.clone();
    identify.data = args.data.clone();
    identify.noise = args.noise.map(|a| (a, args.seed));
    identify.overrides = Overrides {
        free: args.free.clone(),
        ..Overrides::default()
    };
    identify.refine = false;
    identify.figures = false;
    let opts = MapOptions {
        identify,
        pair: args.pair.clone(),
        grid: args.grid,
        span: args.span.clone(),
        through: args.through,
        out: Some(args.out.clone()),
        jobs: args.jobs.map(|n| n as usize),
    };
    let map = costmap::run(&opts)?;
    if map.failed == map.cost.len() {
        bail!("every grid point failed to solve");
    }
    print::print_text(&map.summary())
}
