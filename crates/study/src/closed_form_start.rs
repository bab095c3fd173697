//! A fit that starts from a closed-form pre-fit of its own curve (`identify --start
//! closed-form`, `batch --start closed-form`, Python's `identify(start="closed-form")`;
//! docs/analysis.md, "Closed-form starts"): the half-space solution of the punch
//! (`indentify_analysis::closed_form`: Sneddon's cone, Hertz's sphere, the flat punch;
//! Lee and Radok's Maxwell form over the loading and hold) fitted to the test's loading,
//! then one forward run of the finite element model at that fit's parameters, whose ratio to
//! the half-space force per sample corrects the closed form to the model (mesh, finite
//! specimen, contact kind, strain measure), and the fit repeated with it. The values replace
//! the configuration's starts of the free parameters they cover, clamped to their bounds
//! with a note; where no closed form applies the fit starts from the configuration and the
//! note says why. The start depends on the indent's own curve and configuration only, so a
//! batch's results do not depend on its thread count or order.
//!
//! A law with a yield stress (`Plastic`, `NortonHoff`) takes its own route first
//! (`crate::closed_form_yield`: Dao et al.'s reverse analysis under a 70.3-degree cone,
//! the unloading stiffness and Tabor's hardness under a sphere or another cone: `E`, `sY`
//! and Dao's `n`); where that route has nothing (a flat punch, a tabulated hardening, a
//! curve with no unloading), `E` comes from the loading's elastic closed form as before and
//! a note says why.

use std::time::Instant;

use indentify_analysis::closed_form::{
    ClosedFormError, Curve, Punch as ClosedPunch, fit_maxwell, fit_modulus, model_ratio,
};
use indentify_contact::Punch;
use indentify_identify::Evaluator;
use serde::Serialize;

use crate::format::sig;
use crate::identify::Setup;

/// What a closed-form start did: the values it set, how, and what it could not.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ClosedFormStart {
    /// The closed form used (`Lee and Radok's Maxwell form of Sneddon's cone`, ...), or
    /// empty when none applies.
    pub method: String,
    /// `(parameter, start)` set (after clamping to the bounds), in the law's order.
    pub values: Vec<(String, f64)>,
    /// The half-space values before the model's correction.
    pub half_space: Vec<(String, f64)>,
    /// The RMS of the corrected closed form's residuals, relative to the largest force.
    pub rms_rel: Option<f64>,
    /// Seconds the pre-fit took (its calibration run included).
    pub seconds: f64,
    /// Notes: why no closed form applies, a parameter clamped, one not covered.
    pub notes: Vec<String>,
}

impl ClosedFormStart {
    /// One line for consoles and reports: the values set, or why none.
    pub fn summary(&self) -> String {
        let mut s = if self.values.is_empty() {
            "start: the configuration's (no closed-form start)".to_string()
        } else {
            let v: Vec<String> = self
                .values
                .iter()
                .map(|(n, v)| format!("{n} = {}", sig(*v, 5)))
                .collect();
            format!("start: closed form ({}): {}", self.method, v.join(", "))
        };
        for n in &self.notes {
            s.push_str("; ");
            s.push_str(n);
        }
        s
    }
}

/// The closed-form punch of a finite element punch: cones and pyramids (as their
/// area-equivalent cones) as Sneddon's cone, spheres as Hertz's, flat punches; `Err` names
/// the punch without one.
pub fn closed_punch(p: &Punch) -> Result<ClosedPunch, String> {
    use indentify_contact::punch::{
        BERKOVICH_HALF_ANGLE_DEG, CUBE_CORNER_HALF_ANGLE_DEG, VICKERS_HALF_ANGLE_DEG,
    };
    Ok(match p {
        Punch::Cone { half_angle_deg } => ClosedPunch::Cone {
            half_angle_deg: *half_angle_deg,
        },
        Punch::Berkovich { .. } => ClosedPunch::Cone {
            half_angle_deg: BERKOVICH_HALF_ANGLE_DEG,
        },
        Punch::Vickers { .. } => ClosedPunch::Cone {
            half_angle_deg: VICKERS_HALF_ANGLE_DEG,
        },
        Punch::CubeCorner { .. } => ClosedPunch::Cone {
            half_angle_deg: CUBE_CORNER_HALF_ANGLE_DEG,
        },
        Punch::Sphere { radius } => ClosedPunch::Sphere { radius: *radius },
        Punch::Flat { radius } => ClosedPunch::Flat { radius: *radius },
        Punch::SpheroCone { .. } => {
            return Err(
                "a sphero-cone has no closed-form force (neither Hertz's nor Sneddon's \
                        over the whole loading)"
                    .into(),
            );
        }
        Punch::Tabulated { .. } | Punch::Calibrated { .. } => {
            return Err("a tabulated or calibrated tip profile has no closed-form force".into());
        }
    })
}

/// The no-start outcome with the reason.
fn none(why: String, clock: Instant) -> ClosedFormStart {
    ClosedFormStart {
        notes: vec![format!(
            "no closed-form start: {why}; the fit starts from the configuration"
        )],
        seconds: clock.elapsed().as_secs_f64(),
        ..ClosedFormStart::default()
    }
}

/// The pre-fit of `s` (its one test's loading and hold), applied to `s.id_cfg`'s starts;
/// never fails: where no closed form applies, or the calibration run fails, the starts are
/// left as they are and the outcome's note says why.
pub fn apply(s: &mut Setup) -> ClosedFormStart {
    let clock = Instant::now();
    let at = |n: &str| s.names.iter().position(|m| *m == n);
    let (Some(ie), Some(inu)) = (at("E"), at("nu")) else {
        return none(
            format!(
                "the law {} has no Young's modulus `E` and Poisson's ratio `nu`",
                s.cfg.law.variant()
            ),
            clock,
        );
    };
    if s.problem.tests.len() != 1 {
        return none(
            format!(
                "a joint fit of {} tests (the closed forms fit one curve)",
                s.problem.tests.len()
            ),
            clock,
        );
    }
    if s.problem.tests[0].load.is_some() {
        return none(
            "a load-controlled test (the closed forms fit a force under a prescribed depth)".into(),
            clock,
        );
    }
    let punch = match closed_punch(&s.cfg.punch) {
        Ok(p) => p,
        Err(why) => return none(why, clock),
    };
    let start: Vec<f64> = s
        .id_cfg
        .params
        .iter()
        .map(|p| p.value.unwrap_or(0.0))
        .collect();
    let nu = start[inu];
    let maxwell = s.cfg.law.variant() == "Maxwell";
    let ieta = at("eta").filter(|_| maxwell);
    let mut notes = Vec::new();
    if at("sY").is_some() {
        match crate::closed_form_yield::values(s, punch, &start, nu) {
            Ok(y) => return yield_start(s, y, clock),
            Err(why) => notes.push(format!(
                "no start for the yield stress: {why}; E from the loading's elastic closed form"
            )),
        }
    }
    let (values, half, rms, method) = {
        let sch = s.problem.schedule();
        let curve = Curve {
            t: &sch.t,
            h: &sch.depth,
            f: &s.problem.target,
        };
        // the half-space fit, then one forward run at it and the corrected fit
        let fitted = |rho: &[f64]| -> Result<(f64, f64, f64), ClosedFormError> {
            if ieta.is_some() {
                fit_maxwell(&curve, rho, punch, nu).map(|m| (m.e, m.tau, m.rms_rel))
            } else {
                fit_modulus(&curve, rho, punch, nu).map(|m| (m.e, f64::INFINITY, m.rms_rel))
            }
        };
        let mut first = fitted(&[]);
        if let (Err(e), Some(_)) = (&first, ieta) {
            // no relaxation time: the modulus from the loading alone, eta kept
            notes.push(format!("eta: {e}; eta keeps the configuration's start"));
            first = fit_modulus(&curve, &[], punch, nu).map(|m| (m.e, f64::INFINITY, m.rms_rel));
        }
        let (e0, tau0, _) = match first {
            Ok(v) => v,
            Err(e) => return none(format!("{}: {e}", punch.solution()), clock),
        };
        let viscous = tau0.is_finite();
        let mut at_fit = start.clone();
        at_fit[ie] = e0;
        if let (Some(i), true) = (ieta, viscous) {
            at_fit[i] = tau0 * e0 / (1.0 + nu);
        }
        let fe = s
            .problem
            .install(|| Evaluator::new(&s.problem).and_then(|mut ev| ev.forces(&at_fit)));
        let fe = match fe {
            Ok(f) => f,
            Err(e) => {
                return none(
                    format!("the calibration run at the half-space values failed: {e}"),
                    clock,
                );
            }
        };
        let rho = model_ratio(&sch.t, &sch.depth, &fe, punch, nu, e0, tau0);
        let refit = if viscous {
            fit_maxwell(&curve, &rho, punch, nu).map(|m| (m.e, m.tau, m.rms_rel))
        } else {
            fit_modulus(&curve, &rho, punch, nu).map(|m| (m.e, f64::INFINITY, m.rms_rel))
        };
        let (e1, tau1, rms) = match refit {
            Ok(v) => v,
            Err(e) => return none(format!("the corrected fit: {e}"), clock),
        };
        let mut half = vec![("E".to_string(), e0)];
        let mut values = vec![("E".to_string(), e1)];
        if viscous {
            half.push(("eta".to_string(), tau0 * e0 / (1.0 + nu)));
            values.push(("eta".to_string(), tau1 * e1 / (1.0 + nu)));
        }
        let method = match (viscous, punch) {
            (true, p) => format!("Lee and Radok's Maxwell form of {}", p.solution()),
            (false, p) => p.solution().to_string(),
        };
        (values, half, rms, method)
    };
    let values = set_starts(s, values, &mut notes);
    if !maxwell {
        let others: Vec<&str> = s
            .id_cfg
            .params
            .iter()
            .filter(|p| p.free && p.name != "E")
            .map(|p| p.name.as_str())
            .collect();
        if !others.is_empty() {
            notes.push(format!(
                "{} keep the configuration's start (no closed form)",
                others.join(", ")
            ));
        }
    }
    ClosedFormStart {
        method,
        values,
        half_space: half,
        rms_rel: Some(rms),
        seconds: clock.elapsed().as_secs_f64(),
        notes,
    }
}

/// The outcome of a law with a yield stress: the values set and the free parameters kept.
fn yield_start(
    s: &mut Setup,
    y: crate::closed_form_yield::YieldValues,
    clock: Instant,
) -> ClosedFormStart {
    let mut notes = y.notes;
    let values = set_starts(s, y.values, &mut notes);
    let others: Vec<&str> = s
        .id_cfg
        .params
        .iter()
        .filter(|p| p.free && !values.iter().any(|(n, _)| *n == p.name))
        .map(|p| p.name.as_str())
        .collect();
    if !others.is_empty() {
        notes.push(format!(
            "{} {} the configuration's start (no closed form)",
            others.join(", "),
            if others.len() == 1 { "keeps" } else { "keep" }
        ));
    }
    ClosedFormStart {
        method: y.method,
        values,
        half_space: y.half_space,
        rms_rel: y.rms_rel,
        seconds: clock.elapsed().as_secs_f64(),
        notes,
    }
}

/// Sets the starts of the free parameters among `values` in `s.id_cfg`, clamped to their
/// bounds (a note each); a fixed parameter is left as it is (a note). Returns the values set.
pub(crate) fn set_starts(
    s: &mut Setup,
    values: Vec<(String, f64)>,
    notes: &mut Vec<String>,
) -> Vec<(String, f64)> {
    let infos = s.law.params();
    let mut set = Vec::new();
    for (name, v) in values {
        let Some(k) = s.id_cfg.params.iter().position(|p| p.name == name) else {
            continue;
        };
        let p = &mut s.id_cfg.params[k];
        if !p.free {
            notes.push(format!(
                "{name} is fixed: its closed-form value {} is not used",
                sig(v, 5)
            ));
            continue;
        }
        let info = infos.get(k);
        let lower = p.lower.or(info.map(|i| i.min)).unwrap_or(f64::NEG_INFINITY);
        let upper = p.upper.or(info.map(|i| i.max)).unwrap_or(f64::INFINITY);
        let c = v.clamp(lower, upper);
        if c != v {
            notes.push(format!(
                "{name}: the closed form's {} lies outside its bounds [{}, {}]: clamped to {}",
                sig(v, 5),
                sig(lower, 5),
                sig(upper, 5),
                sig(c, 5)
            ));
        }
        p.value = Some(c);
        set.push((name, c));
    }
    set
}
