//! The Oliver-Pharr analysis of one record: its unloadings found, each fitted and turned
//! into stiffness, contact depth, area, hardness and moduli; the hold before it (creep) and
//! the work of the cycle.

use indentify_records::{Format, Record};
use serde::{Deserialize, Serialize};

use crate::error::AnalysisError;
use crate::fit::{PowerLaw, fit_power_law};
use crate::special::epsilon_of_m;
use crate::tip::Tip;

/// The force range of the unloading fit, as fractions of the unloading's `F_max`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitRange {
    /// Lower end (0 < lower < upper).
    pub lower: f64,
    /// Upper end (lower < upper <= 1).
    pub upper: f64,
}

impl FitRange {
    /// The vendor's default for a file format, and where it comes from:
    ///
    /// - Anton Paar: 40 % to 98 % (the `Unload Fit [40%,98%]` the Anton Paar export
    ///   `anonNI.TXT` states for its own O&P result);
    /// - KLA/Agilent/Keysight workbooks: 50 % to 95 % (the upper half of the unloading,
    ///   the stiffness window that the workbook's `Begin/End Of Stiffness Data Index`
    ///   markers delimit: 94 % to 47 % in `FusedSilica.xlsx`; the cycles of such tests unload
    ///   to 50 %);
    /// - every other format: 40 % to 98 %, as Anton Paar.
    pub fn for_format(format: Format) -> (FitRange, &'static str) {
        match format {
            Format::Kla => (
                FitRange {
                    lower: 0.5,
                    upper: 0.95,
                },
                "KLA default: the upper half of the unloading, as the workbook's stiffness markers",
            ),
            Format::AntonPaar | Format::AntonPaarMulti => (
                FitRange {
                    lower: 0.4,
                    upper: 0.98,
                },
                "Anton Paar default: Unload Fit [40%,98%]",
            ),
            _ => (
                FitRange {
                    lower: 0.4,
                    upper: 0.98,
                },
                "default 40 % to 98 % of F_max (Anton Paar's)",
            ),
        }
    }

    fn validate(&self) -> Result<(), AnalysisError> {
        if !(self.lower > 0.0 && self.lower < self.upper && self.upper <= 1.0) {
            return Err(AnalysisError::Option {
                field: "fit_range".into(),
                value: format!("{}..{}", self.lower, self.upper),
                expected: "0 < lower < upper <= 1 (fractions of F_max)".into(),
            });
        }
        Ok(())
    }
}

/// Where `epsilon` of `h_c = h_max - epsilon F_max / S` comes from.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub enum Epsilon {
    /// The tip's geometric value ([`crate::AreaFunction::epsilon`]: 0.75 Berkovich).
    #[default]
    Tip,
    /// From the fitted exponent `m` ([`crate::epsilon_of_m`]), as ISO 14577-1 allows.
    FromM,
    /// This value.
    Value(f64),
}

/// The options of [`analyze`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Options {
    /// The indenter.
    pub tip: Tip,
    /// Poisson's ratio of the sample (default 0.3).
    pub nu: f64,
    /// The force range of the unloading fit.
    pub fit_range: FitRange,
    /// The contact-depth factor.
    pub epsilon: Epsilon,
    /// `beta` of `E_r = sqrt(pi) S / (2 beta sqrt(A))`; default 1 (ISO 14577-1 has no
    /// correction factor; Anton Paar's own values are reproduced with 1).
    pub beta: f64,
    /// A drop of the force by this fraction of a peak makes the peak an unloading's start
    /// (default 0.1).
    pub drop: f64,
    /// Forces within this fraction of a peak count as the peak (the end of the hold, i.e. the
    /// start of the unloading, is the deepest such sample; the hold starts at the first
    /// sample within a fifth of it; default 0.01).
    pub hold_tolerance: f64,
    /// The shortest hold analysed for creep, s (default 0.5).
    pub min_hold: f64,
}

impl Options {
    /// The defaults for a tip and a format: `nu` 0.3, the format's fit range, the tip's
    /// epsilon, `beta` 1.
    pub fn new(tip: Tip, format: Format) -> Options {
        Options {
            tip,
            nu: 0.3,
            fit_range: FitRange::for_format(format).0,
            epsilon: Epsilon::Tip,
            beta: 1.0,
            drop: 0.1,
            hold_tolerance: 0.01,
            min_hold: 0.5,
        }
    }

    /// Checks every option.
    ///
    /// # Errors
    /// [`AnalysisError::Option`] naming the option and its allowed range.
    pub fn validate(&self) -> Result<(), AnalysisError> {
        self.tip.validate()?;
        self.fit_range.validate()?;
        let bad = |field: &str, v: f64, expected: &str| AnalysisError::Option {
            field: field.into(),
            value: v.to_string(),
            expected: expected.into(),
        };
        if !(self.nu > -1.0 && self.nu < 0.5) {
            return Err(bad("nu", self.nu, "-1 < nu < 0.5"));
        }
        if !(self.beta > 0.5 && self.beta < 2.0) {
            return Err(bad("beta", self.beta, "0.5 < beta < 2"));
        }
        if let Epsilon::Value(e) = self.epsilon {
            if !(e > 0.0 && e <= 1.0) {
                return Err(bad("epsilon", e, "0 < epsilon <= 1"));
            }
        }
        if !(self.drop > 0.0 && self.drop < 1.0) {
            return Err(bad("drop", self.drop, "0 < drop < 1"));
        }
        if !(self.hold_tolerance > 0.0 && self.hold_tolerance < self.drop) {
            return Err(bad(
                "hold_tolerance",
                self.hold_tolerance,
                "0 < tolerance < drop",
            ));
        }
        if !(self.min_hold >= 0.0 && self.min_hold.is_finite()) {
            return Err(bad("min_hold", self.min_hold, "a finite time >= 0 (s)"));
        }
        Ok(())
    }
}

/// The Oliver-Pharr quantities of one unloading (N, mm, MPa).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OliverPharr {
    /// Contact stiffness `S = dF/dh` of the fit at `h_max`, N/mm.
    pub s: f64,
    /// The `epsilon` used.
    pub epsilon: f64,
    /// Contact depth `h_c = h_max - epsilon F_max / S`, mm.
    pub hc: f64,
    /// Projected contact area `A_p(h_c)`, mm^2.
    pub area: f64,
    /// Indentation hardness `H_IT = F_max / A_p`, MPa.
    pub hardness: f64,
    /// Reduced modulus `E_r = sqrt(pi) S / (2 beta sqrt(A_p))`, MPa.
    pub er: f64,
    /// Plane-strain modulus of the sample `E* = 1 / (1/E_r - (1 - nu_i^2)/E_i)`, MPa (`None`
    /// when `E_r` is too large for the tip's modulus).
    pub e_star: Option<f64>,
    /// Indentation modulus `E_IT = (1 - nu^2) E*`, MPa.
    pub e: Option<f64>,
    /// The tangent depth `h_r = h_max - F_max / S` (ISO 14577's intercept), mm.
    pub hr: f64,
}

/// The hold at the peak before an unloading (load control: the force held).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Hold {
    /// Start and end time, s.
    pub t: (f64, f64),
    /// Depth at its start and end, mm.
    pub h: (f64, f64),
    /// Mean force over the hold, N.
    pub f_mean: f64,
    /// Depth increase, mm.
    pub creep: f64,
    /// ISO 14577 `C_IT = 100 (h_1 - h_0) / h_0`, %.
    pub c_it: f64,
    /// Creep rate over the last quarter of the hold (least-squares slope), mm/s.
    pub rate: f64,
    /// Indentation strain rate `rate / h_1` at the end, 1/s.
    pub strain_rate: f64,
    /// Strain-rate sensitivity `d ln H / d ln(h'/h)` over the hold (8 windows, `H ~ F/h^2`
    /// of a self-similar tip), when at least 3 windows creep forward.
    pub srs: Option<f64>,
}

/// The work of a cycle, N mm (= mJ).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Work {
    /// Net work of the force from contact to the start of the unloading, `int F dh`.
    pub total: f64,
    /// Work recovered during the unloading (to its end), `-int F dh`.
    pub elastic: f64,
    /// ISO 14577 `eta_IT = W_elast / W_total`, %.
    pub eta: f64,
}

/// One unloading of a test.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Unloading {
    /// 1-based number within the test.
    pub number: usize,
    /// Sample indices of the peak, the start and the end of the unloading.
    pub samples: (usize, usize, usize),
    /// Time at the start of the unloading, s.
    pub t_start: f64,
    /// Force at the start of the unloading, N.
    pub f_max: f64,
    /// Depth at the start of the unloading, mm.
    pub h_max: f64,
    /// The power-law fit, when it worked.
    pub fit: Option<PowerLaw>,
    /// The Oliver-Pharr values, when the fit worked.
    pub op: Option<OliverPharr>,
    /// The hold before the unloading, when there is one.
    pub hold: Option<Hold>,
    /// The work of the cycle.
    pub work: Work,
    /// Why this unloading gave no values.
    pub error: Option<String>,
    /// Doubts about the values (m outside 1..2, E not computable, ...).
    pub warnings: Vec<String>,
}

/// The analysis of one test.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TestAnalysis {
    /// Test name.
    pub test: String,
    /// Every unloading found, in time order.
    pub unloadings: Vec<Unloading>,
    /// Index (into `unloadings`) of the analysed unloading from the highest force: the
    /// test's values.
    pub main: Option<usize>,
    /// Why the test gave no values at all.
    pub error: Option<String>,
}

impl TestAnalysis {
    /// The test's values: those of its main unloading.
    pub fn values(&self) -> Option<(&Unloading, &OliverPharr)> {
        let u = self.unloadings.get(self.main?)?;
        Some((u, u.op.as_ref()?))
    }
}

/// Peak, start, end of each unloading, and the first sample at the peak's level before it.
struct Found {
    level_start: usize,
    peak: usize,
    start: usize,
    end: usize,
}

fn find_unloadings(h: &[f64], f: &[f64], drop: f64, tol: f64) -> Vec<Found> {
    let n = f.len();
    let f_top = f.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let floor = (1e-3 * f_top).max(f64::MIN_POSITIVE);
    // a force that falls while the depth does not recede is relaxing at a held depth (a
    // depth-controlled hold), not unloading: the unloading starts where the depth recedes
    let h_top = h.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let recede = 1e-3 * h_top;
    let mut out = Vec::new();
    let mut from = 0;
    while from < n {
        let mut k = from;
        let mut i = from;
        let mut confirmed = false;
        // the first drop at a held depth, taken for the unloading when the depth never
        // recedes afterwards (its analysis then says why it is no unloading)
        let mut first_drop: Option<(usize, usize)> = None;
        while i < n {
            if f[i] > f[k] {
                k = i;
            } else if f[k] > floor && f[i] < (1.0 - drop) * f[k] {
                let deepest = h[k..=i].iter().copied().fold(f64::NEG_INFINITY, f64::max);
                if h[i] < deepest - recede {
                    confirmed = true;
                    break;
                }
                // relaxation at the held depth: the peak to unload from is later
                first_drop.get_or_insert((k, i));
                k = i;
            }
            i += 1;
        }
        if !confirmed {
            match first_drop {
                Some((k0, i0)) => (k, i) = (k0, i0),
                None => break,
            }
        }
        // after a relaxation at a held depth the unloading starts at the hold's end, the
        // last sample at the deepest depth, and the hold itself where that depth is reached
        let mut held = None;
        if first_drop.is_some() && confirmed {
            let deepest = h[from..=i]
                .iter()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max);
            let at = |q: &usize| h[*q] >= deepest - 0.1 * recede;
            k = (from..=i).rev().find(at).unwrap_or(k);
            held = (from..=k).find(at);
        }
        let mut m = i;
        let mut j = i;
        while j < n {
            if f[j] < f[m] {
                m = j;
            } else if f[j] > f[m] + 0.5 * drop * f[k] {
                break;
            }
            j += 1;
        }
        let level = (1.0 - tol) * f[k];
        // the end of the hold at the peak: of the samples at the peak's level, the deepest
        // (creep deepens a load-controlled hold; the unloading's first samples, which may
        // still be within the tolerance, are shallower)
        let start = (k..i)
            .filter(|&q| f[q] >= level)
            .max_by(|&a, &b| h[a].total_cmp(&h[b]))
            .unwrap_or(k);
        // the hold starts where the force first comes within a fifth of the tolerance of
        // the peak (0.2 % by default): the loading's last samples are not counted as creep
        let hold_level = (1.0 - 0.2 * tol) * f[k];
        let level_start =
            held.unwrap_or_else(|| (from..=k).find(|&q| f[q] >= hold_level).unwrap_or(k));
        out.push(Found {
            level_start,
            peak: k,
            start,
            end: m,
        });
        if m <= from {
            break;
        }
        from = m;
    }
    out
}

/// Least-squares slope of `y` on `x`.
fn slope(x: &[f64], y: &[f64]) -> Option<f64> {
    let n = x.len();
    if n < 2 {
        return None;
    }
    let mx = x.iter().sum::<f64>() / n as f64;
    let my = y.iter().sum::<f64>() / n as f64;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (&a, &b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
    }
    (sxx > 0.0).then(|| sxy / sxx)
}

fn hold_of(r: &Record, a: usize, b: usize, min_hold: f64) -> Option<Hold> {
    if b <= a + 2 || r.t[b] - r.t[a] < min_hold {
        return None;
    }
    let (t, h, f) = (&r.t[a..=b], &r.h[a..=b], &r.f[a..=b]);
    let n = t.len();
    let (h0, h1) = (h[0], h[n - 1]);
    let q = n - (n / 4).max(3).min(n);
    let rate = slope(&t[q..], &h[q..]).unwrap_or(0.0);
    // strain-rate sensitivity over 8 windows of equal duration
    let (t0, t1) = (t[0], t[n - 1]);
    let mut le = Vec::new();
    let mut lh = Vec::new();
    for w in 0..8 {
        let lo = t0 + (t1 - t0) * w as f64 / 8.0;
        let hi = t0 + (t1 - t0) * (w + 1) as f64 / 8.0;
        let idx: Vec<usize> = (0..n).filter(|&i| t[i] >= lo && t[i] <= hi).collect();
        if idx.len() < 3 {
            continue;
        }
        let tt: Vec<f64> = idx.iter().map(|&i| t[i]).collect();
        let hh: Vec<f64> = idx.iter().map(|&i| h[i]).collect();
        let hm = hh.iter().sum::<f64>() / hh.len() as f64;
        let fm = idx.iter().map(|&i| f[i]).sum::<f64>() / idx.len() as f64;
        if let Some(v) = slope(&tt, &hh) {
            if v > 0.0 && hm > 0.0 && fm > 0.0 {
                le.push((v / hm).ln());
                lh.push((fm / (hm * hm)).ln());
            }
        }
    }
    let srs = if le.len() >= 3 { slope(&le, &lh) } else { None };
    Some(Hold {
        t: (t0, t1),
        h: (h0, h1),
        f_mean: f.iter().sum::<f64>() / n as f64,
        creep: h1 - h0,
        c_it: if h0 > 0.0 {
            100.0 * (h1 - h0) / h0
        } else {
            f64::NAN
        },
        rate,
        strain_rate: if h1 > 0.0 { rate / h1 } else { f64::NAN },
        srs,
    })
}

fn integral(h: &[f64], f: &[f64]) -> f64 {
    (1..h.len())
        .map(|i| 0.5 * (f[i] + f[i - 1]) * (h[i] - h[i - 1]))
        .sum()
}

/// The Oliver-Pharr values of an unloading from its `F_max`, `h_max` and fitted `S`.
///
/// # Errors
/// A sentence: a contact depth that is not positive, an area that is not (a sphere
/// indented deeper than its radius).
pub fn oliver_pharr(
    f_max: f64,
    h_max: f64,
    s: f64,
    epsilon: f64,
    o: &Options,
) -> Result<(OliverPharr, Vec<String>), String> {
    let mut warnings = Vec::new();
    let hc = h_max - epsilon * f_max / s;
    if !(hc > 0.0) {
        return Err(format!(
            "the contact depth h_c = h_max - {epsilon:.3} F_max/S = {:.3} nm is not positive (h_max {:.3} nm, F_max/S {:.3} nm)",
            hc * 1e6,
            h_max * 1e6,
            f_max / s * 1e6
        ));
    }
    let area = o.tip.area.area(hc);
    if !(area > 0.0 && area.is_finite()) {
        return Err(format!(
            "the tip's area function gives A = {area} mm^2 at h_c = {:.3} nm ({})",
            hc * 1e6,
            o.tip.area.describe()
        ));
    }
    let er = std::f64::consts::PI.sqrt() * s / (2.0 * o.beta * area.sqrt());
    let inv = 1.0 / er - o.tip.compliance_share();
    let e_star = if inv > 0.0 {
        Some(1.0 / inv)
    } else {
        warnings.push(format!(
            "E_r = {:.4} GPa is at least the tip's own E_i/(1 - nu_i^2) = {:.4} GPa: the sample modulus cannot be separated",
            er * 1e-3,
            1e-3 / o.tip.compliance_share()
        ));
        None
    };
    Ok((
        OliverPharr {
            s,
            epsilon,
            hc,
            area,
            hardness: f_max / area,
            er,
            e_star,
            e: e_star.map(|v| v * (1.0 - o.nu * o.nu)),
            hr: h_max - f_max / s,
        },
        warnings,
    ))
}

/// Analyses every unloading of a record (time, depth and force from contact: the zero
/// point and any drift and frame-compliance corrections already applied). One unloading's
/// failure does not stop the others; a test without an unloading gets its `error`.
///
/// # Errors
/// [`AnalysisError::Option`] for options out of range (nothing is analysed then).
pub fn analyze(r: &Record, o: &Options) -> Result<TestAnalysis, AnalysisError> {
    o.validate()?;
    let n = r.t.len().min(r.h.len()).min(r.f.len());
    let mut out = TestAnalysis {
        test: r.name.clone(),
        unloadings: Vec::new(),
        main: None,
        error: None,
    };
    if n < 5 {
        out.error = Some(format!(
            "{n} samples; an analysis needs a loading and an unloading"
        ));
        return Ok(out);
    }
    if let Some(i) =
        (0..n).find(|&i| !(r.t[i].is_finite() && r.h[i].is_finite() && r.f[i].is_finite()))
    {
        out.error = Some(format!("sample {i} is not finite"));
        return Ok(out);
    }
    let found = find_unloadings(&r.h[..n], &r.f[..n], o.drop, o.hold_tolerance);
    if found.is_empty() {
        out.error = Some(format!(
            "no unloading: the force never falls by {} % of a peak (largest force {:.4} mN at sample {} of {n})",
            o.drop * 100.0,
            r.f_max() * 1e3,
            r.f.iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))
                .map_or(0, |x| x.0)
        ));
        return Ok(out);
    }
    for (k, u) in found.iter().enumerate() {
        let (s, e) = (u.start, u.end);
        let f_max = r.f[s];
        let h_max = r.h[s];
        let hold = hold_of(r, u.level_start, s, o.min_hold);
        let w_total = integral(&r.h[..=s], &r.f[..=s]);
        let w_el = -integral(&r.h[s..=e], &r.f[s..=e]);
        let mut un = Unloading {
            number: k + 1,
            samples: (u.peak, s, e),
            t_start: r.t[s],
            f_max,
            h_max,
            fit: None,
            op: None,
            hold,
            work: Work {
                total: w_total,
                elastic: w_el,
                eta: if w_total > 0.0 {
                    100.0 * w_el / w_total
                } else {
                    f64::NAN
                },
            },
            error: None,
            warnings: Vec::new(),
        };
        let lo = o.fit_range.lower * f_max;
        let hi = o.fit_range.upper * f_max;
        let (hs, fs): (Vec<f64>, Vec<f64>) = (s..=e)
            .filter(|&i| r.f[i] >= lo && r.f[i] <= hi)
            .map(|i| (r.h[i], r.f[i]))
            .unzip();
        let f_end = r.f[e];
        if f_end > lo + 0.2 * (hi - lo) {
            un.warnings.push(format!(
                "the unloading ends at {:.1} % of F_max, inside the fit range {:.0} %..{:.0} %: fitted over the part that exists",
                100.0 * f_end / f_max,
                o.fit_range.lower * 100.0,
                o.fit_range.upper * 100.0
            ));
        }
        match fit_power_law(&hs, &fs, h_max, f_max) {
            Err(reason) => un.error = Some(reason),
            Ok(fit) => {
                let stiffness = fit.slope(h_max);
                if !(fit.m >= 1.0 && fit.m <= 2.0) {
                    un.warnings.push(format!(
                        "m = {:.3} is outside 1..2, the range of the Oliver-Pharr shapes (flat punch to cone)",
                        fit.m
                    ));
                }
                let eps = match o.epsilon {
                    crate::op::Epsilon::Tip => o.tip.area.epsilon(),
                    crate::op::Epsilon::Value(v) => v,
                    crate::op::Epsilon::FromM => {
                        let v = epsilon_of_m(fit.m.clamp(1.0, 9.99));
                        if !(fit.m >= 1.0) {
                            un.warnings
                                .push("epsilon(m) taken at m = 1 (flat punch): m < 1".into());
                        }
                        v
                    }
                };
                if !(stiffness > 0.0 && stiffness.is_finite()) {
                    un.error = Some(format!(
                        "the fitted stiffness at h_max is {stiffness} N/mm; expected a positive number"
                    ));
                } else {
                    match oliver_pharr(f_max, h_max, stiffness, eps, o) {
                        Ok((op, w)) => {
                            un.op = Some(op);
                            un.warnings.extend(w);
                        }
                        Err(reason) => un.error = Some(reason),
                    }
                }
                un.fit = Some(fit);
            }
        }
        out.unloadings.push(un);
    }
    out.main = out
        .unloadings
        .iter()
        .enumerate()
        .filter(|(_, u)| u.op.is_some())
        .max_by(|a, b| a.1.f_max.total_cmp(&b.1.f_max))
        .map(|(i, _)| i);
    if out.main.is_none() {
        out.error = Some(format!(
            "none of its {} unloading(s) could be analysed: {}",
            out.unloadings.len(),
            out.unloadings
                .iter()
                .map(|u| format!(
                    "unloading {}: {}",
                    u.number,
                    u.error.as_deref().unwrap_or("?")
                ))
                .collect::<Vec<_>>()
                .join("; ")
        ));
    }
    Ok(out)
}
