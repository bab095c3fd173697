//! `indentify laws`: lists every registered law with its parameters (the names `--set
//! law.NAME` and `identify.params` take), units, admissible ranges and kinds, generated
//! from the laws registry (`study::laws_list`).

use std::io::Write as _;

use anyhow::{Context, Result};

/// Arguments of `indentify laws`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Print the listing as JSON (the same data as Python's `indentify.laws()`).
    #[arg(long)]
    pub json: bool,
}

/// Prints the listing to standard output.
///
/// # Errors
/// A law the registry cannot list, a closed standard output.
pub fn run(args: &Args) -> Result<()> {
    let laws = indentify_study::laws_list::laws()?;
    let text = if args.json {
        serde_json::to_string_pretty(&laws)? + "\n"
    } else {
        indentify_study::laws_list::text(&laws)
    };
    std::io::stdout()
        .lock()
        .write_all(text.as_bytes())
        .context("cannot write the listing to standard output")
}
