//! Seeded closed-form starts of a batch's closed-form indents
//! ([`crate::batch::BatchOptions::seeded`], off by default): the indents of one configuration (the same
//! configuration file, manifest columns and test) share one fit instead of each running
//! its own calibration forward run. The **seed** of a configuration is its first indent in
//! manifest order (whatever the shard, thread count or the order the workers take the
//! indents in); it is fitted first, from its own closed-form start
//! ([`crate::closed_form_start`], with its calibration run). Every other indent of the
//! configuration then starts from the half-space closed form of its own curve (arithmetic,
//! no forward run) times the seed's ratio of fitted to half-space value, parameter by
//! parameter (the finite element model's correction of the closed form, which barely
//! depends on the parameters), and the free parameters no closed form covers start at the
//! seed's fitted values; every start is clamped to its bounds. An indent's start thus
//! depends on its own curve and its configuration's seed only, so its result does not
//! depend on the thread count, the order or the shard. Where the seed did not converge, or
//! an indent has no half-space fit, the indent calibrates its own closed form as before and
//! its status says why. Measured in docs/performance.md ("The 100-indent batch").

use indentify_analysis::closed_form::{Curve, fit_maxwell, fit_modulus};

use crate::batch::{IndentStatus, State};
use crate::format::sig;
use crate::identify::{self, IdentifyOptions, Setup};
use crate::source::ConfigSource;

/// What makes two indents the same configuration: its file, the manifest's configuration
/// columns and the test (the `sets` of [`crate::batch`], test included).
pub(crate) fn key(config: &ConfigSource, sets: &[String]) -> String {
    format!("{config:?}\u{1f}{}", sets.join("\u{1f}"))
}

/// A seed's fit as the other indents of its configuration start from it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Seed {
    /// The seed indent's id.
    pub id: String,
    /// `(name, fitted / half-space)` of every parameter its closed form covers.
    pub ratio: Vec<(String, f64)>,
    /// `(name, fitted value)` of every free parameter.
    pub fitted: Vec<(String, f64)>,
}

/// The half-space closed form of `s`'s one test (no model correction, no forward run):
/// `E` from the loading (Sneddon's cone, Hertz's sphere, the flat punch), and `eta` with
/// it for the Maxwell law (Lee and Radok's form over the loading and hold) where the curve
/// tells a relaxation time. `Err` says why there is none.
pub(crate) fn half_space(s: &Setup) -> Result<Vec<(String, f64)>, String> {
    let at = |n: &str| s.names.iter().position(|m| *m == n);
    let (Some(_), Some(inu)) = (at("E"), at("nu")) else {
        return Err(format!(
            "the law {} has no Young's modulus `E` and Poisson's ratio `nu`",
            s.cfg.law.variant()
        ));
    };
    if s.problem.tests.len() != 1 || s.problem.tests[0].load.is_some() {
        return Err("not one depth-controlled test".into());
    }
    let punch = crate::closed_form_start::closed_punch(&s.cfg.punch)?;
    let nu = s.id_cfg.params[inu].value.unwrap_or(0.3);
    let sch = s.problem.schedule();
    let curve = Curve {
        t: &sch.t,
        h: &sch.depth,
        f: &s.problem.target,
    };
    if s.cfg.law.variant() == "Maxwell" && at("eta").is_some() {
        if let Ok(m) = fit_maxwell(&curve, &[], punch, nu) {
            return Ok(vec![
                ("E".to_string(), m.e),
                ("eta".to_string(), m.tau * m.e / (1.0 + nu)),
            ]);
        }
    }
    fit_modulus(&curve, &[], punch, nu)
        .map(|m| vec![("E".to_string(), m.e)])
        .map_err(|e| format!("{}: {e}", punch.solution()))
}

/// The set-up of an indent's identification (its record read, its model built), for its
/// half-space closed form.
fn setup_of(opts: &IdentifyOptions) -> Result<Setup, String> {
    let quiet = IdentifyOptions {
        out: None,
        ..opts.clone()
    };
    identify::resolve(&quiet)
        .and_then(|r| identify::setup(r, &quiet))
        .map_err(|e| e.messages().join(": "))
}

/// The seed of the configuration of `opts` from its finished status: its fitted values
/// over its own half-space closed form. `Err` says why it cannot seed.
pub(crate) fn seed_of(opts: &IdentifyOptions, status: &IndentStatus) -> Result<Seed, String> {
    if status.state != State::Converged {
        return Err(format!(
            "the seed {} did not converge ({})",
            status.id, status.message
        ));
    }
    let s = setup_of(opts)?;
    let half = half_space(&s).map_err(|e| format!("the seed {}: {e}", status.id))?;
    let value = |n: &str| {
        status
            .names
            .iter()
            .position(|m| m == n)
            .and_then(|k| status.values.get(k).copied())
    };
    let mut ratio = Vec::new();
    for (n, h) in half {
        let free = status
            .names
            .iter()
            .position(|m| *m == n)
            .and_then(|k| status.free.get(k).copied())
            .unwrap_or(false);
        match value(&n) {
            Some(v) if free && v.is_finite() && h > 0.0 => ratio.push((n, v / h)),
            _ => {}
        }
    }
    let fitted = status
        .names
        .iter()
        .zip(&status.values)
        .zip(&status.free)
        .filter(|(_, f)| **f)
        .map(|((n, v), _)| (n.clone(), *v))
        .collect();
    Ok(Seed {
        id: status.id.clone(),
        ratio,
        fitted,
    })
}

/// The starts of indent `opts` from `seed` (clamped to the bounds) and the status line
/// saying so; `Err` says why there are none (the indent then calibrates its own start).
pub(crate) fn seeded_starts(
    opts: &IdentifyOptions,
    seed: &Seed,
) -> Result<(Vec<(String, f64)>, String), String> {
    let mut s = setup_of(opts)?;
    let half = half_space(&s)?;
    let mut values: Vec<(String, f64)> = Vec::new();
    let mut how = Vec::new();
    for (n, h) in &half {
        if let Some((_, r)) = seed.ratio.iter().find(|(m, _)| m == n) {
            values.push((n.clone(), h * r));
            how.push(format!("{n} {} x {}", sig(*h, 5), sig(*r, 5)));
        }
    }
    let mut from_seed = Vec::new();
    for (n, v) in &seed.fitted {
        if !values.iter().any(|(m, _)| m == n) {
            values.push((n.clone(), *v));
            from_seed.push(n.clone());
        }
    }
    let mut notes = Vec::new();
    let set = crate::closed_form_start::set_starts(&mut s, values, &mut notes);
    let shown: Vec<String> = set
        .iter()
        .map(|(n, v)| format!("{n} = {}", sig(*v, 5)))
        .collect();
    let mut line = format!(
        "start: seeded by {} (half-space closed form x the seed's fitted / half-space: {}",
        seed.id,
        how.join(", ")
    );
    if !from_seed.is_empty() {
        line.push_str(&format!("; the seed's fitted {}", from_seed.join(", ")));
    }
    line.push_str(&format!("): {}", shown.join(", ")));
    for n in notes {
        line.push_str("; ");
        line.push_str(&n);
    }
    Ok((set, line))
}

/// The seeds among `keys` (one configuration key per indent, in manifest order): the
/// position of each key's first indent.
pub(crate) fn firsts(keys: &[String]) -> Vec<usize> {
    let mut first: Vec<usize> = Vec::new();
    for k in 0..keys.len() {
        if !first.iter().any(|&f| keys[f] == keys[k]) {
            first.push(k);
        }
    }
    first
}
