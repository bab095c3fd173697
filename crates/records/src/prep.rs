//! Preprocessing of a [`Record`]: thermal drift, zero point (contact), frame compliance,
//! load/hold/unload segments, resampling. Each step is a pure function returning the new
//! record and an [`Applied`] account with numbers; [`apply`] runs the chosen ones in a fixed
//! order.

use serde::{Deserialize, Serialize};

use crate::error::PrepError;
use crate::record::{Quantity, Record};

/// Where a correction's coefficient comes from.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub enum Correction {
    /// No correction.
    #[default]
    Off,
    /// The file's hint when it gives one, else no correction (said in the account).
    Auto,
    /// The file's hint; an error ([`PrepError::NoHint`]) when the file gives none.
    FromFile,
    /// This value, in internal units (drift mm/s, compliance mm/N).
    Value(f64),
}

/// Zero-point (contact) detection; see [`zero_point`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ZeroPoint {
    /// Threshold through which the force must rise, as a fraction of `F_max - F_min`
    /// (0 < fraction < 1). Default 0.02.
    pub fraction: f64,
    /// Threshold above the minimum force, N; replaces `fraction` when set (> 0).
    pub threshold: Option<f64>,
    /// Half-width of the pre-contact band around the baseline, in robust standard deviations
    /// (1.4826 MAD) of the baseline force (>= 0). Default 3.
    pub noise_band: f64,
    /// Drop the samples before contact (the approach). Default true.
    pub trim: bool,
    /// Contact at the first sample where the median over 5 samples of `|dF/dh|` exceeds
    /// this stiffness, N/mm (> 0), instead of the force threshold (indentationGUI's
    /// surface; for multi-cycle tests whose first cycles stay below the threshold).
    /// Default `None`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
}

impl Default for ZeroPoint {
    fn default() -> Self {
        Self {
            fraction: 0.02,
            threshold: None,
            noise_band: 3.0,
            trim: true,
            stiffness: None,
        }
    }
}

/// Which quantity the instrument controlled (decides how a hold is recognised).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Control {
    /// From the file's protocol (`Displacement`/`Depth` in the control mode means depth),
    /// else load.
    #[default]
    Auto,
    /// Load (force) control: a hold keeps the force.
    Load,
    /// Depth (displacement) control: a hold keeps the depth.
    Depth,
}

/// Segment detection and mapping; see [`segments`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Segments {
    /// Controlled quantity. Default `Auto`.
    pub control: Control,
    /// Relative tolerance (of the quantity's range) under which a quantity counts as
    /// constant (0 < tolerance < 0.5). Default 0.01.
    pub tolerance: f64,
    /// Shortest hold recognised when the file has no segment ids, s (>= 0). Default 0.5.
    pub min_hold: f64,
}

impl Default for Segments {
    fn default() -> Self {
        Self {
            control: Control::Auto,
            tolerance: 0.01,
            min_hold: 0.5,
        }
    }
}

/// Resampling for the simulation; see [`resample`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Resample {
    /// Number of points of the result (in `[2, MAX_RESAMPLE_POINTS]`, and at least one
    /// more than the number of segments). Default 200. Refused out of range already while
    /// parsing (a RON error then carries the line).
    #[serde(deserialize_with = "deserialize_points")]
    pub n: usize,
    /// Fewest intervals per segment, when `n` allows. Default 5.
    pub min_per_segment: usize,
}

/// The most points [`resample`] makes: each drives a step of the simulation (a record of
/// 10^5 points already takes hours to simulate).
pub const MAX_RESAMPLE_POINTS: usize = 100_000;

/// What `resample.n` allows, in words.
fn points_allowed() -> String {
    format!("an integer in [2, {MAX_RESAMPLE_POINTS}] points")
}

/// `resample.n`, refused outside `[2, MAX_RESAMPLE_POINTS]`.
fn deserialize_points<'de, D: serde::Deserializer<'de>>(d: D) -> Result<usize, D::Error> {
    let n = u64::deserialize(d)?;
    match usize::try_from(n) {
        Ok(n) if (2..=MAX_RESAMPLE_POINTS).contains(&n) => Ok(n),
        _ => Err(serde::de::Error::custom(format!(
            "resample.n = {n} is not allowed: expected {}",
            points_allowed()
        ))),
    }
}

impl Default for Resample {
    fn default() -> Self {
        Self {
            n: 200,
            min_per_segment: 5,
        }
    }
}

/// The preprocessing to run, as embedded in a RON config (every field optional):
///
/// ```ron
/// (
///     drift: Auto,                 // Off | Auto | FromFile | Value(mm/s)
///     zero_point: Some((fraction: 0.02, noise_band: 3.0, trim: true)),
///     compliance: Value(0.0066),   // Off | Auto | FromFile | Value(mm/N)
///     segments: Some((control: Auto, tolerance: 0.01, min_hold: 0.5)),
///     resample: Some((n: 200, min_per_segment: 5)),
/// )
/// ```
///
/// Steps run in this order (see [`apply`]): drift, zero point, compliance, segments,
/// resample. Defaults: zero point and segments on, drift and compliance off, no
/// resampling.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Preprocessing {
    /// Thermal drift `h <- h - rate t` (on the file's time, before the zero point).
    pub drift: Correction,
    /// Contact detection, offsets, trimming and time shift; `None` skips it.
    pub zero_point: Option<ZeroPoint>,
    /// Frame compliance `h <- h - C F` (after the zero point, on the offset force).
    pub compliance: Correction,
    /// Load/hold/unload segments (detected, or mapped from the file's ids); `None` skips.
    pub segments: Option<Segments>,
    /// Resampling to `n` points; `None` keeps the samples.
    pub resample: Option<Resample>,
}

impl Default for Preprocessing {
    fn default() -> Self {
        Self {
            drift: Correction::Off,
            zero_point: Some(ZeroPoint::default()),
            compliance: Correction::Off,
            segments: Some(Segments::default()),
            resample: None,
        }
    }
}

/// The account of one step, for the report: name, a sentence, and its numbers.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Applied {
    /// Step name: `drift`, `zero_point`, `compliance`, `segments`, `resample`.
    pub step: String,
    /// What was done, in words with the main numbers.
    pub description: String,
    /// The numbers (report units: nm, mN, s, nm/s, nm/mN).
    pub values: Vec<Quantity>,
}

impl Applied {
    fn new(step: &str, description: String, values: Vec<Quantity>) -> Self {
        Self {
            step: step.to_owned(),
            description,
            values,
        }
    }
}

/// What a segment does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Phase {
    /// Force and depth rise.
    Load,
    /// Force or depth stays (creep or relaxation).
    Hold,
    /// Force and depth fall.
    Unload,
}

/// A run of samples with the same segment id.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Span {
    /// Segment id.
    pub id: u32,
    /// What it does.
    pub phase: Phase,
    /// First sample index.
    pub start: usize,
    /// Last sample index (inclusive).
    pub end: usize,
    /// Time of the first sample, s.
    pub t0: f64,
    /// Time of the last sample, s.
    pub t1: f64,
}

/// Runs the chosen steps in a fixed order and returns the new record and their accounts:
///
/// 1. drift: `h <- h - rate t` with the file's time (the constant `rate t_contact` is then
///    taken out by the zero point);
/// 2. zero point: contact detection, `h` and `F` offsets, approach trimmed, `t = 0` at
///    contact;
/// 3. compliance: `h <- h - C F` on the offset force (about zero at contact, so `h(0)`
///    stays about 0: the baseline noise times `C`);
/// 4. segments: load/hold/unload, detected or mapped from the file's ids;
/// 5. resample: `n` points from `t = 0`, segment boundaries and peak depth kept.
///
/// # Errors
///
/// [`PrepError::Record`] for an inconsistent record, [`PrepError::Option`] for options out
/// of range, and those of each step.
pub fn apply(record: &Record, p: &Preprocessing) -> Result<(Record, Vec<Applied>), PrepError> {
    validate(record)?;
    let mut r = record.clone();
    let mut done = Vec::new();
    if p.drift != Correction::Off {
        let (x, a) = drift(&r, p.drift)?;
        r = x;
        done.push(a);
    }
    if let Some(z) = &p.zero_point {
        let (x, a) = zero_point(&r, z)?;
        r = x;
        done.push(a);
    }
    if p.compliance != Correction::Off {
        let (x, a) = compliance(&r, p.compliance)?;
        r = x;
        done.push(a);
    }
    if let Some(s) = &p.segments {
        let (x, a) = segments(&r, s)?;
        r = x;
        done.push(a);
    }
    if let Some(s) = &p.resample {
        let (x, a) = resample(&r, s)?;
        r = x;
        done.push(a);
    }
    Ok((r, done))
}

/// Checks what the steps rely on: equal lengths, at least two samples, finite values, a
/// time that never decreases.
///
/// # Errors
///
/// [`PrepError::Record`] naming the first problem.
pub fn validate(r: &Record) -> Result<(), PrepError> {
    let bad = |what: String, expected: &str| PrepError::Record {
        record: r.name.clone(),
        what,
        expected: expected.to_owned(),
    };
    let n = r.t.len();
    if r.h.len() != n || r.f.len() != n || r.segment.as_ref().is_some_and(|s| s.len() != n) {
        return Err(bad(
            format!(
                "lengths differ: t {}, h {}, F {}, segment {}",
                n,
                r.h.len(),
                r.f.len(),
                r.segment.as_ref().map_or(n, Vec::len)
            ),
            "t, h, F (and segment) of equal length",
        ));
    }
    if n < 2 {
        return Err(PrepError::TooShort {
            record: r.name.clone(),
            step: "input",
            n,
            min: 2,
        });
    }
    for i in 0..n {
        if !(r.t[i].is_finite() && r.h[i].is_finite() && r.f[i].is_finite()) {
            return Err(bad(
                format!(
                    "sample {i} is not finite (t {}, h {}, F {})",
                    r.t[i], r.h[i], r.f[i]
                ),
                "finite values",
            ));
        }
        if i > 0 && r.t[i] < r.t[i - 1] {
            return Err(bad(
                format!(
                    "time goes back at sample {i}: {} s then {} s",
                    r.t[i - 1],
                    r.t[i]
                ),
                "a time that never decreases",
            ));
        }
    }
    Ok(())
}

fn option_error(field: &'static str, value: impl std::fmt::Display, expected: &str) -> PrepError {
    PrepError::Option {
        field,
        value: value.to_string(),
        expected: expected.to_owned(),
    }
}

/// The coefficient of a correction: (value, source), or `None` for no correction.
fn coefficient(
    r: &Record,
    c: Correction,
    hint: Option<f64>,
    step: &'static str,
    what: &'static str,
    field: &'static str,
) -> Result<Option<(f64, &'static str)>, PrepError> {
    match c {
        Correction::Off => Ok(None),
        Correction::Auto => Ok(hint.filter(|v| v.is_finite()).map(|v| (v, "the file"))),
        Correction::FromFile => match hint.filter(|v| v.is_finite()) {
            Some(v) => Ok(Some((v, "the file"))),
            None => Err(PrepError::NoHint {
                record: r.name.clone(),
                step,
                what,
            }),
        },
        Correction::Value(v) if v.is_finite() => Ok(Some((v, "the options"))),
        Correction::Value(v) => Err(option_error(field, v, "a finite number")),
    }
}

/// Thermal-drift correction `h <- h - rate t` (time as in the record).
///
/// # Errors
///
/// [`PrepError::NoHint`] for `FromFile` without a file hint; [`PrepError::Option`] for a
/// non-finite value; [`PrepError::Record`] for an inconsistent record.
pub fn drift(r: &Record, c: Correction) -> Result<(Record, Applied), PrepError> {
    validate(r)?;
    let Some((rate, source)) =
        coefficient(r, c, r.meta.drift_rate, "drift", "drift rate", "drift")?
    else {
        return Ok((
            r.clone(),
            Applied::new(
                "drift",
                "no drift correction: the file gives no drift rate".into(),
                vec![],
            ),
        ));
    };
    let mut x = r.clone();
    for (h, t) in x.h.iter_mut().zip(&r.t) {
        *h -= rate * t;
    }
    let t_end = r.t.last().copied().unwrap_or(0.0);
    let total = rate * t_end;
    Ok((
        x,
        Applied::new(
            "drift",
            format!(
                "thermal drift h <- h - rate t with rate {:.6} nm/s from {source}: {:.3} nm at t = {:.3} s",
                rate * 1e6,
                total * 1e6,
                t_end
            ),
            vec![
                Quantity::new("rate", rate * 1e6, "nm/s"),
                Quantity::new("correction at end", total * 1e6, "nm"),
            ],
        ),
    ))
}

/// Frame-compliance correction `h <- h - C F`.
///
/// # Errors
///
/// [`PrepError::NoHint`] for `FromFile` without a file hint; [`PrepError::Option`] for a
/// non-finite value; [`PrepError::Record`] for an inconsistent record.
pub fn compliance(r: &Record, c: Correction) -> Result<(Record, Applied), PrepError> {
    validate(r)?;
    let Some((cf, source)) = coefficient(
        r,
        c,
        r.meta.frame_compliance,
        "compliance",
        "frame compliance",
        "compliance",
    )?
    else {
        return Ok((
            r.clone(),
            Applied::new(
                "compliance",
                "no frame-compliance correction: the file gives no compliance".into(),
                vec![],
            ),
        ));
    };
    let mut x = r.clone();
    for (h, f) in x.h.iter_mut().zip(&r.f) {
        *h -= cf * f;
    }
    let fmax = r.f_max();
    Ok((
        x,
        Applied::new(
            "compliance",
            format!(
                "frame compliance h <- h - C F with C = {:.6} nm/mN from {source}: {:.3} nm at F_max = {:.4} mN",
                cf * 1e3,
                cf * fmax * 1e6,
                fmax * 1e3
            ),
            vec![
                Quantity::new("C", cf * 1e3, "nm/mN"),
                Quantity::new("correction at F_max", cf * fmax * 1e6, "nm"),
            ],
        ),
    ))
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return 0.0;
    }
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn argmax(v: &[f64]) -> usize {
    let mut k = 0;
    for (i, &x) in v.iter().enumerate() {
        if x > v[k] {
            k = i;
        }
    }
    k
}

/// Zero point: finds the contact, subtracts the offsets, trims the approach and puts
/// `t = 0` at contact.
///
/// The force must rise through `F_min + fraction (F_max - F_min)` (or `F_min + threshold`)
/// before its maximum; `i_cross` is the sample after the last one below it. The baseline is
/// the first half of the samples before `i_cross`: `F_0` = their median, `s` = 1.4826 times
/// their median absolute deviation. Contact is the last sample before `i_cross` with
/// `F <= F_0 + noise_band s` (sample 0 if none). A record that starts in contact (no flat
/// stretch: a least-squares line through the baseline window rises over it by more than
/// `2 noise_band` times the scatter about the line)
/// has its contact at sample 0 and `F_0 = F[0]`: instruments that zero themselves at contact
/// (Anton Paar) write such records, and a baseline taken from the start of the loading
/// curve would cut a slice off the depth. Then `h <- h - h[contact]`,
/// `F <- F - F_0`, `t <- t - t[contact]`, and with `trim` the samples before contact go.
///
/// # Errors
///
/// [`PrepError::NoContact`] when the force never rises through the threshold,
/// [`PrepError::TooShort`] when fewer than 2 samples remain, [`PrepError::Option`] for
/// options out of range, [`PrepError::Record`] for an inconsistent record.
pub fn zero_point(r: &Record, o: &ZeroPoint) -> Result<(Record, Applied), PrepError> {
    validate(r)?;
    if !(o.fraction > 0.0 && o.fraction < 1.0) {
        return Err(option_error(
            "zero_point.fraction",
            o.fraction,
            "0 < fraction < 1",
        ));
    }
    if !(o.noise_band >= 0.0 && o.noise_band.is_finite()) {
        return Err(option_error(
            "zero_point.noise_band",
            o.noise_band,
            "a finite number >= 0",
        ));
    }
    if let Some(th) = o.threshold {
        if !(th > 0.0 && th.is_finite()) {
            return Err(option_error(
                "zero_point.threshold",
                th,
                "a finite force > 0 (N)",
            ));
        }
    }
    if let Some(k) = o.stiffness {
        return stiffness_zero_point(r, o, k);
    }
    let f = &r.f;
    let i_max = argmax(f);
    let f_max = f.get(i_max).copied().unwrap_or(0.0);
    let f_min = f
        .get(..=i_max)
        .unwrap_or(&[])
        .iter()
        .copied()
        .fold(f_max, f64::min);
    let rise = o.threshold.unwrap_or(o.fraction * (f_max - f_min));
    let level = f_min + rise;
    let no_contact = || PrepError::NoContact {
        record: r.name.clone(),
        threshold_mn: rise * 1e3,
        baseline_mn: f_min * 1e3,
        max_mn: f_max * 1e3,
        min_mn: f.iter().copied().fold(f64::INFINITY, f64::min) * 1e3,
    };
    if !(rise > 0.0) || !(f_max > level) {
        return Err(no_contact());
    }
    // the sample after the last one below the level, before the maximum
    let i_cross = f
        .get(..=i_max)
        .unwrap_or(&[])
        .iter()
        .rposition(|&x| x < level)
        .map_or(0, |i| i + 1);
    let (base, sigma) = if i_cross >= 1 {
        let m = i_cross.div_ceil(2);
        let mut w: Vec<f64> = f.get(..m).unwrap_or(&[]).to_vec();
        let base = median(&mut w);
        let mut dev: Vec<f64> = w.iter().map(|x| (x - base).abs()).collect();
        (base, 1.4826 * median(&mut dev))
    } else {
        (f.first().copied().unwrap_or(0.0), 0.0)
    };
    // A record that starts at contact (the instrument zeroed itself there) has no flat
    // stretch before the crossing: its "baseline" window rises. Least-squares line through
    // the window: rising when its rise over the window exceeds 2 noise_band times the
    // scatter about the line (a flat, noisy or falling baseline does not).
    let rising = i_cross >= 8 && {
        let m = i_cross.div_ceil(2);
        let (tw, fw) = (r.t.get(..m).unwrap_or(&[]), f.get(..m).unwrap_or(&[]));
        let n = tw.len() as f64;
        let tm = tw.iter().sum::<f64>() / n;
        let fm = fw.iter().sum::<f64>() / n;
        let stt: f64 = tw.iter().map(|t| (t - tm) * (t - tm)).sum();
        let stf: f64 = tw.iter().zip(fw).map(|(t, x)| (t - tm) * (x - fm)).sum();
        let slope = if stt > 0.0 { stf / stt } else { 0.0 };
        let scatter = (tw
            .iter()
            .zip(fw)
            .map(|(t, x)| (x - fm - slope * (t - tm)).powi(2))
            .sum::<f64>()
            / n)
            .sqrt();
        let span = tw.last().copied().unwrap_or(0.0) - tw.first().copied().unwrap_or(0.0);
        slope > 0.0
            && slope * span > 2.0 * o.noise_band.max(1.0) * scatter + 1e-12 * (f_max - f_min).abs()
    };
    let (base, sigma) = if rising {
        (f.first().copied().unwrap_or(0.0), 0.0)
    } else {
        (base, sigma)
    };
    let band = o.noise_band * sigma + 1e-12 * (f_max - f_min).abs();
    let contact = if rising {
        0
    } else {
        f.get(..i_cross)
            .unwrap_or(&[])
            .iter()
            .rposition(|&x| x <= base + band)
            .unwrap_or(0)
    };
    let (t0, h0) = (r.t[contact], r.h[contact]);
    let x = shifted_from(r, contact, o.trim, (t0, h0, base))?;
    let a = Applied::new(
        "zero_point",
        format!(
            "contact at t = {t0:.4} s (sample {contact}{}, force rising through {:.4} mN above {:.4} mN): h offset {:.3} nm, F offset {:.5} mN (baseline noise {:.5} mN), {} approach samples {}; t = 0 at contact",
            if rising {
                ": the record starts in contact, its force rising from the first sample"
            } else {
                ""
            },
            rise * 1e3,
            f_min * 1e3,
            h0 * 1e6,
            base * 1e3,
            sigma * 1e3,
            contact,
            if o.trim { "dropped" } else { "kept" }
        ),
        vec![
            Quantity::new("contact time", t0, "s"),
            Quantity::new("h offset", h0 * 1e6, "nm"),
            Quantity::new("F offset", base * 1e3, "mN"),
            Quantity::new("baseline noise", sigma * 1e3, "mN"),
            Quantity::new("threshold", rise * 1e3, "mN"),
            Quantity::new(
                "samples dropped",
                if o.trim { contact as f64 } else { 0.0 },
                "",
            ),
        ],
    );
    Ok((x, a))
}

/// [`zero_point`] with the contact on the stiffness (`o.stiffness`, N/mm): depth, force
/// and time offset there.
fn stiffness_zero_point(r: &Record, o: &ZeroPoint, k: f64) -> Result<(Record, Applied), PrepError> {
    if !(k > 0.0 && k.is_finite()) {
        return Err(option_error(
            "zero_point.stiffness",
            k,
            "a finite stiffness > 0 (N/mm)",
        ));
    }
    let contact = crate::surface::stiffness_contact(&r.h, &r.f, k).ok_or_else(|| {
        option_error(
            "zero_point.stiffness",
            k,
            &format!(
                "a stiffness the record `{}` reaches (the 5-sample median of its |dF/dh| never \
                 exceeds {k} N/mm)",
                r.name
            ),
        )
    })?;
    let (t0, h0, f0) = (r.t[contact], r.h[contact], r.f[contact]);
    let x = shifted_from(r, contact, o.trim, (t0, h0, f0))?;
    let a = Applied::new(
        "zero_point",
        format!(
            "contact at t = {t0:.4} s (sample {contact}, the 5-sample median of |dF/dh| rising \
             through {k} N/mm): h offset {:.3} nm, F offset {:.5} mN, {contact} approach samples \
             {}; t = 0 at contact",
            h0 * 1e6,
            f0 * 1e3,
            if o.trim { "dropped" } else { "kept" }
        ),
        vec![
            Quantity::new("contact time", t0, "s"),
            Quantity::new("h offset", h0 * 1e6, "nm"),
            Quantity::new("F offset", f0 * 1e3, "mN"),
            Quantity::new("stiffness threshold", k, "N/mm"),
            Quantity::new(
                "samples dropped",
                if o.trim { contact as f64 } else { 0.0 },
                "",
            ),
        ],
    );
    Ok((x, a))
}

/// Relative change of the controlled quantity over a run of file segment ids above which
/// the run is a load (or, falling, an unload); below it, a hold. Holds drift by about 1 %
/// under imperfect control (creep of the force in `anonNI.TXT`), loads change by far more.
pub const MAP_THRESHOLD: f64 = 0.05;

/// Runs of equal segment ids with their phase from the change of the controlled quantity
/// (force, or depth when `depth_control`) over the run, relative to its range: load above
/// `threshold`, unload below `-threshold`, hold in between. Empty when the record has no
/// ids.
pub fn spans(r: &Record, depth_control: bool, threshold: f64) -> Vec<Span> {
    let Some(seg) = &r.segment else {
        return Vec::new();
    };
    let x = if depth_control { &r.h } else { &r.f };
    let n = seg.len().min(x.len()).min(r.t.len());
    let (lo, hi) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let range = (hi - lo).max(f64::MIN_POSITIVE);
    let mut out = Vec::new();
    let mut start = 0;
    for i in 0..n {
        if i + 1 == n || seg[i + 1] != seg[i] {
            let c = (x[i] - x[start]) / range;
            let phase = if c > threshold {
                Phase::Load
            } else if c < -threshold {
                Phase::Unload
            } else {
                Phase::Hold
            };
            out.push(Span {
                id: seg[i],
                phase,
                start,
                end: i,
                t0: r.t[start],
                t1: r.t[i],
            });
            start = i + 1;
        }
    }
    out
}

/// Whether the record was taken under depth control, by the option or the file's protocol.
fn depth_control(r: &Record, c: Control) -> bool {
    match c {
        Control::Depth => true,
        Control::Load => false,
        Control::Auto => r.meta.protocol.control.as_deref().is_some_and(|c| {
            let c = c.to_ascii_lowercase();
            c.contains("displacement") || c.contains("depth")
        }),
    }
}

fn describe(spans: &[Span]) -> String {
    spans
        .iter()
        .map(|s| {
            format!(
                "id {} {:?} {:.3}-{:.3} s ({} samples)",
                s.id,
                s.phase,
                s.t0,
                s.t1,
                s.end + 1 - s.start
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Segments: with the file's ids, maps each run of ids to load/hold/unload ([`spans`] with
/// [`MAP_THRESHOLD`]);
/// without, detects them and sets ids 0, 1, 2 in order.
///
/// Detection uses the controlled quantity `X` (force under load control, depth under depth
/// control): the samples with `X >= X_max - tolerance (X_max - X_min)` run from `a` to `b`;
/// if `t[b] - t[a] >= min_hold` they are the hold, load before, unload after; otherwise
/// load runs to the maximum of `X` and unload follows.
///
/// # Errors
///
/// [`PrepError::Option`] for options out of range, [`PrepError::Record`] for an
/// inconsistent record.
pub fn segments(r: &Record, o: &Segments) -> Result<(Record, Applied), PrepError> {
    validate(r)?;
    if !(o.tolerance > 0.0 && o.tolerance < 0.5) {
        return Err(option_error(
            "segments.tolerance",
            o.tolerance,
            "0 < tolerance < 0.5",
        ));
    }
    if !(o.min_hold >= 0.0 && o.min_hold.is_finite()) {
        return Err(option_error(
            "segments.min_hold",
            o.min_hold,
            "a finite time >= 0 (s)",
        ));
    }
    let depth = depth_control(r, o.control);
    if r.segment.is_some() {
        let sp = spans(r, depth, MAP_THRESHOLD);
        let d = format!(
            "{} segments from the file's ids: {}",
            sp.len(),
            describe(&sp)
        );
        let values = sp
            .iter()
            .map(|s| {
                Quantity::new(
                    format!("id {} {:?} duration", s.id, s.phase),
                    s.t1 - s.t0,
                    "s",
                )
            })
            .collect();
        return Ok((r.clone(), Applied::new("segments", d, values)));
    }
    let x = if depth { &r.h } else { &r.f };
    let i_max = argmax(x);
    let x_max = x.get(i_max).copied().unwrap_or(0.0);
    let x_min = x.iter().copied().fold(x_max, f64::min);
    let level = x_max - o.tolerance * (x_max - x_min);
    let a = x.iter().position(|&v| v >= level).unwrap_or(i_max);
    let b = x.iter().rposition(|&v| v >= level).unwrap_or(i_max);
    let hold = r.t[b] - r.t[a] >= o.min_hold && b > a;
    let phase_of = |i: usize| {
        if hold {
            if i < a {
                Phase::Load
            } else if i <= b {
                Phase::Hold
            } else {
                Phase::Unload
            }
        } else if i <= i_max {
            Phase::Load
        } else {
            Phase::Unload
        }
    };
    let mut ids = Vec::with_capacity(r.len());
    let mut id = 0u32;
    for i in 0..r.len() {
        if i > 0 && phase_of(i) != phase_of(i - 1) {
            id += 1;
        }
        ids.push(id);
    }
    let mut out = r.clone();
    out.segment = Some(ids);
    let sp = spans(&out, depth, 0.0)
        .into_iter()
        .map(|mut s| {
            s.phase = phase_of(s.start);
            s
        })
        .collect::<Vec<_>>();
    let d = format!(
        "{} segments detected ({} control{}): {}",
        sp.len(),
        if depth { "depth" } else { "load" },
        if hold { "" } else { ", no hold" },
        describe(&sp)
    );
    let values = sp
        .iter()
        .map(|s| {
            Quantity::new(
                format!("id {} {:?} duration", s.id, s.phase),
                s.t1 - s.t0,
                "s",
            )
        })
        .collect();
    Ok((out, Applied::new("segments", d, values)))
}

/// Integral of the piecewise-linear interpolant of `(t, y)` from `t[0]` to `x`, given the
/// cumulative trapezoids `c`.
fn cumulative(t: &[f64], y: &[f64], c: &[f64], x: f64) -> f64 {
    let k = t.partition_point(|&s| s <= x).saturating_sub(1);
    let (tk, yk, ck) = (t[k], y[k], c[k]);
    let yx = match (t.get(k + 1), y.get(k + 1)) {
        (Some(&t1), Some(&y1)) if t1 > tk => yk + (y1 - yk) * (x - tk) / (t1 - tk),
        _ => yk,
    };
    ck + (x - tk) * 0.5 * (yk + yx)
}

fn trapezoids(t: &[f64], y: &[f64]) -> Vec<f64> {
    let mut c = Vec::with_capacity(t.len());
    let mut s = 0.0;
    for i in 0..t.len() {
        if i > 0 {
            s += (t[i] - t[i - 1]) * 0.5 * (y[i] + y[i - 1]);
        }
        c.push(s);
    }
    c
}

/// Resamples to `n` points with `t` from 0: the knots (first and last sample, segment
/// boundaries, the peak depth; a boundary within 1% of the duration, or 3 samples, of the
/// peak or of an end merges into it) are kept with their raw values, the other points spread over the intervals between
/// knots in proportion to a share that is half their duration and half the change of depth
/// and force over them, each relative to its total (at least `min_per_segment` intervals
/// each when `n` allows), each the time average of the linearly interpolated raw
/// signal over its own interval (from the midpoint to its left neighbour to the midpoint to
/// its right one): the depth to drive a simulation, the force as the data to fit.
///
/// # Errors
///
/// [`PrepError::Option`] when `n < 2` or `n` is smaller than the number of knots;
/// [`PrepError::TooShort`] for a record with no duration, [`PrepError::Record`] for an
/// inconsistent record.
pub fn resample(r: &Record, o: &Resample) -> Result<(Record, Applied), PrepError> {
    validate(r)?;
    if !(2..=MAX_RESAMPLE_POINTS).contains(&o.n) {
        return Err(option_error("resample.n", o.n, &points_allowed()));
    }
    let len = r.len();
    if len < 2 || r.h.len() != len || r.f.len() != len {
        return Err(PrepError::TooShort {
            record: r.name.clone(),
            step: "resample",
            n: len,
            min: 2,
        });
    }
    let t = &r.t;
    if !(t[len - 1] > t[0]) {
        return Err(PrepError::Record {
            record: r.name.clone(),
            what: format!(
                "all {len} samples are at t = {} s: the record spans no time",
                t[0]
            ),
            expected: "a time column that increases over the test".to_owned(),
        });
    }
    let peak = argmax(&r.h);
    // knots as sample indices: first, segment starts, peak, last
    let mut knots = vec![0, peak, len - 1];
    if let Some(seg) = &r.segment {
        knots.extend((1..len.min(seg.len())).filter(|&i| seg[i] != seg[i - 1]));
    }
    knots.sort_unstable();
    knots.dedup_by(|a, b| t[*a] == t[*b]);
    // a segment boundary within 1% of the duration, or 3 samples, of the peak or of an end
    // merges into it: a sliver between them would take min_per_segment steps from the real segments
    let total_t = t[len - 1] - t[0];
    knots.retain(|&k| {
        k == 0
            || k == len - 1
            || k == peak
            || [0, peak, len - 1]
                .iter()
                .all(|&a| (t[k] - t[a]).abs() > 0.01 * total_t && k.abs_diff(a) > 3)
    });
    if knots.len() < 2 || !(t[len - 1] > t[0]) {
        return Err(PrepError::TooShort {
            record: r.name.clone(),
            step: "resample",
            n: knots.len(),
            min: 2,
        });
    }
    if let Some(k) = knots.last_mut() {
        *k = len - 1;
    }
    let m = knots.len() - 1;
    if o.n < m + 1 {
        return Err(option_error(
            "resample.n",
            o.n,
            &format!(
                "at least {} points (the record has {} knots: ends, segment boundaries, peak)",
                m + 1,
                m + 1
            ),
        ));
    }
    let total = total_t;
    let dur: Vec<f64> = knots.windows(2).map(|w| t[w[1]] - t[w[0]]).collect();
    // share of each interval: half by duration, half by how much depth and force change
    // over it (relative to their ranges), so that a long creep hold does not starve the
    // loading and unloading branches
    let range = |v: &[f64]| {
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        if hi > lo { hi - lo } else { 1.0 }
    };
    let (hr, fr) = (range(&r.h), range(&r.f));
    let change: Vec<f64> = knots
        .windows(2)
        .map(|w| (r.h[w[1]] - r.h[w[0]]).abs() / hr + (r.f[w[1]] - r.f[w[0]]).abs() / fr)
        .collect();
    let change_total: f64 = change.iter().sum();
    let share: Vec<f64> = dur
        .iter()
        .zip(&change)
        .map(|(d, c)| {
            if change_total > 0.0 {
                0.5 * d / total + 0.5 * c / change_total
            } else {
                d / total
            }
        })
        .collect();
    let budget = o.n - 1;
    let min_p = o.min_per_segment.max(1).min(budget / m).max(1);
    let mut p: Vec<usize> = share
        .iter()
        .map(|w| (((budget as f64) * w).floor() as usize).max(min_p))
        .collect();
    let mut sum: usize = p.iter().sum();
    while sum < budget {
        // add to the interval furthest below its share
        let k = (0..m)
            .max_by(|&i, &j| (share[i] / p[i] as f64).total_cmp(&(share[j] / p[j] as f64)))
            .unwrap_or(0);
        p[k] += 1;
        sum += 1;
    }
    while sum > budget {
        // take from the interval furthest above its share that can spare one
        let Some(k) = (0..m)
            .filter(|&i| p[i] > min_p)
            .min_by(|&i, &j| (share[i] / p[i] as f64).total_cmp(&(share[j] / p[j] as f64)))
        else {
            break;
        };
        p[k] -= 1;
        sum -= 1;
    }
    // node times, and the raw sample index of knot nodes
    let mut s: Vec<f64> = Vec::with_capacity(o.n);
    let mut knot_of: Vec<Option<usize>> = Vec::with_capacity(o.n);
    let mut seg_of: Vec<u32> = Vec::with_capacity(o.n);
    for k in 0..m {
        let (i0, i1) = (knots[k], knots[k + 1]);
        let id = r
            .segment
            .as_ref()
            .and_then(|v| v.get(i0).copied())
            .unwrap_or(0);
        for j in 0..p[k] {
            s.push(t[i0] + dur[k] * j as f64 / p[k] as f64);
            knot_of.push((j == 0).then_some(i0));
            seg_of.push(id);
        }
        if k + 1 == m {
            s.push(t[i1]);
            knot_of.push(Some(i1));
            seg_of.push(
                r.segment
                    .as_ref()
                    .and_then(|v| v.get(i1).copied())
                    .unwrap_or(0),
            );
        }
    }
    let ch = trapezoids(t, &r.h);
    let cf = trapezoids(t, &r.f);
    let nn = s.len();
    let mut h = Vec::with_capacity(nn);
    let mut f = Vec::with_capacity(nn);
    for j in 0..nn {
        if let Some(i) = knot_of[j] {
            h.push(r.h[i]);
            f.push(r.f[i]);
            continue;
        }
        let lo = 0.5 * (s[j - 1] + s[j]);
        let hi = 0.5 * (s[j] + s[j + 1]);
        let w = hi - lo;
        h.push((cumulative(t, &r.h, &ch, hi) - cumulative(t, &r.h, &ch, lo)) / w);
        f.push((cumulative(t, &r.f, &cf, hi) - cumulative(t, &r.f, &cf, lo)) / w);
    }
    let t0 = t[0];
    let out = Record {
        name: r.name.clone(),
        t: s.iter().map(|x| x - t0).collect(),
        h,
        f,
        segment: r.segment.as_ref().map(|_| seg_of),
        meta: r.meta.clone(),
    };
    let d = format!(
        "resampled {len} samples to {nn} points over {total:.3} s from t = 0 (shifted by {t0:.4} s): {m} intervals between knots (ends, segment boundaries, peak depth {:.3} nm at {:.3} s) with {:?} steps; interior values are time averages over each point's interval",
        r.h[peak] * 1e6,
        t[peak] - t0,
        p
    );
    let a = Applied::new(
        "resample",
        d,
        vec![
            Quantity::new("samples", len as f64, ""),
            Quantity::new("points", nn as f64, ""),
            Quantity::new("duration", total, "s"),
            Quantity::new("time shift", t0, "s"),
            Quantity::new("peak depth", r.h[peak] * 1e6, "nm"),
        ],
    );
    Ok((out, a))
}

/// `r` with `t`, `h` and `F` shifted by `(t0, h0, f0)` and, when `trim`, the samples
/// before `contact` dropped (the zero point's common last step).
///
/// # Errors
/// [`PrepError::TooShort`] when fewer than 2 samples remain.
fn shifted_from(
    r: &Record,
    contact: usize,
    trim: bool,
    (t0, h0, f0): (f64, f64, f64),
) -> Result<Record, PrepError> {
    let keep = if trim { contact } else { 0 };
    let take = |v: &[f64], off: f64| {
        v.get(keep..)
            .unwrap_or(&[])
            .iter()
            .map(|x| x - off)
            .collect::<Vec<_>>()
    };
    let x = Record {
        name: r.name.clone(),
        t: take(&r.t, t0),
        h: take(&r.h, h0),
        f: take(&r.f, f0),
        segment: r
            .segment
            .as_ref()
            .map(|s| s.get(keep..).unwrap_or(&[]).to_vec()),
        meta: r.meta.clone(),
    };
    if x.len() < 2 {
        return Err(PrepError::TooShort {
            record: r.name.clone(),
            step: "zero_point",
            n: x.len(),
            min: 2,
        });
    }
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::Meta;

    fn rec(t: Vec<f64>, h: Vec<f64>, f: Vec<f64>) -> Record {
        Record {
            name: "synthetic".into(),
            t,
            h,
            f,
            segment: None,
            meta: Meta::default(),
        }
    }

    // true curve sampled at 10 Hz: approach (h < 0, F = 0) until sample 20 (t = 2 s), load
    // 1 mN/s to 10 mN (h 200 nm), 5 s hold (creep 5 nm), unload 1 mN/s
    fn truth(i: usize) -> (f64, f64, f64) {
        let t = i as f64 * 0.1;
        let k = i as f64;
        match i {
            0..=20 => (t, 1e-6 * (k - 20.0), 0.0),
            21..=120 => (t, 2e-6 * (k - 20.0), 1e-4 * (k - 20.0)),
            121..=170 => (t, 2e-4 + 1e-7 * (k - 120.0), 1e-2),
            _ => (t, 2.05e-4 - 1e-6 * (k - 170.0), 1e-2 - 1e-4 * (k - 170.0)),
        }
    }

    const N: usize = 271;
    const H0: f64 = 5e-4;
    const F0: f64 = 2e-5;
    const RATE: f64 = 1e-6;
    const C: f64 = 0.5e-3;

    fn raw() -> Record {
        let (mut t, mut h, mut f) = (vec![], vec![], vec![]);
        for i in 0..N {
            let (ti, hi, fi) = truth(i);
            t.push(ti);
            h.push(hi + H0 + RATE * ti + C * fi);
            f.push(fi + F0);
        }
        rec(t, h, f)
    }

    #[test]
    fn offset_compliance_and_drift_are_corrected_back_exactly() {
        let p = Preprocessing {
            drift: Correction::Value(RATE),
            compliance: Correction::Value(C),
            segments: None,
            ..Preprocessing::default()
        };
        let (r, done) = apply(&raw(), &p).unwrap();
        assert_eq!(
            done.iter().map(|a| a.step.as_str()).collect::<Vec<_>>(),
            ["drift", "zero_point", "compliance"]
        );
        assert_eq!(r.len(), N - 20);
        for j in 0..r.len() {
            let (t, h, f) = truth(j + 20);
            assert!((r.t[j] - (t - 2.0)).abs() < 1e-12, "t at {j}");
            assert!((r.h[j] - h).abs() < 1e-15, "h at {j}: {} vs {h}", r.h[j]);
            assert!((r.f[j] - f).abs() < 1e-15, "F at {j}");
        }
        let z = &done[1];
        let get = |n: &str| z.values.iter().find(|q| q.name == n).unwrap().value;
        assert!((get("contact time") - 2.0).abs() < 1e-12);
        assert!(
            (get("h offset") - H0 * 1e6).abs() < 1e-9,
            "{}",
            z.description
        );
        assert!((get("F offset") - F0 * 1e3).abs() < 1e-12);
        assert!(
            done[0].description.contains("1.000000 nm/s"),
            "{}",
            done[0].description
        );
        assert!(
            done[2].description.contains("0.500000 nm/mN"),
            "{}",
            done[2].description
        );
    }

    #[test]
    fn zero_point_on_noisy_baseline_finds_contact_near_the_true_one() {
        let mut r = raw();
        // deterministic +-1 uN noise on the force
        for (i, f) in r.f.iter_mut().enumerate() {
            *f += if i % 2 == 0 { 1e-6 } else { -1e-6 } * ((i % 7) as f64 / 7.0);
        }
        let (z, a) = zero_point(&r, &ZeroPoint::default()).unwrap();
        let t_c = a.values[0].value;
        assert!((t_c - 2.0).abs() <= 0.15, "{}", a.description);
        assert!(z.t[0] == 0.0);
    }

    #[test]
    fn a_record_that_starts_in_contact_keeps_its_first_sample() {
        // an instrument that zeroed itself at contact: h = 10 nm/s t, F = 2 mN/s^2 t^2 with a
        // little noise, from the first sample on (the baseline window rises)
        let n = 200;
        let t: Vec<f64> = (0..n).map(|i| 0.1 * i as f64).collect();
        let h: Vec<f64> = t.iter().map(|t| 1e-5 * t).collect();
        let f: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, t)| 2e-3 * t * t + if i % 2 == 0 { 1e-8 } else { -1e-8 })
            .collect();
        let r = rec(t, h.clone(), f.clone());
        let (z, a) = zero_point(&r, &ZeroPoint::default()).unwrap();
        assert_eq!(z.len(), n, "{}", a.description);
        assert!(
            a.description.contains("starts in contact"),
            "{}",
            a.description
        );
        assert_eq!(z.h[10], h[10] - h[0]);
        assert_eq!(z.f[10], f[10] - f[0]);
        // the same record after a flat, noisy approach: contact found after it
        let mut t2: Vec<f64> = (0..50).map(|i| -5.0 + 0.1 * i as f64).collect();
        let mut h2: Vec<f64> = t2.iter().map(|t| 1e-5 * t).collect();
        let mut f2: Vec<f64> = (0..50)
            .map(|i| if i % 2 == 0 { 1e-7 } else { -1e-7 })
            .collect();
        t2.extend(r.t.iter());
        h2.extend(h.iter());
        f2.extend(f.iter());
        let (z2, a2) = zero_point(&rec(t2, h2, f2), &ZeroPoint::default()).unwrap();
        assert!(
            !a2.description.contains("starts in contact"),
            "{}",
            a2.description
        );
        assert!((a2.values[0].value).abs() <= 0.5, "{}", a2.description);
        assert!(z2.len() >= n - 5 && z2.len() <= n + 5, "{}", a2.description);
    }

    #[test]
    fn no_contact_is_an_error() {
        let r = rec(vec![0.0, 1.0, 2.0], vec![0.0, 1e-6, 2e-6], vec![1e-5; 3]);
        let e = zero_point(&r, &ZeroPoint::default()).unwrap_err();
        assert!(matches!(e, PrepError::NoContact { .. }), "{e}");
        assert!(e.to_string().contains("no contact"), "{e}");
    }

    #[test]
    fn a_force_negative_throughout_shows_its_range_and_the_sign() {
        // compression counted negative: the force falls from 0 to -3 mN
        let r = rec(
            vec![0.0, 1.0, 2.0, 3.0],
            vec![0.0, 1e-6, 2e-6, 3e-6],
            vec![0.0, -1e-3, -2e-3, -3e-3],
        );
        let e = zero_point(&r, &ZeroPoint::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("-3.0000e0 to 0.0000e0 mN"), "{e}");
        assert!(e.contains("sign reversed"), "{e}");
    }

    #[test]
    fn drift_and_compliance_from_the_file_or_not() {
        let mut r = raw();
        assert!(matches!(
            drift(&r, Correction::FromFile),
            Err(PrepError::NoHint { .. })
        ));
        let (same, a) = drift(&r, Correction::Auto).unwrap();
        assert_eq!(same, r);
        assert!(a.description.contains("no drift"));
        r.meta.drift_rate = Some(RATE);
        r.meta.frame_compliance = Some(C);
        let (d, _) = drift(&r, Correction::FromFile).unwrap();
        assert!((d.h[100] - (r.h[100] - RATE * r.t[100])).abs() < 1e-18);
        let (c, _) = compliance(&r, Correction::Auto).unwrap();
        assert!((c.h[100] - (r.h[100] - C * r.f[100])).abs() < 1e-18);
        assert!(matches!(
            compliance(&r, Correction::Value(f64::NAN)),
            Err(PrepError::Option { .. })
        ));
    }

    #[test]
    fn segments_are_detected_under_load_control() {
        let (z, _) = zero_point(&raw(), &ZeroPoint::default()).unwrap();
        let (s, a) = segments(&z, &Segments::default()).unwrap();
        let sp = spans(&s, false, 0.0);
        assert_eq!(sp.len(), 3, "{}", a.description);
        // hold from 10 s (9.9 mN reached at 9.9 s, tolerance 1 %) to 15.1 s after contact
        assert!(
            (sp[1].t0 - 9.9).abs() < 0.11 && (sp[1].t1 - 15.1).abs() < 0.11,
            "{}",
            a.description
        );
        assert_eq!(
            spans(&s, false, MAP_THRESHOLD)
                .iter()
                .map(|s| s.phase)
                .collect::<Vec<_>>(),
            [Phase::Load, Phase::Hold, Phase::Unload]
        );
    }

    #[test]
    fn file_segment_ids_are_mapped_by_trend() {
        let mut r = raw();
        r.segment = Some(
            (0..N)
                .map(|i| {
                    if i <= 120 {
                        1
                    } else if i <= 170 {
                        2
                    } else {
                        3
                    }
                })
                .collect(),
        );
        let (_, a) = segments(&r, &Segments::default()).unwrap();
        assert!(
            a.description.contains("id 1 Load")
                && a.description.contains("id 2 Hold")
                && a.description.contains("id 3 Unload"),
            "{}",
            a.description
        );
    }

    #[test]
    fn resampling_a_linear_record_is_exact_and_keeps_boundaries_and_peak() {
        let t: Vec<f64> = (0..=1000).map(|i| i as f64 * 0.01).collect();
        let h: Vec<f64> = t
            .iter()
            .map(|&x| if x <= 6.0 { 2.0 * x } else { 24.0 - 2.0 * x })
            .collect();
        let f: Vec<f64> = t.iter().map(|&x| 3.0 * x).collect();
        let mut r = rec(t.iter().map(|x| x + 5.0).collect(), h, f);
        r.segment = Some(t.iter().map(|&x| u32::from(x >= 4.0)).collect());
        let (s, a) = resample(
            &r,
            &Resample {
                n: 11,
                min_per_segment: 2,
            },
        )
        .unwrap();
        assert_eq!(s.len(), 11, "{}", a.description);
        for (j, &x) in s.t.iter().enumerate() {
            assert!((x - j as f64).abs() < 1e-9, "t {x} at {j}");
            let hx = if x <= 6.0 { 2.0 * x } else { 24.0 - 2.0 * x };
            assert!((s.h[j] - hx).abs() < 1e-9, "h {} at {x}", s.h[j]);
            assert!((s.f[j] - 3.0 * x).abs() < 1e-9);
        }
        assert_eq!(s.segment.as_deref().unwrap()[4], 1);
        assert_eq!(s.segment.as_deref().unwrap()[3], 0);
        // uneven n: still monotone, boundary (4 s) and peak (6 s) kept
        let (s, _) = resample(
            &r,
            &Resample {
                n: 17,
                min_per_segment: 3,
            },
        )
        .unwrap();
        assert!(s.t.windows(2).all(|w| w[1] > w[0]));
        assert!(
            s.t.iter().any(|&x| (x - 4.0).abs() < 1e-12)
                && s.t.iter().any(|&x| (x - 6.0).abs() < 1e-12)
        );
        assert!((s.h_max() - 12.0).abs() < 1e-12);
    }

    #[test]
    fn resampling_rejects_too_few_points() {
        let r = rec(
            vec![0.0, 1.0, 2.0],
            vec![0.0, 2.0, 1.0],
            vec![0.0, 1.0, 0.5],
        );
        for n in [0, 1, 2] {
            let e = resample(
                &r,
                &Resample {
                    n,
                    min_per_segment: 1,
                },
            )
            .unwrap_err();
            assert!(
                matches!(
                    e,
                    PrepError::Option {
                        field: "resample.n",
                        ..
                    }
                ),
                "{e}"
            );
        }
        assert_eq!(
            resample(
                &r,
                &Resample {
                    n: 3,
                    min_per_segment: 1
                }
            )
            .unwrap()
            .0
            .len(),
            3
        );
    }

    #[test]
    fn absurd_point_counts_are_refused_in_parsing_and_in_resampling() {
        let r = rec(
            vec![0.0, 1.0, 2.0],
            vec![0.0, 2.0, 1.0],
            vec![0.0, 1.0, 0.5],
        );
        let e = resample(
            &r,
            &Resample {
                n: MAX_RESAMPLE_POINTS + 1,
                min_per_segment: 1,
            },
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("resample.n") && e.contains("100000"), "{e}");
        let parse = |text: &str| ron::from_str::<Resample>(text);
        assert_eq!(parse("(n: 60)").unwrap().n, 60);
        for bad in ["(n: 0)", "(n: 1)", "(n: 100001)", "(n: 1000000000000)"] {
            let e = parse(bad).unwrap_err().to_string();
            assert!(
                e.contains("resample.n =") && e.contains("[2, 100000]"),
                "{bad}: {e}"
            );
        }
        assert!(parse("(n: 6.5)").is_err() && parse("(n: -3)").is_err());
    }

    #[test]
    fn inconsistent_records_are_errors() {
        let r = rec(vec![0.0, 1.0], vec![0.0], vec![0.0, 1.0]);
        assert!(matches!(
            apply(&r, &Preprocessing::default()),
            Err(PrepError::Record { .. })
        ));
        let r = rec(vec![0.0], vec![0.0], vec![0.0]);
        assert!(matches!(
            apply(&r, &Preprocessing::default()),
            Err(PrepError::TooShort { .. })
        ));
        let r = rec(vec![1.0, 0.0], vec![0.0, 1.0], vec![0.0, 1.0]);
        assert!(matches!(
            apply(&r, &Preprocessing::default()),
            Err(PrepError::Record { .. })
        ));
    }

    #[test]
    fn options_deserialize_from_ron_with_defaults_and_deny_unknown_fields() {
        let p: Preprocessing = ron::from_str(
            "(drift: Auto, zero_point: Some((fraction: 0.05)), compliance: Value(0.0066), resample: Some((n: 150)))",
        )
        .unwrap();
        assert_eq!(p.drift, Correction::Auto);
        assert_eq!(p.zero_point.as_ref().unwrap().fraction, 0.05);
        assert!(p.zero_point.as_ref().unwrap().trim);
        assert_eq!(
            p.resample,
            Some(Resample {
                n: 150,
                min_per_segment: 5
            })
        );
        assert_eq!(p.segments, Some(Segments::default()));
        assert_eq!(
            ron::from_str::<Preprocessing>("()").unwrap(),
            Preprocessing::default()
        );
        assert!(ron::from_str::<Preprocessing>("(drfit: Auto)").is_err());
        assert!(ron::from_str::<Preprocessing>("(resample: Some((n: -3)))").is_err());
    }
}
