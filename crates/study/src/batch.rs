//! Batch identification over many indents (a map): a manifest (CSV) lists the indents,
//! each is identified in parallel into `OUT/indents/<id>/`, and `OUT/results.csv`, the heat
//! maps and the histograms are rebuilt from what is there.
//!
//! Manifest columns: `id` (unique; letters, digits, `-`, `_`, `.`), `config` (optional
//! with a base configuration), `data` (a record or curve file), `test` (a multi-test
//! file's test), `x`, `y` (positions, optional), `start` (optional: `oliver-pharr` starts
//! the indent's fit from the Oliver-Pharr analysis of its own record,
//! `crate::start_from_analysis`; empty or `config`: the configuration's start values), and
//! any further column named by a configuration path (`law.E`, `identify.params.E.start`,
//! ...), applied as `--set`.
//! The `law.*` columns take every parameter by its registry name (`law.n`, `law.K`,
//! `law.g2`; `indentify laws`) and are checked for every row before anything runs
//! ([`check_law_columns`]).
//! Relative paths are relative to the manifest's folder.
//!
//! Each indent ends with `status.json` written atomically last: an indent with one is
//! finished (a rerun skips it, `retry_failed` redoes the failed ones); one without is
//! redone. One indent's failure is recorded in its status and never stops the batch.
//! Shards (`K/N`) split the manifest deterministically (rows `i` with `i mod N = K - 1`),
//! so N processes, on one machine or as a Slurm job array, share one output folder, and
//! [`merge`] gathers them. Every indent runs single-threaded: its result does not depend
//! on the number of workers.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use anyhow::{Context as _, anyhow, bail};
use indentify_identify::Cancel;
use indentify_report::{FigureSize, MapData, MapFigure};
use serde::{Deserialize, Serialize};

use crate::config::Overrides;
use crate::error::{Classify, Error, ErrorKind, Result};
use crate::identify::{self, IdentifyOptions};
use crate::source::ConfigSource;

/// The columns with a meaning of their own; any other must be a configuration path.
pub const KNOWN_COLUMNS: [&str; 7] = ["id", "config", "data", "test", "x", "y", "start"];

/// One indent of the manifest.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Indent {
    /// The manifest line (1 = header).
    pub line: usize,
    /// Unique id (the folder name).
    pub id: String,
    /// Its configuration, if not the base one.
    pub config: Option<PathBuf>,
    /// The record or curve.
    pub data: Option<PathBuf>,
    /// Test of a multi-test file, from 1.
    pub test: Option<usize>,
    /// Position.
    pub x: Option<f64>,
    /// Position.
    pub y: Option<f64>,
    /// `path=value` overrides from the further columns.
    pub sets: Vec<String>,
    /// Start the fit from the Oliver-Pharr analysis of the indent's own record (the
    /// `start` column's `oliver-pharr`) instead of the configuration's start values.
    #[serde(default)]
    pub start_from_analysis: bool,
    /// Start the fit from the closed-form pre-fit of the indent's own curve (the `start`
    /// column's `closed-form`; [`crate::closed_form_start`]).
    #[serde(default)]
    pub start_closed_form: bool,
}

/// A manifest read and checked.
#[derive(Clone, Debug, PartialEq)]
pub struct Manifest {
    /// Its path.
    pub path: PathBuf,
    /// The indents, in file order.
    pub indents: Vec<Indent>,
    /// The further columns (configuration paths).
    pub set_columns: Vec<String>,
    /// A hash of its bytes (with the base configuration's), naming the batch.
    pub fingerprint: String,
}

/// FNV-1a, 64 bits: a stable fingerprint of a batch's inputs.
fn fnv(parts: &[&[u8]]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in parts {
        for &b in *p {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        h ^= 0xff;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// Whether `id` can name a folder on every system.
fn valid_id(id: &str) -> bool {
    !id.is_empty()
        && id.len() <= 128
        && id != "."
        && id != ".."
        && id
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
}

/// Reads and checks a manifest; `base` is the base configuration, if any.
///
/// # Errors
/// An unreadable file, no `id` column, a duplicate or invalid id, an unknown column, a
/// malformed number, a row without a configuration when there is no base one; each
/// naming the file, line and column.
pub fn read_manifest(path: &Path, base: Option<&Path>) -> Result<Manifest> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path)
        .with_context(|| format!("cannot read the manifest `{name}`"))
        .kind(ErrorKind::Config)?;
    let base_bytes = match base {
        Some(b) => std::fs::read(b)
            .with_context(|| format!("cannot read the base configuration `{}`", b.display()))
            .kind(ErrorKind::Config)?,
        None => Vec::new(),
    };
    parse_manifest(&bytes, path, base.is_some())
        .map(|(indents, set_columns)| Manifest {
            path: path.to_path_buf(),
            indents,
            set_columns,
            fingerprint: fnv(&[&bytes, &base_bytes]),
        })
        .with_context(|| format!("invalid manifest `{name}`"))
        .kind(ErrorKind::Config)
}

pub(crate) fn parse_manifest(
    bytes: &[u8],
    path: &Path,
    has_base: bool,
) -> anyhow::Result<(Vec<Indent>, Vec<String>)> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    let name = path.display().to_string();
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(bytes);
    let header: Vec<String> = reader
        .headers()
        .with_context(|| format!("{name}:1: cannot read the header"))?
        .iter()
        .map(str::to_string)
        .collect();
    let col = |c: &str| header.iter().position(|h| h == c);
    let Some(id_col) = col("id") else {
        bail!(
            "{name}:1: no `id` column (columns: {}); expected id, and config, data, test, x, y \
             or configuration paths such as law.E",
            header.join(", ")
        );
    };
    let mut set_columns = Vec::new();
    for (k, h) in header.iter().enumerate() {
        if header[..k].contains(h) {
            bail!("{name}:1: the column `{h}` appears twice");
        }
        if KNOWN_COLUMNS.contains(&h.as_str()) {
            continue;
        }
        let path_like = h.contains('.')
            && h.split('.')
                .all(|p| !p.is_empty() && p.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'));
        if !path_like {
            bail!(
                "{name}:1: unknown column `{h}`: expected id, config, data, test, x, y, start, or \
                 a configuration path such as law.E or identify.params.E.start"
            );
        }
        set_columns.push(h.clone());
    }
    let resolve = |s: &str| {
        let p = PathBuf::from(s);
        if p.is_relative() { dir.join(p) } else { p }
    };
    let mut indents: Vec<Indent> = Vec::new();
    for (k, row) in reader.records().enumerate() {
        let row = row.map_err(|e| anyhow!("{name}: {e}"))?;
        let line = row.position().map_or(k + 2, |p| p.line() as usize);
        let cell = |c: Option<usize>| {
            c.and_then(|i| row.get(i))
                .map(str::trim)
                .filter(|s| !s.is_empty())
        };
        let number = |c: &str| -> anyhow::Result<Option<f64>> {
            match cell(col(c)) {
                None => Ok(None),
                Some(s) => match s.parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(Some(v)),
                    _ => bail!("{name}:{line}: column `{c}`: `{s}` is not a finite number"),
                },
            }
        };
        let id = cell(Some(id_col)).unwrap_or("").to_string();
        if !valid_id(&id) {
            bail!(
                "{name}:{line}: id `{id}` is not allowed: expected 1 to 128 letters, digits, \
                 `-`, `_` or `.` (it names the indent's folder)"
            );
        }
        if let Some(first) = indents.iter().find(|i| i.id == id) {
            bail!(
                "{name}:{line}: id `{id}` is used twice (first on line {})",
                first.line
            );
        }
        let test = match cell(col("test")) {
            None => None,
            Some(s) => match s.parse::<usize>() {
                Ok(t) if t >= 1 => Some(t),
                _ => bail!("{name}:{line}: column `test`: `{s}` is not a test number (1, 2, ...)"),
            },
        };
        let (start_from_analysis, start_closed_form) = match cell(col("start")) {
            None | Some("config") => (false, false),
            Some("oliver-pharr") => (true, false),
            Some("closed-form") => (false, true),
            Some(s) => bail!(
                "{name}:{line}: column `start`: `{s}` is not a start: expected oliver-pharr (the \
                 Oliver-Pharr analysis of the indent's record), closed-form (the closed-form \
                 pre-fit of the indent's curve) or config (the configuration's start values; \
                 also an empty cell)"
            ),
        };
        let config = cell(col("config")).map(resolve);
        if config.is_none() && !has_base {
            bail!(
                "{name}:{line}: indent `{id}` has no configuration: fill its `config` column or \
                 give a base configuration (--config BASE.ron)"
            );
        }
        let sets = set_columns
            .iter()
            .filter_map(|c| cell(col(c)).map(|v| format!("{c}={v}")))
            .collect();
        indents.push(Indent {
            line,
            id,
            config,
            data: cell(col("data")).map(resolve),
            test,
            x: number("x")?,
            y: number("y")?,
            sets,
            start_from_analysis,
            start_closed_form,
        });
    }
    if indents.is_empty() {
        bail!("{name}: no indent: expected one row per indent under the header");
    }
    Ok((indents, set_columns))
}

/// A shard `K/N` (1 <= K <= N).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// This shard, from 1.
    pub index: usize,
    /// The number of shards.
    pub count: usize,
}

impl Shard {
    /// Parses `K/N`.
    ///
    /// # Errors
    /// Not of the form `K/N` with 1 <= K <= N.
    pub fn parse(text: &str) -> Result<Shard> {
        let bad = || {
            Error::msg(
                ErrorKind::Config,
                format!("--shard `{text}` is not allowed: expected K/N with 1 <= K <= N, e.g. 2/8"),
            )
        };
        let (k, n) = text.split_once('/').ok_or_else(bad)?;
        let (k, n): (usize, usize) = (
            k.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if k == 0 || n == 0 || k > n {
            return Err(bad());
        }
        Ok(Shard { index: k, count: n })
    }

    /// Whether the manifest row at `position` (from 0) belongs to this shard.
    pub fn contains(&self, position: usize) -> bool {
        position % self.count == self.index - 1
    }
}

/// What a batch does.
#[derive(Clone, Debug)]
pub struct BatchOptions {
    /// The manifest.
    pub manifest: PathBuf,
    /// The output folder.
    pub out: PathBuf,
    /// The base configuration of rows without `config`.
    pub config: Option<PathBuf>,
    /// Worker threads; 0 = every core.
    pub jobs: usize,
    /// Only this shard of the manifest.
    pub shard: Option<Shard>,
    /// Redo the indents that failed (finished ones are always skipped).
    pub retry_failed: bool,
    /// Identification overrides applied to every indent (method, iterations, ...).
    pub overrides: Overrides,
    /// Draw each indent's figures and report.md (slower; off by default).
    pub figures: bool,
    /// Stops the batch: running indents end after their current iteration, no new one
    /// starts.
    pub cancel: Cancel,
    /// Memory for the recorded runs of all workers together (bytes): an indent whose
    /// recording would exceed its share checkpoints (see [`IdentifyOptions::memory_budget`]).
    pub memory_budget: usize,
    /// Start every indent's fit from the closed-form pre-fit of its own curve
    /// (`--start closed-form`; [`crate::closed_form_start`]): each indent's start depends on
    /// its own curve and configuration only, so the results do not depend on the thread
    /// count or the order.
    pub closed_form_start: bool,
    /// Closed-form starts seeded per configuration (default false; `crate::batch_seed`):
    /// the first indent of each configuration in manifest order is fitted first, from its
    /// own closed-form start; every other indent of that configuration starts from the
    /// half-space closed form of its own curve corrected by the seed's fitted / half-space
    /// ratio, without a calibration run of its own. False: every indent calibrates its
    /// own closed form. Off by default: alone it measured no faster (1.64x the base
    /// start's throughput against 1.70x, docs/performance.md "The 100-indent batch"); with
    /// `identify.stop.proposed_step` 2.30x.
    pub seeded: bool,
}

impl BatchOptions {
    /// A batch of `manifest` into `out`, every core, no shard.
    pub fn new(manifest: PathBuf, out: PathBuf) -> BatchOptions {
        BatchOptions {
            manifest,
            out,
            config: None,
            jobs: 0,
            shard: None,
            retry_failed: false,
            overrides: Overrides::default(),
            figures: false,
            cancel: Cancel::default(),
            memory_budget: identify::DEFAULT_MEMORY_BUDGET,
            closed_form_start: false,
            seeded: false,
        }
    }

    /// The number of worker threads.
    pub fn workers(&self) -> usize {
        if self.jobs == 0 {
            std::thread::available_parallelism().map_or(1, usize::from)
        } else {
            self.jobs
        }
    }
}

/// How an indent ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum State {
    /// Identified, converged.
    Converged,
    /// Identified, but the optimizer stopped without converging (iteration limit, stall).
    NotConverged,
    /// No result: bad input or a solver failure (the error says which).
    Failed,
    /// Interrupted before it finished (not written as a status: redone next time).
    Interrupted,
}

impl State {
    /// `converged`, `not_converged`, `failed`, `interrupted`.
    pub fn name(self) -> &'static str {
        match self {
            State::Converged => "converged",
            State::NotConverged => "not_converged",
            State::Failed => "failed",
            State::Interrupted => "interrupted",
        }
    }
}

/// The status of one finished indent (`indents/<id>/status.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IndentStatus {
    /// The id.
    pub id: String,
    /// Position.
    pub x: Option<f64>,
    /// Position.
    pub y: Option<f64>,
    /// How it ended.
    pub state: State,
    /// The stop reason, or the error's messages joined.
    pub message: String,
    /// The error's kind (`config`, `data`, `solver`, `io`) when it failed.
    pub error_kind: Option<String>,
    /// Parameter names, law order.
    pub names: Vec<String>,
    /// Their units.
    #[serde(default)]
    pub units: Vec<String>,
    /// Final values.
    pub values: Vec<f64>,
    /// Gauss-Newton standard deviations (`None` for held or undetermined parameters).
    pub std_dev: Vec<Option<f64>>,
    /// Which parameters were free.
    pub free: Vec<bool>,
    /// R² of the final fit.
    pub r2: Option<f64>,
    /// RMS residual / F_max.
    pub rms_rel: Option<f64>,
    /// Iterations.
    pub iterations: usize,
    /// Wall time (s).
    pub seconds: f64,
    /// The residual tests' verdict (`adequate`, `systematic residuals`, `cannot tell`;
    /// crate::adequacy), `None` for a failed indent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adequacy: Option<String>,
    /// What makes the result less than it looks (systematic residuals, discretization
    /// beyond σ, undetermined, at a bound).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub caveats: Vec<String>,
    /// The closed-form start's summary (the values it set, or why none), when asked for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<String>,
}

/// Progress of a batch.
pub trait BatchObserver: Sync {
    /// The batch starts: `pending` indents to run, `skipped` already finished.
    fn started(&self, _pending: usize, _skipped: usize) {}
    /// An indent finished (`done` of `pending`).
    fn finished(&self, _status: &IndentStatus, _done: usize, _pending: usize) {}
}

/// An observer that ignores everything.
impl BatchObserver for () {}

/// The outcome of a batch run or a merge.
#[derive(Clone, Debug)]
pub struct BatchSummary {
    /// Indents in the manifest.
    pub total: usize,
    /// Indents of this shard.
    pub in_shard: usize,
    /// Skipped as already finished.
    pub skipped: usize,
    /// Run now.
    pub ran: usize,
    /// Statuses found for the whole manifest, by state.
    pub counts: BTreeMap<&'static str, usize>,
    /// Indents of the manifest without a status (other shards not run yet, interrupted).
    pub missing: Vec<String>,
    /// results.csv.
    pub results: PathBuf,
    /// The map figures written.
    pub figures: Vec<PathBuf>,
    /// Why there are no maps, or indents left out of them (positions missing), in words.
    pub maps_note: Option<String>,
    /// Wall time (s).
    pub seconds: f64,
}

/// `OUT/batch.json`: which batch the folder holds.
#[derive(Debug, Serialize, Deserialize, PartialEq)]
struct BatchFile {
    manifest: String,
    fingerprint: String,
    ids: Vec<String>,
    positions: Vec<(Option<f64>, Option<f64>)>,
}

/// Claims `out` for the batch of `manifest`, or refuses a folder holding another batch.
fn claim(out: &Path, manifest: &Manifest) -> Result<()> {
    crate::atomic::ensure_writable_dir(&out.join("indents")).kind(ErrorKind::Io)?;
    let path = out.join("batch.json");
    let mine = BatchFile {
        manifest: manifest.path.display().to_string(),
        fingerprint: manifest.fingerprint.clone(),
        ids: manifest.indents.iter().map(|i| i.id.clone()).collect(),
        positions: manifest.indents.iter().map(|i| (i.x, i.y)).collect(),
    };
    if let Ok(text) = std::fs::read_to_string(&path) {
        let theirs: BatchFile = serde_json::from_str(&text)
            .with_context(|| format!("`{}` is not a batch file", path.display()))
            .kind(ErrorKind::Io)?;
        if theirs.fingerprint != mine.fingerprint {
            return Err(Error::msg(
                ErrorKind::Io,
                format!(
                    "the output folder `{}` holds another batch (manifest `{}`, fingerprint {}; \
                     this one is {}): choose another --out, or remove the folder",
                    out.display(),
                    theirs.manifest,
                    theirs.fingerprint,
                    mine.fingerprint
                ),
            ));
        }
        return Ok(());
    }
    let text = serde_json::to_string_pretty(&mine).expect("a batch file serializes");
    crate::atomic::write(&path, text + "\n").kind(ErrorKind::Io)
}

fn status_path(out: &Path, id: &str) -> PathBuf {
    out.join("indents").join(id).join("status.json")
}

/// The status of indent `id` in `out`, if it finished.
pub fn read_status(out: &Path, id: &str) -> Option<IndentStatus> {
    let text = std::fs::read_to_string(status_path(out, id)).ok()?;
    match serde_json::from_str(&text) {
        Ok(s) => Some(s),
        Err(e) => {
            tracing::warn!(
                "warning: `{}` is not a status ({e}): the indent will be redone",
                status_path(out, id).display()
            );
            None
        }
    }
}

/// Runs the batch: the pending indents of the shard in parallel, then results.csv and the
/// maps over every indent that has a status.
///
/// # Errors
/// An invalid manifest or option, an output folder that cannot be written or holds
/// another batch. Failures of single indents are recorded, not returned.
pub fn run(opts: &BatchOptions, observer: &dyn BatchObserver) -> Result<BatchSummary> {
    let start = Instant::now();
    let manifest = read_manifest(&opts.manifest, opts.config.as_deref())?;
    if let Some(base) = &opts.config {
        // the base configuration must at least load
        ConfigSource::Path(base.clone()).load(&[])?;
    }
    check_law_columns(&manifest, opts.config.as_deref())?;
    claim(&opts.out, &manifest)?;
    let in_shard: Vec<&Indent> = manifest
        .indents
        .iter()
        .enumerate()
        .filter(|(k, _)| opts.shard.is_none_or(|s| s.contains(*k)))
        .map(|(_, i)| i)
        .collect();
    let pending: Vec<&Indent> = in_shard
        .iter()
        .copied()
        .filter(|i| match read_status(&opts.out, &i.id) {
            None => true,
            Some(s) => opts.retry_failed && s.state == State::Failed,
        })
        .collect();
    let skipped = in_shard.len() - pending.len();
    observer.started(pending.len(), skipped);
    let jobs = opts.workers();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| Error::msg(ErrorKind::Io, format!("cannot start {jobs} workers: {e}")))?;
    let done = Mutex::new(0usize);
    let write_error: Mutex<Option<Error>> = Mutex::new(None);
    let n_pending = pending.len();
    let finish = |indent: &Indent, status: &IndentStatus| {
        if status.state != State::Interrupted {
            let path = status_path(&opts.out, &indent.id);
            let text = serde_json::to_string_pretty(&status).expect("a status serializes") + "\n";
            let written = path
                .parent()
                .map_or(Ok(()), std::fs::create_dir_all)
                .map_err(anyhow::Error::from)
                .and_then(|()| crate::atomic::write(&path, text));
            if let Err(e) = written {
                let mut w = write_error.lock().expect("no worker panics");
                w.get_or_insert(Error::new(ErrorKind::Io, e));
                opts.cancel.raise();
                return;
            }
        }
        let n = {
            let mut d = done.lock().expect("no worker panics");
            *d += 1;
            *d
        };
        observer.finished(status, n, n_pending);
    };
    pool.install(|| {
        use rayon::prelude::*;
        // the seeds first (each configuration's first closed-form indent of the manifest)
        let seeds = seed_phase(opts, &manifest, &pending, &finish);
        // then one indent per task, in manifest order as far as the workers allow
        pending
            .par_iter()
            .with_max_len(1)
            .filter(|i| !seeds.ran.contains(&i.id))
            .for_each(|indent| {
                if opts.cancel.is_raised() {
                    return;
                }
                let status = run_one(opts, indent, seeds.of(opts, indent), true);
                finish(indent, &status);
            });
    });
    if let Some(e) = write_error.into_inner().expect("no worker panics") {
        return Err(e);
    }
    let mut summary = gather(&opts.out, &manifest)?;
    summary.in_shard = in_shard.len();
    summary.skipped = skipped;
    summary.ran = *done.lock().expect("no worker panics");
    summary.seconds = start.elapsed().as_secs_f64();
    Ok(summary)
}

impl IndentStatus {
    /// A failed status of `indent` with no message yet.
    fn failed(indent: &Indent) -> IndentStatus {
        IndentStatus {
            id: indent.id.clone(),
            x: indent.x,
            y: indent.y,
            state: State::Failed,
            message: String::new(),
            error_kind: None,
            names: Vec::new(),
            units: Vec::new(),
            values: Vec::new(),
            std_dev: Vec::new(),
            free: Vec::new(),
            r2: None,
            rms_rel: None,
            iterations: 0,
            seconds: 0.0,
            adequacy: None,
            caveats: Vec::new(),
            start: None,
        }
    }
}

/// The seeds a batch ran or read before its other indents (`crate::batch_seed`).
#[derive(Default)]
struct Seeds {
    /// Ids of the seeds this run identified (their statuses written).
    ran: Vec<String>,
    /// Per configuration key: its seed, or why its indents cannot be seeded.
    by_key: Vec<(String, std::result::Result<crate::batch_seed::Seed, String>)>,
}

impl Seeds {
    /// The seed `indent` starts from (`None`: not a seeded closed-form indent).
    fn of(
        &self,
        opts: &BatchOptions,
        indent: &Indent,
    ) -> Option<&std::result::Result<crate::batch_seed::Seed, String>> {
        if !(opts.closed_form_start || indent.start_closed_form) {
            return None;
        }
        let key = seed_key(opts, indent);
        self.by_key.iter().find(|(k, _)| *k == key).map(|(_, s)| s)
    }
}

/// The configuration key of `indent` (`crate::batch_seed::key`).
fn seed_key(opts: &BatchOptions, indent: &Indent) -> String {
    let (config, sets) = indent_source(indent, opts.config.as_deref());
    crate::batch_seed::key(&config, &sets)
}

/// Identifies the seed of every configuration that has a pending closed-form indent (its
/// first closed-form indent in the manifest, in this shard or not), in parallel: a seed
/// pending here is run and finished (`finish`), one finished earlier is read from its
/// status, one of another shard without a status is run without files. Nothing when the
/// batch is not seeded.
fn seed_phase(
    opts: &BatchOptions,
    manifest: &Manifest,
    pending: &[&Indent],
    finish: &(dyn Fn(&Indent, &IndentStatus) + Sync),
) -> Seeds {
    use rayon::prelude::*;
    if !opts.seeded {
        return Seeds::default();
    }
    let closed: Vec<&Indent> = manifest
        .indents
        .iter()
        .filter(|i| opts.closed_form_start || i.start_closed_form)
        .collect();
    let keys: Vec<String> = closed.iter().map(|i| seed_key(opts, i)).collect();
    let needed: Vec<(String, &Indent)> = crate::batch_seed::firsts(&keys)
        .into_iter()
        .filter(|&f| {
            pending.iter().any(|p| {
                (opts.closed_form_start || p.start_closed_form) && seed_key(opts, p) == keys[f]
            })
        })
        .map(|f| (keys[f].clone(), closed[f]))
        .collect();
    let done: Vec<(String, _, bool)> = needed
        .par_iter()
        .with_max_len(1)
        .map(|(key, seed)| {
            let here = pending.iter().any(|p| p.id == seed.id);
            let status = match read_status(&opts.out, &seed.id) {
                Some(st) if !here => st,
                _ => {
                    let mut st = run_one(opts, seed, None, here);
                    if here {
                        st.start = Some(match st.start.take() {
                            Some(s) => format!("{s}; the seed of its configuration"),
                            None => "the seed of its configuration".into(),
                        });
                        finish(seed, &st);
                    }
                    st
                }
            };
            let id_opts = indent_options(opts, seed, opts.overrides.clone(), true, false);
            let s = crate::batch_seed::seed_of(&id_opts, &status);
            (key.clone(), s, here)
        })
        .collect();
    Seeds {
        ran: needed
            .iter()
            .zip(&done)
            .filter(|(_, d)| d.2)
            .map(|((_, i), _)| i.id.clone())
            .collect(),
        by_key: done.into_iter().map(|(k, s, _)| (k, s)).collect(),
    }
}

/// The identification options of `indent` in a batch (`files`: its report folder, else
/// none).
fn indent_options(
    opts: &BatchOptions,
    indent: &Indent,
    overrides: Overrides,
    closed_form: bool,
    files: bool,
) -> IdentifyOptions {
    let (config, sets) = indent_source(indent, opts.config.as_deref());
    IdentifyOptions {
        config,
        sets,
        data: indent.data.clone(),
        out: files.then(|| opts.out.join("indents").join(&indent.id)),
        overrides,
        resume: false,
        // an indent without a status is redone from the start
        force: true,
        noise: None,
        figures: opts.figures,
        cancel: opts.cancel.clone(),
        checkpoint: None,
        // every worker holds one run: the budget is shared between them
        memory_budget: opts.memory_budget / opts.workers().max(1),
        refine: false,
        starts: None,
        profiles: None,
        // the indents are the parallel work: one thread each
        jobs: Some(1),
        closed_form_start: closed_form,
    }
}

/// Identifies one indent; never fails: a failure is its status. `seed`: the seed of its
/// configuration for a seeded closed-form indent (or why there is none); `files`: write
/// its report folder.
fn run_one(
    opts: &BatchOptions,
    indent: &Indent,
    seed: Option<&std::result::Result<crate::batch_seed::Seed, String>>,
    files: bool,
) -> IndentStatus {
    let t0 = Instant::now();
    let (config, sets) = indent_source(indent, opts.config.as_deref());
    if let Err(e) = check_test_column(indent, &config) {
        return IndentStatus {
            message: e.messages().join(": "),
            error_kind: Some(e.kind().name().to_string()),
            seconds: t0.elapsed().as_secs_f64(),
            ..IndentStatus::failed(indent)
        };
    }
    let mut overrides = opts.overrides.clone();
    if indent.start_from_analysis {
        // the free parameters' starts from the O&P analysis of this indent's record
        match crate::start_from_analysis::starts(&config, &sets, indent.data.as_deref()) {
            Ok(s) => {
                overrides
                    .starts
                    .retain(|(n, _)| !s.starts.iter().any(|(m, _)| m == n));
                overrides.starts.extend(s.starts);
            }
            Err(e) => {
                let why = e.messages().join(": ");
                return IndentStatus {
                    message: if why.starts_with("start from the Oliver-Pharr analysis") {
                        why
                    } else {
                        format!("start from the Oliver-Pharr analysis: {why}")
                    },
                    error_kind: Some(e.kind().name().to_string()),
                    seconds: t0.elapsed().as_secs_f64(),
                    ..IndentStatus::failed(indent)
                };
            }
        }
    }
    let mut closed_form = opts.closed_form_start || indent.start_closed_form;
    let mut seeded_start = None;
    let mut not_seeded = None;
    match seed {
        Some(Ok(seed)) if seed.id != indent.id => {
            let probe = indent_options(opts, indent, overrides.clone(), false, false);
            match crate::batch_seed::seeded_starts(&probe, seed) {
                Ok((starts, line)) => {
                    overrides
                        .starts
                        .retain(|(n, _)| !starts.iter().any(|(m, _)| m == n));
                    overrides.starts.extend(starts);
                    closed_form = false;
                    seeded_start = Some(line);
                }
                Err(why) => not_seeded = Some(why),
            }
        }
        Some(Err(why)) => not_seeded = Some(why.clone()),
        _ => {}
    }
    let id_opts = indent_options(opts, indent, overrides, closed_form, files);
    let mut status = IndentStatus::failed(indent);
    match identify::run(&id_opts, &mut ()) {
        Ok(o) => {
            status.state = if o.converged() {
                State::Converged
            } else if o.result.stop_reason == indentify_identify::StopReason::Interrupted {
                State::Interrupted
            } else {
                State::NotConverged
            };
            status.message = o.result.stop_reason.to_string();
            status.names = o.names.iter().map(|n| n.to_string()).collect();
            status.units = o.result.params.iter().map(|p| p.unit.to_string()).collect();
            status.values = o.result.params.iter().map(|p| p.value).collect();
            status.free = o.result.params.iter().map(|p| p.free).collect();
            status.std_dev = o.names.iter().map(|n| o.std_dev(n)).collect();
            status.r2 = o.quality.as_ref().map(|q| q.r2);
            status.rms_rel = o.quality.as_ref().map(|q| q.rms_rel);
            status.iterations = o.result.iterations;
            status.adequacy = o.adequacy().map(|a| a.verdict.as_str().to_string());
            status.caveats = o.caveats();
            status.start = seeded_start.or_else(|| o.start.as_ref().map(|c| c.summary()));
            if let (Some(line), Some(why)) = (status.start.as_mut(), not_seeded) {
                line.push_str(&format!("; not seeded: {why}"));
            }
        }
        Err(e) => {
            status.message = e.messages().join(": ");
            status.error_kind = Some(e.kind().name().to_string());
        }
    }
    status.seconds = t0.elapsed().as_secs_f64();
    status
}

/// Rebuilds results.csv and the maps of `out` from the statuses of every indent.
///
/// # Errors
/// A folder without a batch, or one that cannot be written.
pub fn merge(out: &Path) -> Result<BatchSummary> {
    let start = Instant::now();
    let path = out.join("batch.json");
    let text = std::fs::read_to_string(&path)
        .with_context(|| {
            format!(
                "`{}` holds no batch (no batch.json): run `indentify batch` into it first",
                out.display()
            )
        })
        .kind(ErrorKind::Io)?;
    let b: BatchFile = serde_json::from_str(&text)
        .with_context(|| format!("`{}` is not a batch file", path.display()))
        .kind(ErrorKind::Io)?;
    let manifest = Manifest {
        path: PathBuf::from(&b.manifest),
        indents: b
            .ids
            .iter()
            .zip(&b.positions)
            .enumerate()
            .map(|(k, (id, (x, y)))| Indent {
                line: k + 2,
                id: id.clone(),
                config: None,
                data: None,
                test: None,
                x: *x,
                y: *y,
                sets: Vec::new(),
                start_from_analysis: false,
                start_closed_form: false,
            })
            .collect(),
        set_columns: Vec::new(),
        fingerprint: b.fingerprint,
    };
    let mut s = gather(out, &manifest)?;
    s.seconds = start.elapsed().as_secs_f64();
    Ok(s)
}

/// results.csv and the maps from the statuses found.
fn gather(out: &Path, manifest: &Manifest) -> Result<BatchSummary> {
    let mut statuses = Vec::new();
    let mut missing = Vec::new();
    let mut counts: BTreeMap<&'static str, usize> = BTreeMap::new();
    for i in &manifest.indents {
        match read_status(out, &i.id) {
            Some(s) => {
                *counts.entry(s.state.name()).or_default() += 1;
                statuses.push(s);
            }
            None => missing.push(i.id.clone()),
        }
    }
    let names: Vec<String> = statuses
        .iter()
        .find(|s| !s.names.is_empty())
        .map_or_else(Vec::new, |s| s.names.clone());
    let results = out.join("results.csv");
    crate::atomic::write(&results, results_csv(&statuses, &names)).kind(ErrorKind::Io)?;
    let figures = write_maps(out, &statuses, &names)?;
    let maps_note = maps_note(manifest, &statuses);
    Ok(BatchSummary {
        total: manifest.indents.len(),
        in_shard: manifest.indents.len(),
        skipped: 0,
        ran: 0,
        counts,
        missing,
        results,
        figures,
        maps_note,
        seconds: 0.0,
    })
}

/// Why no map is drawn (no indent has both `x` and `y`), or how many indents the maps
/// leave out; `None` when every indent with a status is on them.
fn maps_note(manifest: &Manifest, statuses: &[IndentStatus]) -> Option<String> {
    if statuses.is_empty() {
        return None;
    }
    let placed = statuses
        .iter()
        .filter(|s| s.x.is_some() && s.y.is_some())
        .count();
    if placed == statuses.len() {
        return None;
    }
    let missing: Vec<&str> = [
        ("x", manifest.indents.iter().all(|i| i.x.is_none())),
        ("y", manifest.indents.iter().all(|i| i.y.is_none())),
    ]
    .into_iter()
    .filter_map(|(c, none)| none.then_some(c))
    .collect();
    Some(if placed == 0 {
        let why = if missing.is_empty() {
            "no indent has both `x` and `y`".to_string()
        } else {
            format!(
                "the manifest has no {} column",
                missing
                    .iter()
                    .map(|c| format!("`{c}`"))
                    .collect::<Vec<_>>()
                    .join(" or ")
            )
        };
        format!(
            "no maps are drawn: {why} (each indent's position in mm; results.csv has every \
             result)"
        )
    } else {
        format!(
            "{} of {} indents have no `x` or `y` and are left out of the maps",
            statuses.len() - placed,
            statuses.len()
        )
    })
}

/// A number for CSV: shortest round-trip text, empty for none or non-finite, no `-0`.
fn num(v: Option<f64>) -> String {
    match v {
        Some(v) if v.is_finite() => {
            if v == 0.0 {
                "0".into()
            } else {
                v.to_string()
            }
        }
        _ => String::new(),
    }
}

/// `id,x,y,<p>,<p>_std,...,R2,rms_rel,status,iterations,seconds,error,adequacy`.
fn results_csv(statuses: &[IndentStatus], names: &[String]) -> Vec<u8> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header = vec!["id".to_string(), "x".into(), "y".into()];
    for n in names {
        header.push(n.clone());
        header.push(format!("{n}_std"));
    }
    header.extend(
        [
            "R2",
            "rms_rel",
            "status",
            "iterations",
            "seconds",
            "error",
            "adequacy",
        ]
        .map(String::from),
    );
    w.write_record(&header).expect("writing to memory");
    for s in statuses {
        let mut row = vec![s.id.clone(), num(s.x), num(s.y)];
        for n in names {
            let k = s.names.iter().position(|m| m == n);
            row.push(num(k.map(|k| s.values[k])));
            row.push(num(k.and_then(|k| s.std_dev.get(k).copied().flatten())));
        }
        row.push(num(s.r2));
        row.push(num(s.rms_rel));
        row.push(s.state.name().into());
        row.push(s.iterations.to_string());
        row.push(format!("{:.3}", s.seconds));
        row.push(if s.state == State::Failed {
            s.message.clone()
        } else {
            String::new()
        });
        row.push(s.adequacy.clone().unwrap_or_default());
        w.write_record(&row).expect("writing to memory");
    }
    w.into_inner().expect("writing to memory")
}

/// Heat maps and histograms of every free parameter, of its standard deviation
/// (`<p>_std_map`) and of R², when positions are given (in mm).
fn write_maps(out: &Path, statuses: &[IndentStatus], names: &[String]) -> Result<Vec<PathBuf>> {
    let placed: Vec<&IndentStatus> = statuses
        .iter()
        .filter(|s| s.x.is_some() && s.y.is_some())
        .collect();
    if placed.is_empty() {
        return Ok(Vec::new());
    }
    let dir = out.join("maps");
    crate::atomic::ensure_writable_dir(&dir).kind(ErrorKind::Io)?;
    let x: Vec<f64> = placed.iter().map(|s| s.x.unwrap_or(f64::NAN)).collect();
    let y: Vec<f64> = placed.iter().map(|s| s.y.unwrap_or(f64::NAN)).collect();
    let mut quantities: Vec<(String, String, Vec<f64>)> = Vec::new();
    for (k, n) in names.iter().enumerate() {
        let free = placed
            .iter()
            .any(|s| s.free.get(k).copied().unwrap_or(false));
        if !free {
            continue;
        }
        let values = placed
            .iter()
            .map(|s| {
                let ok = s.state != State::Failed;
                s.names
                    .iter()
                    .position(|m| m == n)
                    .map_or(f64::NAN, |j| if ok { s.values[j] } else { f64::NAN })
            })
            .collect();
        let unit = placed
            .iter()
            .find_map(|s| s.units.get(k).filter(|u| !u.is_empty() && *u != "-"))
            .map_or(String::new(), |u| format!(" ({u})"));
        quantities.push((n.clone(), format!("{n}{unit}"), values));
    }
    // each free parameter's standard deviation (NaN: held, undetermined, failed)
    let sigma_maps: Vec<(String, String, Vec<f64>)> = quantities
        .iter()
        .map(|(n, title, _)| {
            let values = placed
                .iter()
                .map(|s| {
                    s.names
                        .iter()
                        .position(|m| m == n)
                        .and_then(|j| s.std_dev.get(j).copied().flatten())
                        .filter(|_| s.state != State::Failed)
                        .unwrap_or(f64::NAN)
                })
                .collect();
            (format!("{n}_std"), format!("σ of {title}"), values)
        })
        .collect();
    quantities.extend(sigma_maps);
    quantities.push((
        "R2".into(),
        "R²".into(),
        placed.iter().map(|s| s.r2.unwrap_or(f64::NAN)).collect(),
    ));
    let mut written = Vec::new();
    for (stem, title, values) in quantities {
        if !values.iter().any(|v| v.is_finite()) {
            continue;
        }
        let data = MapData {
            title,
            x: x.clone(),
            y: y.clone(),
            values,
            // manifest positions are in mm, the internal length unit
            position_unit: "mm".into(),
        };
        for (fig, suffix) in [(MapFigure::HeatMap, "map"), (MapFigure::Histogram, "hist")] {
            let svg = data
                .svg(fig, FigureSize::default())
                .map_err(|e| Error::msg(ErrorKind::Io, format!("cannot draw {stem}: {e}")))?;
            let png = data
                .png(fig, FigureSize::default())
                .map_err(|e| Error::msg(ErrorKind::Io, format!("cannot draw {stem}: {e}")))?;
            for (ext, bytes) in [("svg", svg.into_bytes()), ("png", png)] {
                let p = dir.join(format!("{stem}_{suffix}.{ext}"));
                crate::atomic::write(&p, bytes).kind(ErrorKind::Io)?;
                written.push(p);
            }
        }
    }
    Ok(written)
}

/// Checks every indent of `manifest` as its run will read it, without solving anything:
/// its configuration (the row's or `base`) loads with the row's configuration columns
/// applied (`law.foo` unknown, `law.E=-5` out of range), its identification settings
/// resolve with `overrides`, and a `test` column meets a configuration that reads a record
/// (`data`). `batch slurm` calls it before writing a job array, so that a manifest that
/// would fail on every indent fails before anything is queued. A missing or bad data file
/// is one indent's failure, recorded in its status as in any batch, not a refusal.
///
/// # Errors
/// The first bad indent, naming the manifest, its line and id.
pub fn validate(manifest: &Manifest, base: Option<&Path>, overrides: &Overrides) -> Result<()> {
    for indent in &manifest.indents {
        check_indent(indent, base, overrides).map_err(|e| {
            e.context(format!(
                "{}:{}: indent `{}`",
                manifest.path.display(),
                indent.line,
                indent.id
            ))
        })?;
    }
    Ok(())
}

/// Checks the `law.*` columns of every indent before anything runs: each row's law
/// values (`law.E`, and every parameter of the laws with internal variables by its
/// registry name: `law.n`, `law.Q`, `law.K`, `law.g2`, `law.tau2`, ...) must name a
/// parameter of the row's law and lie in its range. A row whose configuration does not
/// load at all stays that indent's failure, as any other.
///
/// # Errors
/// The first bad cell, naming the manifest, its line, the indent and the column, with the
/// law's message (the parameter's range, or the paths available).
pub fn check_law_columns(manifest: &Manifest, base: Option<&Path>) -> Result<()> {
    for indent in &manifest.indents {
        let sets: Vec<String> = indent
            .sets
            .iter()
            .filter(|s| s.starts_with("law."))
            .cloned()
            .collect();
        if sets.is_empty() {
            continue;
        }
        let (config, _) = indent_source(indent, base);
        if config.load(&sets).is_ok() || config.load(&[]).is_err() {
            continue;
        }
        for k in 0..sets.len() {
            if let Err(e) = config.load(&sets[..=k]) {
                let column = sets[k].split_once('=').map_or("", |p| p.0);
                return Err(e.context(format!(
                    "{}:{}: indent `{}`, column `{column}`",
                    manifest.path.display(),
                    indent.line,
                    indent.id
                )));
            }
        }
    }
    Ok(())
}

/// The configuration of `indent` and its `--set` paths (its columns, then `data.test`).
fn indent_source(indent: &Indent, base: Option<&Path>) -> (ConfigSource, Vec<String>) {
    let config = match (&indent.config, base) {
        (Some(c), _) => c.clone(),
        (None, Some(b)) => b.to_path_buf(),
        (None, None) => unreachable!("read_manifest requires a configuration per indent"),
    };
    let mut sets = indent.sets.clone();
    if let Some(t) = indent.test {
        sets.push(format!("data.test={t}"));
    }
    (ConfigSource::Path(config), sets)
}

/// A `test` column needs a configuration that reads a record (`data`): with one that
/// simulates its `history`, `data.test` has nothing to apply to.
fn check_test_column(indent: &Indent, config: &ConfigSource) -> Result<()> {
    let Some(t) = indent.test else {
        return Ok(());
    };
    if config.load(&indent.sets)?.data.is_none() {
        return Err(Error::msg(
            ErrorKind::Config,
            format!(
                "the `test` column ({t}) picks a test of a multi-test record, but `{}` has no \
                 `data` section (it simulates its `history`): use a configuration that reads a \
                 record, or leave the `test` cell empty",
                config.name()
            ),
        ));
    }
    Ok(())
}

/// [`validate`] for one indent.
fn check_indent(indent: &Indent, base: Option<&Path>, overrides: &Overrides) -> Result<()> {
    let (config, sets) = indent_source(indent, base);
    check_test_column(indent, &config)?;
    let mut opts = IdentifyOptions::new(config);
    opts.sets = sets;
    opts.data = indent.data.clone();
    opts.overrides = overrides.clone();
    identify::resolve(&opts).map(|_| ())
}

/// A Slurm job array running the shards of a batch.
#[derive(Clone, Debug)]
pub struct SlurmOptions {
    /// The manifest.
    pub manifest: PathBuf,
    /// The shared output folder.
    pub out: PathBuf,
    /// The base configuration.
    pub config: Option<PathBuf>,
    /// Number of array tasks (= shards).
    pub array: usize,
    /// `--partition`.
    pub partition: Option<String>,
    /// `--time` (e.g. `02:00:00`).
    pub time: Option<String>,
    /// `--mem` (e.g. `4G`).
    pub mem: Option<String>,
    /// `--cpus-per-task` (each task runs that many indents at once).
    pub cpus_per_task: usize,
    /// The `indentify` executable the tasks run.
    pub executable: PathBuf,
}

/// The sbatch script of a job array: task `K` runs `indentify batch ... --shard K/N` with
/// `--jobs` = its CPUs. Paths are made absolute (tasks start elsewhere).
///
/// # Errors
/// An array size of 0, a path that cannot be made absolute, an option with a newline.
pub fn slurm_script(o: &SlurmOptions) -> Result<String> {
    if o.array == 0 || o.cpus_per_task == 0 {
        return Err(Error::msg(
            ErrorKind::Config,
            "--array and --cpus-per-task must be at least 1",
        ));
    }
    let abs = |p: &Path| -> Result<String> {
        std::path::absolute(p)
            .map(|p| p.display().to_string())
            .with_context(|| format!("cannot make `{}` absolute", p.display()))
            .kind(ErrorKind::Config)
    };
    let quote = |s: &str| format!("'{}'", s.replace('\'', r"'\''"));
    for v in [&o.partition, &o.time, &o.mem].into_iter().flatten() {
        if v.contains(['\n', '\r']) || v.trim().is_empty() {
            return Err(Error::msg(
                ErrorKind::Config,
                format!("the Slurm option `{v}` is empty or holds a line break"),
            ));
        }
    }
    let out = abs(&o.out)?;
    let mut s = String::from("#!/bin/bash\n");
    s.push_str("# Written by `indentify batch slurm`: one array task per shard of the manifest.\n");
    s.push_str("#SBATCH --job-name=indentify-batch\n");
    s.push_str(&format!("#SBATCH --array=1-{}\n", o.array));
    s.push_str(&format!("#SBATCH --cpus-per-task={}\n", o.cpus_per_task));
    s.push_str(&format!("#SBATCH --output={out}/slurm-%A_%a.out\n"));
    if let Some(p) = &o.partition {
        s.push_str(&format!("#SBATCH --partition={p}\n"));
    }
    if let Some(t) = &o.time {
        s.push_str(&format!("#SBATCH --time={t}\n"));
    }
    if let Some(m) = &o.mem {
        s.push_str(&format!("#SBATCH --mem={m}\n"));
    }
    s.push_str("set -euo pipefail\n");
    let mut cmd = format!(
        "exec {} batch {} --out {}",
        quote(&abs(&o.executable)?),
        quote(&abs(&o.manifest)?),
        quote(&out)
    );
    if let Some(c) = &o.config {
        cmd.push_str(&format!(" --config {}", quote(&abs(c)?)));
    }
    cmd.push_str(&format!(
        " --shard \"${{SLURM_ARRAY_TASK_ID}}/{}\" --jobs \"${{SLURM_CPUS_PER_TASK:-1}}\" --quiet\n",
        o.array
    ));
    s.push_str(&cmd);
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn manifest(text: &str, base: bool) -> anyhow::Result<(Vec<Indent>, Vec<String>)> {
        parse_manifest(text.as_bytes(), Path::new("maps/m.csv"), base)
    }

    #[test]
    fn manifests_read_paths_positions_and_set_columns() {
        let (rows, sets) = manifest(
            "id,data,x,y,law.E,test\na1,r/a1.csv,0,0.5,25000,\nb2,/abs/b.txt,1,0.5,,2\n",
            true,
        )
        .unwrap();
        assert_eq!(sets, ["law.E"]);
        assert_eq!(rows[0].data, Some(PathBuf::from("maps/r/a1.csv")));
        assert_eq!(rows[1].data, Some(PathBuf::from("/abs/b.txt")));
        assert_eq!(rows[0].sets, ["law.E=25000"]);
        assert!(rows[1].sets.is_empty());
        assert_eq!(
            (rows[1].x, rows[1].y, rows[1].test),
            (Some(1.0), Some(0.5), Some(2))
        );
        assert_eq!(rows[1].line, 3);
    }

    #[test]
    fn bad_manifests_name_line_and_column() {
        let cases = [
            ("data\nx.csv\n", "no `id` column"),
            (
                "id,data\na,x\na,y\n",
                "m.csv:3: id `a` is used twice (first on line 2)",
            ),
            ("id,data\na b,x\n", "id `a b` is not allowed"),
            ("id,colour\na,red\n", "unknown column `colour`"),
            (
                "id,x\na,1e999\n",
                "m.csv:2: column `x`: `1e999` is not a finite number",
            ),
            ("id,test\na,0\n", "column `test`: `0` is not a test number"),
            ("id,data\n", "no indent"),
            ("id,id\na,a\n", "the column `id` appears twice"),
        ];
        for (text, want) in cases {
            let e = format!("{:#}", manifest(text, true).unwrap_err());
            assert!(e.contains(want), "{text:?}: {e}");
        }
        let e = format!("{:#}", manifest("id,data\na,x.csv\n", false).unwrap_err());
        assert!(e.contains("has no configuration"), "{e}");
    }

    #[test]
    fn shards_partition_the_manifest() {
        for n in 1..=5 {
            let mut seen = vec![0; 23];
            for k in 1..=n {
                let s = Shard::parse(&format!("{k}/{n}")).unwrap();
                for (p, c) in seen.iter_mut().enumerate() {
                    if s.contains(p) {
                        *c += 1;
                    }
                }
            }
            assert!(seen.iter().all(|&c| c == 1), "{n}: {seen:?}");
        }
        for bad in ["0/3", "4/3", "1/0", "3", "a/b", "-1/2"] {
            let e = Shard::parse(bad).unwrap_err().to_string();
            assert!(e.contains("1 <= K <= N"), "{bad}: {e}");
        }
    }

    #[test]
    fn results_have_one_row_per_status_and_no_negative_zero() {
        let st = |id: &str, state: State, e: f64| IndentStatus {
            id: id.into(),
            x: Some(-0.0),
            y: None,
            state,
            message: if state == State::Failed {
                "cannot read `x.csv`".into()
            } else {
                "gradient norm below tolerance".into()
            },
            error_kind: None,
            names: vec!["E".into(), "nu".into()],
            units: vec!["MPa".into(), "-".into()],
            values: vec![e, 0.3],
            std_dev: vec![Some(12.5), None],
            free: vec![true, false],
            r2: Some(0.99),
            rms_rel: Some(0.01),
            iterations: 7,
            seconds: 1.23456,
            adequacy: (state != State::Failed).then(|| "systematic residuals".into()),
            caveats: Vec::new(),
            start: None,
        };
        let csv = results_csv(
            &[st("a", State::Converged, 2e4), st("b", State::Failed, 0.0)],
            &["E".into(), "nu".into()],
        );
        let text = String::from_utf8(csv).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[0],
            "id,x,y,E,E_std,nu,nu_std,R2,rms_rel,status,iterations,seconds,error,adequacy"
        );
        assert_eq!(
            lines[1],
            "a,0,,20000,12.5,0.3,,0.99,0.01,converged,7,1.235,,systematic residuals"
        );
        assert!(
            lines[2].ends_with("failed,7,1.235,cannot read `x.csv`,"),
            "{}",
            lines[2]
        );
        assert!(!text.contains("-0"), "{text}");
    }

    #[test]
    fn slurm_scripts_run_one_shard_per_array_task() {
        let s = slurm_script(&SlurmOptions {
            manifest: "/data/m.csv".into(),
            out: "/scratch/out".into(),
            config: Some("/data/base.ron".into()),
            array: 4,
            partition: Some("short".into()),
            time: Some("01:00:00".into()),
            mem: None,
            cpus_per_task: 2,
            executable: "/opt/bin/indentify".into(),
        })
        .unwrap();
        assert!(s.starts_with("#!/bin/bash\n"));
        for want in [
            "#SBATCH --array=1-4\n",
            "#SBATCH --cpus-per-task=2\n",
            "#SBATCH --partition=short\n",
            "#SBATCH --time=01:00:00\n",
            "#SBATCH --output=/scratch/out/slurm-%A_%a.out\n",
            "exec '/opt/bin/indentify' batch '/data/m.csv' --out '/scratch/out' --config \
             '/data/base.ron' --shard \"${SLURM_ARRAY_TASK_ID}/4\"",
        ] {
            assert!(s.contains(want), "{want}\n{s}");
        }
        assert!(!s.contains("--mem"));
    }
}
