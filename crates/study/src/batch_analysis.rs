//! `indentify batch MANIFEST --analyze`: the Oliver-Pharr analysis of every indent of a
//! manifest (its `data` and `test` columns; `config` and configuration columns are not
//! used), in parallel on `jobs` threads with the results in manifest order (the same for
//! any thread count), written atomically as `OUT/analysis.csv` (one row per indent,
//! display units) and, when the manifest gives positions, as heat maps and histograms of
//! `H_IT` and `E_IT` with units and equal aspect (`OUT/maps/H_IT_map.svg`, ...): the quick
//! look before an FE map (docs/scale-out.md). Each indent is analysed as
//! `indentify analyze` analyses a test (`crate::analyze`); one that cannot be (no
//! unloading, unreadable file) carries its reason and the others are analysed.

use std::path::{Path, PathBuf};
use std::time::Instant;

use indentify_analysis::{Epsilon, FitRange, Options, Tip};
use indentify_records::{Format, ReadOptions};
use indentify_report::{FigureSize, MapData, MapFigure};
use rayon::prelude::*;
use serde::Serialize;

use crate::analyze::OpValues;
use crate::batch::Indent;
use crate::error::{Classify, Error, ErrorKind, Result};
use crate::format::sig;

/// What to analyse and how.
#[derive(Debug, Clone)]
pub struct BatchAnalysisOptions {
    /// The manifest (CSV: `id`, `data`, `test`, `x`, `y`).
    pub manifest: PathBuf,
    /// The output folder.
    pub out: PathBuf,
    /// The tip (every indent's).
    pub tip: Tip,
    /// Poisson's ratio of the sample.
    pub nu: f64,
    /// The unloading fit's force range; `None`: each file format's vendor default.
    pub fit_range: Option<FitRange>,
    /// Where epsilon comes from.
    pub epsilon: Epsilon,
    /// `beta` of `E_r`.
    pub beta: f64,
    /// Worker threads (0: every core).
    pub jobs: usize,
}

impl BatchAnalysisOptions {
    /// Ideal diamond Berkovich, `nu` 0.3, the vendor's fit range, the tip's epsilon,
    /// `beta` 1, every core.
    pub fn new(manifest: impl Into<PathBuf>, out: impl Into<PathBuf>) -> BatchAnalysisOptions {
        BatchAnalysisOptions {
            manifest: manifest.into(),
            out: out.into(),
            tip: Tip::berkovich(),
            nu: 0.3,
            fit_range: None,
            epsilon: Epsilon::Tip,
            beta: 1.0,
            jobs: 0,
        }
    }
}

/// One indent's O&P values (MPa, N/mm, mm, N) from its main unloading.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IndentAnalysis {
    /// The manifest id.
    pub id: String,
    /// Position (mm).
    pub x: Option<f64>,
    /// Position (mm).
    pub y: Option<f64>,
    /// The O&P values of the main unloading (`analyze`'s, one struct for both).
    #[serde(flatten)]
    pub values: OpValues,
    /// The unloading exponent.
    pub m: Option<f64>,
    /// Why the indent gave no values.
    pub error: Option<String>,
}

/// The outcome of [`run`].
#[derive(Debug, Clone, Serialize)]
pub struct BatchAnalysisOutcome {
    /// Every indent, in manifest order.
    pub indents: Vec<IndentAnalysis>,
    /// Indents with values.
    pub analysed: usize,
    /// Indents without (their `error` says why).
    pub failed: usize,
    /// Wall time, s.
    pub seconds: f64,
    /// Files written.
    pub written: Vec<PathBuf>,
}

/// The manifest's indents (no configuration needed: an analysis reads only `data`,
/// `test`, `x` and `y`).
///
/// # Errors
/// As [`crate::batch::read_manifest`].
pub fn read_manifest(path: &Path) -> Result<Vec<Indent>> {
    let bytes = std::fs::read(path).map_err(|e| {
        Error::msg(
            ErrorKind::Config,
            format!("cannot read the manifest `{}`: {e}", path.display()),
        )
    })?;
    crate::batch::parse_manifest(&bytes, path, true)
        .map(|(indents, _)| indents)
        .map_err(|e| {
            Error::msg(
                ErrorKind::Config,
                format!("invalid manifest `{}`: {e:#}", path.display()),
            )
        })
}

fn analyse_indent(
    indent: &Indent,
    o: &BatchAnalysisOptions,
    prep: &dyn Fn(Format) -> indentify_records::Preprocessing,
) -> IndentAnalysis {
    let mut a = IndentAnalysis {
        id: indent.id.clone(),
        x: indent.x,
        y: indent.y,
        values: OpValues::default(),
        m: None,
        error: None,
    };
    if let Err(e) = fill(&mut a, indent, o, prep) {
        a.error = Some(e);
    }
    a
}

fn fill(
    a: &mut IndentAnalysis,
    indent: &Indent,
    o: &BatchAnalysisOptions,
    prep: &dyn Fn(Format) -> indentify_records::Preprocessing,
) -> std::result::Result<(), String> {
    let Some(file) = &indent.data else {
        return Err("no `data` file in the manifest row".into());
    };
    let bytes =
        std::fs::read(file).map_err(|e| format!("cannot read `{}`: {e}", file.display()))?;
    let name = file.display().to_string();
    let records = indentify_records::read(
        &bytes,
        &name,
        &ReadOptions {
            format: Format::Auto,
            test: indent.test,
        },
    )
    .map_err(|e| e.to_string())?;
    let r = records
        .first()
        .ok_or_else(|| format!("`{name}` holds no test"))?;
    let format = r.meta.format;
    let (x, _) = indentify_records::apply(r, &prep(format)).map_err(|e| e.to_string())?;
    let opts = Options {
        nu: o.nu,
        fit_range: o.fit_range.unwrap_or(FitRange::for_format(format).0),
        epsilon: o.epsilon,
        beta: o.beta,
        ..Options::new(o.tip.clone(), format)
    };
    opts.validate().map_err(|e| e.to_string())?;
    let t = indentify_analysis::analyze(&x, &opts).map_err(|e| e.to_string())?;
    let (u, _) = t.values().ok_or_else(|| {
        t.error
            .clone()
            .unwrap_or_else(|| "no unloading could be analysed".into())
    })?;
    a.values = OpValues::of(&t);
    a.m = u.fit.as_ref().map(|f| f.m);
    Ok(())
}

/// Analyses every indent of the manifest and writes `analysis.csv` and the maps.
///
/// # Errors
/// An unreadable or invalid manifest, options out of range, an output folder that
/// cannot be written; one indent's failure is its row's `error`, not an error.
pub fn run(o: &BatchAnalysisOptions) -> Result<BatchAnalysisOutcome> {
    let start = Instant::now();
    let manifest = read_manifest(&o.manifest)?;
    Options {
        nu: o.nu,
        epsilon: o.epsilon,
        beta: o.beta,
        ..Options::new(o.tip.clone(), Format::Csv)
    }
    .validate()
    .map_err(|e| Error::msg(ErrorKind::Config, e))?;
    crate::atomic::ensure_writable_dir(&o.out).kind(ErrorKind::Io)?;
    let compliance = o.tip.frame_compliance;
    let prep = move |f: Format| {
        crate::analyze::preprocessing(compliance, crate::analyze::zero_point_default(f))
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(o.jobs)
        .build()
        .map_err(|e| {
            Error::msg(
                ErrorKind::Config,
                format!("cannot start {} threads: {e}", o.jobs),
            )
        })?;
    let indents: Vec<IndentAnalysis> = pool.install(|| {
        manifest
            .par_iter()
            .map(|i| analyse_indent(i, o, &prep))
            .collect()
    });
    let analysed = indents.iter().filter(|a| a.error.is_none()).count();
    let mut out = BatchAnalysisOutcome {
        failed: indents.len() - analysed,
        analysed,
        indents,
        seconds: 0.0,
        written: Vec::new(),
    };
    let csv = o.out.join("analysis.csv");
    crate::atomic::write(&csv, to_csv(&out.indents)).kind(ErrorKind::Io)?;
    out.written.push(csv);
    out.written.extend(write_maps(&o.out, &out.indents)?);
    out.seconds = start.elapsed().as_secs_f64();
    Ok(out)
}

fn cell(v: Option<f64>, scale: f64, digits: usize) -> String {
    v.map_or(String::new(), |x| sig(x * scale, digits))
}

/// One row per indent, display units (mm, mN, nm, mN/nm, GPa).
pub fn to_csv(indents: &[IndentAnalysis]) -> String {
    let mut s =
        String::from("id,x_mm,y_mm,Fmax_mN,hmax_nm,hc_nm,S_mN_per_nm,m,H_GPa,Er_GPa,E_GPa,error\n");
    for a in indents {
        let cells = [
            a.id.clone(),
            a.x.map_or(String::new(), |v| v.to_string()),
            a.y.map_or(String::new(), |v| v.to_string()),
            cell(a.values.fmax, 1e3, 6),
            cell(a.values.hmax, 1e6, 6),
            cell(a.values.hc, 1e6, 6),
            cell(a.values.s, 1e-3, 6),
            cell(a.m, 1.0, 5),
            cell(a.values.h, 1e-3, 6),
            cell(a.values.er, 1e-3, 6),
            cell(a.values.e, 1e-3, 6),
            a.error
                .as_deref()
                .unwrap_or("")
                .replace([',', '"', '\n'], " "),
        ];
        s.push_str(&cells.join(","));
        s.push('\n');
    }
    s
}

/// Heat maps and histograms of H_IT and E_IT (GPa) over the indents with positions.
fn write_maps(out: &Path, indents: &[IndentAnalysis]) -> Result<Vec<PathBuf>> {
    let placed: Vec<&IndentAnalysis> = indents
        .iter()
        .filter(|a| a.x.is_some() && a.y.is_some())
        .collect();
    if placed.is_empty() {
        return Ok(Vec::new());
    }
    let dir = out.join("maps");
    crate::atomic::ensure_writable_dir(&dir).kind(ErrorKind::Io)?;
    let x: Vec<f64> = placed.iter().map(|a| a.x.unwrap_or(f64::NAN)).collect();
    let y: Vec<f64> = placed.iter().map(|a| a.y.unwrap_or(f64::NAN)).collect();
    let mut written = Vec::new();
    for (stem, title, values) in [
        (
            "H_IT",
            "indentation hardness H_IT (GPa)",
            placed
                .iter()
                .map(|a| a.values.h.map_or(f64::NAN, |v| v * 1e-3))
                .collect::<Vec<_>>(),
        ),
        (
            "E_IT",
            "indentation modulus E_IT (GPa)",
            placed
                .iter()
                .map(|a| a.values.e.map_or(f64::NAN, |v| v * 1e-3))
                .collect(),
        ),
    ] {
        if !values.iter().any(|v| v.is_finite()) {
            continue;
        }
        let data = MapData {
            title: title.into(),
            x: x.clone(),
            y: y.clone(),
            values,
            position_unit: "mm".into(),
        };
        for (fig, suffix) in [(MapFigure::HeatMap, "map"), (MapFigure::Histogram, "hist")] {
            let svg = data
                .svg(fig, FigureSize::default())
                .map_err(|e| Error::msg(ErrorKind::Io, format!("cannot draw {stem}: {e}")))?;
            let p = dir.join(format!("{stem}_{suffix}.svg"));
            crate::atomic::write(&p, svg).kind(ErrorKind::Io)?;
            written.push(p);
        }
    }
    Ok(written)
}
