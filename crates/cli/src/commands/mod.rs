//! The subcommands of `indentify`, one module each.

pub mod analyze;
pub mod batch;
pub mod check;
pub mod design;
pub mod gradient;
pub mod gradient_check;
pub mod identify;
pub mod init;
pub mod laws;
pub mod map;
pub mod serve;
pub mod simulate;

/// A count option (`--max-iter`, `--seed`): an integer >= 0. clap reads `-1` as a value
/// (`allow_negative_numbers`) so that the message names the option and its range instead
/// of "unexpected argument '-1'".
pub fn parse_count(text: &str) -> Result<u64, String> {
    text.trim()
        .parse::<u64>()
        .map_err(|_| format!("expected an integer >= 0, got `{text}`"))
}

/// [`parse_count`] as `usize`.
pub fn parse_usize(text: &str) -> Result<usize, String> {
    parse_count(text).and_then(|n| usize::try_from(n).map_err(|e| e.to_string()))
}
