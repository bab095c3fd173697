//! Standard output of the commands: text reports and JSON objects.

use std::io::Write as _;

use anyhow::{Context, Result};
use serde::Serialize;

/// Writes `value` as one pretty-printed JSON object to standard output.
///
/// # Errors
/// A closed standard output.
pub fn print_json<T: Serialize>(value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).context("cannot represent the report")?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "{text}").context("cannot write to standard output")
}

/// Writes `text` to standard output.
///
/// # Errors
/// A closed standard output.
pub fn print_text(text: &str) -> Result<()> {
    std::io::stdout()
        .lock()
        .write_all(text.as_bytes())
        .context("cannot write to standard output")
}
