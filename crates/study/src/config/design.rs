//! The `design` section of a configuration: the candidate protocols that `indentify
//! design` ranks ([`crate::design`]); ignored by the other commands. A candidate's tests
//! may be depth-controlled (the force observed, `noise`) or load-controlled (a history
//! with `force` segments: the depth observed, `depth_noise`).

use serde::{Deserialize, Serialize};

use super::{NoiseSetting, TestSpec};

/// The `design: (...)` section of a configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "design")]
pub struct DesignSection {
    /// The noise the standard deviations assume: `Relative(f)` (standard deviation `f`
    /// times the observable) or `Absolute(s)` (N): on the force of depth-controlled tests,
    /// and on the depth of load-controlled tests when `depth_noise` is not given (a
    /// `Relative` level only: a force in N is no depth).
    pub noise: NoiseSetting,
    /// The noise of the depth, the observable of load-controlled tests (a history with
    /// `force` segments): `Relative(f)` (standard deviation `f h`) or `Absolute(s)` (mm).
    /// Default: `noise` when it is `Relative`; required with an `Absolute` `noise` when a
    /// candidate has a load-controlled test.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_noise: Option<NoiseSetting>,
    /// The candidate protocols (at least one).
    pub candidates: Vec<Candidate>,
}

/// One candidate protocol: a test, or tests fitted jointly.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "candidate")]
pub struct Candidate {
    /// Its label in the table.
    pub name: String,
    /// Its tests, as in a joint fit's `tests` list.
    pub tests: Vec<TestSpec>,
}

impl DesignSection {
    /// Checks the section: a stated noise level > 0, at least one candidate, each named
    /// once and with at least one test.
    ///
    /// # Errors
    /// The first problem, naming the field.
    pub fn validate(&self) -> anyhow::Result<()> {
        match self.noise {
            NoiseSetting::Relative(_) | NoiseSetting::Absolute(_) => {
                self.noise.check("design.noise")?
            }
            other => anyhow::bail!(
                "design.noise = {other:?} is not allowed: a design needs a stated noise level, \
                 Relative(f) (standard deviation f x |F|, e.g. Relative(0.01) for 1%) or \
                 Absolute(s) (standard deviation s in N)"
            ),
        }
        match self.depth_noise {
            None => {}
            Some(n @ (NoiseSetting::Relative(v) | NoiseSetting::Absolute(v)))
                if !(v.is_finite() && v > 0.0) =>
            {
                anyhow::bail!(
                    "design.depth_noise = {n:?} is not allowed: the noise level must be a finite \
                     number > 0 (Relative(f): standard deviation f x h, e.g. Relative(0.01) for \
                     1%; Absolute(s): standard deviation s in mm)"
                );
            }
            Some(NoiseSetting::Relative(_) | NoiseSetting::Absolute(_)) => {}
            Some(other) => anyhow::bail!(
                "design.depth_noise = {other:?} is not allowed: a design needs a stated noise \
                 level of the depth, Relative(f) (standard deviation f x h) or Absolute(s) \
                 (standard deviation s in mm)"
            ),
        }
        if self.candidates.is_empty() {
            anyhow::bail!(
                "design.candidates is empty: expected at least one candidate, e.g. \
                 candidates: [(name: \"load 1 s\", tests: [(history: (segments: [...]))])]"
            );
        }
        for (k, c) in self.candidates.iter().enumerate() {
            if c.name.trim().is_empty() {
                anyhow::bail!("design.candidates[{k}].name is empty: expected a label");
            }
            if let Some(j) = self.candidates[..k].iter().position(|o| o.name == c.name) {
                anyhow::bail!(
                    "design.candidates[{k}].name `{}` is also the name of candidates[{j}]: \
                     expected distinct names",
                    c.name
                );
            }
            if c.tests.is_empty() {
                anyhow::bail!(
                    "design.candidates[{k}].tests (`{}`) is empty: expected at least one test",
                    c.name
                );
            }
        }
        Ok(())
    }
}
