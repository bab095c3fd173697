//! A fit that starts from the Oliver-Pharr analysis of its own record: the configuration's
//! record (`data.file`, `data.test`, or a record given instead), analysed with the
//! configuration's punch as the tip and the law's `nu` (`crate::op_beside::tip_of`,
//! `crate::first_guess`), gives the start values of the free parameters it says something
//! about (`E`, `sY`, `K`, `eta`, ...; `first_guess::guess`). The Python package's
//! `identify(start="oliver-pharr")` and `first_guess(...)` call it (docs/analysis.md, "First
//! guesses").

use std::path::Path;

use crate::config::{IdentifySection, Overrides, ParamSetting};
use crate::error::{Error, ErrorKind, Result};
use crate::first_guess::{FirstGuess, analyse_file, guess};
use crate::source::ConfigSource;

/// The guess and the start values of the configuration's free parameters it sets.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Starts {
    /// `(parameter, start)` for the free parameters the analysis gives.
    pub starts: Vec<(String, f64)>,
    /// The whole guess (O&P values, every guessed value, how each was obtained).
    pub guess: FirstGuess,
}

/// The start values of `source` (with `sets` applied) from the O&P analysis of its record,
/// or of `data` (a record file) when given.
///
/// # Errors
/// A configuration that does not load, has no record (synthesized data has no test to
/// analyse) or a punch without an area function; a record that cannot be analysed (no
/// unloading: the reason names the test).
pub fn starts(source: &ConfigSource, sets: &[String], data: Option<&Path>) -> Result<Starts> {
    let cfg = source.load(sets)?;
    let (path, test) = match (data, &cfg.data) {
        (Some(p), d) => (p.to_path_buf(), d.as_ref().and_then(|d| d.test)),
        (None, Some(d)) => (d.path(cfg.base_dir.as_deref()), d.test),
        (None, None) => {
            return Err(Error::msg(
                ErrorKind::Config,
                "start from the Oliver-Pharr analysis: the configuration has no `data` record \
                 to analyse (give one, or state the start values)",
            ));
        }
    };
    let tip = crate::op_beside::tip_of(&cfg.punch, cfg.base_dir.as_deref()).map_err(|e| {
        Error::msg(
            ErrorKind::Config,
            format!("start from the Oliver-Pharr analysis: {e}"),
        )
    })?;
    let named = cfg.law.named_params();
    let nu = named
        .iter()
        .find(|(n, _)| *n == "nu")
        .map_or(0.3, |(_, v)| *v);
    let op = analyse_file(&path, test, &tip, nu)?;
    let g = guess(&cfg.law, &op);
    let built = cfg
        .law
        .material()
        .map_err(|e| Error::msg(ErrorKind::Config, format!("{e:#}")))?;
    let settings = IdentifySection::settings(
        cfg.identify.as_ref(),
        &*built.material,
        &Overrides::default(),
    )
    .map_err(|e| Error::msg(ErrorKind::Config, format!("{e:#}")))?;
    let starts = g
        .values
        .iter()
        .filter(|(n, v)| {
            v.is_finite()
                && settings
                    .iter()
                    .any(|(s, p)| s == n && matches!(p, ParamSetting::Free { .. }))
        })
        .cloned()
        .collect();
    Ok(Starts { starts, guess: g })
}
