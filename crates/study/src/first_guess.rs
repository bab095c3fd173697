//! First guesses of a law's parameters from the Oliver-Pharr analysis of a record, and the
//! O&P numbers a fit reports beside its own (docs/analysis.md, "First guesses").
//!
//! - `E` is the indentation modulus `E_IT` of the test's main unloading (with the law's
//!   `nu`);
//! - the representative flow stress is `sigma_r = H_IT / C` with Tabor's constraint factor
//!   [`CONSTRAINT_FACTOR`] (`C = 3`);
//! - the representative strain rate is the hold's indentation strain rate at its end,
//!   `eps' = h'/h` (`analysis::Hold::strain_rate`);
//! - Maxwell: `eta = 2 sigma_r / (3 eps')` (uniaxial flow `eps'_zz = 2 sigma / (3 eta)` of
//!   `g = P sigma / eta`);
//! - Norton-Hoff: the law's `m` kept (the template's start value), the overstress share
//!   `phi = m * SRS` (from the uniaxial `sigma = sY + K eps'^(1/m)`, whose strain-rate
//!   sensitivity is `d ln sigma / d ln eps' = phi / m`), clamped to `[0.05, 0.9]` (0.5 when
//!   the hold gives no SRS), `sY = (1 - phi) sigma_r`, `K = phi sigma_r / eps'^(1/m)`;
//!   without a hold `sY = sigma_r` and `K`, `m` stay the template's;
//! - `Plastic` (`sY` at Tabor's representative strain through the law's own hardening, `K`
//!   of a `Norton` rate as Norton-Hoff's) and `Prony` (`g1`, `tau1` from the hold's creep
//!   by Lee-Radok): `crate::first_guess_laws`.
//!
//! These are starts for a minimizer, not results: a pile-up, the tip's bluntness or time
//! dependence make O&P differ from the FE fit, which is why a fit reports both.

use std::path::Path;

use indentify_analysis::{AreaFunction, Options, Tip};
use indentify_contact::Punch;
use indentify_records::{Format, Record};
use serde::Serialize;

use crate::config::LawSpec;
use crate::error::{Error, ErrorKind, Result};
use crate::format::sig;

/// Tabor's constraint factor `H = C sigma_r` of a fully plastic contact (`C = 3`).
pub const CONSTRAINT_FACTOR: f64 = 3.0;

/// The Oliver-Pharr values of one test (its main unloading and the hold before it), in
/// MPa, N/mm, mm, N, 1/s.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OpSummary {
    /// Test name.
    pub test: String,
    /// Indentation modulus E_IT, MPa.
    #[serde(rename = "E")]
    pub e: f64,
    /// Indentation hardness H_IT, MPa.
    #[serde(rename = "H")]
    pub h: f64,
    /// Reduced modulus, MPa.
    #[serde(rename = "Er")]
    pub er: f64,
    /// Contact stiffness, N/mm.
    #[serde(rename = "S")]
    pub s: f64,
    /// Contact depth, mm.
    pub hc: f64,
    /// Depth at the start of the unloading, mm.
    pub hmax: f64,
    /// Force at the start of the unloading, N.
    #[serde(rename = "Fmax")]
    pub fmax: f64,
    /// The hold's indentation strain rate at its end `h'/h`, 1/s (when it creeps forward).
    pub strain_rate: Option<f64>,
    /// The hold's strain-rate sensitivity, when it gives one.
    pub srs: Option<f64>,
    /// Sample Poisson's ratio used for E_IT.
    pub nu: f64,
    /// The hold's creep (duration, depths, end rate, the tip's exponent), when it creeps
    /// forward: what `Prony`'s guess reads (`crate::first_guess_laws`).
    #[serde(skip)]
    pub hold: Option<crate::first_guess_laws::HoldCreep>,
}

/// A law's start values from an [`OpSummary`], and how each was obtained.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FirstGuess {
    /// The O&P values it comes from.
    pub op: OpSummary,
    /// `(parameter, value)` set from the analysis (the others keep their values).
    pub values: Vec<(String, f64)>,
    /// One line per parameter: how it was obtained, or why it was kept.
    pub notes: Vec<String>,
}

/// The analysis tip of a punch: pyramids as their ideal area function (a rounded tip is
/// not represented: give a calibrated tip), cones, spheres and flat punches exactly, a
/// sphero-cone as its cone; `None` for tabulated and calibrated punches (the caller reads
/// the tip file).
pub fn tip_for_punch(p: &Punch) -> Option<Tip> {
    let area = match p {
        Punch::Berkovich { .. } | Punch::Vickers { .. } => AreaFunction::Berkovich,
        Punch::CubeCorner { .. } => AreaFunction::Cone {
            half_angle_deg: indentify_contact::punch::CUBE_CORNER_HALF_ANGLE_DEG,
        },
        Punch::Cone { half_angle_deg } | Punch::SpheroCone { half_angle_deg, .. } => {
            AreaFunction::Cone {
                half_angle_deg: *half_angle_deg,
            }
        }
        Punch::Sphere { radius } => AreaFunction::Sphere { radius: *radius },
        Punch::Flat { radius } => AreaFunction::Flat { radius: *radius },
        Punch::Tabulated { .. } | Punch::Calibrated { .. } => return None,
    };
    Some(Tip::diamond(area))
}

/// Preprocesses `r` as `indentify analyze` does (the format's zero point, the file's drift
/// correction, the tip's frame compliance or the file's) and analyses it.
///
/// # Errors
/// A record the preprocessing refuses, no analysed unloading (the reason named).
pub fn analyse_record(r: &Record, tip: &Tip, nu: f64) -> Result<OpSummary> {
    let format = r.meta.format;
    let zero = crate::analyze::zero_point_default(format);
    let prep = crate::analyze::preprocessing(tip.frame_compliance, zero);
    // the test's name, or the record's file name (not its path: a configuration names
    // the record relative to its own folder)
    let name = r.meta.test_name.clone().unwrap_or_else(|| {
        Path::new(&r.name)
            .file_name()
            .map_or_else(|| r.name.clone(), |f| f.to_string_lossy().into_owned())
    });
    let fail = |why: String| Error::msg(ErrorKind::Data, format!("test `{name}`: {why}"));
    let (x, _) = indentify_records::apply(r, &prep).map_err(|e| fail(e.to_string()))?;
    let o = Options {
        nu,
        ..Options::new(tip.clone(), format)
    };
    o.validate().map_err(|e| fail(e.to_string()))?;
    let a = indentify_analysis::analyze(&x, &o).map_err(|e| fail(e.to_string()))?;
    let (u, op) = a.values().ok_or_else(|| {
        fail(
            a.error
                .clone()
                .unwrap_or_else(|| "no unloading could be analysed".into()),
        )
    })?;
    let e = op.e.ok_or_else(|| {
        fail(format!(
            "E_r = {} MPa is not below the tip's own modulus: no E_IT",
            sig(op.er, 4)
        ))
    })?;
    let hold = u.hold.as_ref();
    Ok(OpSummary {
        test: name,
        e,
        h: op.hardness,
        er: op.er,
        s: op.s,
        hc: op.hc,
        hmax: u.h_max,
        fmax: u.f_max,
        strain_rate: hold.map(|h| h.strain_rate).filter(|v| *v > 0.0),
        srs: hold.and_then(|h| h.srs).filter(|v| v.is_finite()),
        nu,
        hold: hold
            .filter(|h| h.strain_rate > 0.0 && h.h.1 > h.h.0 && h.h.0 > 0.0)
            .map(|h| crate::first_guess_laws::HoldCreep {
                duration: h.t.1 - h.t.0,
                h: h.h,
                strain_rate: h.strain_rate,
                q: match tip.area {
                    AreaFunction::Sphere { .. } => 1.5,
                    AreaFunction::Flat { .. } => 1.0,
                    _ => 2.0,
                },
            }),
    })
}

/// Reads test `test` (1-based; `None`: the first) of `file` and analyses it with `tip`.
///
/// # Errors
/// An unreadable file, and those of [`analyse_record`].
pub fn analyse_file(file: &Path, test: Option<usize>, tip: &Tip, nu: f64) -> Result<OpSummary> {
    let bytes = std::fs::read(file).map_err(|e| {
        Error::msg(
            ErrorKind::Io,
            format!("cannot read `{}`: {e}", file.display()),
        )
    })?;
    let records = indentify_records::read(
        &bytes,
        &file.display().to_string(),
        &indentify_records::ReadOptions {
            format: Format::Auto,
            test,
        },
    )
    .map_err(|e| Error::msg(ErrorKind::Data, e.to_string()))?;
    let r = records.first().ok_or_else(|| {
        Error::msg(
            ErrorKind::Data,
            format!("`{}` holds no test", file.display()),
        )
    })?;
    analyse_record(r, tip, nu)
}

/// The start values of `law`'s parameters from `op` (module docs); `nu` and parameters the
/// analysis says nothing about keep their values.
pub fn guess(law: &LawSpec, op: &OpSummary) -> FirstGuess {
    let sigma = op.h / CONSTRAINT_FACTOR;
    let mut values = vec![("E".to_string(), op.e)];
    let mut notes = vec![format!(
        "E = {} MPa: the O&P indentation modulus E_IT (nu = {})",
        sig(op.e, 4),
        op.nu
    )];
    let rate = op.strain_rate;
    let param = |name: &str| {
        law.named_params()
            .iter()
            .find(|(n, _)| *n == name)
            .map_or(f64::NAN, |p| p.1)
    };
    match law.variant() {
        "Maxwell" => match rate {
            Some(r) => {
                let v = 2.0 * sigma / (3.0 * r);
                values.push(("eta".into(), v));
                notes.push(format!(
                    "eta = {} MPa s = 2 sigma_r / (3 eps'), sigma_r = H/{CONSTRAINT_FACTOR} = {} \
                     MPa, eps' = {} 1/s at the end of the hold",
                    sig(v, 4),
                    sig(sigma, 4),
                    sig(r, 3)
                ));
            }
            None => notes.push(format!(
                "eta = {} kept: the record has no hold that creeps forward",
                sig(param("eta"), 4)
            )),
        },
        "NortonHoff" => match rate {
            Some(r) => {
                let m = param("m");
                let phi = op.srs.map_or(0.5, |s| (m * s).clamp(0.05, 0.9));
                let s_y = (1.0 - phi) * sigma;
                let kk = phi * sigma / r.powf(1.0 / m);
                values.push(("K".into(), kk));
                values.push(("sY".into(), s_y));
                notes.push(format!(
                    "sY = {} MPa, K = {} MPa s^(1/m): sigma_r = H/{CONSTRAINT_FACTOR} = {} MPa \
                     = sY + K eps'^(1/m) at the hold's eps' = {} 1/s, overstress share {} ({}), \
                     m = {m} kept",
                    sig(s_y, 4),
                    sig(kk, 4),
                    sig(sigma, 4),
                    sig(r, 3),
                    sig(phi, 3),
                    op.srs.map_or_else(
                        || "no strain-rate sensitivity from the hold: 0.5 assumed".to_string(),
                        |s| format!("m x SRS, SRS = {}", sig(s, 3))
                    ),
                ));
            }
            None => {
                let m = param("m");
                values.push(("sY".into(), sigma));
                notes.push(format!(
                    "sY = {} MPa = H/{CONSTRAINT_FACTOR}; K = {}, m = {m} kept: the record has \
                     no hold that creeps forward",
                    sig(sigma, 4),
                    sig(param("K"), 4)
                ));
            }
        },
        "Plastic" => crate::first_guess_laws::plastic(law, op, &mut values, &mut notes),
        "Prony" => crate::first_guess_laws::prony(law, op, &mut values, &mut notes),
        // Elastic: E only
        _ => {}
    }
    FirstGuess {
        op: op.clone(),
        values,
        notes,
    }
}

/// Sets the guessed values in `law`.
pub fn apply(law: &mut LawSpec, g: &FirstGuess) {
    for (name, v) in &g.values {
        if !law.set_number(name, *v) {
            crate::first_guess_laws::set_list_number(law, name, *v);
        }
    }
}

/// One line per O&P value for a console or a report: `E_IT = ... MPa, H_IT = ... MPa, ...`.
pub fn describe(op: &OpSummary) -> String {
    let mut s = format!(
        "Oliver-Pharr ({}): E_IT = {} MPa, H_IT = {} MPa, E_r = {} MPa, S = {} N/mm, h_c = {} \
         mm, h_max = {} mm, F_max = {} N",
        op.test,
        sig(op.e, 4),
        sig(op.h, 4),
        sig(op.er, 4),
        sig(op.s, 4),
        sig(op.hc, 4),
        sig(op.hmax, 4),
        sig(op.fmax, 4)
    );
    if let Some(r) = op.strain_rate {
        s.push_str(&format!(", hold strain rate {} 1/s", sig(r, 3)));
    }
    if let Some(m) = op.srs {
        s.push_str(&format!(", SRS {}", sig(m, 3)));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use indentify_analysis::calibrate::reduced_modulus;

    /// An elastic cone (Sneddon `F = (2/pi) E_r tan(theta) h^2`) loaded and unloaded.
    fn sneddon(e: f64, nu: f64, tip: &Tip) -> Record {
        let er = reduced_modulus(e, nu, tip);
        let tan = 70.3f64.to_radians().tan();
        let mut r = Record {
            name: "cone".into(),
            t: vec![],
            h: vec![],
            f: vec![],
            segment: None,
            meta: Default::default(),
        };
        for i in 0..=200 {
            let h = 1e-3 * (1.0 - (i as f64 - 100.0).abs() / 100.0);
            r.t.push(i as f64);
            r.h.push(h);
            r.f.push(2.0 / std::f64::consts::PI * er * tan * h * h);
        }
        r
    }

    fn op(h: f64, rate: Option<f64>, srs: Option<f64>) -> OpSummary {
        OpSummary {
            test: "t".into(),
            e: 7e4,
            h,
            er: 6e4,
            s: 100.0,
            hc: 1e-3,
            hmax: 1.2e-3,
            fmax: 0.1,
            strain_rate: rate,
            srs,
            nu: 0.3,
            hold: None,
        }
    }

    /// The value of the parameter `name` of `law`.
    fn p(law: &LawSpec, name: &str) -> f64 {
        law.named_params()
            .iter()
            .find(|(n, _)| *n == name)
            .map(|q| q.1)
            .unwrap()
    }

    /// Sneddon's elastic cone with a diamond tip: the guess of E is the sample's modulus
    /// (the closed form through the tip's compliance), to the analysis's accuracy.
    #[test]
    fn e_of_an_elastic_cone_is_sneddons() {
        let tip = tip_for_punch(&Punch::Cone {
            half_angle_deg: 70.3,
        })
        .unwrap();
        let r = sneddon(2e5, 0.25, &tip);
        let s = analyse_record(&r, &tip, 0.25).unwrap();
        assert!((s.e / 2e5 - 1.0).abs() < 1e-5, "{s:?}");
        let mut law = crate::config::Reference::R0Elastic.config().law;
        let g = guess(&law, &s);
        apply(&mut law, &g);
        assert_eq!(p(&law, "E"), s.e);
        assert_eq!(p(&law, "nu"), 0.3, "nu is not guessed");
    }

    /// The viscous guesses invert their own flow rules: Maxwell's uniaxial rate
    /// `2 sigma_r / (3 eta)` is the hold's rate; Norton-Hoff's `sY + K eps'^(1/m)` is
    /// `sigma_r` and its rate sensitivity `K eps'^(1/m) / (m sigma_r)` the hold's SRS.
    #[test]
    fn viscous_guesses_reproduce_the_hold() {
        let (h, rate, srs) = (3000.0, 2e-3, 0.04);
        let sigma = h / CONSTRAINT_FACTOR;
        let mut mx = LawSpec::numbers("Maxwell", &[("E", 1.0), ("nu", 0.3), ("eta", 1.0)]).unwrap();
        let g = guess(&mx, &op(h, Some(rate), Some(srs)));
        apply(&mut mx, &g);
        assert_eq!(p(&mx, "E"), 7e4);
        assert!((2.0 * sigma / (3.0 * p(&mx, "eta")) / rate - 1.0).abs() < 1e-12);
        let nh_at = |k: f64| {
            LawSpec::numbers(
                "NortonHoff",
                &[("E", 1.0), ("nu", 0.3), ("K", k), ("m", 5.0), ("sY", 1.0)],
            )
            .unwrap()
        };
        let mut nh = nh_at(1.0);
        let g = guess(&nh, &op(h, Some(rate), Some(srs)));
        apply(&mut nh, &g);
        let (k, m, s_y) = (p(&nh, "K"), p(&nh, "m"), p(&nh, "sY"));
        let over = k * rate.powf(1.0 / m);
        assert!(((s_y + over) / sigma - 1.0).abs() < 1e-12);
        assert!((over / (m * sigma) / srs - 1.0).abs() < 1e-12);
        assert_eq!(m, 5.0);
        // no hold: sY = H/3, K and m kept
        let mut nh2 = nh_at(1500.0);
        let g = guess(&nh2, &op(h, None, None));
        apply(&mut nh2, &g);
        assert_eq!(
            nh2.named_params(),
            vec![
                ("E", 7e4),
                ("nu", 0.3),
                ("K", 1500.0),
                ("m", 5.0),
                ("sY", sigma)
            ]
        );
        assert!(
            g.notes.iter().any(|n| n.contains("no hold")),
            "{:?}",
            g.notes
        );
    }

    /// A record with no unloading names the test and the reason.
    #[test]
    fn no_unloading_is_a_clear_error() {
        let tip = Tip::berkovich();
        let mut r = sneddon(1e5, 0.3, &tip);
        r.t.truncate(100);
        r.h.truncate(100);
        r.f.truncate(100);
        let e = analyse_record(&r, &tip, 0.3).unwrap_err().to_string();
        assert!(e.contains("test `cone`"), "{e}");
    }

    #[test]
    fn tips_of_punches() {
        assert_eq!(
            tip_for_punch(&Punch::Berkovich { tip_radius: None })
                .unwrap()
                .area,
            AreaFunction::Berkovich
        );
        assert!(
            tip_for_punch(&Punch::Tabulated {
                r: vec![0.0, 1.0],
                z: vec![0.0, 1.0]
            })
            .is_none()
        );
    }
}
