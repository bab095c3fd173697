//! The commands beyond `identify` and `simulate`: `analyze` (Oliver-Pharr over a record),
//! `design` (candidate protocols ranked), `batch` (every test of a record, or a manifest,
//! identified as a map whose indents are published as they finish) and `map` (a cost
//! map); and joint configurations built from several tests of one record. Each is checked
//! when submitted as the CLI checks it and executed by the `study` pipeline the CLI calls,
//! into the run's folder.

use std::path::{Path, PathBuf};

use indentify_study::analyze::{self, AnalyzeOptions};
use indentify_study::batch::{self, BatchObserver, BatchOptions, IndentStatus};
use indentify_study::config::{Config, TestSpec};
use indentify_study::costmap::{self, MapOptions, Through};
use indentify_study::design::{self, DesignOptions};
use indentify_study::explore::StartsOptions;
use indentify_study::identify::IdentifyOptions;
use indentify_study::{ConfigSource, ProfileSettings};
use serde_json::{Value, json};

use crate::api::ApiError;
use crate::records;
use crate::runs::{
    End, ErrorBody, MAX_MAP_GRID, MAX_STARTS, RecordRef, Run, RunRequest, Status, TestPick,
    error_body,
};
use crate::workspace::{Workspace, normalize};

/// The manifest a batch run reads, in its folder.
pub(crate) const MANIFEST: &str = "manifest.csv";

/// The configuration a `design` run takes without one: `examples/r2-design.ron`.
pub(crate) const DESIGN_TEMPLATE: &str = include_str!("../../../examples/r2-design.ron");

/// What a checked request writes into its run folder and how the CLI repeats it.
pub(crate) struct Prepared {
    /// Files (name, bytes) written before the run is queued.
    pub(crate) files: Vec<(String, Vec<u8>)>,
    /// `--set` overrides the run still applies when it loads config.ron.
    pub(crate) sets: Vec<String>,
    /// The command line that repeats the run from its folder.
    pub(crate) cli: String,
}

/// When a running `command` stops after a `DELETE` (the answer's `message`).
pub(crate) fn when_it_stops(command: &str) -> &'static str {
    match command {
        "identify" => "stopping after the iteration (or profile re-fits) in progress",
        "batch" => "stopping after the indents in progress",
        "design" => "stopping after the candidates in progress",
        "map" => "stopping after the grid points (or fit iteration) in progress",
        "simulate" => "stopping after the forward run's step in progress",
        "calibrate" => "the calibration ends as cancelled when its fits are over",
        _ => "the analysis ends as cancelled when its pass over the record is over",
    }
}

/// The message of a run that ended after a stop request without stopping itself.
pub(crate) fn cancelled_message(command: &str, ended: Status, error: Option<&ErrorBody>) -> String {
    let kept = match (command, ended) {
        ("simulate", Status::Done) => "the forward run in progress finished; its curve is kept",
        ("analyze", Status::Done) => "the analysis in progress finished; its tables are kept",
        ("calibrate", Status::Done) => "the calibration in progress finished; tip.ron is kept",
        ("design" | "map", _) => "stopped before every evaluation was done; nothing written",
        _ => "its files are kept",
    };
    match error {
        Some(e) if !e.messages.iter().any(|m| m.contains("interrupted")) => format!(
            "cancelled ({kept}); it had also failed: {}",
            e.messages.join(": ")
        ),
        _ => format!("cancelled: {kept}"),
    }
}

fn bad(kind: &str, msg: String) -> ApiError {
    ApiError::bad_request(kind, vec![msg])
}

/// `analyze`: checks the record, tip and nu; nothing to write but the command line.
pub(crate) fn prepare_analyze(
    req: &RunRequest,
    record: Option<&RecordRef>,
    sets: &[String],
) -> Result<Prepared, ApiError> {
    let Some((_, rel, _)) = record else {
        return Err(bad(
            "config",
            "analyze needs a record: upload the file (POST /api/records) and give its id as \
             `record`"
                .into(),
        ));
    };
    if req.config.is_some() || !sets.is_empty() {
        return Err(bad(
            "config",
            "analyze takes no configuration and no `sets`: give `tip`, `nu` and `test`".into(),
        ));
    }
    let tip = req.tip.as_deref().unwrap_or("berkovich");
    analyze::tip_from_name(tip).map_err(|e| bad("config", format!("{e:#}")))?;
    let nu = req.nu.unwrap_or(0.3);
    if !(0.0..0.5).contains(&nu) {
        return Err(bad(
            "config",
            format!("--nu {nu} is not allowed: expected Poisson's ratio in [0, 0.5)"),
        ));
    }
    let mut cli = format!("indentify analyze {rel} --tip {tip} --nu {nu} --out .");
    if let Some(k) = req.test {
        cli.push_str(&format!(" --test {k}"));
    }
    Ok(Prepared {
        files: Vec::new(),
        sets: Vec::new(),
        cli,
    })
}

/// A joint configuration (`tests`) of the picked tests, from the one-test configuration
/// `cfg` (its `data` section repeated per test), as RON text. A pick names a test of
/// `record` or of its own `record` (found by `lookup`): a test of another record reads
/// its own file (format detected) and, when its file states a tip other than the first
/// record's test, takes that tip as its own `punch`.
pub(crate) fn joint_config(
    cfg: &Config,
    picks: &[TestPick],
    record: Option<&RecordRef>,
    command: &str,
    lookup: &dyn Fn(&str) -> Result<RecordRef, ApiError>,
) -> Result<String, ApiError> {
    if !matches!(command, "identify" | "map") {
        return Err(bad(
            "config",
            format!("`tests` (a joint fit) is for identify and map, not {command}"),
        ));
    }
    let (Some(base), Some(data)) = (record, &cfg.data) else {
        return Err(bad(
            "config",
            "`tests` picks tests of a record: give `record` (and a configuration with a `data` \
             section, or none: the record's template)"
                .into(),
        ));
    };
    if picks.is_empty() {
        return Err(bad(
            "config",
            "`tests` is empty: pick at least one test".into(),
        ));
    }
    let mut others: Vec<RecordRef> = Vec::new();
    for p in picks {
        if let Some(rid) = p.record.as_deref().filter(|r| *r != base.0) {
            if !others.iter().any(|o| o.0 == rid) {
                others.push(lookup(rid)?);
            }
        }
    }
    let several = !others.is_empty();
    // the tip the base configuration's punch was made for: the record's test's stated tip
    let base_tip = |k: usize| base.2["tests"][k.saturating_sub(1)]["tip"].clone();
    let base_k = cfg.data.as_ref().and_then(|d| d.test).unwrap_or(1);
    let mut specs = Vec::with_capacity(picks.len());
    for (i, p) in picks.iter().enumerate() {
        let (rid, rel, info) = match p.record.as_deref() {
            Some(r) if r != base.0 => others.iter().find(|o| o.0 == r).unwrap_or(base),
            _ => base,
        };
        let n = info["tests"].as_array().map_or(0, Vec::len);
        if p.test == 0 || p.test > n {
            return Err(bad(
                "data",
                format!(
                    "tests[{i}].test = {} is not a test of record `{rid}` (1 to {n})",
                    p.test
                ),
            ));
        }
        let same_record = |q: &TestPick| q.record.as_deref().unwrap_or(&base.0) == rid.as_str();
        if picks[..i]
            .iter()
            .any(|q| q.test == p.test && same_record(q))
        {
            return Err(bad(
                "config",
                format!(
                    "tests[{i}]: test {} of record `{rid}` is picked twice",
                    p.test
                ),
            ));
        }
        if let Some(w) = p.weight {
            if !(w.is_finite() && w > 0.0) {
                return Err(bad(
                    "config",
                    format!("tests[{i}].weight = {w} is not allowed: expected a number > 0"),
                ));
            }
        }
        let t = &info["tests"][p.test - 1];
        let mut name = t["name"]
            .as_str()
            .map_or_else(|| format!("test {}", p.test), String::from);
        if several {
            name = format!("{name} ({})", info["name"].as_str().unwrap_or(rid));
        }
        let mut d = data.clone();
        d.test = Some(p.test);
        let mut punch = None;
        if rid != &base.0 {
            d.file.clone_from(rel);
            d.format = Default::default();
            if t["tip"] != base_tip(base_k) {
                punch = Some(stated_punch(t));
            }
        }
        specs.push(TestSpec {
            name: Some(name),
            specimen: None,
            punch,
            contact: None,
            history: None,
            data: Some(d),
            weight: p.weight,
        });
    }
    let mut joint = cfg.clone();
    joint.data = None;
    joint.tests = Some(specs);
    let text = ron::ser::to_string_pretty(&joint, ron::ser::PrettyConfig::new())
        .map_err(ApiError::internal)?;
    let what = picks
        .iter()
        .map(|p| match p.record.as_deref() {
            Some(r) if several => format!("{r}:{}", p.test),
            _ if several => format!("{}:{}", base.0, p.test),
            _ => p.test.to_string(),
        })
        .collect::<Vec<_>>()
        .join(", ");
    let what = if several {
        format!("record:test {what}")
    } else {
        format!("tests {what} of record {}", base.0)
    };
    Ok(format!(
        "// Written by `indentify serve`: a joint fit of {what} (every --set applied). \
         Units: N, mm, s, MPa.\n{text}\n"
    ))
}

/// The punch a record's test states (record.json's `tip`, `tip_radius`), Berkovich when
/// it states none the templates recognize (as `GET /api/templates` assumes).
fn stated_punch(t: &Value) -> indentify_study::Punch {
    indentify_study::templates::tip_from_metadata(&indentify_study::records::Meta {
        tip: t["tip"].as_str().map(String::from),
        tip_radius: t["tip_radius"].as_f64(),
        ..Default::default()
    })
    .unwrap_or(indentify_study::Punch::Berkovich { tip_radius: None })
}

/// The command's own checks on a loaded configuration and the request's options.
pub(crate) fn check_command(req: &RunRequest, cfg: &Config) -> Result<(), ApiError> {
    match req.command.as_str() {
        "design" if cfg.design.is_none() => Err(bad(
            "config",
            "the configuration has no `design` section (the candidates to rank): start from \
             GET /api/templates/design (examples/r2-design.ron)"
                .into(),
        )),
        "batch" if cfg.tests.is_some() => Err(bad(
            "config",
            "a batch identifies each indent on its own: give a one-test configuration (a \
             `data` section), not a joint one"
                .into(),
        )),
        "map" => {
            let pair = req.pair.as_deref().unwrap_or_default();
            if pair.len() != 2 {
                return Err(bad(
                    "config",
                    format!(
                        "map needs `pair`: the two free parameters to map, e.g. [\"E\", \"eta\"] \
                         (given: {})",
                        pair.len()
                    ),
                ));
            }
            let grid = req.grid.unwrap_or(9);
            if !(3..=MAX_MAP_GRID).contains(&grid) {
                return Err(bad(
                    "config",
                    format!(
                        "grid = {grid} is not allowed here: expected 3 to {MAX_MAP_GRID} points \
                         per side (`indentify map` takes up to {})",
                        costmap::MAX_GRID
                    ),
                ));
            }
            if let Some(s) = req.span {
                if !(s.is_finite() && s > 0.0) {
                    return Err(bad(
                        "config",
                        format!("span = {s} is not allowed: expected a number > 0"),
                    ));
                }
            }
            Through::parse(req.through.as_deref().unwrap_or("fit"))
                .map(|_| ())
                .map_err(|e| bad("config", e))
        }
        _ => Ok(()),
    }
}

/// The batch's manifest: the request's (its `data` cells name records by id, rewritten to
/// their paths; a `config` column is refused: every indent takes the run's config.ron), or
/// one indent per test of `record`.
pub(crate) fn manifest_text(
    ws: &Workspace,
    req: &RunRequest,
    record: Option<&RecordRef>,
) -> Result<String, ApiError> {
    let Some(text) = &req.manifest else {
        let Some((_, rel, info)) = record else {
            return Err(bad(
                "config",
                "batch needs a record (its tests become the indents) or a `manifest`".into(),
            ));
        };
        let n = info["tests"].as_array().map_or(0, Vec::len);
        let mut out = String::from("id,data,test,x\n");
        for k in 1..=n {
            out.push_str(&format!("test-{k},{rel},{k},{k}\n"));
        }
        return Ok(out);
    };
    if text.contains('"') {
        return Err(bad(
            "config",
            "manifest: quoted fields are not taken here: plain comma-separated values".into(),
        ));
    }
    let mut lines = text
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'));
    let header: Vec<String> = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(|h| h.trim().to_string())
        .collect();
    if header.iter().any(|h| h == "config") {
        return Err(bad(
            "config",
            "manifest: a `config` column is not taken here: every indent takes the run's \
             configuration (give `config`, and per-indent values in columns such as law.E)"
                .into(),
        ));
    }
    let data_col = header.iter().position(|h| h == "data");
    let rel = |cell: &str| -> Result<String, ApiError> {
        match (cell.trim(), record) {
            ("", Some((_, rel, _))) => Ok(rel.clone()),
            ("", None) => Err(bad(
                "config",
                "manifest: an indent without `data` and no `record` in the request".into(),
            )),
            (id, _) => records::file_of(ws, id).map(|(rel, _)| rel).map_err(|_| {
                bad(
                    "config",
                    format!(
                        "manifest: data `{id}` is not a record of this workspace: the `data` \
                         column names records by id (POST /api/records)"
                    ),
                )
            }),
        }
    };
    let mut out = header.join(",");
    if data_col.is_none() {
        out.push_str(",data");
    }
    out.push('\n');
    for line in lines {
        let mut cells: Vec<String> = line.split(',').map(|c| c.trim().to_string()).collect();
        match data_col {
            Some(c) if c < cells.len() => cells[c] = rel(&cells[c])?,
            Some(_) => cells.push(rel("")?),
            None => {
                cells.resize(header.len(), String::new());
                cells.push(rel("")?);
            }
        }
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    Ok(out)
}

/// `indentify map ...` for a map request.
pub(crate) fn map_cli(req: &RunRequest) -> String {
    let mut cli = format!(
        "indentify map config.ron --pair {} --grid {} --through {} --out .",
        req.pair.as_deref().unwrap_or_default().join(","),
        req.grid.unwrap_or(9),
        req.through.as_deref().unwrap_or("fit")
    );
    if let Some(s) = req.span {
        cli.push_str(&format!(" --span {s}"));
    }
    cli
}

fn config_of(run: &Run) -> ConfigSource {
    ConfigSource::Path(run.dir.join("config.ron"))
}

fn io_error(e: impl std::fmt::Display) -> ErrorBody {
    ErrorBody {
        kind: "io".into(),
        messages: vec![format!("{e:#}")],
    }
}

/// The record's file of an analyze run (its folder's `../../records/ID/NAME`).
pub(crate) fn record_file(run: &Run) -> Result<PathBuf, ErrorBody> {
    let rid = run.meta().record.unwrap_or_default();
    let ws_root = run.dir.join("../..");
    let ws = Workspace::open(&normalize(&ws_root)).map_err(io_error)?;
    records::file_of(&ws, &rid)
        .map(|(_, path)| path)
        .map_err(|_| io_error(format!("record `{rid}` is gone from the workspace")))
}

/// `analyze`: the Oliver-Pharr analysis of the record, analysis.json and analysis.csv.
pub(crate) fn run_analyze(run: &Run) -> Result<End, ErrorBody> {
    run.update(true, |m| m.progress.stage = "analyzing".into());
    let req = &run.spec.req;
    let tip = analyze::tip_from_name(req.tip.as_deref().unwrap_or("berkovich")).map_err(|e| {
        ErrorBody {
            kind: "config".into(),
            messages: vec![format!("{e:#}")],
        }
    })?;
    let opts = AnalyzeOptions {
        test: req.test,
        tip,
        nu: req.nu.unwrap_or(0.3),
        out: Some(run.dir.clone()),
        ..AnalyzeOptions::new(record_file(run)?)
    };
    let o = analyze::run(&opts).map_err(|e| error_body(&e))?;
    let tests: Vec<Value> = o
        .tests
        .iter()
        .map(|t| {
            json!({"index": t.index, "test": t.test, "E": t.values.e, "H": t.values.h, "Er": t.values.er, "S": t.values.s,
                   "hc": t.values.hc, "hmax": t.values.hmax, "Fmax": t.values.fmax, "error": t.error})
        })
        .collect();
    let failed = o.tests.iter().filter(|t| t.error.is_some()).count();
    let summary = json!({"command": "analyze", "format": o.format, "tests": tests,
                         "seconds": o.seconds, "fit_range_source": o.fit_range_source});
    let message =
        (failed > 0).then(|| format!("{failed} test(s) could not be analysed (see the table)"));
    Ok((Status::Done, Some(summary), None, message))
}

/// `design`: the candidates evaluated and ranked, design.json and design.md.
pub(crate) fn run_design(run: &Run) -> Result<End, ErrorBody> {
    run.update(true, |m| m.progress.stage = "designing".into());
    let mut opts = DesignOptions::new(config_of(run));
    opts.sets = run.spec.sets.clone();
    opts.out = Some(run.dir.clone());
    let d = design::run_cancellable(&opts, &run.cancel).map_err(|e| error_body(&e))?;
    let ranked: Vec<Value> = d
        .rank_d
        .iter()
        .map(|&k| {
            let c = &d.candidates[k];
            json!({"name": c.name, "log_det": c.log_det, "worst": c.worst.0,
                   "worst_rel_std_dev": c.worst.1, "undetermined": c.undetermined.len()})
        })
        .collect();
    let summary = json!({"command": "design", "noise": d.noise, "names": d.names,
                         "ranked": ranked, "seconds": d.seconds});
    Ok((Status::Done, Some(summary), None, None))
}

/// `map`: J over a grid of two parameters, map.json/csv/svg/png.
pub(crate) fn run_map(run: &Run) -> Result<End, ErrorBody> {
    run.update(true, |m| m.progress.stage = "mapping".into());
    let req = &run.spec.req;
    let mut identify = IdentifyOptions::new(config_of(run));
    identify.sets = run.spec.sets.clone();
    identify.cancel = run.cancel.clone();
    identify.refine = false;
    identify.figures = false;
    let through =
        Through::parse(req.through.as_deref().unwrap_or("fit")).map_err(|e| ErrorBody {
            kind: "config".into(),
            messages: vec![e],
        })?;
    let opts = MapOptions {
        identify,
        pair: req.pair.clone().unwrap_or_default(),
        grid: req.grid.unwrap_or(9),
        span: req.span.map(|s| vec![s]).unwrap_or_default(),
        through,
        out: Some(run.dir.clone()),
        jobs: None,
    };
    let map = costmap::run(&opts).map_err(|e| error_body(&e))?;
    let summary = json!({"command": "map", "names": map.names, "grid": opts.grid,
                         "J_centre": map.centre_cost, "grid_min": map.grid_min,
                         "failed": map.failed, "seconds": map.seconds});
    if map.failed == map.cost.len() {
        return Ok((
            Status::Failed,
            Some(summary),
            Some(ErrorBody {
                kind: "solver".into(),
                messages: vec!["every grid point failed to solve".into()],
            }),
            None,
        ));
    }
    Ok((Status::Done, Some(summary), None, None))
}

/// A batch's observer: each finished indent into the run's progress (the page's live map).
struct BatchWeb<'a> {
    run: &'a Run,
}

impl BatchObserver for BatchWeb<'_> {
    fn started(&self, pending: usize, skipped: usize) {
        self.run.update(true, |m| {
            m.progress.stage = "batch".into();
            m.progress.max_iterations = pending + skipped;
            m.progress.iteration = skipped;
        });
    }

    fn finished(&self, status: &IndentStatus, _done: usize, _pending: usize) {
        let v = serde_json::to_value(status).unwrap_or(Value::Null);
        self.run.update(false, |m| {
            m.progress.iteration += 1;
            if let Some(slot) = m
                .progress
                .indents
                .iter_mut()
                .find(|i| i["id"].as_str() == Some(status.id.as_str()))
            {
                *slot = v;
            }
        });
    }
}

/// `batch`: every indent of the manifest identified into `indents/ID/`, results.csv and
/// the maps; each finished indent published at once.
pub(crate) fn run_batch(run: &Run) -> Result<End, ErrorBody> {
    let manifest_path = run.dir.join(MANIFEST);
    let config = run.dir.join("config.ron");
    let manifest =
        batch::read_manifest(&manifest_path, Some(&config)).map_err(|e| error_body(&e))?;
    run.update(true, |m| {
        m.progress.stage = "batch".into();
        m.progress.max_iterations = manifest.indents.len();
        m.progress.indents = manifest
            .indents
            .iter()
            .map(|i| json!({"id": i.id, "x": i.x, "y": i.y, "state": "pending"}))
            .collect();
    });
    let mut opts = BatchOptions::new(manifest_path, run.dir.clone());
    opts.config = Some(config);
    opts.figures = true;
    opts.cancel = run.cancel.clone();
    let s = batch::run(&opts, &BatchWeb { run }).map_err(|e| error_body(&e))?;
    let figures: Vec<String> = s
        .figures
        .iter()
        .filter_map(|p| relative(&run.dir, p))
        .collect();
    let summary = json!({"command": "batch", "total": s.total, "ran": s.ran,
                         "counts": s.counts, "missing": s.missing, "results": "results.csv",
                         "figures": figures, "seconds": s.seconds});
    if run.cancel.is_raised() {
        let msg = format!(
            "cancelled: {} of {} indents finished (their folders are kept)",
            s.total - s.missing.len(),
            s.total
        );
        return Ok((Status::Cancelled, Some(summary), None, Some(msg)));
    }
    let failed = s.counts.get("failed").copied().unwrap_or(0);
    let message = (failed > 0).then(|| format!("{failed} indent(s) failed (see the map)"));
    Ok((Status::Done, Some(summary), None, message))
}

fn relative(dir: &Path, p: &Path) -> Option<String> {
    p.strip_prefix(dir)
        .ok()
        .map(|r| r.to_string_lossy().replace('\\', "/"))
}

/// The multi-start options of a request: `starts` only for identify, 1 to [`MAX_STARTS`];
/// `seed` only with `starts` (as the CLI's `--seed`).
pub(crate) fn check_starts(req: &RunRequest) -> Result<(), ApiError> {
    match (req.starts, req.seed) {
        (None, None) => Ok(()),
        (None, Some(_)) => Err(bad(
            "config",
            "seed needs starts: it seeds the multi-start's Latin-hypercube starts".into(),
        )),
        (Some(_), _) if req.command != "identify" => Err(bad(
            "config",
            format!(
                "starts is an option of identify, not of {} (a multi-start of the fit)",
                req.command
            ),
        )),
        (Some(n), _) if !(1..=MAX_STARTS).contains(&n) => Err(bad(
            "config",
            format!(
                "starts = {n} is not allowed here: expected 1 to {MAX_STARTS} starts (`indentify \
                 identify --starts` takes up to 10000)"
            ),
        )),
        _ => Ok(()),
    }
}

/// Multi-start settings of a request (`--starts N --seed S`).
pub(crate) fn starts(req: &RunRequest) -> Option<StartsOptions> {
    req.starts
        .map(|n| StartsOptions::new(n, req.seed.unwrap_or(1)))
}

/// Profile settings of a request (`--profiles`).
pub(crate) fn profiles(req: &RunRequest) -> Option<ProfileSettings> {
    req.profiles.then(ProfileSettings::default)
}
