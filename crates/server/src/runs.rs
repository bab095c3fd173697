//! Runs: a request checked and turned into `runs/<id>/` (config.ron, status.json), queued,
//! executed by a fixed pool of worker threads calling the `study` pipelines, its progress
//! published to subscribers (server-sent events) and to `status.json` (written atomically,
//! so a restarted server lists every run and the CLI and Python can read them).

use std::collections::{BTreeMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Instant;

use axum::http::StatusCode;
use indentify_study::config::{Config, Reference};
use indentify_study::identify::{self, IdentifyOptions, Observer, RunInfo};
use indentify_study::simulate::{self, SimulateOptions};
use indentify_study::{Cancel, IterationRecord, StopReason};
use indentify_study::{ConfigSource, DEFAULT_CONFIG};
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use tokio::sync::broadcast;

use crate::api::ApiError;
use crate::workspace::{Workspace, normalize, safe_relative};
use crate::{jobs, records};

/// Seconds since the Unix epoch.
pub fn now() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// The commands a run may execute.
pub const COMMANDS: [&str; 7] = [
    "identify",
    "simulate",
    "analyze",
    "design",
    "batch",
    "map",
    "calibrate",
];

/// The commands a `DELETE` can stop while they run: every one. An identification stops
/// after its iteration in progress (or its profile re-fits in progress), a batch after its
/// indents in progress, a design after its candidates in progress, a map after its grid
/// points in progress, a simulation after its forward run's step in progress; an analysis
/// and a calibration (passes over the record's unloadings) end as cancelled when their
/// pass is over.
pub const CANCELLABLE: [&str; 7] = COMMANDS;

/// The file of a run's folder that `GET /api/runs/{id}` answers as `result`.
pub fn result_file(command: &str) -> &'static str {
    match command {
        "analyze" => "analysis.json",
        "calibrate" => "calibration.json",
        "design" => "design.json",
        "batch" => "batch.json",
        "map" => "map.json",
        _ => "result.json",
    }
}

/// A run's state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Waiting for a worker.
    Queued,
    /// On a worker.
    Running,
    /// Finished (converged or not: see `summary.converged`).
    Done,
    /// Refused at run time (data, solver) or interrupted by a server stop.
    Failed,
    /// Cancelled (`DELETE /api/runs/{id}`): before it started, or after an iteration.
    Cancelled,
}

impl Status {
    /// Whether the run is over.
    pub fn is_final(self) -> bool {
        matches!(self, Status::Done | Status::Failed | Status::Cancelled)
    }
}

/// Live progress of a run.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Progress {
    /// `queued`, `starting`, `fitting`, `report`, `simulating`, `finished`.
    pub stage: String,
    /// The last completed iteration (0: the start).
    pub iteration: usize,
    /// The iteration limit.
    pub max_iterations: usize,
    /// J at the last iteration (N^2).
    pub cost: Option<f64>,
    /// |grad J| (scaled) at the last iteration.
    pub grad_norm: Option<f64>,
    /// Every parameter's name.
    pub names: Vec<String>,
    /// Which are free.
    pub free: Vec<bool>,
    /// Their values at the last iteration.
    pub params: Vec<f64>,
    /// Forward and adjoint solves so far.
    pub forward_solves: usize,
    /// Adjoint solves so far.
    pub adjoint_solves: usize,
    /// Seconds since the run started.
    pub elapsed: f64,
    /// Seconds left at most (the iteration limit at the mean iteration time so far).
    pub eta: Option<f64>,
    /// J of every iteration so far (the first 1000).
    pub costs: Vec<f64>,
    /// A batch: every indent of the manifest (`id`, `x`, `y`, `state`: `pending` until it
    /// ends, then its status's state, `values`, `std_dev`, `names`, `rms_rel`, `message`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub indents: Vec<Value>,
}

/// An error as the CLI prints it: the kind and the message chain, outermost first.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ErrorBody {
    /// `config`, `data`, `solver`, `io`, `internal`.
    pub kind: String,
    /// The messages.
    pub messages: Vec<String>,
}

/// `status.json`: what the run is, where it stands, how it ended.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunMeta {
    /// The run's id (its folder's name).
    pub id: String,
    /// `identify` or `simulate`.
    pub command: String,
    /// Where it stands.
    pub status: Status,
    /// Submission, start and end times (s since the Unix epoch).
    pub created: f64,
    /// Start.
    pub started: Option<f64>,
    /// End.
    pub finished: Option<f64>,
    /// The record's id, if any.
    pub record: Option<String>,
    /// The test of the record (from 1).
    pub test: Option<usize>,
    /// The `--set` overrides applied when the run loads config.ron (empty when they are
    /// written into it).
    pub sets: Vec<String>,
    /// The equivalent command line, run from the run's folder.
    pub cli: String,
    /// Live progress.
    pub progress: Progress,
    /// The outcome in brief (law, J, converged, parameters), once done.
    pub summary: Option<Value>,
    /// Why it failed.
    pub error: Option<ErrorBody>,
    /// A remark (not converged, cancelled, undetermined parameters).
    pub message: Option<String>,
}

/// A run request (`POST /api/runs`).
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunRequest {
    /// `identify` or `simulate`.
    pub command: String,
    /// RON text; without it, the record's template (Maxwell) or the embedded default (R1).
    #[serde(default)]
    pub config: Option<String>,
    /// A record id (`POST /api/records`): it becomes `data.file`.
    #[serde(default)]
    pub record: Option<String>,
    /// The record's test (from 1): `data.test`.
    #[serde(default)]
    pub test: Option<usize>,
    /// `dotted.path: value` overrides (numbers, booleans or text), applied in key order,
    /// or a list of `path=value` strings, applied in order.
    #[serde(default)]
    pub sets: Option<Value>,
    /// identify: the iteration limit (`--max-iter`).
    #[serde(default)]
    pub max_iter: Option<usize>,
    /// identify: skip the discretization error (`--no-refine`).
    #[serde(default)]
    pub no_refine: bool,
    /// identify: a joint fit of these tests of `record` (each with an optional weight),
    /// built from the record's template or `config` (which then needs a `data` section).
    #[serde(default)]
    pub tests: Option<Vec<TestPick>>,
    /// identify: profile-likelihood intervals of every free parameter (`--profiles`).
    #[serde(default)]
    pub profiles: bool,
    /// identify: a multi-start of this many Latin-hypercube starts (`--starts`, 1 to
    /// [`MAX_STARTS`] here); result.json then has `multistart` (the distinct minima).
    #[serde(default)]
    pub starts: Option<usize>,
    /// identify: the multi-start's seed (`--seed`, default 1; needs `starts`).
    #[serde(default)]
    pub seed: Option<u64>,
    /// analyze: the tip (`berkovich`, `cone:DEG`, `sphere:UM`, `flat:UM`; `--tip`).
    #[serde(default)]
    pub tip: Option<String>,
    /// analyze: Poisson's ratio of the sample (`--nu`, default 0.3); calibrate: the
    /// reference's (required).
    #[serde(default)]
    pub nu: Option<f64>,
    /// calibrate: the reference's Young's modulus, GPa (`--modulus`, required).
    #[serde(default)]
    pub modulus: Option<f64>,
    /// calibrate: the number of area coefficients (`--terms`, default 3, 1 to 6).
    #[serde(default)]
    pub terms: Option<usize>,
    /// map: the two parameters (`--pair`).
    #[serde(default)]
    pub pair: Option<Vec<String>>,
    /// map: points per side (`--grid`, default 9, at most [`MAX_MAP_GRID`] here).
    #[serde(default)]
    pub grid: Option<usize>,
    /// map: half-width in the scaled variables (`--span`, default 0.5).
    #[serde(default)]
    pub span: Option<f64>,
    /// map: the slice's centre, `fit`, `law` or `start` (`--through`, default `fit`).
    #[serde(default)]
    pub through: Option<String>,
    /// batch: the manifest (CSV text; its `data` cells name records by id). Without it,
    /// every test of `record` is an indent.
    #[serde(default)]
    pub manifest: Option<String>,
}

/// A test of a joint fit (`tests` of a run request).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TestPick {
    /// The record of this test (an id of `POST /api/records`); default: the request's
    /// `record`. Tests of several records make one joint fit.
    #[serde(default)]
    pub record: Option<String>,
    /// The record's test, from 1.
    pub test: usize,
    /// Its weight in the joint cost (default `1 / (n F_max^2)`).
    #[serde(default)]
    pub weight: Option<f64>,
}

/// The most starts of a multi-start the server runs (the CLI allows 10,000).
pub const MAX_STARTS: usize = 200;

/// The largest map the server computes (points per side; the CLI allows more).
pub const MAX_MAP_GRID: usize = 41;

/// What a worker needs to execute a run: the `--set` overrides config.ron still needs
/// and the request (its command's options).
#[derive(Clone, Debug, Default)]
pub(crate) struct Spec {
    pub(crate) sets: Vec<String>,
    pub(crate) req: RunRequest,
}

/// A run in memory.
pub struct Run {
    /// Its id.
    pub id: String,
    pub(crate) dir: PathBuf,
    meta: Mutex<RunMeta>,
    pub(crate) cancel: Cancel,
    pub(crate) spec: Spec,
    events: broadcast::Sender<Arc<String>>,
    saved: Mutex<Option<Instant>>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // a worker that panicked while holding a lock leaves the data usable
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

impl Run {
    fn new(id: String, dir: PathBuf, meta: RunMeta, spec: Spec) -> Arc<Run> {
        Arc::new(Run {
            id,
            dir,
            meta: Mutex::new(meta),
            cancel: Cancel::default(),
            spec,
            events: broadcast::channel(256).0,
            saved: Mutex::new(None),
        })
    }

    /// A copy of its metadata.
    pub fn meta(&self) -> RunMeta {
        lock(&self.meta).clone()
    }

    /// Its folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Subscribes to its snapshots (each event: the whole `status.json` as JSON).
    pub fn subscribe(&self) -> broadcast::Receiver<Arc<String>> {
        self.events.subscribe()
    }

    /// Changes the metadata, publishes the snapshot and writes status.json (at most once a
    /// second unless `force` or the run ended).
    pub(crate) fn update(&self, force: bool, f: impl FnOnce(&mut RunMeta)) {
        // `saved` first: two threads' updates (a worker's final one and a DELETE's) reach
        // status.json and the events in the order they changed the metadata
        let mut saved = lock(&self.saved);
        let snapshot = {
            let mut m = lock(&self.meta);
            f(&mut m);
            m.clone()
        };
        let text = serde_json::to_string(&snapshot).unwrap_or_default();
        let _ = self.events.send(Arc::new(text.clone()));
        let due = force
            || snapshot.status.is_final()
            || saved.is_none_or(|t| t.elapsed().as_secs_f64() >= 1.0);
        if due {
            *saved = Some(Instant::now());
            if let Err(e) = indentify_study::atomic::write(&self.dir.join("status.json"), text) {
                tracing::warn!("run {}: {e:#}", self.id);
            }
        }
    }
}

/// A record named by a request: its id, its path from a run folder, its record.json.
pub(crate) type RecordRef = (String, String, Value);

/// Every run, the queue and the workers' rendezvous.
pub struct Runs {
    ws: Workspace,
    table: Mutex<BTreeMap<String, Arc<Run>>>,
    queue: Mutex<VecDeque<Arc<Run>>>,
    ready: Condvar,
    max_queue: usize,
    counter: AtomicU64,
}

impl Runs {
    /// The runs of `ws` (those of an earlier server included: a run that was queued or
    /// running when it stopped is marked failed), and `workers` threads executing new ones.
    pub fn start(ws: Workspace, workers: usize, max_queue: usize) -> Arc<Runs> {
        let runs = Arc::new(Runs {
            ws,
            table: Mutex::new(BTreeMap::new()),
            queue: Mutex::new(VecDeque::new()),
            ready: Condvar::new(),
            max_queue,
            counter: AtomicU64::new(0),
        });
        runs.reload();
        for k in 0..workers.max(1) {
            let r = Arc::clone(&runs);
            let spawned = std::thread::Builder::new()
                .name(format!("indentify-run-{k}"))
                .spawn(move || r.work());
            if let Err(e) = spawned {
                tracing::error!("cannot start a worker thread: {e}");
            }
        }
        runs
    }

    fn reload(&self) {
        let Ok(entries) = std::fs::read_dir(self.ws.runs()) else {
            return;
        };
        let mut table = lock(&self.table);
        for e in entries.flatten() {
            let id = e.file_name().to_string_lossy().into_owned();
            let Some(dir) = self.ws.run_dir(&id) else {
                continue;
            };
            let Ok(bytes) = std::fs::read(dir.join("status.json")) else {
                continue;
            };
            let Ok(meta) = serde_json::from_slice::<RunMeta>(&bytes) else {
                tracing::warn!("run {id}: unreadable status.json, not listed");
                continue;
            };
            let interrupted = !meta.status.is_final();
            let run = Run::new(id.clone(), dir, meta, Spec::default());
            if interrupted {
                run.update(true, |m| {
                    m.status = Status::Failed;
                    m.finished = Some(now());
                    m.error = Some(ErrorBody {
                        kind: "io".into(),
                        messages: vec![
                            "the server stopped before this run finished; the files it wrote \
                             are kept in its folder (submit it again to rerun it)"
                                .into(),
                        ],
                    });
                });
            }
            table.insert(id, run);
        }
    }

    /// The run `id`.
    ///
    /// # Errors
    /// An unknown or malformed id (404).
    pub fn get(&self, id: &str) -> Result<Arc<Run>, ApiError> {
        lock(&self.table)
            .get(id)
            .cloned()
            .ok_or_else(|| ApiError::not_found(format!("no run `{id}` in this workspace")))
    }

    /// Every run's metadata, newest first.
    pub fn list(&self) -> Vec<RunMeta> {
        let mut v: Vec<RunMeta> = lock(&self.table).values().map(|r| r.meta()).collect();
        v.sort_by(|a, b| b.created.total_cmp(&a.created).then(b.id.cmp(&a.id)));
        v
    }

    /// Runs waiting for a worker.
    pub fn queued(&self) -> usize {
        lock(&self.queue).len()
    }

    /// The workspace.
    pub fn workspace(&self) -> &Workspace {
        &self.ws
    }

    fn new_id(&self) -> String {
        let n = self.counter.fetch_add(1, Ordering::Relaxed);
        let ms = (now() * 1000.0) as u64;
        format!("r{ms}-{n}")
    }

    /// Checks a request as the CLI checks its command line and configuration, writes the
    /// run's folder and queues it. Nothing is written for a refused request.
    ///
    /// # Errors
    /// A 400 with the CLI's messages (unknown command, configuration, `--set`, a data
    /// file outside the workspace's records, a test out of range), 404 for an unknown
    /// record, 503 when the queue is full.
    pub fn submit(&self, mut req: RunRequest) -> Result<String, ApiError> {
        if !COMMANDS.contains(&req.command.as_str()) {
            return Err(ApiError::bad_request(
                "config",
                vec![format!(
                    "unknown command `{}`: expected one of {}",
                    req.command,
                    COMMANDS.join(", ")
                )],
            ));
        }
        if self.queued() >= self.max_queue {
            return Err(ApiError::new(
                StatusCode::SERVICE_UNAVAILABLE,
                "busy",
                vec![format!(
                    "{} runs are waiting already (the limit): submit this one when some have \
                     finished",
                    self.max_queue
                )],
            ));
        }
        let user_sets = sets_of(req.sets.as_ref())?;
        jobs::check_starts(&req)?;
        // a joint fit of tests of several records without `record`: the first pick's
        // record gives the one-test template (and the run's `record`)
        if req.record.is_none() {
            if let Some(first) = req.tests.as_ref().and_then(|t| t.first()) {
                req.record.clone_from(&first.record);
            }
        }
        let id = self.new_id();
        let dir = self
            .ws
            .run_dir(&id)
            .ok_or_else(|| ApiError::internal("bad run id"))?;
        let record = self.resolve_record(&req)?;
        let prepared = if req.command == "analyze" {
            jobs::prepare_analyze(&req, record.as_ref(), &user_sets)?
        } else if req.command == "calibrate" {
            crate::calibrate::prepare(&req, record.as_ref(), &user_sets)?
        } else {
            self.prepare_config(&req, &id, &dir, record.as_ref(), user_sets)?
        };
        let meta = RunMeta {
            id: id.clone(),
            command: req.command.clone(),
            status: Status::Queued,
            created: now(),
            started: None,
            finished: None,
            record: record.map(|r| r.0),
            test: req.test,
            sets: prepared.sets.clone(),
            cli: prepared.cli,
            progress: Progress {
                stage: "queued".into(),
                ..Progress::default()
            },
            summary: None,
            error: None,
            message: None,
        };
        std::fs::create_dir_all(&dir).map_err(ApiError::io)?;
        for (name, bytes) in &prepared.files {
            if let Err(e) = indentify_study::atomic::write(&dir.join(name), bytes) {
                let _ = std::fs::remove_dir_all(&dir);
                return Err(ApiError::internal(e));
            }
        }
        if req.command == "batch" {
            // the manifest as study reads it (ids, columns, numbers), before anything runs
            let read = indentify_study::batch::read_manifest(
                &dir.join(jobs::MANIFEST),
                Some(&dir.join("config.ron")),
            );
            if let Err(e) = read {
                let _ = std::fs::remove_dir_all(&dir);
                return Err(ApiError::study(&e));
            }
        }
        let spec = Spec {
            sets: prepared.sets,
            req,
        };
        let run = Run::new(id.clone(), dir, meta, spec);
        run.update(true, |_| {});
        lock(&self.table).insert(id.clone(), Arc::clone(&run));
        lock(&self.queue).push_back(run);
        self.ready.notify_one();
        Ok(id)
    }

    /// The files, `--set` list and command line of a run that loads a configuration
    /// (every command but `analyze`): the configuration checked as the CLI checks it.
    fn prepare_config(
        &self,
        req: &RunRequest,
        id: &str,
        dir: &Path,
        record: Option<&RecordRef>,
        user_sets: Vec<String>,
    ) -> Result<jobs::Prepared, ApiError> {
        let name = "config.ron";
        let text = match (&req.config, record) {
            (Some(t), _) => t.clone(),
            (None, _) if req.command == "design" => jobs::DESIGN_TEMPLATE.to_string(),
            (None, Some((_, rel, info))) => {
                crate::api::record_template(Reference::R1Maxwell, rel, info, req.test, None)?
            }
            (None, None) => DEFAULT_CONFIG.to_string(),
        };
        // first as written (the user's own errors name only the user's own --set)
        let source = ConfigSource::Text {
            text: text.clone(),
            name: name.to_string(),
        };
        let cfg = source.load(&user_sets).map_err(|e| ApiError::study(&e))?;
        let mut sets = Vec::new();
        if let Some((rid, rel, _)) = record {
            if cfg.data.is_none() {
                let why = if cfg.tests.is_some() {
                    "it is a joint configuration: its records are named by each entry of \
                     `tests` (data.file = \"../../records/ID/NAME\")"
                } else {
                    "it drives the punch with a `history`: take a record's template \
                     (GET /api/templates/LAW?record=ID) or leave `record` out"
                };
                return Err(ApiError::bad_request(
                    "config",
                    vec![format!(
                        "record `{rid}` cannot be used: the configuration has no `data` \
                         section; {why}"
                    )],
                ));
            }
            sets.push(format!("data.file={rel}"));
            if let Some(k) = req.test {
                sets.push(format!("data.test={k}"));
            }
        }
        sets.extend(user_sets);
        let mut cfg = source.load(&sets).map_err(|e| ApiError::study(&e))?;
        cfg.base_dir = Some(dir.to_path_buf());
        let joint = match &req.tests {
            Some(picks) => {
                let lookup = |rid: &str| -> Result<RecordRef, ApiError> {
                    let info = records::load(&self.ws, rid)?;
                    let (rel, _) = records::file_of(&self.ws, rid)?;
                    Ok((rid.to_string(), rel, info))
                };
                Some(jobs::joint_config(
                    &cfg,
                    picks,
                    record,
                    req.command.as_str(),
                    &lookup,
                )?)
            }
            None => None,
        };
        if let Some(j) = &joint {
            cfg = ConfigSource::Text {
                text: j.clone(),
                name: name.to_string(),
            }
            .load(&[])
            .map_err(|e| ApiError::study(&e))?;
            cfg.base_dir = Some(dir.to_path_buf());
        }
        self.check_files(&cfg, dir)?;
        jobs::check_command(req, &cfg)?;
        // config.ron: the resolved configuration, annotated, when it has no `tests` (the
        // annotated form writes one test) and no `design`; a joint one built here is
        // written whole; one sent by the user is kept as sent, with its --set.
        let (ron, run_sets) = match joint {
            Some(j) => (j, Vec::new()),
            None if cfg.tests.is_none() && cfg.design.is_none() => {
                let header = vec![format!(
                    "Written by `indentify serve` for run {id} ({}); every --set applied.",
                    req.command
                )];
                (
                    indentify_study::templates::annotated(&cfg, &header),
                    Vec::new(),
                )
            }
            None => (text, sets),
        };
        let mut files = vec![(name.to_string(), ron.into_bytes())];
        if req.command == "batch" {
            let manifest = jobs::manifest_text(&self.ws, req, record)?;
            files.push((jobs::MANIFEST.to_string(), manifest.into_bytes()));
        }
        Ok(jobs::Prepared {
            cli: cli_line(req, &run_sets),
            files,
            sets: run_sets,
        })
    }

    /// The record a request names (its id, its path relative to a run folder, its
    /// record.json), checked against the request's test number.
    fn resolve_record(&self, req: &RunRequest) -> Result<Option<RecordRef>, ApiError> {
        Ok(match &req.record {
            Some(rid) => {
                let info = records::load(&self.ws, rid)?;
                let n = info["tests"].as_array().map_or(0, Vec::len);
                if let Some(k) = req.test {
                    if k == 0 || k > n {
                        return Err(ApiError::bad_request(
                            "data",
                            vec![format!(
                                "test {k} is not a test of record `{rid}`: it holds {n} test{} \
                             (1 to {n})",
                                if n == 1 { "" } else { "s" }
                            )],
                        ));
                    }
                }
                let (rel, _) = records::file_of(&self.ws, rid)?;
                Some((rid.clone(), rel, info))
            }
            None if req.test.is_some() => {
                return Err(ApiError::bad_request(
                    "config",
                    vec!["`test` chooses a test of a record: give `record` too".into()],
                ));
            }
            None => None,
        })
    }

    /// Refuses a configuration whose data files are not records of this workspace.
    fn check_files(&self, cfg: &Config, dir: &Path) -> Result<(), ApiError> {
        // a calibrated tip: only a tip uploaded to this workspace (POST /api/tips)
        let punches = std::iter::once(&cfg.punch)
            .chain(cfg.tests.iter().flatten().filter_map(|t| t.punch.as_ref()));
        for p in punches {
            if let indentify_study::Punch::Calibrated { file, .. } = p {
                if !self.ws.is_tip_file(&normalize(&dir.join(file))) {
                    return Err(ApiError::bad_request(
                        "config",
                        vec![format!(
                            "punch: Calibrated(file: \"{file}\") is not a tip of this \
                             workspace: upload the tip file (POST /api/tips) and name it as \
                             its answer's `punch` says (\"{}\")",
                            crate::tips::relative_path("ID")
                        )],
                    ));
                }
            }
        }
        let mut files: Vec<&str> = cfg.data.iter().map(|d| d.file.as_str()).collect();
        for t in cfg.tests.iter().flatten() {
            files.extend(t.data.iter().map(|d| d.file.as_str()));
        }
        for f in files {
            let path = normalize(&dir.join(f));
            if !self.ws.is_record_file(&path) {
                return Err(ApiError::bad_request(
                    "config",
                    vec![format!(
                        "data.file `{f}` is not a record of this workspace: upload the file \
                         (POST /api/records) and give its id as `record` (or name it \
                         \"../../records/ID/NAME\")"
                    )],
                ));
            }
        }
        Ok(())
    }

    /// Cancels run `id`: a queued run at once, a running one at its next stop point (see
    /// [`CANCELLABLE`]).
    ///
    /// # Errors
    /// An unknown run (404); a finished run (409). Nothing is deleted in any case.
    pub fn cancel(&self, id: &str) -> Result<RunMeta, ApiError> {
        let run = self.get(id)?;
        let removed = {
            let mut q = lock(&self.queue);
            let before = q.len();
            q.retain(|r| r.id != id);
            q.len() != before
        };
        if removed {
            run.update(true, |m| {
                m.status = Status::Cancelled;
                m.finished = Some(now());
                m.progress.stage = "finished".into();
                m.message = Some("cancelled before it started".into());
            });
            return Ok(run.meta());
        }
        let meta = run.meta();
        match meta.status {
            Status::Running => {
                run.cancel.raise();
                run.update(true, |m| {
                    // the run may have ended in between: its final message stays
                    if m.status == Status::Running {
                        m.message =
                            Some(format!("cancel asked: {}", jobs::when_it_stops(&m.command)));
                    }
                });
                Ok(run.meta())
            }
            s => Err(ApiError::new(
                StatusCode::CONFLICT,
                "state",
                vec![format!(
                    "run `{id}` is {} already: nothing to cancel (its files are kept)",
                    serde_json::to_value(s)
                        .ok()
                        .and_then(|v| v.as_str().map(String::from))
                        .unwrap_or_default()
                )],
            )),
        }
    }

    /// A worker: takes queued runs one at a time until the process ends.
    fn work(&self) {
        loop {
            let run = {
                let mut q = lock(&self.queue);
                loop {
                    if let Some(r) = q.pop_front() {
                        break r;
                    }
                    q = self
                        .ready
                        .wait(q)
                        .unwrap_or_else(std::sync::PoisonError::into_inner);
                }
            };
            execute(&run);
        }
    }
}

/// The request's `sets` as `path=value` strings.
fn sets_of(v: Option<&Value>) -> Result<Vec<String>, ApiError> {
    let bad = |what: String| ApiError::bad_request("config", vec![what]);
    match v {
        None | Some(Value::Null) => Ok(Vec::new()),
        Some(Value::Object(map)) => map
            .iter()
            .map(|(k, v)| match v {
                Value::String(s) => Ok(format!("{k}={s}")),
                Value::Number(n) => Ok(format!("{k}={n}")),
                Value::Bool(b) => Ok(format!("{k}={b}")),
                other => Err(bad(format!(
                    "sets.{k} = {other} is not allowed: expected a number, a boolean or text"
                ))),
            })
            .collect(),
        Some(Value::Array(items)) => items
            .iter()
            .map(|v| {
                v.as_str()
                    .map(String::from)
                    .ok_or_else(|| bad(format!("sets: `{v}` is not a `path=value` string")))
            })
            .collect(),
        Some(other) => Err(bad(format!(
            "sets = {other} is not allowed: expected an object {{\"law.E\": 25000}} or a list \
             [\"law.E=25000\"]"
        ))),
    }
}

/// Executes a run on the calling worker; a panic inside the pipelines fails the run only.
fn execute(run: &Arc<Run>) {
    run.update(true, |m| {
        m.status = Status::Running;
        m.started = Some(now());
        m.progress.stage = "starting".into();
    });
    let command = run.meta().command;
    let outcome =
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match command.as_str() {
            "identify" => run_identify(run),
            "analyze" => jobs::run_analyze(run),
            "calibrate" => crate::calibrate::run(run),
            "design" => jobs::run_design(run),
            "batch" => jobs::run_batch(run),
            "map" => jobs::run_map(run),
            _ => run_simulate(run),
        }));
    let (status, summary, error, message) = match outcome {
        Ok(Ok(end)) => end,
        Ok(Err(e)) => (Status::Failed, None, Some(e), None),
        Err(panic) => {
            let what = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_string()))
                .unwrap_or_else(|| "a panic".into());
            (
                Status::Failed,
                None,
                Some(ErrorBody {
                    kind: "internal".into(),
                    messages: vec![format!("internal error in the run: {what}")],
                }),
                None,
            )
        }
    };
    // a stop request that the pipeline could only honour at its end (simulate, analyze) or
    // that ended it with an `interrupted` error (design, map): the run is cancelled, and
    // whatever it wrote is kept
    let (status, error, message) = if run.cancel.is_raised() && status != Status::Cancelled {
        (
            Status::Cancelled,
            None,
            Some(jobs::cancelled_message(&command, status, error.as_ref())),
        )
    } else {
        (status, error, message)
    };
    run.update(true, |m| {
        m.status = status;
        m.finished = Some(now());
        m.progress.stage = "finished".into();
        m.progress.eta = Some(0.0);
        m.summary = summary;
        m.error = error;
        if message.is_some() {
            m.message = message;
        }
    });
}

pub(crate) type End = (Status, Option<Value>, Option<ErrorBody>, Option<String>);

pub(crate) fn error_body(e: &indentify_study::Error) -> ErrorBody {
    ErrorBody {
        kind: e.kind().name().into(),
        messages: e.messages(),
    }
}

/// The identification's observer: progress into the run's metadata and events.
struct Web<'a> {
    run: &'a Run,
    start: Instant,
    first: Option<f64>,
}

impl Observer for Web<'_> {
    fn started(&mut self, info: &RunInfo) {
        self.run.update(true, |m| {
            m.progress.stage = "fitting".into();
            m.progress.names = info.names.iter().map(|s| (*s).to_string()).collect();
            m.progress.free = info.free.clone();
            m.progress.max_iterations = info.max_iterations;
        });
    }

    fn iteration(&mut self, r: &IterationRecord) {
        let elapsed = self.start.elapsed().as_secs_f64();
        let first = *self.first.get_or_insert(elapsed);
        self.run.update(false, |m| {
            let p = &mut m.progress;
            p.iteration = r.iteration;
            p.cost = Some(r.cost);
            p.grad_norm = Some(r.grad_norm);
            p.params = r.params.clone();
            p.forward_solves = r.forward_solves;
            p.adjoint_solves = r.adjoint_solves;
            p.elapsed = elapsed;
            p.eta = (r.iteration > 0).then(|| {
                let per = (elapsed - first) / r.iteration as f64;
                per * p.max_iterations.saturating_sub(r.iteration) as f64
            });
            if p.costs.len() < 1000 {
                p.costs.push(r.cost);
            }
        });
    }
}

fn run_identify(run: &Run) -> Result<End, ErrorBody> {
    let mut opts = IdentifyOptions::new(ConfigSource::Path(run.dir.join("config.ron")));
    opts.sets = run.spec.sets.clone();
    opts.out = Some(run.dir.clone());
    opts.cancel = run.cancel.clone();
    opts.refine = !run.spec.req.no_refine;
    opts.overrides.max_iterations = run.spec.req.max_iter;
    opts.profiles = jobs::profiles(&run.spec.req);
    opts.starts = jobs::starts(&run.spec.req);
    let mut web = Web {
        run,
        start: Instant::now(),
        first: None,
    };
    let o = identify::run(&opts, &mut web).map_err(|e| error_body(&e))?;
    let r = &o.result;
    let id = r.identifiability.as_ref();
    let params: Vec<Value> = r
        .params
        .iter()
        .map(|p| {
            json!({
                "name": p.name, "unit": p.unit, "free": p.free, "start": p.start,
                "value": p.value, "std_dev": o.std_dev(p.name),
                "undetermined": id.is_some_and(|i| i.is_undetermined(p.name)),
                "at_lower": p.at_lower, "at_upper": p.at_upper,
            })
        })
        .collect();
    let summary = json!({
        "law": o.law, "method": r.method.name(), "converged": o.converged(),
        "stop_reason": r.stop_reason.to_string(), "J": r.cost, "J_start": r.initial_cost,
        "iterations": r.iterations, "seconds": r.seconds, "wall_seconds": o.wall_seconds,
        "r2": o.quality.as_ref().map(|q| q.r2), "parameters": params,
        "data": o.data, "warnings": o.warnings,
    });
    let (status, message) = match &r.stop_reason {
        StopReason::Interrupted => (
            Status::Cancelled,
            Some(format!(
                "cancelled after iteration {}: the result so far is in result.json",
                r.iterations
            )),
        ),
        StopReason::Undetermined { met, params } => (
            Status::Done,
            Some(format!(
                "stopped ({met}) where the data do not determine {}. What to do: {}",
                params.join("; "),
                StopReason::UNDETERMINED_ADVICE
            )),
        ),
        _ if !o.converged() => (
            Status::Done,
            Some(format!(
                "did not converge: {} after {} iterations (change the start, bounds or method, \
                 or continue with `indentify identify config.ron --out . --resume`)",
                r.stop_reason, r.iterations
            )),
        ),
        _ => (Status::Done, None),
    };
    Ok((status, Some(summary), None, message))
}

fn run_simulate(run: &Run) -> Result<End, ErrorBody> {
    run.update(true, |m| m.progress.stage = "simulating".into());
    let mut opts = SimulateOptions::new(ConfigSource::Path(run.dir.join("config.ron")));
    opts.sets = run.spec.sets.clone();
    opts.out = Some(run.dir.join("curve.csv"));
    let o = simulate::run_cancellable(&opts, &run.cancel).map_err(|e| error_body(&e))?;
    let peak = o
        .rows
        .iter()
        .copied()
        .fold(o.rows[0], |best, r| if r.f > best.f { r } else { best });
    let summary = json!({
        "command": "simulate", "law": o.law, "params": o.params, "punch": o.punch,
        "mesh": o.mesher.describe(), "nodes": o.size.0, "elements": o.size.1,
        "steps": o.rows.len() - 1, "schedule_steps": o.schedule_steps,
        "newton_iterations": o.trajectory.total_iterations(),
        "max_force": peak.f, "at_depth": peak.h, "seconds": o.seconds,
        "failure": o.failure, "curve": "curve.csv",
    });
    let written = indentify_study::atomic::write(
        &run.dir.join("result.json"),
        serde_json::to_vec_pretty(&summary).unwrap_or_default(),
    );
    if let Err(e) = written {
        return Err(ErrorBody {
            kind: "io".into(),
            messages: vec![format!("{e:#}")],
        });
    }
    let reached = o.rows.last().map_or(0.0, |r| r.t);
    match &o.failure {
        Some(why) if why.contains(indentify_study::stoppable::STOPPED) => Ok((
            Status::Cancelled,
            Some(summary),
            None,
            Some(format!(
                "cancelled: the forward run stopped ({why}); the curve up to t = {reached} s \
                 is kept in curve.csv"
            )),
        )),
        Some(why) => Ok((
            Status::Failed,
            Some(summary.clone()),
            Some(ErrorBody {
                kind: "solver".into(),
                messages: vec![format!(
                    "the simulation stopped: {why}; the curve up to t = {} s was written (try \
                     smaller steps in `history.segments` or a larger `solver.max_cuts`)",
                    o.rows.last().map_or(0.0, |r| r.t)
                )],
            }),
            None,
        )),
        None => Ok((Status::Done, Some(summary), None, None)),
    }
}

/// The files of a run folder (three levels deep; no hidden or temporary files), with sizes.
pub fn files(dir: &Path) -> Vec<Value> {
    let mut out = Vec::new();
    let mut walk = vec![(dir.to_path_buf(), String::new(), 0)];
    while let Some((d, prefix, depth)) = walk.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let rel = format!("{prefix}{name}");
            if safe_relative(&rel).is_none() {
                continue;
            }
            let Ok(ft) = e.file_type() else { continue };
            // two levels: a joint fit's test-K/ and a batch's indents/ID/
            if ft.is_dir() && depth < 2 {
                walk.push((e.path(), format!("{rel}/"), depth + 1));
            } else if ft.is_file() {
                let size = e.metadata().map_or(0, |m| m.len());
                out.push(json!({"name": rel, "bytes": size}));
            }
        }
    }
    out.sort_by(|a, b| a["name"].as_str().cmp(&b["name"].as_str()));
    out
}

/// The command line that repeats a run from its folder.
fn cli_line(req: &RunRequest, run_sets: &[String]) -> String {
    let mut cli = match req.command.as_str() {
        "simulate" => "indentify simulate config.ron --out curve.csv".to_string(),
        "batch" => format!(
            "indentify batch {} --config config.ron --out .",
            jobs::MANIFEST
        ),
        "map" => jobs::map_cli(req),
        c => format!("indentify {c} config.ron --out ."),
    };
    for s in run_sets {
        cli.push_str(&format!(" --set '{s}'"));
    }
    if req.command == "identify" {
        if let Some(n) = req.max_iter {
            cli.push_str(&format!(" --max-iter {n}"));
        }
        if req.no_refine {
            cli.push_str(" --no-refine");
        }
        if req.profiles {
            cli.push_str(" --profiles");
        }
        if let Some(n) = req.starts {
            cli.push_str(&format!(" --starts {n} --seed {}", req.seed.unwrap_or(1)));
        }
    }
    cli
}
