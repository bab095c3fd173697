//! First guesses of the laws with internal variables (`Plastic`, `Prony`) from a record's
//! Oliver-Pharr analysis (docs/analysis.md, "First guesses"); `crate::first_guess` calls
//! these after setting `E = E_IT`.
//!
//! **Plastic.** Tabor's rule `H = C sigma_y(eps_r)` with `C = 3` read at his
//! representative plastic strain `eps_r = 0.08` of a pyramid or cone (Tabor, *The Hardness
//! of Metals*, 1951; Johnson, *Contact Mechanics*, 1985, section 6.4): `sY` is solved so that
//! the law's own hardening curve, its other parameters kept, gives the static flow stress
//! at `eps_r`. With a `Norton` rate and a hold that creeps, the split into a static and an
//! overstress part is Norton-Hoff's (`crate::first_guess`): `phi = m SRS` clamped to
//! `[0.05, 0.9]` (0.5 without an SRS), `sigma_y(eps_r) = (1 - phi) H/3`,
//! `K = phi (H/3) / eps'^(1/m)` with `m` kept. Hardening parameters (`H`, `n`, `Q`, `b`,
//! `eps0`, a table) are kept: one curve's O&P numbers do not separate them.
//!
//! **Prony.** One term `(g1, tau1)` from the creep of the hold under constant force, by
//! Lee and Radok's correspondence for a self-similar tip: with the force applied at the
//! hold's start and `nu` constant, `h^q` follows the shear creep compliance `J(t)`
//! (`q = 2` for a cone or pyramid, `3/2` for a sphere, 1 for a flat punch). The standard
//! linear solid `G(t) = G0 (1 - g (1 - e^(-t/tau)))` creeps as
//! `J(t) G0 = (1 - g e^(-t/tau_c)) / (1 - g)` with `tau_c = tau / (1 - g)`. Over a hold
//! of duration `T` the record gives the compliance ratio `rho = (h1/h0)^q = J(T)/J(0)` and
//! the end rate `r = q h'/h = d ln J / dt (T)`. With `u = T/tau_c`, `x = e^-u`:
//! `(e^u - 1)/u = (rho - 1)/(r T rho)` (one root `u > 0` when the right side exceeds 1, i.e.
//! the creep decelerates), `g = (rho - 1)/(rho - x)`, `tau = tau_c (1 - g)`. Without a hold
//! that decelerates, `g1`, `tau1` keep their values. The loading is not instantaneous and
//! creep already runs during it, so these are starts, not results.

use indentify_laws::Hardening;
use indentify_laws::registry::SpecValue;

use crate::config::LawSpec;
use crate::first_guess::{CONSTRAINT_FACTOR, OpSummary};
use crate::format::sig;

/// Tabor's representative plastic strain of a pyramid or cone.
pub const REPRESENTATIVE_STRAIN: f64 = 0.08;

/// Sets the parameter `name` of a list element (`g1` is the `g` of `terms[0]`), which
/// [`LawSpec::set_number`] does not reach; `false` when the law has no such parameter or
/// refuses the value.
pub fn set_list_number(law: &mut LawSpec, name: &str, value: f64) -> bool {
    let stem = name.trim_end_matches(|c: char| c.is_ascii_digit());
    let Some(i) = name[stem.len()..]
        .parse::<usize>()
        .ok()
        .and_then(|k| k.checked_sub(1))
    else {
        return false;
    };
    let mut fields = law.fields().to_vec();
    let mut found = false;
    for (_, v) in fields.iter_mut() {
        if let SpecValue::List(items) = v {
            if let Some(SpecValue::Variant { fields: f, .. }) = items.get_mut(i) {
                for (n, x) in f.iter_mut() {
                    if n == stem {
                        *x = SpecValue::Number(value);
                        found = true;
                    }
                }
            }
        }
    }
    match LawSpec::from_fields(law.variant(), fields) {
        Ok(spec) if found => {
            *law = spec;
            true
        }
        _ => false,
    }
}

/// The hold's creep as Prony's guess reads it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldCreep {
    /// Duration, s.
    pub duration: f64,
    /// Depth at its start and end, mm.
    pub h: (f64, f64),
    /// Indentation strain rate `h'/h` at its end, 1/s.
    pub strain_rate: f64,
    /// The exponent `q` of `F ~ h^q` of the tip (2 cone/pyramid, 1.5 sphere, 1 flat).
    pub q: f64,
}

/// The hardening form of a `Plastic` specification.
fn hardening(law: &LawSpec) -> Option<Hardening> {
    let (name, fields) = law.fields().iter().find_map(|(n, v)| match v {
        SpecValue::Variant { name, fields } if n == "hardening" => Some((name, fields)),
        _ => None,
    })?;
    Some(match name.as_str() {
        "Linear" => Hardening::Linear,
        "Power" => Hardening::Power,
        "Voce" => Hardening::Voce,
        "Swift" => Hardening::Swift,
        "Table" => {
            let Some((_, SpecValue::List(items))) = fields.iter().find(|(n, _)| n == "points")
            else {
                return None;
            };
            let pts: Option<Vec<(f64, f64)>> = items
                .iter()
                .map(|p| match p {
                    SpecValue::Tuple(v) | SpecValue::List(v) => match v.as_slice() {
                        [SpecValue::Number(a), SpecValue::Number(b)] => Some((*a, *b)),
                        _ => None,
                    },
                    _ => None,
                })
                .collect();
            Hardening::Table(indentify_laws::Table::new(&pts?).ok()?)
        }
        _ => return None,
    })
}

/// The `sY` for which `sigma_y(eps_r)` of `form` at parameters `c` (`c[2]` = `sY`) is
/// `target`, by bisection on `(0, target]` (the flow stress grows with `sY` for every
/// form); `None` when even `sY -> 0` exceeds `target`.
pub fn solve_sy(form: &Hardening, c: &[f64], eps_r: f64, target: f64) -> Option<f64> {
    let at = |sy: f64| {
        let mut c = c.to_vec();
        c[2] = sy;
        form.value(&c, eps_r).0
    };
    let (mut lo, mut hi) = (target * 1e-9, target);
    if at(lo) > target {
        return None;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if at(mid) > target {
            hi = mid;
        } else {
            lo = mid;
        }
        if hi - lo <= 1e-15 * target {
            break;
        }
    }
    Some(0.5 * (lo + hi))
}

/// `Plastic`'s `sY` (and `K` with a `Norton` rate) from `op`, appended to `values` and
/// `notes` (`E` already guessed there).
pub fn plastic(
    law: &LawSpec,
    op: &OpSummary,
    values: &mut Vec<(String, f64)>,
    notes: &mut Vec<String>,
) {
    let sigma = op.h / CONSTRAINT_FACTOR;
    let named = law.named_params();
    let mut c: Vec<f64> = named.iter().map(|p| p.1).collect();
    c[0] = op.e;
    let param = |name: &str| named.iter().find(|p| p.0 == name).map(|p| p.1);
    let norton = param("K").zip(param("m"));
    let (static_part, rate_note) = match (norton, op.strain_rate) {
        (Some((_, m)), Some(r)) => {
            let phi = op.srs.map_or(0.5, |s| (m * s).clamp(0.05, 0.9));
            let kk = phi * sigma / r.powf(1.0 / m);
            values.push(("K".into(), kk));
            (
                (1.0 - phi) * sigma,
                format!(
                    "; K = {} MPa s^(1/m): overstress K eps'^(1/m) = {} of sigma_r at the hold's \
                     eps' = {} 1/s ({}), m = {m} kept",
                    sig(kk, 4),
                    sig(phi, 3),
                    sig(r, 3),
                    op.srs.map_or_else(
                        || "no strain-rate sensitivity from the hold: 0.5 assumed".to_string(),
                        |s| format!("m x SRS, SRS = {}", sig(s, 3))
                    ),
                ),
            )
        }
        (Some((k, m)), None) => (
            sigma,
            format!(
                "; K = {}, m = {m} kept: the record has no hold that creeps forward",
                sig(k, 4)
            ),
        ),
        (None, _) => (sigma, String::new()),
    };
    let form = hardening(law);
    let solved = form
        .as_ref()
        .and_then(|f| solve_sy(f, &c, REPRESENTATIVE_STRAIN, static_part));
    let s_y = solved.unwrap_or(0.1 * static_part);
    values.push(("sY".into(), s_y));
    let how = if solved.is_some() {
        format!(
            "the law's {} hardening, its parameters kept, gives sigma_y({REPRESENTATIVE_STRAIN}) \
             = {} MPa",
            form.as_ref().map_or("", Hardening::kind),
            sig(static_part, 4)
        )
    } else {
        format!(
            "the hardening alone exceeds {} MPa at eps_p = {REPRESENTATIVE_STRAIN}: sY set to a \
             tenth of it (lower the hardening's start values)",
            sig(static_part, 4)
        )
    };
    notes.push(format!(
        "sY = {} MPa: Tabor, sigma_r = H/{CONSTRAINT_FACTOR} = {} MPa at the representative \
         plastic strain {REPRESENTATIVE_STRAIN}; {how}{rate_note}",
        sig(s_y, 4),
        sig(sigma, 4),
    ));
}

/// `(g, tau)` of a one-term Prony series whose Lee-Radok creep over the hold `c`
/// reproduces its compliance ratio and end rate (module docs); `None` when the creep does
/// not decelerate (or does not creep).
pub fn prony_term(c: &HoldCreep) -> Option<(f64, f64)> {
    let (h0, h1) = c.h;
    let t = c.duration;
    let rho = (h1 / h0).powf(c.q);
    let r = c.q * c.strain_rate;
    if !(rho > 1.0 && r > 0.0 && t > 0.0 && rho.is_finite()) {
        return None;
    }
    let a = (rho - 1.0) / (r * t * rho);
    if a.is_nan() || a <= 1.0 {
        return None;
    }
    // (e^u - 1)/u = a, increasing in u from 1 at u = 0
    let f = |u: f64| u.exp_m1() / u - a;
    let (mut lo, mut hi) = (1e-12, 1.0);
    while f(hi) < 0.0 {
        hi *= 2.0;
        if hi > 700.0 {
            return None;
        }
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let u = 0.5 * (lo + hi);
    let x = (-u).exp();
    let g = (rho - 1.0) / (rho - x);
    let tau = t / u * (1.0 - g);
    Some((g, tau))
}

/// `Prony`'s `g1`, `tau1` from the hold's creep (module docs).
pub fn prony(
    law: &LawSpec,
    op: &OpSummary,
    values: &mut Vec<(String, f64)>,
    notes: &mut Vec<String>,
) {
    let kept = |why: &str| {
        let p = law.named_params();
        let v = |n: &str| p.iter().find(|q| q.0 == n).map_or(f64::NAN, |q| q.1);
        format!(
            "g1 = {}, tau1 = {} s kept: {why}",
            sig(v("g1"), 3),
            sig(v("tau1"), 3)
        )
    };
    let Some(hold) = op.hold else {
        notes.push(kept("the record has no hold that creeps forward"));
        return;
    };
    match prony_term(&hold) {
        Some((g, tau)) => {
            values.push(("g1".into(), g));
            values.push(("tau1".into(), tau));
            notes.push(format!(
                "g1 = {}, tau1 = {} s: the standard linear solid whose Lee-Radok creep \
                 (h^{} ~ J(t), force held from the hold's start) gives the hold's depth ratio \
                 {}/{} mm over {} s and its end rate {} 1/s",
                sig(g, 4),
                sig(tau, 4),
                hold.q,
                sig(hold.h.1, 4),
                sig(hold.h.0, 4),
                sig(hold.duration, 3),
                sig(hold.strain_rate, 3)
            ));
        }
        None => notes.push(kept(
            "the hold's creep does not decelerate (its end rate is not below its mean rate)",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shear creep compliance of the standard linear solid, times G0.
    fn creep(g: f64, tau: f64, t: f64) -> f64 {
        (1.0 - g * (-t * (1.0 - g) / tau).exp()) / (1.0 - g)
    }

    /// The guessed term's creep compliance reproduces the hold it came from: the ratio
    /// `J(T)/J(0) = (h1/h0)^q` and `d ln J/dt (T) = q h'/h`, against the closed form of the
    /// standard linear solid (not the inversion's own algebra).
    #[test]
    fn prony_term_reproduces_the_hold() {
        for (g0, tau0, t, q) in [
            (0.3, 2.0, 10.0, 2.0),
            (0.6, 0.5, 3.0, 1.5),
            (0.1, 20.0, 5.0, 2.0),
        ] {
            // a hold made by the law itself
            let ratio = creep(g0, tau0, t) / creep(g0, tau0, 0.0);
            let d = 1e-6 * t;
            let rate = ((creep(g0, tau0, t + d)).ln() - (creep(g0, tau0, t - d)).ln()) / (2.0 * d);
            let hold = HoldCreep {
                duration: t,
                h: (1e-3, 1e-3 * ratio.powf(1.0 / q)),
                strain_rate: rate / q,
                q,
            };
            let (g, tau) = prony_term(&hold).unwrap();
            assert!((g / g0 - 1.0).abs() < 1e-6, "{g} vs {g0}");
            assert!((tau / tau0 - 1.0).abs() < 1e-6, "{tau} vs {tau0}");
            let back = creep(g, tau, t) / creep(g, tau, 0.0);
            assert!((back / ratio - 1.0).abs() < 1e-9);
        }
        // accelerating or no creep: no guess
        let flat = HoldCreep {
            duration: 10.0,
            h: (1e-3, 1.01e-3),
            strain_rate: 1e-2,
            q: 2.0,
        };
        assert!(prony_term(&flat).is_none());
        assert!(
            prony_term(&HoldCreep {
                h: (1e-3, 1e-3),
                ..flat
            })
            .is_none()
        );
    }

    /// The guessed `g1`, `tau1` reach the law's first term (a list element).
    #[test]
    fn list_parameters_are_set() {
        let mut law: LawSpec = ron::from_str(
            "Prony(E: 3000.0, nu: 0.3, terms: [(g: 0.3, tau: 1.0), (g: 0.1, tau: 9.0)])",
        )
        .unwrap();
        assert!(set_list_number(&mut law, "g1", 0.2));
        assert!(set_list_number(&mut law, "tau2", 4.0));
        assert!(!set_list_number(&mut law, "g3", 0.1));
        assert!(!set_list_number(&mut law, "g1", 1.5));
        let p: Vec<f64> = law.named_params().iter().map(|q| q.1).collect();
        assert_eq!(p, [3000.0, 0.3, 0.2, 1.0, 0.1, 4.0]);
    }

    /// `sY` solved for every hardening form gives the target flow stress at the
    /// representative strain through the laws crate's own hardening curve, and the
    /// closed forms of the linear and Voce curves.
    #[test]
    fn sy_hits_the_flow_stress_for_every_form() {
        let target = 500.0;
        let e = 7e4;
        let p = REPRESENTATIVE_STRAIN;
        let cases: [(Hardening, Vec<f64>); 4] = [
            (Hardening::Linear, vec![e, 0.3, 1.0, 1000.0]),
            (Hardening::Power, vec![e, 0.3, 1.0, 0.2]),
            (Hardening::Voce, vec![e, 0.3, 1.0, 100.0, 20.0]),
            (Hardening::Swift, vec![e, 0.3, 1.0, 0.01, 0.2]),
        ];
        for (form, c) in cases {
            let sy = solve_sy(&form, &c, p, target).unwrap();
            let mut c2 = c.clone();
            c2[2] = sy;
            let got = form.value(&c2, p).0;
            assert!((got / target - 1.0).abs() < 1e-12, "{form:?}: {got}");
            match form {
                Hardening::Linear => assert!((sy - (target - 1000.0 * p)).abs() < 1e-9),
                Hardening::Voce => {
                    let closed = target - 100.0 * (1.0 - (-20.0f64 * p).exp());
                    assert!((sy - closed).abs() < 1e-9);
                }
                _ => {}
            }
        }
        // hardening alone above the target: no sY
        assert!(solve_sy(&Hardening::Linear, &[e, 0.3, 1.0, 1e5], p, target).is_none());
    }
}
