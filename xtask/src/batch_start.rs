//! Batch manifests whose rows start from their own record's Oliver-Pharr first guess
//! (`cargo xtask fit-cost --batch`): the `identify.params.NAME.start` columns computed
//! once from each row's record (`indentify_study::start_from_analysis::starts`), so that
//! an indent's start is fixed by the manifest, whatever the thread count or the order the
//! workers take the indents in; and a row's closed-form start as the product computes it
//! (`indentify_study::closed_form_start`, what `indentify batch --start closed-form` runs),
//! for the stage profile.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use indentify_study::ConfigSource;
use indentify_study::closed_form_start::ClosedFormStart;
use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::synthetic::MapFiles;

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

/// The identification options of row `id` of `map` (its record, the base configuration).
fn row_options(map: &MapFiles, id: &str) -> IdentifyOptions {
    let dir = map.manifest.parent().unwrap_or(Path::new("."));
    let mut o = IdentifyOptions::new(ConfigSource::Path(map.base.clone()));
    o.data = Some(dir.join("records").join(format!("{id}.csv")));
    o.jobs = Some(1);
    o
}

/// The closed-form start of row `id` of `map`, as `indentify batch --start closed-form`
/// computes it (its calibration run included): the values set, or why none.
///
/// # Errors
/// A row whose problem cannot be set up.
pub fn closed_form_start(map: &MapFiles, id: &str) -> Result<ClosedFormStart> {
    let opts = row_options(map, id);
    let mut s = identify::setup(identify::resolve(&opts)?, &opts)?;
    Ok(indentify_study::closed_form_start::apply(&mut s))
}
