//! `indentify init`: prints an annotated template configuration, one per law, set to the
//! reference problems R0-R2, or a template for a measured record (`--data FILE`).

use std::io::Write as _;

use anyhow::{Context, Result};
use clap::ValueEnum;
use indentify_study::config::Reference;
use indentify_study::templates::{data_template, template};

/// Arguments of `indentify init`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The law of the template: its values are those of reference problem R0, R1 or R2.
    #[arg(value_enum)]
    pub law: LawKind,

    /// A template for a measured record instead: its depth drives the simulation (no
    /// `history`), a Berkovich tip, the automatic specimen, 60 resampled points, every
    /// parameter but nu free within the law's ranges. The path is written as given: make it
    /// relative to the folder where the configuration will live, or absolute.
    #[arg(long, value_name = "FILE")]
    pub data: Option<String>,
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
}

impl LawKind {
    /// The reference problem of this law.
    pub fn reference(self) -> Reference {
        match self {
            LawKind::Elastic => Reference::R0Elastic,
            LawKind::Maxwell => Reference::R1Maxwell,
            LawKind::NortonHoff => Reference::R2NortonHoff,
        }
    }
}

/// Prints the template to stdout.
///
/// # Errors
/// A closed standard output.
pub fn run(args: &Args) -> Result<()> {
    let reference = args.law.reference();
    let text = match &args.data {
        Some(file) => data_template(reference, file),
        None => template(reference),
    };
    std::io::stdout()
        .lock()
        .write_all(text.as_bytes())
        .context("cannot write the template to standard output")
}
