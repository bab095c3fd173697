//! The instrument's parameters in a configuration (docs/theory.md §13.6, docs/cli.md
//! "Instrument parameters"): the frame compliance `Cf` (mm/N), the drift rate `vd`
//! (mm/s) and a depth offset per test `h0` (mm; `h0[1]`, `h0[2]`, ... in a joint
//! configuration) exist when `identify.params`, `--free`, `--fixed` or `--start` name them;
//! the law is then an [`indentify_identify::Instrumented`] one (its parameters followed by
//! theirs, each 0 unless set) and the problem adds them to each load-controlled test's
//! depths; a depth-controlled test runs through the frame (its recorded depth is the
//! machine's: the punch is driven through the frame's spring, docs/theory.md §13.7).

use std::sync::Arc;

use anyhow::anyhow;
use indentify_identify::{Problem, Test};
use indentify_laws::Material;

use crate::config::{Config, IdentifySection, Overrides};
use crate::error::{Error, ErrorKind, Result};

/// `law` and its values with the instrument's parameters that `cfg`'s `identify` section
/// and `overrides` name appended (0 each), for `cfg`'s tests; unchanged without.
pub(crate) fn with_instrument(
    cfg: &Config,
    law: Arc<dyn Material>,
    values: Vec<f64>,
    overrides: &Overrides,
) -> (Arc<dyn Material>, Vec<f64>) {
    let (instrument, _) = crate::config::instrument_of(cfg.identify.as_ref(), overrides);
    if instrument.is_empty() {
        return (law, values);
    }
    crate::config::instrumented(law, &values, instrument, cfg.n_tests())
}

/// The problem of `tests` with `cfg`'s law (`law`: as [`with_instrument`] made it) and
/// instrument.
///
/// # Errors
/// [`ErrorKind::Config`]: the problem's own errors.
pub(crate) fn problem(
    cfg: &Config,
    _name: &str,
    law: &Arc<dyn Material>,
    tests: Vec<Test>,
    overrides: &Overrides,
) -> Result<Problem> {
    let section: Option<&IdentifySection> = cfg.identify.as_ref();
    let (instrument, _) = crate::config::instrument_of(section, overrides);
    if instrument.is_empty() {
        return Problem::joint(law.clone(), tests)
            .map_err(|e| Error::new(ErrorKind::Config, anyhow!(e)));
    }
    // the solver runs the law itself: rebuild it (the configuration's, without the
    // instrument)
    let (inner, _) = cfg
        .law
        .build()
        .map_err(|e| Error::new(ErrorKind::Config, e))?;
    Problem::joint_instrumented(inner, instrument, tests)
        .map_err(|e| Error::new(ErrorKind::Config, anyhow!(e)))
}
