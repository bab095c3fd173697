//! `indentify analyze` and `indentify calibrate`: map their arguments onto
//! `indentify_study::analyze` (the Oliver-Pharr pipeline and the tip calibration) and print
//! the table, the JSON or the calibration summary.

use std::path::PathBuf;

use anyhow::{Result, bail};
use indentify_study::analyze::{self, AnalyzeOptions, CalibrateOptions};
use indentify_study::{Epsilon, FitRange, Tip};

use crate::print;

/// Arguments of `indentify analyze`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The instrument file (CSV, Anton Paar TXT, Hysitron, KLA .xlsx/.xls, ...).
    pub file: PathBuf,

    /// Analyse only this 1-based test of a multi-test file.
    #[arg(long, value_name = "K")]
    pub test: Option<usize>,

    /// The tip: berkovich (ideal, A = 24.5 hc^2), cone:HALF_ANGLE_DEG, sphere:RADIUS_UM,
    /// flat:RADIUS_UM; diamond (E_i 1141 GPa, nu_i 0.07).
    #[arg(
        long,
        value_name = "SHAPE",
        default_value = "berkovich",
        conflicts_with = "tip_file"
    )]
    pub tip: String,

    /// A tip file written by `indentify calibrate` (area function, frame compliance).
    #[arg(long, value_name = "TIP.ron")]
    pub tip_file: Option<PathBuf>,

    /// Poisson's ratio of the sample.
    #[arg(long, value_name = "NU", default_value_t = 0.3)]
    pub nu: f64,

    /// Force range of the unloading fit, as fractions of F_max: LOWER,UPPER (default: the
    /// vendor's for the format: 0.4,0.98 Anton Paar and others, 0.5,0.95 KLA).
    #[arg(long, value_name = "LO,HI", value_delimiter = ',', num_args = 1)]
    pub fit_range: Option<Vec<f64>>,

    /// epsilon of h_c = h_max - epsilon F_max/S: `tip` (0.75 Berkovich and sphere, 0.727
    /// cone, 1 flat), `m` (from the fitted exponent, ISO 14577), or a number.
    #[arg(long, value_name = "tip|m|VALUE", default_value = "tip")]
    pub epsilon: String,

    /// beta of E_r = sqrt(pi) S / (2 beta sqrt(A)).
    #[arg(long, value_name = "BETA", default_value_t = 1.0)]
    pub beta: f64,

    /// The vendor's results table to compare with (Anton Paar `_data.TXT`; by default the
    /// file's sibling `<stem>_data.<ext>` when it exists).
    #[arg(long, value_name = "FILE")]
    pub results: Option<PathBuf>,

    /// Contact detection (zero point): `auto` (off for Anton Paar files, which the instrument
    /// zeroes at contact; on for the others), `on`, `off` (the file's own zero), or
    /// `stiffness:K`: the first sample where the 5-sample median of |dF/dh| exceeds K mN/um
    /// (indentationGUI's surface; for multi-cycle tests whose first cycles stay below the
    /// force threshold).
    #[arg(long, value_name = "auto|on|off|stiffness:K", default_value = "auto")]
    pub zero_point: String,

    /// Print the outcome as JSON (N, mm, N/mm, MPa) instead of the table.
    #[arg(long)]
    pub json: bool,

    /// Write analysis.json and analysis.csv into this folder.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// A tip from its command-line name (`indentify_study::analyze::tip_from_name`).
///
/// # Errors
/// An unknown shape or a parameter that is not a number.
pub fn tip_from_name(s: &str) -> Result<Tip> {
    analyze::tip_from_name(s)
}

fn epsilon(s: &str) -> Result<Epsilon> {
    analyze::epsilon_from_name(s)
}

/// The fit range of `--fit-range LO,HI`; a count other than 2 gives NaN ends, which the
/// analysis refuses naming `fit_range`.
fn fit_range(v: &Option<Vec<f64>>) -> Option<FitRange> {
    v.as_ref().map(|v| match v.as_slice() {
        [lower, upper] => FitRange {
            lower: *lower,
            upper: *upper,
        },
        _ => FitRange {
            lower: f64::NAN,
            upper: f64::NAN,
        },
    })
}

/// Analyses the file, prints the table (or the JSON).
///
/// # Errors
/// Unreadable or unknown input, options out of range, an unwritable folder.
pub fn run(args: &Args) -> Result<()> {
    let tip = match &args.tip_file {
        Some(p) => analyze::read_tip(p)?,
        None => tip_from_name(&args.tip)?,
    };
    let opts = AnalyzeOptions {
        test: args.test,
        tip,
        nu: args.nu,
        fit_range: fit_range(&args.fit_range),
        epsilon: epsilon(&args.epsilon)?,
        beta: args.beta,
        results: args.results.clone(),
        out: args.out.clone(),
        zero_point: match args.zero_point.as_str() {
            "auto" => None,
            "on" => Some(true),
            "off" => Some(false),
            s if s.starts_with("stiffness:") => Some(true),
            other => {
                bail!("--zero-point {other}: expected auto, on, off or stiffness:K (K in mN/um)")
            }
        },
        surface_stiffness: match args.zero_point.strip_prefix("stiffness:") {
            None => None,
            Some(k) => match k.parse::<f64>() {
                Ok(v) if v > 0.0 && v.is_finite() => Some(v),
                _ => bail!("--zero-point stiffness:{k}: expected a stiffness > 0 in mN/um"),
            },
        },
        ..AnalyzeOptions::new(args.file.clone())
    };
    let o = analyze::run(&opts)?;
    if args.json {
        return print::print_json(&o);
    }
    let mut text = format!(
        "{} ({}): {} test(s); tip {}; nu {}, beta {}, fit {:.0} %..{:.0} % of F_max ({})\n",
        o.file,
        o.format,
        o.tests.len(),
        o.tip.area.describe(),
        o.nu,
        o.beta,
        o.fit_range.lower * 100.0,
        o.fit_range.upper * 100.0,
        o.fit_range_source
    );
    text.push_str(&analyze::summary_table(&o));
    for w in &o.written {
        text.push_str(&format!("wrote {w}\n"));
    }
    print::print_text(&text)
}

/// Arguments of `indentify calibrate`.
#[derive(Debug, clap::Args)]
pub struct CalibrateArgs {
    /// The reference's file (fused silica, several tests or load cycles).
    pub file: PathBuf,

    /// The reference's Young's modulus, GPa (fused silica 72).
    #[arg(long, value_name = "GPA")]
    pub modulus: f64,

    /// The reference's Poisson's ratio (fused silica 0.17 to 0.18).
    #[arg(long, value_name = "NU")]
    pub nu: f64,

    /// The tip file to write (RON).
    #[arg(long, value_name = "TIP.ron")]
    pub out: PathBuf,

    /// Use only these 1-based tests (comma-separated).
    #[arg(long, value_name = "K,...", value_delimiter = ',')]
    pub tests: Option<Vec<usize>>,

    /// A known frame compliance, nm/mN (instead of fitting it).
    #[arg(long, value_name = "NM_PER_MN")]
    pub compliance: Option<f64>,

    /// Fit the frame compliance on the unloadings with F_max at least this fraction of the
    /// largest.
    #[arg(long, value_name = "FRACTION", default_value_t = 0.25)]
    pub compliance_range: f64,

    /// Number of area coefficients C0, C1, ... (1 to 6).
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub terms: usize,

    /// Force range of the unloading fit, LOWER,UPPER fractions of F_max (default: the
    /// vendor's).
    #[arg(long, value_name = "LO,HI", value_delimiter = ',', num_args = 1)]
    pub fit_range: Option<Vec<f64>>,

    /// beta of E_r = sqrt(pi) S / (2 beta sqrt(A)).
    #[arg(long, value_name = "BETA", default_value_t = 1.0)]
    pub beta: f64,

    /// Print the outcome as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Calibrates, writes the tip file, prints the summary.
///
/// # Errors
/// Unreadable input, a calibration without a usable result, an unwritable tip file.
pub fn run_calibrate(args: &CalibrateArgs) -> Result<()> {
    let opts = CalibrateOptions {
        tests: args.tests.clone(),
        compliance: args.compliance.map(|c| c * 1e-3),
        compliance_range: args.compliance_range,
        terms: args.terms,
        fit_range: fit_range(&args.fit_range),
        beta: args.beta,
        out: Some(args.out.clone()),
        ..CalibrateOptions::new(args.file.clone(), args.modulus * 1e3, args.nu)
    };
    let o = analyze::calibrate(&opts)?;
    if args.json {
        return print::print_json(&o);
    }
    let mut text = analyze::calibration_summary(&o);
    if let Some(w) = &o.written {
        text.push_str(&format!("wrote {w}\n"));
    }
    print::print_text(&text)
}
