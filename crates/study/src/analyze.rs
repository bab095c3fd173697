//! `indentify analyze` and `indentify calibrate`: the Oliver-Pharr pipeline over an
//! instrument file. Reads the file through `indentify_records` (every test, or one),
//! preprocesses each test (zero point, the file's drift correction when it gives one, the
//! tip's frame compliance or the file's), analyses it with `indentify_analysis` (tests in
//! parallel, results in file order), and writes `analysis.json` and `analysis.csv`
//! atomically with the figures (`crate::analysis_figures`); `calibrate` fits the frame compliance and the area function on a reference
//! and writes the tip file. The method is in `docs/analysis.md`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use indentify_analysis::calibrate::{self, AreaFit, Compliance, Point};
use indentify_analysis::{AreaFunction, Epsilon, FitRange, Options, TestAnalysis, Tip};
use indentify_records::{
    Applied, Correction, Format, Preprocessing, Quantity, ReadOptions, Record, ZeroPoint,
};
use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, ErrorKind, Result};
use crate::format::{sig, table};

/// What to analyse and how.
#[derive(Debug, Clone)]
pub struct AnalyzeOptions {
    /// The instrument file.
    pub file: PathBuf,
    /// 1-based test of a multi-test file; `None`: every test.
    pub test: Option<usize>,
    /// The indenter (from `--tip` or a tip file).
    pub tip: Tip,
    /// Poisson's ratio of the sample.
    pub nu: f64,
    /// The unloading fit's force range; `None`: the format's vendor default.
    pub fit_range: Option<FitRange>,
    /// Where epsilon comes from.
    pub epsilon: Epsilon,
    /// `beta` of `E_r`.
    pub beta: f64,
    /// A vendor results table to attach (Anton Paar `_data.TXT`); `None`: the file's
    /// sibling `<stem>_data.TXT` when it exists.
    pub results: Option<PathBuf>,
    /// Folder for analysis.json and analysis.csv; `None` writes nothing.
    pub out: Option<PathBuf>,
    /// Detect the contact and take the depth and force offsets there (`records::prep`'s
    /// zero point): `Some(false)` keeps the file's own zero; `None` decides by the format
    /// ([`zero_point_default`]).
    pub zero_point: Option<bool>,
    /// Find the contact on the stiffness instead: the first sample where the 5-sample
    /// median of `|dF/dh|` exceeds this, N/mm (= mN/µm; indentationGUI's surface, 1 on
    /// fused silica); implies the zero point. `None`: the force threshold.
    pub surface_stiffness: Option<f64>,
}

impl AnalyzeOptions {
    /// The defaults for a file: ideal diamond Berkovich, `nu` 0.3, the vendor's fit range,
    /// the tip's epsilon, `beta` 1.
    pub fn new(file: impl Into<PathBuf>) -> AnalyzeOptions {
        AnalyzeOptions {
            file: file.into(),
            test: None,
            tip: Tip::berkovich(),
            nu: 0.3,
            fit_range: None,
            epsilon: Epsilon::Tip,
            beta: 1.0,
            results: None,
            out: None,
            zero_point: None,
            surface_stiffness: None,
        }
    }
}

/// The O&P values of a test's main unloading (MPa, N/mm, mm, N), `None` when it gave
/// none: one struct for `analyze`'s tests and `batch --analyze`'s indents (flattened into
/// their JSON as `E`, `H`, `Er`, `S`, `hc`, `hmax`, `Fmax`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct OpValues {
    /// Indentation modulus E_IT, MPa.
    #[serde(rename = "E")]
    pub e: Option<f64>,
    /// Indentation hardness H_IT, MPa.
    #[serde(rename = "H")]
    pub h: Option<f64>,
    /// Reduced modulus, MPa.
    #[serde(rename = "Er")]
    pub er: Option<f64>,
    /// Contact stiffness, N/mm.
    #[serde(rename = "S")]
    pub s: Option<f64>,
    /// Contact depth, mm.
    pub hc: Option<f64>,
    /// Depth at the start of the unloading, mm.
    pub hmax: Option<f64>,
    /// Force at the start of the unloading, N.
    #[serde(rename = "Fmax")]
    pub fmax: Option<f64>,
}

impl OpValues {
    /// The values of an analysis' main unloading (all `None` without one).
    pub fn of(a: &TestAnalysis) -> OpValues {
        let Some((u, op)) = a.values() else {
            return OpValues::default();
        };
        OpValues {
            e: op.e,
            h: Some(op.hardness),
            er: Some(op.er),
            s: Some(op.s),
            hc: Some(op.hc),
            hmax: Some(u.h_max),
            fmax: Some(u.f_max),
        }
    }
}

/// One test's outcome: the summary values (from its main unloading, in N, mm, N/mm, MPa),
/// the preprocessing applied, every unloading, the vendor's values.
#[derive(Debug, Clone, Serialize)]
pub struct TestOutcome {
    /// 1-based index in the file.
    pub index: usize,
    /// Test name.
    pub test: String,
    /// The O&P values of the main unloading.
    #[serde(flatten)]
    pub values: OpValues,
    /// Why the test gave no values.
    pub error: Option<String>,
    /// The preprocessing steps applied.
    pub preprocessing: Vec<Applied>,
    /// The analysis (every unloading).
    pub analysis: Option<TestAnalysis>,
    /// The vendor's own results as the file gives them.
    pub vendor: Vec<Quantity>,
}

/// The outcome of [`run`].
#[derive(Debug, Clone, Serialize)]
pub struct AnalyzeOutcome {
    /// The file.
    pub file: String,
    /// Its format.
    pub format: String,
    /// The tip (its own modulus `tip.modulus`, MPa).
    pub tip: Tip,
    /// Poisson's ratio of the sample.
    pub nu: f64,
    /// `beta`.
    pub beta: f64,
    /// Epsilon's source.
    pub epsilon: Epsilon,
    /// The fit range used, and where it comes from.
    pub fit_range: FitRange,
    /// Where the fit range comes from.
    pub fit_range_source: String,
    /// Every test.
    pub tests: Vec<TestOutcome>,
    /// Wall time, s.
    pub seconds: f64,
    /// Files written.
    pub written: Vec<String>,
}

fn data_error(e: impl std::fmt::Display) -> Error {
    Error::msg(ErrorKind::Data, e)
}

fn read_records(file: &Path, test: Option<usize>) -> Result<Vec<Record>> {
    let bytes = std::fs::read(file)
        .with_context(|| format!("cannot read `{}`", file.display()))
        .map_err(|e| Error::new(ErrorKind::Io, e))?;
    let name = file.display().to_string();
    indentify_records::read(
        &bytes,
        &name,
        &ReadOptions {
            format: Format::Auto,
            test,
        },
    )
    .map_err(data_error)
}

/// Whether the zero point is detected by default for a format: not for Anton Paar exports
/// (they start at the instrument's contact, and the vendor's own O&P values are reproduced
/// from that zero); yes for every other format. KLA workbooks start at the instrument's
/// `Surface Index`, but in `FusedSilica.xlsx` the depth there is ~70 nm short of the
/// contact the force shows (100 nm at 0.09 mN on fused silica): the detection on the force
/// gives moduli that agree across load cycles, the file's zero does not (docs/analysis.md).
/// The detection drops the cycles below its threshold (2 % of the force range).
pub fn zero_point_default(format: Format) -> bool {
    !matches!(format, Format::AntonPaar | Format::AntonPaarMulti)
}

/// The preprocessing of the analysis: the file's drift correction when it gives one, the
/// zero point when asked (contact where the force rises through 2 % of its range; a record that
/// starts in contact keeps sample 0), the frame compliance `compliance` (mm/N) or the
/// file's.
pub fn preprocessing(compliance: Option<f64>, zero_point: bool) -> Preprocessing {
    Preprocessing {
        drift: Correction::Auto,
        zero_point: zero_point.then(ZeroPoint::default),
        compliance: compliance.map_or(Correction::Auto, Correction::Value),
        segments: None,
        resample: None,
    }
}

fn analyse_records(
    records: &[Record],
    first_index: usize,
    o: &Options,
    prep: &Preprocessing,
) -> Vec<TestOutcome> {
    records
        .par_iter()
        .enumerate()
        .map(|(i, r)| {
            let mut t = TestOutcome {
                index: first_index + i,
                test: r.meta.test_name.clone().unwrap_or_else(|| r.name.clone()),
                values: OpValues::default(),
                error: None,
                preprocessing: Vec::new(),
                analysis: None,
                vendor: r.meta.results.clone(),
            };
            let (x, applied) = match indentify_records::apply(r, prep) {
                Ok(v) => v,
                Err(e) => {
                    t.error = Some(format!("preprocessing: {e}"));
                    return t;
                }
            };
            t.preprocessing = applied;
            match indentify_analysis::analyze(&x, o) {
                Ok(a) => {
                    t.values = OpValues::of(&a);
                    t.error = a.error.clone();
                    t.analysis = Some(a);
                }
                Err(e) => t.error = Some(e.to_string()),
            }
            t
        })
        .collect()
}

/// The vendor results table beside an Anton Paar multi-test file, attached to its records.
fn attach_vendor(records: &mut [Record], file: &Path, results: Option<&Path>) -> Result<()> {
    let path = match results {
        Some(p) => p.to_path_buf(),
        None => {
            let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned());
            let ext = file.extension().map(|s| s.to_string_lossy().into_owned());
            let (Some(stem), Some(ext)) = (stem, ext) else {
                return Ok(());
            };
            let p = file.with_file_name(format!("{stem}_data.{ext}"));
            if !p.is_file() {
                return Ok(());
            }
            p
        }
    };
    let bytes = std::fs::read(&path)
        .with_context(|| format!("cannot read `{}`", path.display()))
        .map_err(|e| Error::new(ErrorKind::Io, e))?;
    let table =
        indentify_records::read_results(&bytes, &path.display().to_string()).map_err(data_error)?;
    indentify_records::attach_results(records, &table);
    Ok(())
}

/// Reads, preprocesses and analyses every test (or the selected one); writes
/// `analysis.json` and `analysis.csv` into `opts.out` when given. A test that cannot be
/// analysed carries its `error`; the others are analysed.
///
/// # Errors
/// An unreadable file or one of unknown layout, options out of range, an output folder
/// that cannot be written.
pub fn run(opts: &AnalyzeOptions) -> Result<AnalyzeOutcome> {
    let start = Instant::now();
    let mut records = read_records(&opts.file, opts.test)?;
    attach_vendor(&mut records, &opts.file, opts.results.as_deref())?;
    let format = records.first().map_or(Format::Csv, |r| r.meta.format);
    let (default_range, source) = FitRange::for_format(format);
    let o = Options {
        tip: opts.tip.clone(),
        nu: opts.nu,
        fit_range: opts.fit_range.unwrap_or(default_range),
        epsilon: opts.epsilon,
        beta: opts.beta,
        ..Options::new(opts.tip.clone(), format)
    };
    o.validate().map_err(|e| Error::msg(ErrorKind::Config, e))?;
    if let Some(dir) = &opts.out {
        crate::atomic::ensure_writable_dir(dir).map_err(|e| Error::new(ErrorKind::Io, e))?;
    }
    let zero = opts.zero_point.unwrap_or(zero_point_default(format));
    let mut prep = preprocessing(opts.tip.frame_compliance, zero);
    if let Some(k) = opts.surface_stiffness {
        prep.zero_point = Some(ZeroPoint {
            stiffness: Some(k),
            ..ZeroPoint::default()
        });
    }
    let tests = analyse_records(&records, opts.test.unwrap_or(1), &o, &prep);
    let mut out = AnalyzeOutcome {
        file: opts.file.display().to_string(),
        format: format.name().into(),
        tip: opts.tip.clone(),
        nu: opts.nu,
        beta: opts.beta,
        epsilon: opts.epsilon,
        fit_range: o.fit_range,
        fit_range_source: if opts.fit_range.is_some() {
            "given".into()
        } else {
            source.into()
        },
        tests,
        seconds: 0.0,
        written: Vec::new(),
    };
    if let Some(dir) = &opts.out {
        let json = dir.join("analysis.json");
        let csv = dir.join("analysis.csv");
        out.seconds = start.elapsed().as_secs_f64();
        crate::atomic::write(&json, to_json(&out)).map_err(|e| Error::new(ErrorKind::Io, e))?;
        crate::atomic::write(&csv, to_csv(&out)).map_err(|e| Error::new(ErrorKind::Io, e))?;
        out.written = vec![json.display().to_string(), csv.display().to_string()];
        // the unloading fits and H and E against depth (crate::analysis_figures)
        let figures = crate::analysis_figures::write(dir, &out, &records, &prep)?;
        out.written
            .extend(figures.iter().map(|p| p.display().to_string()));
    }
    out.seconds = start.elapsed().as_secs_f64();
    Ok(out)
}

/// The outcome as JSON (internal units: N, mm, N/mm, MPa, s).
pub fn to_json(o: &AnalyzeOutcome) -> String {
    serde_json::to_string_pretty(o).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}

fn opt(v: Option<f64>, scale: f64, digits: usize) -> String {
    v.map_or(String::new(), |x| sig(x * scale, digits))
}

/// One CSV row per unloading, in display units (mN, nm, GPa, mN/nm, pJ).
pub fn to_csv(o: &AnalyzeOutcome) -> String {
    let mut s = String::from(
        "test,name,unloading,t_start_s,Fmax_mN,hmax_nm,m,hf_nm,fit_points,fit_r2,S_mN_per_nm,epsilon,hc_nm,Ap_nm2,H_GPa,Er_GPa,Estar_GPa,E_GPa,hold_s,creep_nm,CIT_pct,creep_rate_nm_per_s,srs,Wtotal_pJ,Welast_pJ,eta_pct,error\n",
    );
    for t in &o.tests {
        let name = t.test.replace([',', '"', '\n'], " ");
        let Some(a) = &t.analysis else {
            s.push_str(&format!(
                "{},{name},,,,,,,,,,,,,,,,,,,,,,,,,{}\n",
                t.index,
                t.error
                    .as_deref()
                    .unwrap_or("")
                    .replace([',', '"', '\n'], " ")
            ));
            continue;
        };
        for u in &a.unloadings {
            let fit = u.fit.as_ref();
            let op = u.op.as_ref();
            let hold = u.hold.as_ref();
            let cells = [
                t.index.to_string(),
                name.clone(),
                u.number.to_string(),
                sig(u.t_start, 6),
                sig(u.f_max * 1e3, 6),
                sig(u.h_max * 1e6, 6),
                opt(fit.map(|f| f.m), 1.0, 5),
                opt(fit.map(|f| f.h_f), 1e6, 6),
                fit.map_or(String::new(), |f| f.n.to_string()),
                opt(fit.map(|f| f.r2), 1.0, 6),
                opt(op.map(|p| p.s), 1e-3, 6),
                opt(op.map(|p| p.epsilon), 1.0, 4),
                opt(op.map(|p| p.hc), 1e6, 6),
                opt(op.map(|p| p.area), 1e12, 6),
                opt(op.map(|p| p.hardness), 1e-3, 5),
                opt(op.map(|p| p.er), 1e-3, 5),
                opt(op.and_then(|p| p.e_star), 1e-3, 5),
                opt(op.and_then(|p| p.e), 1e-3, 5),
                opt(hold.map(|h| h.t.1 - h.t.0), 1.0, 4),
                opt(hold.map(|h| h.creep), 1e6, 5),
                opt(hold.map(|h| h.c_it), 1.0, 4),
                opt(hold.map(|h| h.rate), 1e6, 4),
                opt(hold.and_then(|h| h.srs), 1.0, 4),
                sig(u.work.total * 1e9, 6),
                sig(u.work.elastic * 1e9, 6),
                sig(u.work.eta, 4),
                u.error
                    .as_deref()
                    .unwrap_or("")
                    .replace([',', '"', '\n'], " "),
            ];
            s.push_str(&cells.join(","));
            s.push('\n');
        }
    }
    s
}

/// The per-test table (display units), with the vendor's values beside ours where the
/// file gives them, then each failed test's or unloading's reason.
pub fn summary_table(o: &AnalyzeOutcome) -> String {
    let mut rows = vec![vec![
        "test".to_string(),
        "Fmax mN".into(),
        "hmax nm".into(),
        "S mN/nm".into(),
        "hc nm".into(),
        "H GPa".into(),
        "Er GPa".into(),
        "E GPa".into(),
        "m".into(),
        "unloadings".into(),
        "vendor H, E GPa".into(),
    ]];
    let mut notes = Vec::new();
    for t in &o.tests {
        let a = t.analysis.as_ref();
        let main = a.and_then(|a| a.values());
        let n_ok = a.map_or(0, |a| {
            a.unloadings.iter().filter(|u| u.op.is_some()).count()
        });
        let n_all = a.map_or(0, |a| a.unloadings.len());
        rows.push(vec![
            format!("{} {}", t.index, t.test),
            opt(t.values.fmax, 1e3, 5),
            opt(t.values.hmax, 1e6, 5),
            opt(t.values.s, 1e-3, 4),
            opt(t.values.hc, 1e6, 5),
            opt(t.values.h, 1e-3, 4),
            opt(t.values.er, 1e-3, 4),
            opt(t.values.e, 1e-3, 4),
            main.and_then(|(u, _)| u.fit.as_ref().map(|f| sig(f.m, 3)))
                .unwrap_or_default(),
            format!("{n_ok}/{n_all}"),
            vendor_pair(&t.vendor),
        ]);
        if let Some(e) = &t.error {
            notes.push(format!("test {} ({}): {e}", t.index, t.test));
        } else if let Some(a) = a {
            for u in &a.unloadings {
                if let Some(e) = &u.error {
                    notes.push(format!(
                        "test {} ({}), unloading {}: {e}",
                        t.index, t.test, u.number
                    ));
                }
            }
        }
    }
    let mut s = table(&rows, "  ");
    for n in notes {
        s.push_str(&format!("  ! {n}\n"));
    }
    s
}

/// The vendor's H and E (GPa) when the file gives them under a known name.
fn vendor_pair(v: &[Quantity]) -> String {
    let find = |names: &[&str]| {
        v.iter()
            .find(|q| names.iter().any(|n| q.name.eq_ignore_ascii_case(n)))
            .and_then(|q| match q.unit.trim() {
                "GPa" => Some(q.value),
                "MPa" => Some(q.value * 1e-3),
                _ => None,
            })
    };
    let h = find(&["HIT (O&P)", "HIT", "Hardness", "H_IT"]);
    let e = find(&["EIT (O&P)", "EIT", "Modulus", "E_IT"]);
    match (h, e) {
        (None, None) => String::new(),
        (h, e) => format!(
            "{}, {}",
            h.map_or("-".into(), |x| sig(x, 4)),
            e.map_or("-".into(), |x| sig(x, 4))
        ),
    }
}

/// What to calibrate on and how.
#[derive(Debug, Clone)]
pub struct CalibrateOptions {
    /// The reference's file (fused silica).
    pub file: PathBuf,
    /// Only these 1-based tests; `None`: all.
    pub tests: Option<Vec<usize>>,
    /// The reference's Young's modulus, MPa.
    pub modulus: f64,
    /// The reference's Poisson's ratio.
    pub nu: f64,
    /// The tip's material and nominal shape (the start of the calibration).
    pub tip: Tip,
    /// `beta`.
    pub beta: f64,
    /// The unloading fit's range; `None`: the format's default.
    pub fit_range: Option<FitRange>,
    /// A known frame compliance, mm/N; `None`: fitted.
    pub compliance: Option<f64>,
    /// The frame-compliance fit uses the unloadings with `F_max` at least this fraction
    /// of the largest (default 0.25).
    pub compliance_range: f64,
    /// Number of area coefficients (default 3: C0, C1, C2).
    pub terms: usize,
    /// The tip file to write.
    pub out: Option<PathBuf>,
}

impl CalibrateOptions {
    /// Defaults: diamond Berkovich, `beta` 1, fitted compliance from the unloadings above
    /// 25 % of the largest force, 3 area coefficients.
    pub fn new(file: impl Into<PathBuf>, modulus: f64, nu: f64) -> CalibrateOptions {
        CalibrateOptions {
            file: file.into(),
            tests: None,
            modulus,
            nu,
            tip: Tip::berkovich(),
            beta: 1.0,
            fit_range: None,
            compliance: None,
            compliance_range: 0.25,
            terms: 3,
            out: None,
        }
    }
}

/// The outcome of [`calibrate()`].
#[derive(Debug, Clone, Serialize)]
pub struct CalibrateOutcome {
    /// The calibrated tip (what the tip file holds).
    pub tip: Tip,
    /// The frame-compliance fit (`None` when it was given).
    pub compliance: Option<Compliance>,
    /// The compliance used, mm/N.
    pub compliance_used: f64,
    /// The area-function fit.
    pub area: AreaFit,
    /// The reference's reduced modulus, MPa.
    pub er: f64,
    /// Tests or unloadings that gave no point, with the reason.
    pub skipped: Vec<String>,
    /// Wall time, s.
    pub seconds: f64,
    /// The tip file written.
    pub written: Option<String>,
}

fn points(tests: &[TestOutcome], skipped: &mut Vec<String>) -> Vec<Point> {
    let mut p = Vec::new();
    for t in tests {
        if let Some(e) = &t.error {
            skipped.push(format!("test {} ({}): {e}", t.index, t.test));
        }
        let Some(a) = &t.analysis else { continue };
        for u in &a.unloadings {
            match (&u.op, &u.error) {
                (Some(op), _) => p.push(Point {
                    test: t.test.clone(),
                    unloading: u.number,
                    f_max: u.f_max,
                    h_max: u.h_max,
                    s: op.s,
                }),
                (None, Some(e)) => skipped.push(format!(
                    "test {} ({}), unloading {}: {e}",
                    t.index, t.test, u.number
                )),
                _ => {}
            }
        }
    }
    p
}

/// Calibrates the frame compliance and the ISO area function on a reference of known
/// modulus, and writes the tip file (RON) when `out` is given.
///
/// # Errors
/// An unreadable file, options out of range, a calibration that gives a negative
/// compliance or no area function (the message says why), an unwritable tip file.
pub fn calibrate(opts: &CalibrateOptions) -> Result<CalibrateOutcome> {
    let start = Instant::now();
    if !(opts.modulus > 0.0 && opts.modulus.is_finite()) {
        return Err(Error::msg(
            ErrorKind::Config,
            format!(
                "--modulus {} is not allowed; expected the reference's Young's modulus > 0 (MPa)",
                opts.modulus
            ),
        ));
    }
    let mut records = read_records(&opts.file, None)?;
    let all = records.len();
    if let Some(sel) = &opts.tests {
        for &k in sel {
            if !(1..=all).contains(&k) {
                return Err(Error::msg(
                    ErrorKind::Config,
                    format!("test {k} does not exist; expected 1 to {all}"),
                ));
            }
        }
        records = records
            .into_iter()
            .enumerate()
            .filter(|(i, _)| sel.contains(&(i + 1)))
            .map(|x| x.1)
            .collect();
    }
    let format = records.first().map_or(Format::Csv, |r| r.meta.format);
    let mut tip = opts.tip.clone();
    tip.frame_compliance = None;
    let o = Options {
        fit_range: opts.fit_range.unwrap_or(FitRange::for_format(format).0),
        beta: opts.beta,
        nu: opts.nu,
        ..Options::new(tip.clone(), format)
    };
    o.validate().map_err(|e| Error::msg(ErrorKind::Config, e))?;
    if let Some(p) = &opts.out {
        if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
            crate::atomic::ensure_writable_dir(dir).map_err(|e| Error::new(ErrorKind::Io, e))?;
        }
    }
    let calib = |e: indentify_analysis::AnalysisError| Error::msg(ErrorKind::Data, e);
    let mut skipped = Vec::new();
    let (compliance, c) = match opts.compliance {
        Some(c) => {
            if !(c >= 0.0 && c.is_finite()) {
                return Err(Error::msg(
                    ErrorKind::Config,
                    format!(
                        "--compliance {c} is not allowed; expected a finite compliance >= 0 (mm/N)"
                    ),
                ));
            }
            (None, c)
        }
        None => {
            let raw = analyse_records(
                &records,
                1,
                &o,
                &preprocessing(Some(0.0), zero_point_default(format)),
            );
            let mut ignore = Vec::new();
            let pts = points(&raw, &mut ignore);
            let fit = calibrate::frame_compliance(&pts, opts.compliance_range).map_err(calib)?;
            let c = fit.c;
            (Some(fit), c)
        }
    };
    let corrected = analyse_records(
        &records,
        1,
        &o,
        &preprocessing(Some(c), zero_point_default(format)),
    );
    let pts = points(&corrected, &mut skipped);
    let er = calibrate::reduced_modulus(opts.modulus, opts.nu, &tip);
    let area = calibrate::area_function(
        &pts,
        &tip.area,
        er,
        opts.beta,
        tip.area.epsilon(),
        opts.terms,
    )
    .map_err(calib)?;
    let tip = Tip {
        name: format!(
            "calibrated on {} (E {} GPa, nu {}): {} unloadings, h_c {:.0} to {:.0} nm",
            opts.file
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
            sig(opts.modulus * 1e-3, 4),
            opts.nu,
            area.n,
            area.hc_range.0 * 1e6,
            area.hc_range.1 * 1e6
        ),
        area: AreaFunction::Iso {
            coefficients: area.coefficients.clone(),
        },
        modulus: tip.modulus,
        poisson: tip.poisson,
        frame_compliance: Some(c),
        radius: area.radius,
    };
    let mut out = CalibrateOutcome {
        tip,
        compliance,
        compliance_used: c,
        area,
        er,
        skipped,
        seconds: 0.0,
        written: None,
    };
    if let Some(p) = &opts.out {
        crate::atomic::write(p, tip_ron(&out.tip)).map_err(|e| Error::new(ErrorKind::Io, e))?;
        out.written = Some(p.display().to_string());
    }
    out.seconds = start.elapsed().as_secs_f64();
    Ok(out)
}

/// The tip as a RON tip file.
pub fn tip_ron(tip: &Tip) -> String {
    let body = ron::ser::to_string_pretty(tip, ron::ser::PrettyConfig::default())
        .unwrap_or_else(|e| format!("// cannot serialize the tip: {e}"));
    format!(
        "// indentify tip file: the area function A(h_c) (h_c in mm, A in mm^2; Iso: C0 h^2 + C1 h + C2 h^(1/2) + ...),\n// the tip's modulus (MPa) and Poisson's ratio, the frame compliance (mm/N), an equivalent radius (mm).\n{body}\n"
    )
}

/// A tip from its name, as `indentify analyze --tip` and the server take it: `berkovich`
/// (or `vickers`, the same area function), `cone:HALF_ANGLE_DEG`, `sphere:RADIUS_UM`,
/// `flat:RADIUS_UM`; a diamond tip, validated.
///
/// # Errors
/// An unknown shape or a parameter that is not a number, naming the allowed forms.
pub fn tip_from_name(s: &str) -> anyhow::Result<Tip> {
    let (shape, value) = s.split_once(':').map_or((s, None), |(a, b)| (a, Some(b)));
    let num = |what: &str| -> anyhow::Result<f64> {
        let Some(v) = value else {
            anyhow::bail!("--tip {s}: the {shape} needs its {what}, as {shape}:VALUE")
        };
        v.trim()
            .parse::<f64>()
            .map_err(|_| anyhow::anyhow!("--tip {s}: '{v}' is not a number ({what})"))
    };
    let area = match shape.trim().to_ascii_lowercase().as_str() {
        "berkovich" | "vickers" => AreaFunction::Berkovich,
        "cone" => AreaFunction::Cone {
            half_angle_deg: num("half-angle in degrees")?,
        },
        "sphere" => AreaFunction::Sphere {
            radius: num("radius in um")? * 1e-3,
        },
        "flat" => AreaFunction::Flat {
            radius: num("radius in um")? * 1e-3,
        },
        other => anyhow::bail!(
            "--tip {other} is not a known shape; expected berkovich, cone:HALF_ANGLE_DEG, \
             sphere:RADIUS_UM or flat:RADIUS_UM"
        ),
    };
    let tip = Tip::diamond(area);
    tip.validate()?;
    Ok(tip)
}

/// `epsilon` from its name: `tip` (the tip's own), `m` (from the unloading exponent) or a
/// number.
///
/// # Errors
/// Anything else, naming the allowed values.
pub fn epsilon_from_name(s: &str) -> anyhow::Result<Epsilon> {
    match s.trim() {
        "tip" => Ok(Epsilon::Tip),
        "m" => Ok(Epsilon::FromM),
        v => v
            .parse::<f64>()
            .map(Epsilon::Value)
            .map_err(|_| anyhow::anyhow!("--epsilon {v}: expected tip, m or a number")),
    }
}

/// Reads a tip file.
///
/// # Errors
/// An unreadable file, RON that is not a tip (the message names the line), values out of
/// range.
pub fn read_tip(path: &Path) -> Result<Tip> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the tip file `{}`", path.display()))
        .map_err(|e| Error::new(ErrorKind::Io, e))?;
    let tip: Tip = ron::from_str(&text).map_err(|e| {
        Error::msg(
            ErrorKind::Config,
            format!("{}:{}: {}", path.display(), e.span.start.line, e.code),
        )
    })?;
    tip.validate()
        .map_err(|e| Error::msg(ErrorKind::Config, format!("{}: {e}", path.display())))?;
    Ok(tip)
}

/// The calibration in words: compliance, coefficients, radius, what was dropped.
pub fn calibration_summary(o: &CalibrateOutcome) -> String {
    let mut s = String::new();
    match &o.compliance {
        Some(c) => s.push_str(&format!(
            "frame compliance C_f = {} nm/mN (1/S = C_f + k/sqrt(F) over {} unloadings from {} mN, R^2 {})\n",
            sig(c.c * 1e3, 4),
            c.n,
            sig(c.f_min * 1e3, 3),
            sig(c.r2, 4)
        )),
        None => s.push_str(&format!(
            "frame compliance C_f = {} nm/mN (given)\n",
            sig(o.compliance_used * 1e3, 4)
        )),
    }
    s.push_str(&format!(
        "reference E_r = {} GPa; area function from {} unloadings, h_c {} to {} nm, rms misfit {} %:\n  {}\n",
        sig(o.er * 1e-3, 4),
        o.area.n,
        sig(o.area.hc_range.0 * 1e6, 4),
        sig(o.area.hc_range.1 * 1e6, 4),
        sig(o.area.rms_rel * 100.0, 3),
        o.tip.area.describe()
    ));
    if let Some(r) = o.area.radius {
        s.push_str(&format!(
            "equivalent tip radius (sphere through the shallowest quarter) {} nm\n",
            sig(r * 1e6, 4)
        ));
    }
    for w in &o.area.warnings {
        s.push_str(&format!("  ! {w}\n"));
    }
    for (t, u, r) in &o.area.rejected {
        s.push_str(&format!(
            "  ! dropped as an outlier: {t}, unloading {u} (area misfit {} %)\n",
            sig(r * 100.0, 3)
        ));
    }
    for k in &o.skipped {
        s.push_str(&format!("  ! skipped: {k}\n"));
    }
    s
}
