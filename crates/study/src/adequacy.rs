//! What a fit's headline must say besides "converged": whether the law can describe the
//! record (the residual tests of [`indentify_report::adequacy`], per test for a joint fit)
//! and the caveats that make the printed standard deviations too tight to trust
//! (systematic residuals, a discretization shift beyond the deviation, undetermined
//! parameters, values at a bound). The console, result.json, report.md, the figures and a
//! batch's status all take them from here, so they say the same thing. The statistics and
//! thresholds are in `docs/adequacy.md`.
//!
//! The exit status of `indentify identify` still reports the optimizer (0 converged,
//! 1 not converged, 3 undetermined, 130 interrupted): a converged fit with systematic
//! residuals or a discretization error beyond its deviations exits 0, and says so on the
//! headline line, in result.json (`adequacy.verdict`, `caveats`) and in the reports.

use indentify_identify::NoiseModel;
use indentify_report::{Adequacy, Verdict};
use serde::Serialize;

use crate::identify::{FitCurves, IdentifyOutcome};

/// The adequacy of a fit: each test's assessment and the worst verdict.
#[derive(Clone, Debug, Serialize)]
pub struct FitAdequacy {
    /// The worst of the tests' verdicts.
    pub verdict: Verdict,
    /// Each test's assessment (one for a one-test fit).
    pub tests: Vec<TestAdequacy>,
}

/// One test's assessment.
#[derive(Clone, Debug, Serialize)]
pub struct TestAdequacy {
    /// The test's label (the configuration's name for a one-test fit).
    pub test: String,
    /// Its statistics and verdict.
    #[serde(flatten)]
    pub adequacy: Adequacy,
}

impl FitAdequacy {
    /// The verdict in words for one line: `systematic residuals (test 2: RMS 5.2 σ_rec,
    /// runs z = -6.1)`.
    pub fn short(&self) -> String {
        let worst: Vec<String> = self
            .tests
            .iter()
            .filter(|t| t.adequacy.verdict == self.verdict)
            .map(|t| {
                let s = t.adequacy.short();
                let s = s.trim_start_matches("adequacy: ");
                if self.tests.len() > 1 {
                    format!("{}: {s}", t.test)
                } else {
                    s.to_string()
                }
            })
            .collect();
        if self.tests.len() > 1 {
            format!("{}: {}", self.verdict.as_str(), worst.join("; "))
        } else {
            worst.join("; ")
        }
    }
}

/// A multiple of σ: `2.4`, `9.4e8` (a noise-free fit's deviations are tiny).
fn sigmas(x: f64) -> String {
    if x >= 1e3 {
        format!("{x:.1e}")
    } else {
        format!("{x:.1}")
    }
}

/// Whether the fit states multiplicative noise (`Relative`, `RelativeEstimated`): its
/// residuals are then tested standardized by the fitted value.
pub fn states_relative_noise(result: &indentify_identify::IdentifyResult) -> bool {
    result.identifiability.as_ref().is_some_and(|i| {
        matches!(
            i.noise,
            NoiseModel::Relative(_) | NoiseModel::RelativeEstimated
        )
    })
}

/// The adequacy of `curves` fitted with `free` parameters; `relative` when the fit states
/// multiplicative noise (`noise: Relative` / `RelativeEstimated`, the model of `--noise`):
/// the residuals are then standardized by it before the tests (docs/adequacy.md).
pub fn assess(curves: &FitCurves, free: usize, relative: bool) -> Option<Adequacy> {
    assess_series(
        &curves.t,
        &curves.f_data,
        &curves.f_final,
        curves.observable,
        free,
        relative,
    )
}

/// [`assess`] of the series `data` and `model` at times `t`, observing `observable`
/// (depths are assessed alike; only the messages' units change).
pub fn assess_series(
    t: &[f64],
    data: &[f64],
    model: &[f64],
    observable: indentify_report::Observable,
    free: usize,
    relative: bool,
) -> Option<Adequacy> {
    let a = if relative {
        Adequacy::assess_relative(t, data, model, free)
    } else {
        Adequacy::assess(t, data, model, free)
    };
    match observable {
        indentify_report::Observable::Depth => a.map(Adequacy::of_depth),
        indentify_report::Observable::Force => a,
    }
}

impl IdentifyOutcome {
    /// The residual tests of the fit: each test of a joint fit on its own curve (its
    /// residuals against its own record's noise), a one-test fit on its curve. `None`
    /// when no curve could be assessed.
    pub fn adequacy(&self) -> Option<FitAdequacy> {
        let free = self.result.params.iter().filter(|p| p.free).count();
        let relative = states_relative_noise(&self.result);
        let tests: Vec<TestAdequacy> = if self.tests.is_empty() {
            assess(&self.fit, free, relative)
                .map(|adequacy| TestAdequacy {
                    test: self.config.clone(),
                    adequacy,
                })
                .into_iter()
                .collect()
        } else {
            self.tests
                .iter()
                .filter_map(|t| {
                    assess(&t.fit, free, relative).map(|adequacy| TestAdequacy {
                        test: t.name.clone(),
                        adequacy,
                    })
                })
                .collect()
        };
        let verdict = indentify_report::adequacy::worst_verdict(tests.iter().map(|t| &t.adequacy))?;
        Some(FitAdequacy { verdict, tests })
    }

    /// What makes the printed result less than it looks, one short clause each (empty for
    /// a fit with nothing to add): systematic residuals, parameters the discretization
    /// moves by more than their deviation, undetermined parameters, values at a bound.
    pub fn caveats(&self) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(a) = self.adequacy()
            && a.verdict == Verdict::Systematic
        {
            out.push(format!(
                "{}: the standard deviations assume a law that fits",
                a.short()
            ));
        }
        if let Some(d) = &self.discretization {
            let moved: Vec<String> = self
                .result
                .params
                .iter()
                .enumerate()
                .filter_map(|(k, p)| {
                    let (s, sd) = (d.shift[k]?, self.std_dev(p.name)?);
                    (s.abs() > sd).then(|| {
                        format!(
                            "{} {:+.1}% ({} σ)",
                            p.name,
                            100.0 * s / p.value.abs().max(f64::MIN_POSITIVE),
                            sigmas(s.abs() / sd)
                        )
                    })
                })
                .collect();
            if !moved.is_empty() {
                out.push(format!(
                    "discretization error beyond the standard deviation: a refined mesh would \
                     move {}",
                    moved.join(", ")
                ));
            }
        }
        if let Some(i) = &self.result.identifiability
            && !i.undetermined.is_empty()
        {
            out.push(undetermined_caveat(
                &i.undetermined,
                self.result
                    .params
                    .iter()
                    .filter(|p| p.free && !i.undetermined.contains(&p.name))
                    .count(),
            ));
        }
        let bound: Vec<String> = self
            .result
            .params
            .iter()
            .filter(|p| p.free && (p.at_lower || p.at_upper))
            .map(|p| {
                format!(
                    "{} at its {} bound",
                    p.name,
                    if p.at_lower { "lower" } else { "upper" }
                )
            })
            .collect();
        if !bound.is_empty() {
            out.push(bound.join(", "));
        }
        out
    }

    /// The headline's status: `converged`, `converged, with caveats (below)` or
    /// `NOT converged`.
    pub fn headline_status(&self) -> &'static str {
        if !self.converged() {
            "NOT converged"
        } else if self.caveats().is_empty() {
            "converged"
        } else {
            "converged, with caveats (below)"
        }
    }

    /// The console's lines under the fit quality: `  adequacy: ...` (each test's for a
    /// joint fit, with the verdict's message when it is not adequate), then one
    /// `  CAVEAT: ...` line per caveat.
    pub fn adequacy_lines(&self) -> String {
        let mut text = String::new();
        if let Some(a) = self.adequacy() {
            for t in &a.tests {
                let label = if a.tests.len() > 1 {
                    format!("{}: ", t.test)
                } else {
                    String::new()
                };
                text.push_str(&format!("  adequacy: {label}{}\n", t.adequacy.message));
            }
        }
        for c in self.caveats() {
            text.push_str(&format!("  CAVEAT: {c}\n"));
        }
        text
    }
}

/// The caveat of undetermined parameters: which, and that the `determined` others'
/// standard deviations are conditional on them (computed with them held at their values,
/// so they leave out the undetermined direction and can be far too small).
pub fn undetermined_caveat(undetermined: &[&str], determined: usize) -> String {
    let names = undetermined.join(", ");
    if determined == 0 {
        return format!("undetermined: {names}");
    }
    let (them, value) = if undetermined.len() == 1 {
        ("it", "its value")
    } else {
        ("them", "their values")
    };
    format!(
        "undetermined: {names}; the other standard deviations are conditional on {them} held \
         at {value} (they leave out the undetermined direction and can be far too small)"
    )
}
