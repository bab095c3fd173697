//! Batch manifests whose rows start from their own record's Oliver-Pharr first guess
//! (`cargo xtask fit-cost --batch`): the `identify.params.NAME.start` columns computed
//! once from each row's record (`indentify_study::start_from_analysis::starts`), so that
//! an indent's start is fixed by the manifest, whatever the thread count or the order the
//! workers take the indents in.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use indentify_contact::Punch;
use indentify_identify::Evaluator;
use indentify_study::ConfigSource;
use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::synthetic::MapFiles;

use crate::lee_radok;

/// Writes `OUT` = the map's manifest with the columns `identify.params.NAME.start` of
/// every free parameter the O&P first guess of the row's record gives (rows without a
/// guess keep the base start: the column left empty, and the first reason is logged).
/// Returns the path and how many rows have a guess.
pub fn start_manifest(map: &MapFiles, out: &Path) -> Result<(PathBuf, usize)> {
    let dir = map.manifest.parent().unwrap_or(Path::new("."));
    let base = ConfigSource::Path(map.base.clone());
    let mut rows: Vec<(String, Vec<(String, f64)>)> = Vec::new();
    for (id, ..) in &map.indents {
        let record = dir.join("records").join(format!("{id}.csv"));
        let starts = match indentify_study::start_from_analysis::starts(&base, &[], Some(&record)) {
            Ok(s) => s.starts,
            Err(e) => {
                eprintln!("{id}: no first guess: {}", e.messages().join(": "));
                Vec::new()
            }
        };
        rows.push((id.clone(), starts));
    }
    let starts: Vec<Vec<(String, f64)>> = rows.into_iter().map(|(_, s)| s).collect();
    write_starts(map, out, &starts)
}

/// Writes `out` = the map's manifest with a column `identify.params.NAME.start` for every
/// name of `rows` (one list per manifest row, in order; a row's missing names left empty).
/// Returns the path and how many rows have a start.
fn write_starts(
    map: &MapFiles,
    out: &Path,
    rows: &[Vec<(String, f64)>],
) -> Result<(PathBuf, usize)> {
    let mut names: Vec<String> = Vec::new();
    for (n, _) in rows.iter().flatten() {
        if !names.contains(n) {
            names.push(n.clone());
        }
    }
    let text = std::fs::read_to_string(&map.manifest)
        .with_context(|| format!("reading {}", map.manifest.display()))?;
    let mut lines = text.lines();
    let header = lines.next().unwrap_or_default();
    let mut s = String::from(header);
    for n in &names {
        let _ = write!(s, ",identify.params.{n}.start");
    }
    s.push('\n');
    let mut guessed = 0;
    for (line, starts) in lines.zip(rows) {
        s.push_str(line);
        if !starts.is_empty() {
            guessed += 1;
        }
        for n in &names {
            s.push(',');
            if let Some((_, v)) = starts.iter().find(|(m, _)| m == n) {
                let _ = write!(s, "{v:e}");
            }
        }
        s.push('\n');
    }
    std::fs::write(out, s).with_context(|| format!("writing {}", out.display()))?;
    Ok((out.to_path_buf(), guessed))
}

/// Start overrides: `(name, value)` of each parameter given.
pub type Starts = Vec<(String, f64)>;

/// The Lee-Radok pre-fit's model ratio for the map's configuration: one forward run of
/// the finite element model at the base start on the first row's schedule
/// ([`crate::lee_radok::calibrate`]), with the cone's half-angle and the law's `nu`.
pub struct Calibration {
    /// The model ratio per sample.
    pub rho: Vec<f64>,
    /// The cone's half-angle (degrees).
    pub angle: f64,
    /// Poisson's ratio.
    pub nu: f64,
    /// The positions of `E` and `eta` in the law's parameters.
    pub e_eta: (usize, usize),
    /// Seconds it took.
    pub seconds: f64,
}

/// The identification options of row `id` of `map` (its record, the base configuration).
fn row_options(map: &MapFiles, id: &str) -> IdentifyOptions {
    let dir = map.manifest.parent().unwrap_or(Path::new("."));
    let mut o = IdentifyOptions::new(ConfigSource::Path(map.base.clone()));
    o.data = Some(dir.join("records").join(format!("{id}.csv")));
    o.jobs = Some(1);
    o
}

/// Calibrates the pre-fit on `map`'s configuration (a Maxwell law under a cone).
///
/// # Errors
/// Another law or punch, a failing forward run.
pub fn calibrate(map: &MapFiles) -> Result<Calibration> {
    let clock = std::time::Instant::now();
    let first = map.indents.first().context("an empty map")?;
    let opts = row_options(map, &first.0);
    let resolved = identify::resolve(&opts)?;
    let Punch::Cone { half_angle_deg } = resolved.cfg.punch else {
        bail!("the Lee-Radok pre-fit needs a cone");
    };
    let at = |n: &str| resolved.names.iter().position(|m| *m == n);
    let (Some(ie), Some(inu), Some(ieta), "Maxwell") =
        (at("E"), at("nu"), at("eta"), resolved.cfg.law.variant())
    else {
        bail!("the Lee-Radok pre-fit needs the Maxwell law (E, nu, eta)");
    };
    let start: Vec<f64> = resolved
        .id_cfg
        .params
        .iter()
        .map(|p| p.value.unwrap_or(0.0))
        .collect();
    let s = identify::setup(resolved, &opts)?;
    let fe = s
        .problem
        .install(|| Evaluator::new(&s.problem).and_then(|mut ev| ev.forces(&start)))?;
    let sch = s.problem.schedule();
    let nu = start[inu];
    let rho = lee_radok::calibrate(
        &sch.t,
        &sch.depth,
        &fe,
        half_angle_deg,
        nu,
        start[ie],
        start[ieta],
    );
    Ok(Calibration {
        rho,
        angle: half_angle_deg,
        nu,
        e_eta: (ie, ieta),
        seconds: clock.elapsed().as_secs_f64(),
    })
}

/// The pre-fit of row `id` of `map` as start overrides (`E`, `eta`), or why there is none.
///
/// # Errors
/// A row whose problem cannot be set up.
pub fn lee_radok_starts(
    map: &MapFiles,
    id: &str,
    cal: &Calibration,
) -> Result<Option<(Starts, lee_radok::Prefit)>> {
    let (problem, _) = identify::problem(&row_options(map, id))?;
    let sch = problem.schedule();
    let curve = lee_radok::Curve {
        t: &sch.t,
        h: &sch.depth,
        f: &problem.target,
    };
    Ok(lee_radok::prefit(&curve, &cal.rho, cal.angle, cal.nu)
        .map(|p| (vec![("E".to_string(), p.e), ("eta".to_string(), p.eta)], p)))
}

/// Writes `OUT` = the map's manifest with the columns `identify.params.E.start` and
/// `identify.params.eta.start` of each row's Lee-Radok pre-fit (one calibration run for
/// the manifest, then arithmetic per row: [`crate::lee_radok`]); a row without a pre-fit
/// keeps the base start (cells left empty, the reason logged). Returns the path and how
/// many rows have a start.
///
/// # Errors
/// As [`calibrate`]; an unreadable manifest or unwritable `out`.
pub fn lee_radok_manifest(map: &MapFiles, out: &Path) -> Result<(PathBuf, usize)> {
    let cal = calibrate(map)?;
    let mut rows = Vec::new();
    for (id, ..) in &map.indents {
        match lee_radok_starts(map, id, &cal)? {
            Some((s, _)) => rows.push(s),
            None => {
                eprintln!("{id}: no Lee-Radok pre-fit (no relaxation time in the search range)");
                rows.push(Vec::new());
            }
        }
    }
    write_starts(map, out, &rows)
}
