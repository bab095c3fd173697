//! `indentify init`: prints an annotated template configuration, one per law, set to the
//! reference problems R0-R2, or a template for a measured record (`--data FILE`).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use indentify_study::config::Reference;
use indentify_study::templates::{
    DataTemplate, data_law, data_path_for, data_template_law, data_template_with_guess,
    law_template, parse_tip, template, tip_from_metadata,
};

/// Arguments of `indentify init`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The law of the template: its values are those of reference problem R0, R1 or R2.
    #[arg(value_enum)]
    pub law: LawKind,

    /// A template for a measured record instead: the file is read (its tests listed, its
    /// tip taken from its metadata when it states one); its depth drives the simulation
    /// (no `history`), the automatic specimen, 60 resampled points, every parameter but nu
    /// free within ranges that work on real records. With --out the path is written
    /// relative to the configuration's folder (where it is looked up); without, as given
    /// (save the configuration in the current folder, or give --out).
    #[arg(long, value_name = "FILE")]
    pub data: Option<String>,

    /// The test of a multi-test file (from 1; default 1).
    #[arg(long, value_name = "K", requires = "data")]
    pub test: Option<usize>,

    /// The tip: berkovich, vickers, cube-corner, sphere:R (mm) or cone:DEG (default: the
    /// file's, else Berkovich).
    #[arg(long, value_name = "TIP", requires = "data")]
    pub tip: Option<String>,

    /// Keep the template's start values instead of those of the record's Oliver-Pharr
    /// analysis (E from E_IT, sY from H/3 (Plastic: at Tabor's representative strain 0.08
    /// through the law's hardening), viscous parameters and Prony's g1, tau1 from the
    /// hold's creep; docs/analysis.md).
    #[arg(long, requires = "data")]
    pub no_guess: bool,

    /// Write the configuration to this file (atomically) instead of standard output.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

/// The laws `init` has a template for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum LawKind {
    /// Linear isotropic elasticity (R0, Sneddon's cone).
    Elastic,
    /// Maxwell viscoelasticity (R1).
    Maxwell,
    /// Norton-Hoff viscoplasticity with a yield stress (R2).
    NortonHoff,
    /// J2 plasticity, linear hardening (R1's cone and history).
    PlasticLinear,
    /// J2 plasticity, power-law hardening (Dao's form).
    PlasticPower,
    /// J2 plasticity, Voce saturation hardening.
    PlasticVoce,
    /// J2 plasticity, Swift hardening.
    PlasticSwift,
    /// J2 plasticity, a tabulated hardening curve.
    PlasticTable,
    /// J2 plasticity, power-law hardening and a Norton overstress rate.
    PlasticNorton,
    /// A Prony series (generalized Maxwell in shear).
    Prony,
}

impl LawKind {
    /// The reference problem of this law.
    pub fn reference(self) -> Reference {
        match self {
            LawKind::Elastic => Reference::R0Elastic,
            LawKind::Maxwell => Reference::R1Maxwell,
            _ => Reference::R2NortonHoff,
        }
    }

    /// The registry template's kind (`plastic-power`), for a law beyond R0-R2.
    pub fn registry_kind(self) -> Option<String> {
        match self {
            LawKind::Elastic | LawKind::Maxwell | LawKind::NortonHoff => None,
            k => k.to_possible_value().map(|v| v.get_name().to_string()),
        }
    }
}

/// Prints the template to stdout, or writes it to `--out`.
///
/// # Errors
/// An unreadable record, an unwritable `--out`, a closed standard output.
pub fn run(args: &Args) -> Result<()> {
    let reference = args.law.reference();
    let text = match &args.data {
        Some(file) => {
            let mut d = inspect(file, args)?;
            let kind = args.law.registry_kind();
            let law = match &kind {
                Some(k) => data_law(k)?,
                None => reference.config().law,
            };
            let guess = if args.no_guess {
                None
            } else {
                first_guess(file, &d, &law)
            };
            if let Some(out) = &args.out {
                d.file = data_path_for(Path::new(file), out).with_context(|| {
                    format!(
                        "cannot name `{file}` from the folder of `{}` (does the folder exist?)",
                        out.display()
                    )
                })?;
            }
            match &kind {
                Some(k) => data_template_law(k, law, &d, guess.as_ref()),
                None => data_template_with_guess(reference, &d, guess.as_ref()),
            }
        }
        None => match args.law.registry_kind() {
            Some(kind) => law_template(&kind)?,
            None => template(reference),
        },
    };
    match &args.out {
        Some(out) => {
            indentify_study::atomic::write(out, text)?;
            tracing::info!("wrote {}", out.display());
            Ok(())
        }
        None => std::io::stdout()
            .lock()
            .write_all(text.as_bytes())
            .context("cannot write the template to standard output"),
    }
}

/// The law's start values from the record's Oliver-Pharr analysis; `None` (with a
/// warning: the template's values stay) when the tip has no analysis area function or the
/// test cannot be analysed.
fn first_guess(
    file: &str,
    d: &DataTemplate,
    law: &indentify_study::config::LawSpec,
) -> Option<indentify_study::first_guess::FirstGuess> {
    use indentify_study::first_guess as fg;
    let Some(tip) = fg::tip_for_punch(&d.punch) else {
        tracing::warn!(
            "no first guess: the punch {} has no analysis area function (the template's start \
             values stay)",
            d.punch.describe()
        );
        return None;
    };
    // the nu the data template fixes
    let nu = 0.3;
    match fg::analyse_file(Path::new(file), d.test, &tip, nu) {
        Ok(op) => {
            let g = fg::guess(law, &op);
            tracing::info!("{}", fg::describe(&op));
            Some(g)
        }
        Err(e) => {
            tracing::warn!(
                "no first guess from the Oliver-Pharr analysis ({e}): the template's start \
                 values stay"
            );
            None
        }
    }
}

/// Reads the record `file` for its tests and tip.
fn inspect(file: &str, args: &Args) -> Result<DataTemplate> {
    let bytes =
        std::fs::read(file).with_context(|| format!("cannot read the data file `{file}`"))?;
    let records = indentify_study::records::read(&bytes, file, &Default::default())
        .with_context(|| format!("cannot read `{file}` as an instrument record"))?;
    let tests: Vec<String> = records
        .iter()
        .enumerate()
        .map(|(k, r)| {
            r.meta
                .test_name
                .clone()
                .unwrap_or_else(|| format!("{}", k + 1))
        })
        .collect();
    let test = match (args.test, records.len()) {
        (Some(t), n) if t == 0 || t > n => bail!(
            "--test {t} is not a test of `{file}`: it holds {n} test{} ({})",
            if n == 1 { "" } else { "s" },
            tests.join(", ")
        ),
        (Some(t), n) if n > 1 => Some(t),
        (None, n) if n > 1 => Some(1),
        _ => None,
    };
    let record = &records[test.map_or(0, |t| t - 1)];
    let (punch, punch_source) = match (&args.tip, tip_from_metadata(&record.meta)) {
        (Some(t), _) => (
            parse_tip(t)?,
            format!("{} (--tip {t})", parse_tip(t)?.describe()),
        ),
        (None, Some(p)) => {
            let d = p.describe();
            (p, format!("{d}, as the file states"))
        }
        (None, None) => (
            indentify_study::Punch::Berkovich { tip_radius: None },
            "Berkovich, assumed: the file does not state its tip (give --tip, or edit `punch`)"
                .to_string(),
        ),
    };
    Ok(DataTemplate {
        file: file.to_string(),
        test,
        tests: if records.len() > 1 { tests } else { Vec::new() },
        punch,
        punch_source,
    })
}
