//! The closed-form start of a law with a yield stress (`Plastic` with any hardening and
//! rate, `NortonHoff`; docs/analysis.md, "Closed-form starts for laws with a yield
//! stress"): `E`, the representative stress and, for Dao's power form, `n` from the
//! curve's loading curvature, unloading slope and work ratio, then `sY` from the
//! representative stress through the law's own hardening, corrected by one forward run of
//! the finite element model.
//!
//! - A 70.3-degree cone (Berkovich and Vickers as their area-equivalent cone) with an
//!   unloading to zero force: Dao et al.'s reverse analysis
//!   (`indentify_analysis::dao::reverse`): `E`, `sigma_r = sigma(0.033)`, `n`.
//! - A sphere, any other cone, or an unloading that stops before zero force: the modulus
//!   from the unloading stiffness and Tabor's representative stress `p_m/3` at the
//!   representative strain `0.2 a/R` or `0.2 cot(alpha)`
//!   (`indentify_analysis::tabor::stiffness_and_hardness`); the hardening's own
//!   parameters keep their starts.
//! - A Norton rate (`Plastic` with `rate: Norton`, `NortonHoff`): the overstress
//!   `K rate^(1/m)` at the loading's mean log strain rate, with the configuration's `K`,
//!   `m`, is taken off the representative stress before `sY` is solved for; `K` and `m`
//!   keep their starts.
//! - The correction: the model's forces at those values are read the same way, and each
//!   value `v` becomes `v^2 / v_model` (`E`, `sigma_r`; `n` as `2 n - n_model`), the defect
//!   of the analysis on the model at the start taken off the data's. A second forward run
//!   at the corrected values decides: the start is whichever of the two the model fits
//!   better (the kept parameters' errors, `K` and `m` of a rate, also move the model's
//!   curve, and the correction then carries them; the note says which was kept).

use indentify_analysis::closed_form::Punch as ClosedPunch;
use indentify_analysis::dao::{self, Features, ReverseInput};
use indentify_analysis::tabor;
use indentify_identify::Evaluator;
use indentify_laws::Hardening;

use crate::format::sig;
use crate::identify::Setup;

/// The law's yield structure, from its parameter names.
#[derive(Clone, Debug)]
struct YieldLaw {
    /// The J2 hardening (`None`: Norton-Hoff, `sigma_y = sY`).
    hardening: Option<Hardening>,
    /// Indices of `E`, `sY`, the power form's `n` (if any), `K` and `m` (if a rate).
    ie: usize,
    isy: usize,
    in_: Option<usize>,
    rate: Option<(usize, usize)>,
}

impl YieldLaw {
    fn of(s: &Setup) -> Result<YieldLaw, String> {
        let at = |n: &str| s.names.iter().position(|m| *m == n);
        let (Some(ie), Some(isy)) = (at("E"), at("sY")) else {
            return Err("the law has no `E` and `sY`".into());
        };
        let rate = at("K").zip(at("m"));
        let hardening = match s.cfg.law.variant() {
            "NortonHoff" => None,
            "Plastic" => Some(if at("eps0").is_some() {
                Hardening::Swift
            } else if at("n").is_some() {
                Hardening::Power
            } else if at("H").is_some() {
                Hardening::Linear
            } else if at("Q").is_some() {
                Hardening::Voce
            } else {
                return Err(
                    "a tabulated hardening has no flow stress to solve `sY` from here".into(),
                );
            }),
            other => return Err(format!("the law {other} has no yield stress")),
        };
        // Dao's n is set only where it is the power form's and free (a held n is used)
        let free = |i: &usize| s.id_cfg.params.get(*i).is_some_and(|p| p.free);
        let in_ = at("n")
            .filter(|_| matches!(hardening, Some(Hardening::Power)))
            .filter(free);
        Ok(YieldLaw {
            hardening,
            ie,
            isy,
            in_,
            rate,
        })
    }

    /// The flow stress at plastic strain `p` of parameters `c` (`sY` for Norton-Hoff).
    fn flow(&self, c: &[f64], p: f64) -> f64 {
        match &self.hardening {
            Some(h) => h.value(c, p).0,
            None => c[self.isy],
        }
    }

    /// The `sY` at which the flow stress at `p` is `target`, the other parameters those of
    /// `c` (bisection on `ln sY`: the flow stress increases with `sY` in every form);
    /// `None` when the hardening alone exceeds `target` (`H p`, `Q (1 - e^(-b p))` above it).
    fn sy_for(&self, c: &[f64], p: f64, target: f64) -> Option<f64> {
        let mut c = c.to_vec();
        let (mut lo, mut hi) = ((target * 1e-9).ln(), target.ln());
        c[self.isy] = lo.exp();
        if self.flow(&c, p) > target {
            return None;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            c[self.isy] = mid.exp();
            if self.flow(&c, p) > target {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Some((0.5 * (lo + hi)).exp())
    }
}

/// What one curve's analysis gives: `E`, the representative stress and strain, `n`.
#[derive(Clone, Copy, Debug)]
struct Analysed {
    e: f64,
    sigma_r: f64,
    eps_r: f64,
    n: Option<f64>,
}

/// The route a punch and curve take.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Route {
    Dao,
    Tabor,
}

fn analyse(
    h: &[f64],
    f: &[f64],
    route: Route,
    punch: ClosedPunch,
    nu: f64,
    n_hint: Option<f64>,
    notes: &mut Vec<String>,
) -> Result<(Analysed, Features), String> {
    let m = dao::measure(h, f).map_err(|e| e.to_string())?;
    match route {
        Route::Dao => {
            let r = ReverseInput::of(&m, true)
                .and_then(|i| dao::reverse(&i, nu, n_hint))
                .map_err(|e| format!("Dao's reverse analysis: {e}"))?;
            if r.n_clamped {
                notes.push(format!(
                    "n: Dao's Pi2 has no root in [0, 0.5] at this unloading slope; n = {} is \
                     the nearest end",
                    sig(r.n, 3)
                ));
            }
            if r.n_roots > 1 {
                notes.push(format!(
                    "n: Dao's Pi2 has {} roots in [0, 0.5]; the one nearest the configuration's \
                     start is taken",
                    r.n_roots
                ));
            }
            Ok((
                Analysed {
                    e: r.e,
                    sigma_r: r.sigma_r,
                    eps_r: dao::EPS_R,
                    n: Some(r.n),
                },
                m,
            ))
        }
        Route::Tabor => {
            let t = tabor::stiffness_and_hardness(&m, punch, nu).map_err(|e| e.to_string())?;
            Ok((
                Analysed {
                    e: t.e,
                    sigma_r: t.sigma_r,
                    eps_r: t.eps_r,
                    n: None,
                },
                m,
            ))
        }
    }
}

/// The loading's mean log strain rate over its upper half, `ln(h_m/h_1)/(t_m - t_1)` (1/s).
fn loading_rate(t: &[f64], h: &[f64], m: &Features) -> f64 {
    let end = m.loading_end;
    let k = (0..=end).find(|&k| h[k] >= 0.5 * h[end]).unwrap_or(0);
    if end > k && h[k] > 0.0 && t[end] > t[k] {
        (h[end] / h[k]).ln() / (t[end] - t[k])
    } else {
        0.0
    }
}

/// What the yield start sets, before the bounds: `(name, value)` pairs, the half-space
/// (uncorrected) ones, the method and notes.
pub(crate) struct YieldValues {
    pub values: Vec<(String, f64)>,
    pub half_space: Vec<(String, f64)>,
    pub method: String,
    /// The model's RMS misfit at the values set, relative to the largest force (when a
    /// calibration run was made).
    pub rms_rel: Option<f64>,
    pub notes: Vec<String>,
}

/// The RMS of `model - data` relative to the largest data force.
fn rms_rel(model: &[f64], data: &[f64]) -> f64 {
    let n = model.len().min(data.len()).max(1);
    let sse: f64 = model.iter().zip(data).map(|(a, b)| (a - b).powi(2)).sum();
    let f_max = data.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    (sse / n as f64).sqrt() / f_max
}

fn pct(x: f64) -> String {
    format!("{}%", sig(100.0 * x, 3))
}

/// The parameters of the analysis `a` set on `start`: `E`, `n` (Dao's route, the power
/// form), `sY` from `sigma_r` less the rate's overstress (`None` when that is not
/// positive).
fn set(law: &YieldLaw, start: &[f64], a: &Analysed, over: f64) -> (Vec<f64>, Option<f64>) {
    let mut c = start.to_vec();
    c[law.ie] = a.e;
    if let (Some(i), Some(n)) = (law.in_, a.n) {
        c[i] = n;
    }
    let target = a.sigma_r - over;
    let sy = if target > 0.0 {
        law.sy_for(&c, a.eps_r, target)
    } else {
        None
    };
    if let Some(v) = sy {
        c[law.isy] = v;
    }
    (c, sy)
}

/// The yield start of `s` at `start` (the configuration's starts) for `punch`: `Err` says
/// why none applies here (the caller falls back to the elastic closed form).
pub(crate) fn values(
    s: &Setup,
    punch: ClosedPunch,
    start: &[f64],
    nu: f64,
) -> Result<YieldValues, String> {
    let law = YieldLaw::of(s)?;
    let route = match punch {
        ClosedPunch::Cone { half_angle_deg }
            if (half_angle_deg - dao::HALF_ANGLE_DEG).abs() < 0.05 =>
        {
            Route::Dao
        }
        ClosedPunch::Cone { .. } | ClosedPunch::Sphere { .. } => Route::Tabor,
        ClosedPunch::Flat { .. } => {
            return Err("a flat punch has no representative strain".into());
        }
    };
    let sch = s.problem.schedule();
    let (t, h, f) = (&sch.t, &sch.depth, &s.problem.target);
    let mut notes = Vec::new();
    let n_hint = law.in_.map(|i| start[i]);
    // Dao's route needs the work ratio: an unloading to zero force
    let (route, (a0, m0)) = match analyse(h, f, route, punch, nu, n_hint, &mut notes) {
        Ok(v) => (route, v),
        Err(e) if route == Route::Dao => {
            notes.push(format!("{e}; Tabor's hardness instead"));
            (
                Route::Tabor,
                analyse(h, f, Route::Tabor, punch, nu, n_hint, &mut notes)?,
            )
        }
        Err(e) => return Err(e),
    };
    let rate = loading_rate(t, h, &m0);
    let over = match law.rate {
        Some((ik, im)) if rate > 0.0 => start[ik] * rate.powf(1.0 / start[im]),
        _ => 0.0,
    };
    let (c0, sy0) = set(&law, start, &a0, over);
    // a rate's K, m keep their starts: their errors move the model's curve and a
    // calibration run would carry them into the correction (measured on R2:
    // docs/performance.md), so the analysis' values are the start, with no forward run
    let (c1, sy1, corrected, rms) = if law.rate.is_some() {
        notes.push(
            "not corrected by a calibration run (the rate's K, m keep the configuration's \
             starts, whose errors a correction would carry)"
                .into(),
        );
        (c0.clone(), sy0, a0, None)
    } else {
        let how = (route, punch, nu, n_hint);
        calibrate(s, &law, start, (&c0, sy0, &a0), over, how, &mut notes)?
    };
    let pick = |c: &[f64], sy: Option<f64>| {
        let mut v = vec![("E".to_string(), c[law.ie])];
        if sy.is_some() {
            v.push(("sY".to_string(), c[law.isy]));
        }
        if let (Some(i), Some(_)) = (law.in_, a0.n) {
            v.push(("n".to_string(), c[i]));
        }
        v
    };
    if sy1.is_none() && over < corrected.sigma_r {
        notes.push(format!(
            "sY keeps the configuration's start: the hardening's own increase at the \
             representative plastic strain {} with the configuration's parameters exceeds \
             the representative stress {} MPa{}",
            sig(corrected.eps_r, 3),
            sig(corrected.sigma_r, 4),
            if over > 0.0 {
                format!(" less the rate's overstress {} MPa", sig(over, 4))
            } else {
                String::new()
            }
        ));
    } else if sy1.is_none() {
        notes.push(format!(
            "sY keeps the configuration's start: the rate's overstress {} MPa (K (h'/h)^(1/m) \
             at the loading's {} 1/s with the configuration's K, m) exceeds the \
             representative stress {} MPa",
            sig(over, 4),
            sig(rate, 3),
            sig(corrected.sigma_r, 4)
        ));
    } else if over > 0.0 {
        notes.push(format!(
            "sY: the representative stress {} MPa less the rate's overstress {} MPa \
             (K (h'/h)^(1/m) at the loading's {} 1/s with the configuration's K, m)",
            sig(corrected.sigma_r, 4),
            sig(over, 4),
            sig(rate, 3)
        ));
    }
    let method = match (route, punch) {
        (Route::Dao, _) => "Dao et al.'s reverse analysis of the 70.3-degree cone".to_string(),
        (Route::Tabor, ClosedPunch::Sphere { .. }) => {
            "the unloading stiffness and Tabor's hardness of the sphere".to_string()
        }
        (Route::Tabor, _) => "the unloading stiffness and Tabor's hardness of the cone".to_string(),
    };
    Ok(YieldValues {
        values: pick(&c1, sy1),
        half_space: pick(&c0, sy0),
        method,
        rms_rel: rms,
        notes,
    })
}

/// The values of one analysis: the parameters, `sY` (if set), the analysis.
type Set<'a> = (&'a [f64], Option<f64>, &'a Analysed);

/// The calibration's outcome: the parameters, `sY` (if set), the analysis kept, the
/// model's misfit there.
type Calibrated = (Vec<f64>, Option<f64>, Analysed, Option<f64>);

/// The calibration: the model's forces at the analysis' values `c0` read the same way, the
/// correction, and a second run at the corrected values; the start is whichever the model
/// fits better. Returns the values, `sY` (if set), the analysis kept and the model's misfit
/// there.
fn calibrate(
    s: &Setup,
    law: &YieldLaw,
    start: &[f64],
    (c0, sy0, a0): Set<'_>,
    over: f64,
    (route, punch, nu, n_hint): (Route, ClosedPunch, f64, Option<f64>),
    notes: &mut Vec<String>,
) -> Result<Calibrated, String> {
    let sch = s.problem.schedule();
    let (h, f) = (&sch.depth, &s.problem.target);
    let run = |c: &[f64]| {
        s.problem
            .install(|| Evaluator::new(&s.problem).and_then(|mut ev| ev.forces(c)))
    };
    let fe =
        run(c0).map_err(|e| format!("the calibration run at the analysis' values failed: {e}"))?;
    let mut fe_notes = Vec::new();
    let (a1, _) = analyse(h, &fe, route, punch, nu, n_hint, &mut fe_notes)
        .map_err(|e| format!("the calibration run's curve: {e}"))?;
    let corrected = Analysed {
        e: a0.e * a0.e / a1.e,
        sigma_r: a0.sigma_r * a0.sigma_r / a1.sigma_r,
        eps_r: a0.eps_r,
        n: a0
            .n
            .zip(a1.n)
            .map(|(n0, n1)| (2.0 * n0 - n1).clamp(dao::N_RANGE.0, dao::N_RANGE.1)),
    };
    let (c1, sy1) = set(law, start, &corrected, over);
    // the correction kept only where the model fits the data better with it (a second run)
    let rms0 = rms_rel(&fe, f);
    let rms1 = run(&c1).map(|m| rms_rel(&m, f)).unwrap_or(f64::INFINITY);
    Ok(if rms1 <= rms0 {
        notes.push(format!(
            "corrected by a calibration run: the model's misfit {} of the largest force \
             with the correction, {} without",
            pct(rms1),
            pct(rms0)
        ));
        (c1, sy1, corrected, Some(rms1))
    } else {
        notes.push(format!(
            "the calibration run's correction not kept: the model's misfit {} of the largest \
             force without it, {} with",
            pct(rms0),
            pct(rms1)
        ));
        (c0.to_vec(), sy0, *a0, Some(rms0))
    })
}
