//! The identification pipeline, one for a one-test configuration and a joint one (a
//! configuration is set up as its list of tests, [`TestSetup`]): a configuration and its
//! data -> the least-squares misfit
//! minimized with its adjoint gradient (`indentify_identify`) -> the result, the fitted
//! curves and, with an output folder, the report directory (`result.json`, `history.csv`
//! written as iterations complete, `fit.csv`, `report.md`/`report.json` and figures).
//!
//! Every file but the history is written atomically, after the run: a run refused for bad
//! input writes nothing, an interrupted one leaves the previous complete files. A folder
//! that holds another run's history is refused unless the run resumes it or is forced.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context as _, anyhow};
use indentify_contact::{DirectSolver, SolverOptions};
use indentify_identify::{
    Cancel, ForceRecord, Identifiability, IdentifyConfig, IdentifyResult, IterationRecord, Problem,
    multiplicative_noise, resume,
};
use indentify_laws::Material;
use indentify_report::Observable;
use serde::Serialize;
use std::sync::Arc;

use crate::config::{Config, IdentifySection, Measured, Overrides, Prepared};
use crate::discretization::{self as disc, Discretization};
use crate::error::{Classify, Error, ErrorKind, Result};
use crate::figures::{self, Written};
use crate::format::{Named, assignments};
use crate::history::HistoryWriter;
use crate::solve::{ensure_differentiable, forward, param_names};
use crate::source::ConfigSource;

/// What to identify, from what, and where the report goes.
#[derive(Clone, Debug)]
pub struct IdentifyOptions {
    /// The configuration.
    pub config: ConfigSource,
    /// `dotted.path=value` overrides.
    pub sets: Vec<String>,
    /// A measured curve (CSV with `t` and `F`), or the record replacing `data.file`.
    pub data: Option<PathBuf>,
    /// The report directory; `None` writes nothing.
    pub out: Option<PathBuf>,
    /// Free / fixed / start / method / iteration-limit overrides.
    pub overrides: Overrides,
    /// Continue from the last line of `out/history.csv`.
    pub resume: bool,
    /// Replace another run's report in `out`.
    pub force: bool,
    /// Synthesized data only: multiplicative noise amplitude and seed.
    pub noise: Option<(f64, u64)>,
    /// Draw the figures and write report.md/json (real-data reports); off for batch runs
    /// that only need result.json and fit.csv.
    pub figures: bool,
    /// Stops the run after its current iteration when raised.
    pub cancel: Cancel,
    /// Record no fields: save the solver state every N schedule steps and replay the
    /// segments for each gradient (memory bounded; same results to round-off).
    pub checkpoint: Option<usize>,
    /// Without `checkpoint`, checkpoint automatically (every about sqrt(steps) steps) when
    /// recording every step's fields would take more than this many bytes.
    pub memory_budget: usize,
    /// After the fit, re-run the forward problem at the optimum on a 2x refined mesh with
    /// halved time steps and report the force change and the parameter shift it implies
    /// ([`crate::discretization`]); does not change the fit. Default true.
    pub refine: bool,
    /// Multi-start (`--starts N --seed S`): N Latin-hypercube starts run in parallel, the
    /// best reported, the minima listed ([`crate::explore`]). `None`: the one start of the
    /// configuration.
    pub starts: Option<crate::explore::StartsOptions>,
    /// Profile-likelihood intervals of every free parameter after the fit (`--profiles`).
    pub profiles: Option<indentify_identify::profile::ProfileSettings>,
    /// Threads solving the tests of a joint fit in parallel (`None`: the current rayon
    /// pool, all cores by default). The results do not depend on it.
    pub jobs: Option<usize>,
    /// Start the free parameters a closed form covers from the pre-fit of the test's own
    /// curve (`--start closed-form`, [`crate::closed_form_start`]) instead of the
    /// configuration's starts; ignored when resuming or with a multi-start.
    pub closed_form_start: bool,
}

/// The default [`IdentifyOptions::memory_budget`]: 1 GiB.
pub const DEFAULT_MEMORY_BUDGET: usize = 1 << 30;

/// Bytes that recording every step's fields takes for a model of `n_dofs` dofs and `n_qp`
/// Gauss points over `steps` steps (the dominant part of `Trajectory::recorded_bytes`).
pub fn recording_bytes(n_dofs: usize, n_qp: usize, steps: usize) -> usize {
    (steps + 1) * (8 * n_dofs + 32 * n_qp)
}

impl IdentifyOptions {
    /// The identification of `config` with its own settings, no report directory.
    pub fn new(config: ConfigSource) -> IdentifyOptions {
        IdentifyOptions {
            config,
            sets: Vec::new(),
            data: None,
            out: None,
            overrides: Overrides::default(),
            resume: false,
            force: false,
            noise: None,
            figures: true,
            cancel: Cancel::default(),
            checkpoint: None,
            memory_budget: DEFAULT_MEMORY_BUDGET,
            refine: true,
            starts: None,
            profiles: None,
            jobs: None,
            closed_form_start: false,
        }
    }
}

/// Progress of a run, for front ends (progress bars, Python callbacks, logs).
pub trait Observer {
    /// The run is set up and about to start.
    fn started(&mut self, _info: &RunInfo) {}
    /// An iteration completed (the start is iteration 0; a resumed run first repeats the
    /// iterate it resumes from).
    fn iteration(&mut self, _record: &IterationRecord) {}
}

/// An observer that ignores everything.
impl Observer for () {}

/// What a run is about to do.
#[derive(Clone, Debug, Serialize)]
pub struct RunInfo {
    /// The configuration's name.
    pub config: String,
    /// The law's name.
    pub law: &'static str,
    /// Every parameter name, in the law's order.
    pub names: Vec<&'static str>,
    /// Which are free.
    pub free: Vec<bool>,
    /// The held values as `name = value`.
    pub held: Vec<String>,
    /// The method's name.
    pub method: &'static str,
    /// The iteration limit.
    pub max_iterations: usize,
    /// The iteration resumed from, if any.
    pub resumed_at: Option<usize>,
    /// Where the data come from.
    pub data: String,
    /// The report directory.
    pub out: Option<PathBuf>,
    /// The unit of `J`: "N^2" (the force fitted), "mm^2" (every test load-controlled, the
    /// depth fitted) or "weighted" (a joint fit of both).
    pub cost_unit: &'static str,
}

/// The curves of the fit at the schedule times.
///
/// `f_data`, `f_start` and `f_final` are the observable's: forces (N) when the depth drives
/// the run, depths (mm) under load control ([`Observable::Depth`], docs/theory.md §13),
/// where `h` is then the force (N) of the run at the result (the prescribed force on the
/// load-controlled steps).
#[derive(Clone, Debug, Serialize)]
pub struct FitCurves {
    /// What is fitted: the force, or the depth under load control (`"observable":
    /// "Depth"` in result.json; absent for the force).
    #[serde(skip_serializing_if = "Observable::is_force")]
    pub observable: Observable,
    /// Times (s).
    pub t: Vec<f64>,
    /// Depths (mm); under load control the force at the result (N).
    pub h: Vec<f64>,
    /// Data: force (N), or depth (mm) under load control.
    pub f_data: Vec<f64>,
    /// The simulated observable at the start.
    pub f_start: Vec<f64>,
    /// The simulated observable at the result.
    pub f_final: Vec<f64>,
}

/// The files of a report directory.
#[derive(Clone, Debug, Serialize)]
pub struct ReportFiles {
    /// result.json.
    pub result: PathBuf,
    /// history.csv.
    pub history: PathBuf,
    /// fit.csv.
    pub fit: PathBuf,
    /// report.md, report.json and the figures, when drawn (a joint fit: the index
    /// report.md, the first test's `test-1/report.json`, every test's figures).
    pub report: Option<(PathBuf, PathBuf, Vec<PathBuf>)>,
    /// Why the report or figures are missing, when they are.
    pub report_error: Option<String>,
}

/// The outcome of an identification.
#[derive(Clone, Debug)]
pub struct IdentifyOutcome {
    /// The configuration's name.
    pub config: String,
    /// The law's name.
    pub law: &'static str,
    /// The parameter names.
    pub names: Vec<&'static str>,
    /// The optimizer's result (parameters, cost, counts, stop reason, identifiability).
    pub result: IdentifyResult,
    /// The law values that generated synthesized data.
    pub truth: Option<Vec<f64>>,
    /// Where the data come from.
    pub data: String,
    /// The measured record and its file's test label, if any.
    pub test: Option<String>,
    /// The curves.
    pub fit: FitCurves,
    /// R², RMS and largest residual of the final curve.
    pub quality: Option<indentify_report::FitQuality>,
    /// The report files, with an output folder.
    pub files: Option<ReportFiles>,
    /// Whether the run resumed an earlier one.
    pub resumed: bool,
    /// Where the model is stretched beyond its validity (also in the report).
    pub warnings: Vec<String>,
    /// Wall time of the whole pipeline (s).
    pub wall_seconds: f64,
    /// The discretization error of the fit (`None` with `refine: false`, or when the
    /// refined run failed: then a warning says why; not computed for joint fits).
    pub discretization: Option<Discretization>,
    /// The multi-start summary (with [`IdentifyOptions::starts`]).
    pub multistart: Option<crate::explore::MultiStartOutcome>,
    /// The profile likelihoods (with [`IdentifyOptions::profiles`]).
    pub profiles: Option<Vec<indentify_identify::profile::Profile>>,
    /// A joint fit's tests (empty for a one-test configuration): each test's curves and
    /// fit quality. [`IdentifyOutcome::fit`] then holds every test's curves end to end
    /// and [`IdentifyOutcome::quality`] the quality over all of them.
    pub tests: Vec<TestFit>,
    /// The Oliver-Pharr analysis of a one-test fit's measured record beside the fitted
    /// `E` (`None` for synthesized data and joint fits: a joint fit's are its tests',
    /// [`TestFit::oliver_pharr`]; docs/analysis.md).
    pub oliver_pharr: Option<crate::op_beside::OpBeside>,
    /// The closed-form start, when asked for ([`IdentifyOptions::closed_form_start`]): the
    /// values it set, or why none.
    pub start: Option<crate::closed_form_start::ClosedFormStart>,
    /// The coarse phase of a fit run coarse to fine (`identify.coarse_to_fine`): its
    /// counts and end point, or why the fit fell back to full fidelity.
    pub coarse: Option<crate::coarse_to_fine::CoarsePhase>,
}

/// One test of a joint fit.
#[derive(Clone, Debug, Serialize)]
pub struct TestFit {
    /// Its label (`name`, or `test K`).
    pub name: String,
    /// Where its data come from.
    pub data: String,
    /// Its weight `w_k` in `J = sum_k w_k J_k`.
    pub weight: f64,
    /// Whether the weight is the default `1 / (n F_max^2)`.
    pub default_weight: bool,
    /// Its share of the final cost, `w_k J_k` (N^2 times the weight's unit).
    pub cost: f64,
    /// Its curves.
    pub fit: FitCurves,
    /// R², RMS and largest residual of its final curve.
    pub quality: Option<indentify_report::FitQuality>,
    /// The Oliver-Pharr analysis of its measured record beside the shared fitted `E`
    /// (`None` for synthesized data; docs/analysis.md).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub oliver_pharr: Option<crate::op_beside::OpBeside>,
}

impl IdentifyOutcome {
    /// Whether the run converged.
    pub fn converged(&self) -> bool {
        self.result.stop_reason.is_converged()
    }

    /// The final value of parameter `name`.
    pub fn value(&self, name: &str) -> Option<f64> {
        self.result
            .params
            .iter()
            .find(|p| p.name == name)
            .map(|p| p.value)
    }

    /// Gauss-Newton standard deviation of parameter `name` (free and identifiable only).
    pub fn std_dev(&self, name: &str) -> Option<f64> {
        let i = self.result.identifiability.as_ref()?;
        let k = i.names.iter().position(|n| *n == name)?;
        Some(i.std_dev[k]).filter(|s| s.is_finite())
    }
}

/// Where the data come from.
pub(crate) struct Data {
    pub(crate) record: ForceRecord,
    pub(crate) describe: String,
    pub(crate) truth: Option<Vec<f64>>,
}

/// A configuration resolved before any solve: its law, the identification settings.
pub struct Resolved {
    /// The configuration's name.
    pub name: String,
    /// The configuration, `--set` overrides applied.
    pub cfg: Config,
    /// The law.
    pub law: Arc<dyn Material>,
    /// The `law` section's values (law order).
    pub law_values: Vec<f64>,
    /// The parameter names (law order).
    pub names: Vec<&'static str>,
    /// The identification settings, command-line overrides applied.
    pub id_cfg: IdentifyConfig,
}

/// Loads the configuration of `opts` and resolves its identification settings.
///
/// # Errors
/// [`ErrorKind::Config`] for an invalid configuration, settings, start or noise.
pub fn resolve(opts: &IdentifyOptions) -> Result<Resolved> {
    let name = opts.config.name();
    let cfg = opts.config.load(&opts.sets)?;
    let (law, law_values) = cfg.law.build().kind(ErrorKind::Config)?;
    // the instrument's parameters (Cf, vd, h0) after the law's when a name asks for them
    let (law, law_values) =
        crate::instrument::with_instrument(&cfg, law, law_values, &opts.overrides);
    let law = &law;
    let names = param_names(&**law);
    let mut id_cfg =
        IdentifySection::resolve_with(cfg.identify.as_ref(), &**law, &law_values, &opts.overrides)
            .with_context(|| format!("invalid identification settings for `{name}`"))
            .kind(ErrorKind::Config)?;
    id_cfg.cancel = opts.cancel.clone();
    let start: Vec<f64> = id_cfg
        .params
        .iter()
        .map(|p| p.value.unwrap_or(0.0))
        .collect();
    ensure_differentiable(&**law, &start, "cannot identify from this start")
        .kind(ErrorKind::Config)?;
    check_noise(opts.noise)?;
    // the deviations assume the noise the user asked for: synthesized multiplicative noise
    // F (1 + a xi), xi uniform in [-1, 1], has the standard deviation a / sqrt(3) |F|
    // (docs/cli.md, "Noise models"); a model stated by the caller is kept
    if let Some((a, _)) = opts.noise
        && a > 0.0
        && opts.overrides.noise.is_none()
        && id_cfg.noise == indentify_identify::NoiseModel::Residual
    {
        id_cfg.noise = indentify_identify::NoiseModel::Relative(a / 3f64.sqrt());
    }
    if opts.noise.is_some() && cfg.data.is_some() {
        return Err(Error::msg(
            ErrorKind::Config,
            format!(
                "noise perturbs synthesized data only, and `{name}` fits a measured record (its \
                 `data` section)"
            ),
        ));
    }
    Ok(Resolved {
        name,
        cfg,
        law: law.clone(),
        law_values,
        names,
        id_cfg,
    })
}

/// One test of a set-up configuration, besides its [`indentify_identify::Test`] in the
/// [`Problem`]: its label, data, weight, solver options, its own one-test configuration
/// and mesher. A configuration without `tests` is a list of one such test (weight 1).
pub struct TestSetup {
    /// Its label: `tests[k].name` (default `test K`) of a joint configuration, the
    /// configuration's name for a one-test configuration.
    pub label: String,
    /// The name of its runs in messages: `config [label]` in a joint configuration, the
    /// configuration's name alone.
    pub run_name: String,
    /// Where its data come from, described.
    pub data: String,
    /// The law values that synthesized its data (`None`: measured or given data).
    pub truth: Option<Vec<f64>>,
    /// Its measured record, if any.
    pub measured: Option<Measured>,
    /// Whether its weight is the default `1 / (n F_max^2)` (a joint configuration's test
    /// without `weight`).
    pub default_weight: bool,
    /// The direct solver's options (checkpointing decided).
    pub solver_opts: SolverOptions,
    /// Its one-test configuration ([`Config::test_config`], or the configuration itself).
    pub config: Config,
    /// Its specimen's mesher.
    pub mesher: crate::config::Mesher,
}

/// Everything an identification needs, set up: the [`Problem`] (models, schedules, data:
/// one test, or every test of a joint configuration) and the settings. Shared by [`run`],
/// the gradient check, the cost map and the test design.
pub struct Setup {
    /// The configuration's name.
    pub name: String,
    /// The configuration.
    pub cfg: Config,
    /// The law.
    pub law: Arc<dyn Material>,
    /// The `law` section's values.
    pub law_values: Vec<f64>,
    /// Parameter names.
    pub names: Vec<&'static str>,
    /// Identification settings.
    pub id_cfg: IdentifyConfig,
    /// The identification problem.
    pub problem: Problem,
    /// The tests, in the problem's order (one for a configuration without `tests`).
    pub tests: Vec<TestSetup>,
    /// Validity warnings of every test.
    pub warnings: Vec<String>,
}

impl Setup {
    /// Whether the configuration is a joint one (a `tests` list, even of one test).
    pub fn is_joint(&self) -> bool {
        self.cfg.tests.is_some()
    }

    /// Where the data come from, described: the test's data, or `N tests: label: data;
    /// ...` for a joint configuration.
    pub fn data_description(&self) -> String {
        if self.is_joint() {
            format!("{} tests: {}", self.tests.len(), self.describe_tests())
        } else {
            self.tests[0].data.clone()
        }
    }

    /// `label: data; label: data` over the tests.
    fn describe_tests(&self) -> String {
        self.tests
            .iter()
            .map(|t| format!("{}: {}", t.label, t.data))
            .collect::<Vec<_>>()
            .join("; ")
    }
}

/// Reads the data and builds the problem of a resolved configuration: its one test, or
/// every test of a joint configuration (`tests: [...]`), each prepared, its data loaded
/// (synthesized at the `law` values with the noise seed [`test_seed`] for test `k` when
/// it has no record) and weighted (1 for a one-test configuration, else its `weight` or
/// the default `1 / (n F_max^2)`); a joint configuration's tests are solved on
/// `opts.jobs` threads when given.
///
/// # Errors
/// [`ErrorKind::Data`] for data that cannot be read or compared, [`ErrorKind::Config`] for
/// a specimen or history that cannot be set up or `--data` given for a joint
/// configuration, [`ErrorKind::Solver`] when synthesizing the data fails.
pub fn setup(resolved: Resolved, opts: &IdentifyOptions) -> Result<Setup> {
    let Resolved {
        name,
        mut cfg,
        law,
        law_values,
        names,
        id_cfg,
    } = resolved;
    if let Some(path) = &opts.data {
        if let Some(tests) = &cfg.tests {
            return Err(Error::msg(
                ErrorKind::Config,
                format!(
                    "--data replaces the record of a one-test configuration, and `{name}` is a \
                     joint configuration of {} tests: give each test's record in \
                     tests[K].data",
                    tests.len()
                ),
            ));
        }
        if let Some(d) = &mut cfg.data {
            // the data path replaces the configuration's record, read with its preprocessing
            d.file = absolute(path);
        }
    }
    let (problem, tests, warnings) = set_up_tests(&cfg, &name, &law, &law_values, opts)?;
    Ok(Setup {
        name,
        cfg,
        law,
        law_values,
        names,
        id_cfg,
        problem,
        tests,
        warnings,
    })
}

/// The [`Problem`] of `cfg` (see [`setup`]) at `law_values`, its tests and their
/// warnings. `opts.data` (a curve file) is read by a one-test configuration without a
/// record only.
///
/// # Errors
/// As [`setup`].
pub(crate) fn set_up_tests(
    cfg: &Config,
    name: &str,
    law: &Arc<dyn Material>,
    law_values: &[f64],
    opts: &IdentifyOptions,
) -> Result<(Problem, Vec<TestSetup>, Vec<String>)> {
    let n_tests = cfg.n_tests();
    let mut tests = Vec::with_capacity(n_tests);
    let mut infos = Vec::with_capacity(n_tests);
    let mut warnings = Vec::new();
    for k in 0..n_tests {
        let (test, info, w) = set_up_test(cfg, k, name, law, law_values, opts)?;
        tests.push(test);
        infos.push(info);
        warnings.extend(w);
    }
    let mut problem = crate::instrument::problem(cfg, name, law, tests, &opts.overrides)?;
    // a one-test problem runs on the current pool (a batch indent's worker may lend its
    // idle neighbours to the sensitivities)
    if let (Some(j), Some(_)) = (opts.jobs, &cfg.tests) {
        problem
            .set_threads(j)
            .map_err(|e| Error::new(ErrorKind::Config, anyhow!(e)))?;
    }
    Ok((problem, infos, warnings))
}

/// Test `k` of `cfg` (the configuration itself without `tests`): prepared, its data
/// loaded, weighted; its warnings.
fn set_up_test(
    cfg: &Config,
    k: usize,
    name: &str,
    law: &Arc<dyn Material>,
    law_values: &[f64],
    opts: &IdentifyOptions,
) -> Result<(indentify_identify::Test, TestSetup, Vec<String>)> {
    let (config, label, run_name, what) = match &cfg.tests {
        Some(_) => {
            let sub = cfg
                .test_config(k)
                .with_context(|| format!("in tests[{k}] of `{name}`"))
                .kind(ErrorKind::Config)?;
            let label = cfg.test_name(k);
            let run_name = format!("{name} [{label}]");
            (sub, label, run_name, format!("tests[{k}] of `{name}`"))
        }
        None => (
            cfg.clone(),
            name.to_string(),
            name.to_string(),
            format!("`{name}`"),
        ),
    };
    if opts.noise.is_some() && config.data.is_some() {
        return Err(Error::msg(
            ErrorKind::Config,
            format!(
                "noise perturbs synthesized data only, and {what} fits a measured record (its \
                 `data` section)"
            ),
        ));
    }
    // under load control (force segments, `data.drive: Force`) the depth is the observable
    let (prepared, load) = prepare_driven(&config, &run_name)?;
    let mut solver_opts = config.solver.options(false);
    let noise = opts.noise.map(|(a, seed)| (a, test_seed(seed, k)));
    let data = match &load {
        None => load_data(
            &prepared,
            opts.data.as_deref(),
            noise,
            &run_name,
            law,
            law_values,
            &solver_opts,
        )?,
        Some(h) => crate::identify_load::load_depths(
            &prepared,
            h,
            opts.data.as_deref(),
            noise,
            &run_name,
            (law, law_values),
            &solver_opts,
        )?,
    };
    // load control replays its checkpoints with the history's drive
    // (`Adjoint::gradient_load_replayed`)
    solver_opts.checkpoint_every = checkpoint_interval(opts, &prepared)?;
    let Prepared {
        schedule,
        model,
        mesher,
        measured,
        warnings,
        ..
    } = prepared;
    let given = match &cfg.tests {
        Some(t) => t[k].weight,
        None => Some(1.0),
    };
    let compare = || format!("cannot compare the data with {what}");
    let weight = match given {
        Some(w) => w,
        None => indentify_identify::Test::default_weight(&schedule, &data.record)
            .with_context(compare)
            .kind(ErrorKind::Data)?,
    };
    let test = match load {
        Some(h) => indentify_identify::Test::new_load(
            model,
            h,
            &data.record,
            None,
            solver_opts.clone(),
            weight,
        ),
        None => indentify_identify::Test::new(
            model,
            schedule,
            &data.record,
            None,
            solver_opts.clone(),
            weight,
        ),
    }
    .with_context(compare)
    .kind(ErrorKind::Data)?;
    let info = TestSetup {
        label,
        run_name,
        data: data.describe,
        truth: data.truth,
        measured,
        default_weight: given.is_none(),
        solver_opts,
        config,
        mesher,
    };
    Ok((test, info, warnings))
}

/// The identification [`Problem`] of `opts`' configuration (one test or a joint `tests`
/// list; data loaded or synthesized as [`run`] does) and the `law` values, without
/// fitting: for benchmarks and studies that evaluate the cost themselves.
///
/// # Errors
/// As [`run`] before any fit.
pub fn problem(opts: &IdentifyOptions) -> Result<(Problem, Vec<f64>)> {
    let resolved = resolve(opts)?;
    let values = resolved.law_values.clone();
    Ok((setup(resolved, opts)?.problem, values))
}

/// Runs the identification described by `opts`, reporting progress to `observer`: a
/// one-test configuration, or the tests of a joint one (`tests: [...]`) fitted at once
/// with shared parameters.
///
/// A run that stops without converging (iteration limit, stall, interruption) is `Ok`:
/// its [`IdentifyOutcome::converged`] says so, and its report is written.
///
/// # Errors
/// Invalid configuration, settings or data ([`ErrorKind::Config`], [`ErrorKind::Data`])
/// before any solve and before any file is written; an unwritable or occupied report
/// directory ([`ErrorKind::Io`]); a start that cannot be solved ([`ErrorKind::Solver`]).
pub fn run(opts: &IdentifyOptions, observer: &mut dyn Observer) -> Result<IdentifyOutcome> {
    let wall = Instant::now();
    let resolved = resolve(opts)?;
    if let Some(starts) = &opts.starts {
        starts.check()?;
    }
    let paths = match &opts.out {
        Some(out) => Some(check_report_dir(out, opts.resume, opts.force)?),
        None => None,
    };
    if opts.starts.is_some() && opts.resume {
        return Err(Error::msg(
            ErrorKind::Config,
            "--starts cannot be combined with --resume: a multi-start has no single history to \
             continue",
        ));
    }
    let mut s = setup(resolved, opts)?;
    let start = (opts.closed_form_start && !opts.resume && opts.starts.is_none())
        .then(|| crate::closed_form_start::apply(&mut s));
    if let Some(c) = &start {
        tracing::info!("{}", c.summary());
    }
    if opts.profiles.is_some() {
        // the profiles' threshold needs s^2 from the identifiability summary
        s.id_cfg.identifiability = true;
    }
    let coarse = coarse_plan(&s, opts)?;

    // the folder marked as holding a run in progress (the earlier run moved aside under
    // --force), then the history, once every input is known good
    if let Some(p) = &paths {
        let what = format!("the identification of `{}`", s.name);
        crate::run_folder::begin(&p.dir, opts.force && !opts.resume, &what).kind(ErrorKind::Io)?;
    }
    let (mut history, resume_from) = open_history(paths.as_ref(), opts.resume, &s.names)?;
    observer.started(&RunInfo {
        resumed_at: resume_from.as_ref().map(|r| r.iteration),
        data: if s.is_joint() {
            format!(
                "{} tests fitted jointly ({})",
                s.tests.len(),
                s.describe_tests()
            )
        } else {
            s.tests[0].data.clone()
        },
        cost_unit: match s.problem.tests.iter().filter(|t| t.load.is_some()).count() {
            0 => "N^2",
            n if n == s.problem.tests.len() => "mm^2",
            _ => "weighted",
        },
        ..run_info(&s.name, &s.law, &s.names, &s.id_cfg, opts)
    });
    let (result, multistart, coarse) = fit(
        &s,
        opts,
        (resume_from.as_ref(), coarse),
        &mut history,
        paths.as_ref(),
        observer,
    )?;
    let profiles = profiles(&s, opts, &result)?;
    let mut outcome = outcome(&s, result, resume_from.is_some())?;
    outcome.multistart = multistart;
    outcome.profiles = profiles;
    outcome.start = start;
    outcome.coarse = coarse;
    let s = std::sync::Arc::new(s);
    if opts.refine {
        discretization_check(&mut outcome, &s, &opts.cancel);
    }
    if let Some(p) = paths {
        outcome.files = Some(write_report(&p, &outcome, opts, &s)?);
        // every file of the run written: the mark goes last
        crate::run_folder::finish(&p.dir).kind(ErrorKind::Io)?;
    }
    outcome.wall_seconds = wall.elapsed().as_secs_f64();
    Ok(outcome)
}

/// The fit: the optimizer from the start (or the resumed iterate), or the multi-start's
/// best run (each start a fit of every test) with its summary; the history written.
#[allow(clippy::type_complexity)]
fn fit(
    s: &Setup,
    opts: &IdentifyOptions,
    (resume_from, coarse): (Option<&IterationRecord>, Option<CoarsePlan>),
    history: &mut Option<HistoryWriter>,
    paths: Option<&Paths>,
    observer: &mut dyn Observer,
) -> Result<(
    IdentifyResult,
    Option<crate::explore::MultiStartOutcome>,
    Option<crate::coarse_to_fine::CoarsePhase>,
)> {
    let name = &s.name;
    let mut phase = None;
    let (result, multistart) = match &opts.starts {
        Some(starts) => {
            let (summary, best) = crate::explore::multistart(&s.problem, &s.id_cfg, starts)
                .map_err(|e| e.context(format!("the multi-start of `{name}` failed")))?;
            // the best run's history
            for r in &best.history {
                if let Some(h) = history.as_mut() {
                    h.record(r).kind(ErrorKind::Io)?;
                }
                observer.iteration(r);
            }
            (Ok(best), Some(summary))
        }
        None => match coarse {
            Some(plan) => {
                let (fine_cfg, p) = coarse_phase(s, plan);
                let r = optimize(&s.problem, &fine_cfg, None, history.as_mut(), observer)
                    .map(|r| with_configured_start(r, &s.id_cfg, &p));
                phase = Some(p);
                (r, None)
            }
            None => (
                optimize(
                    &s.problem,
                    &s.id_cfg,
                    resume_from,
                    history.as_mut(),
                    observer,
                ),
                None,
            ),
        },
    };
    let result = result.map_err(|e| {
        let kept = match (history, paths) {
            (Some(h), Some(p)) if h.lines > 0 => format!(
                "; the history so far ({} lines) is in `{}`",
                h.lines,
                p.history.display()
            ),
            _ => String::new(),
        };
        let what = if s.is_joint() {
            "joint identification"
        } else {
            "identification"
        };
        e.context(format!("the {what} of `{name}` failed{kept}"))
    })?;
    Ok((result, multistart, phase))
}

/// The coarse phase of a fit run coarse to fine: its iteration limit and coarse problem.
struct CoarsePlan {
    iterations: usize,
    problem: Problem,
    model: String,
}

/// The coarse phase `identify.coarse_to_fine` asks for, its coarse model built before any
/// solve (`None`: full fidelity; skipped, with a note, when resuming).
///
/// # Errors
/// A schedule that cannot be honoured (a coarse mesh below the contact resolution, a
/// load-controlled test, a mesh that cannot be coarsened) or combined with `--starts`,
/// naming the field.
fn coarse_plan(s: &Setup, opts: &IdentifyOptions) -> Result<Option<CoarsePlan>> {
    let Some(c) = s.cfg.identify.as_ref().and_then(|i| i.coarse_to_fine) else {
        return Ok(None);
    };
    if opts.starts.is_some() {
        return Err(Error::msg(
            ErrorKind::Config,
            "identify.coarse_to_fine cannot be combined with --starts: a multi-start runs \
             every start at full fidelity (set identify.coarse_to_fine: None)",
        ));
    }
    if opts.resume {
        tracing::info!(
            "  identify.coarse_to_fine: resuming, the fit continues at full fidelity (no \
             coarse phase)"
        );
        return Ok(None);
    }
    let (problem, model) = crate::coarse_to_fine::coarse_problem(s)
        .context(
            "identify.coarse_to_fine: the fidelity schedule cannot be honoured (set \
             identify.coarse_to_fine: None for a fit at full fidelity)",
        )
        .kind(ErrorKind::Config)?;
    Ok(Some(CoarsePlan {
        iterations: c.iterations,
        problem,
        model,
    }))
}

/// Runs the coarse phase of `plan` (its iterations logged, not in the history): the
/// fine phase's configuration and what the phase did.
fn coarse_phase(
    s: &Setup,
    plan: CoarsePlan,
) -> (IdentifyConfig, crate::coarse_to_fine::CoarsePhase) {
    let mut log = |r: &IterationRecord| {
        tracing::info!(
            "  coarse iteration {}: J = {:.6e} ({:.1} s)",
            r.iteration,
            r.cost,
            r.seconds
        );
    };
    let (cfg, phase) = crate::coarse_to_fine::coarse_phase(
        s,
        Ok((plan.problem, plan.model)),
        &s.id_cfg,
        plan.iterations,
        &mut log,
    );
    tracing::info!("  {}", phase.summary());
    (cfg, phase)
}

/// The fine phase's result with the configuration's start as its start (the report's
/// start curve is then solved again at it, one forward run) when the coarse phase moved
/// the start.
fn with_configured_start(
    mut r: IdentifyResult,
    id_cfg: &IdentifyConfig,
    phase: &crate::coarse_to_fine::CoarsePhase,
) -> IdentifyResult {
    if phase.result.is_none() {
        return r;
    }
    for p in r.params.iter_mut() {
        if let Some(v) = id_cfg
            .params
            .iter()
            .find(|q| q.name == p.name)
            .and_then(|q| q.value)
        {
            p.start = v;
        }
    }
    r.initial_forces.clear();
    r
}

/// The profile likelihoods after the fit, when asked and not interrupted (each profile
/// point a constrained re-fit of every test).
fn profiles(
    s: &Setup,
    opts: &IdentifyOptions,
    result: &IdentifyResult,
) -> Result<Option<Vec<indentify_identify::profile::Profile>>> {
    let Some(settings) = &opts.profiles else {
        return Ok(None);
    };
    if opts.cancel.is_raised() {
        tracing::warn!("warning: interrupted: no profiles");
        return Ok(None);
    }
    let wall = Instant::now();
    let profiles = crate::explore::profiles(&s.problem, &s.id_cfg, result, settings)
        .map_err(|e| e.context(format!("the profiles of `{}` failed", s.name)))?;
    if opts.cancel.is_raised() {
        tracing::warn!("warning: interrupted during the profiles: no profiles");
        return Ok(None);
    }
    tracing::info!(
        "  profiles: {} {}re-fits in {:.1} s",
        profiles.iter().map(|p| p.points.len() - 1).sum::<usize>(),
        if s.is_joint() { "joint " } else { "" },
        wall.elapsed().as_secs_f64()
    );
    Ok(Some(profiles))
}

/// The outcome of a fit before its explorations, discretization error and files: each
/// test's curves at the start and at the result, and every test's end to end.
fn outcome(s: &Setup, result: IdentifyResult, resumed: bool) -> Result<IdentifyOutcome> {
    let fits = test_fits(s, &result, resumed)?;
    // one observable for the whole fit, or mixed (force and depth tests of a joint fit)
    let observable = fits.first().map_or(Observable::Force, |f| f.fit.observable);
    let mixed = fits.iter().any(|f| f.fit.observable != observable);
    let mut all = FitCurves {
        observable,
        t: Vec::new(),
        h: Vec::new(),
        f_data: Vec::new(),
        f_start: Vec::new(),
        f_final: Vec::new(),
    };
    for f in &fits {
        all.t.extend(&f.fit.t);
        all.h.extend(&f.fit.h);
        all.f_data.extend(&f.fit.f_data);
        all.f_start.extend(&f.fit.f_start);
        all.f_final.extend(&f.fit.f_final);
    }
    let joint = s.is_joint();
    let oliver_pharr = if joint {
        None
    } else {
        oliver_pharr(&s.tests[0], &result)
    };
    Ok(IdentifyOutcome {
        config: s.name.clone(),
        law: s.law.name(),
        names: s.names.clone(),
        // a quality over forces and depths together would mix units: each test has its own
        quality: if mixed {
            None
        } else {
            indentify_report::FitQuality::compute(&all.f_data, &all.f_final).ok()
        },
        result,
        truth: s.tests[0].truth.clone(),
        data: s.data_description(),
        test: match &s.tests[..] {
            [one] if !joint => one
                .measured
                .as_ref()
                .and_then(|m| m.raw.meta.test_name.clone()),
            _ => None,
        },
        fit: all,
        files: None,
        resumed,
        warnings: s.warnings.clone(),
        wall_seconds: 0.0,
        discretization: None,
        multistart: None,
        profiles: None,
        tests: if joint { fits } else { Vec::new() },
        oliver_pharr,
        start: None,
        coarse: None,
    })
}

/// The O&P analysis of a one-test fit's measured record beside the fitted `E`, with the
/// fitted `nu` (0.3 when the law has none).
fn oliver_pharr(test: &TestSetup, result: &IdentifyResult) -> Option<crate::op_beside::OpBeside> {
    let m = test.measured.as_ref()?;
    let value = |n: &str| result.params.iter().find(|p| p.name == n).map(|p| p.value);
    Some(crate::op_beside::compare(
        &m.raw,
        &test.config.punch,
        test.config.base_dir.as_deref(),
        value("E"),
        value("nu").unwrap_or(0.3),
    ))
}

/// Each test's curves at the start and at the result (the result's forces are the
/// optimizer's; so are the start's forces of a depth-controlled test of a run that was not
/// resumed, the optimizer's first forward run, at the start's round trip through the
/// scaled variables; otherwise the start is solved again, the tests one after the other)
/// and fit quality.
fn test_fits(s: &Setup, result: &IdentifyResult, resumed: bool) -> Result<Vec<TestFit>> {
    let start_params: Vec<f64> = result.params.iter().map(|p| p.start).collect();
    let mut fits = Vec::with_capacity(s.tests.len());
    for (k, (test, info)) in s.problem.tests.iter().zip(&s.tests).enumerate() {
        let quiet = SolverOptions {
            record_fields: false,
            ..info.solver_opts.clone()
        };
        let mut solver = DirectSolver::new(&test.model).kind(ErrorKind::Solver)?;
        // the observables at `c` and the run's forces (the prescribed series under load
        // control)
        let mut curve_at = |c: &[f64]| -> Result<(Vec<f64>, Vec<f64>)> {
            let traj = match &test.load {
                Some(h) => {
                    crate::identify_load::run(&mut solver, &*s.law, c, h, &quiet, &info.run_name)?
                }
                None => forward(
                    &mut solver,
                    &*s.law,
                    c,
                    &test.schedule,
                    &quiet,
                    &info.run_name,
                )
                .kind(ErrorKind::Solver)?,
            };
            Ok((s.problem.observables_of(k, c, &traj), traj.forces()))
        };
        let kept = (!resumed && test.load.is_none())
            .then(|| result.initial_forces.get(s.problem.rows_of(k)))
            .flatten()
            .filter(|_| result.initial_forces.len() == s.problem.target.len());
        let f_start = match kept {
            Some(f) => f.to_vec(),
            None => curve_at(&start_params)?.0,
        };
        let fit = match &test.load {
            Some(_) => {
                // the force at the result: a run there (the observables too)
                let (h_final, force) = curve_at(&result.c)?;
                FitCurves {
                    observable: Observable::Depth,
                    t: test.schedule.t.clone(),
                    h: force,
                    f_data: test.target.clone(),
                    f_start,
                    f_final: h_final,
                }
            }
            None => FitCurves {
                observable: Observable::Force,
                t: test.schedule.t.clone(),
                h: test.schedule.depth.clone(),
                f_data: test.target.clone(),
                f_start,
                f_final: match result.forces.get(s.problem.rows_of(k)) {
                    Some(f) if result.forces.len() == s.problem.target.len() => f.to_vec(),
                    _ => curve_at(&result.c)?.0,
                },
            },
        };
        fits.push(TestFit {
            name: info.label.clone(),
            data: info.data.clone(),
            weight: test.weight,
            default_weight: info.default_weight,
            cost: test.cost_of(&fit.f_final),
            quality: indentify_report::FitQuality::compute(&fit.f_data, &fit.f_final).ok(),
            fit,
            // a one-test fit has its own (IdentifyOutcome::oliver_pharr)
            oliver_pharr: if s.is_joint() {
                oliver_pharr(info, result)
            } else {
                None
            },
        });
    }
    Ok(fits)
}

/// The noise seed of test `k` (from 0) of a joint fit: `seed` for the first test (a
/// one-test configuration's own), and for test `k >= 1` the first output of
/// `SplitMix64::new(seed ^ (k * 0xD1B54A32D192ED03))`, a hash that puts each test's draws
/// at an unrelated place of the generator's cycle.
///
/// (Before, test `k` used `seed + k * 0x9E3779B97F4A7C15`: SplitMix64 advances its state by
/// that same constant, so test `k`'s draws were test 0's shifted by `k` points and the
/// tests' noises were copies of each other, one point apart.)
pub fn test_seed(seed: u64, k: usize) -> u64 {
    if k == 0 {
        return seed;
    }
    indentify_identify::SplitMix64::new(seed ^ (k as u64).wrapping_mul(0xD1B5_4A32_D192_ED03))
        .next_u64()
}

/// What a run interrupted before or during the discretization check says.
pub const DISCRETIZATION_SKIPPED: &str = "interrupted: the discretization check was skipped \
     (no refined-mesh error in this report; run again without interrupting, or with \
     --no-refine to skip it on purpose)";

/// The discretization error of `outcome`'s fit ([`disc::compute`]: every test refined, the
/// tests in parallel) on a thread of its own, so that an interruption (`cancel`) skips it
/// at once: a refined run cannot stop midway, and its thread is left to end on its own.
/// Its summary is logged and its warnings added; a failure or a skip is a warning, never
/// an error (the fit stands).
fn discretization_check(outcome: &mut IdentifyOutcome, s: &std::sync::Arc<Setup>, cancel: &Cancel) {
    let skipped = |outcome: &mut IdentifyOutcome| {
        tracing::warn!("warning: {DISCRETIZATION_SKIPPED}");
        outcome.warnings.push(DISCRETIZATION_SKIPPED.to_string());
    };
    if cancel.is_raised() {
        return skipped(outcome);
    }
    if s.problem.tests.iter().any(|t| t.load.is_some()) {
        // the refined run re-solves the depth schedule; a load-controlled test has none
        let why = "no discretization check: it re-runs depth-driven tests only, and this fit \
                   has a load-controlled test (run with --no-refine to skip it on purpose)";
        tracing::warn!("warning: {why}");
        outcome.warnings.push(why.to_string());
        return;
    }
    tracing::info!(
        "  discretization check: the fit re-run on a 2x refined mesh with twice the steps \
         (Ctrl-C skips it)"
    );
    let (tx, rx) = std::sync::mpsc::channel();
    let setup = std::sync::Arc::clone(s);
    let c = outcome.result.c.clone();
    let free: Vec<bool> = outcome.result.params.iter().map(|p| p.free).collect();
    let spawned = std::thread::Builder::new()
        .name("discretization check".into())
        .spawn(move || {
            let tests: Vec<disc::TestInputs<'_>> = setup
                .tests
                .iter()
                .map(|t| disc::TestInputs {
                    name: t.label.clone(),
                    config: &t.config,
                    mesher: &t.mesher,
                    solver: &t.solver_opts,
                })
                .collect();
            let _ = tx.send(disc::compute(&disc::Inputs {
                tests: &tests,
                problem: &setup.problem,
                c: &c,
                free: &free,
                name: &setup.name,
            }));
        });
    let computed = match spawned {
        Err(e) => Err(anyhow!("cannot start its thread: {e}")),
        Ok(_) => loop {
            match rx.recv_timeout(std::time::Duration::from_millis(50)) {
                Ok(r) => break r,
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) if cancel.is_raised() => {
                    return skipped(outcome);
                }
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                    break Err(anyhow!("its thread ended without a result"));
                }
            }
        },
    };
    match computed {
        Ok(d) => {
            tracing::info!("{}", d.summary());
            for w in discretization_warnings(outcome, &d) {
                tracing::warn!("warning: {w}");
                outcome.warnings.push(w);
            }
            outcome.discretization = Some(d);
        }
        Err(e) => {
            let w = format!("no discretization error: {e:#}");
            tracing::warn!("warning: {w}");
            outcome.warnings.push(w);
        }
    }
}

/// One warning per parameter that the discretization moves by more than its standard
/// deviation.
pub fn discretization_warnings(outcome: &IdentifyOutcome, d: &Discretization) -> Vec<String> {
    let mut out = Vec::new();
    for (k, p) in outcome.result.params.iter().enumerate() {
        let (Some(shift), Some(sd)) = (d.shift[k], outcome.std_dev(p.name)) else {
            continue;
        };
        if shift.abs() > sd {
            let unit = if p.unit == "-" { "" } else { p.unit };
            out.push(format!(
                "the mesh/time discretization moves {} by {}{}{unit}, more than its standard \
                 deviation {}{}{unit}: refine the mesh (specimen nr and nz, or elements_in_contact) \
                 or the steps (history.segments[].steps, or the record's points: \
                 data.preprocessing.resample)",
                p.name,
                crate::format::sig(shift, 3),
                if unit.is_empty() { "" } else { " " },
                crate::format::sig(sd, 3),
                if unit.is_empty() { "" } else { " " },
            ));
        }
    }
    out
}

/// Refuses a noise amplitude outside [0, 1).
///
/// # Errors
/// A [`ErrorKind::Config`] error naming `--noise` and the range.
pub fn check_noise(noise: Option<(f64, u64)>) -> Result<()> {
    match noise {
        Some((a, _)) if !(0.0..1.0).contains(&a) => Err(Error::msg(
            ErrorKind::Config,
            format!("--noise {a} is not allowed: expected an amplitude in [0, 1) (0.1 = +-10%)"),
        )),
        _ => Ok(()),
    }
}

/// The checkpoint interval of a run: the one asked, or about sqrt(steps) when recording
/// every step would exceed the memory budget, or 0 (record everything).
fn checkpoint_interval(opts: &IdentifyOptions, prepared: &Prepared) -> Result<usize> {
    if let Some(n) = opts.checkpoint {
        if n == 0 {
            return Err(Error::msg(
                ErrorKind::Config,
                "--checkpoint 0 is not allowed: expected a number of schedule steps >= 1",
            ));
        }
        return Ok(n);
    }
    let steps = prepared.schedule.n_steps();
    let bytes = recording_bytes(
        prepared.model.disc.n_dofs(),
        prepared.model.disc.n_qp(),
        steps,
    );
    if bytes <= opts.memory_budget {
        return Ok(0);
    }
    let n = ((steps as f64).sqrt().ceil() as usize).max(1);
    tracing::info!(
        "  recording the {steps} steps' fields would take {} (budget {}): checkpointing every \
         {n} steps instead",
        crate::format::bytes(bytes),
        crate::format::bytes(opts.memory_budget)
    );
    Ok(n)
}

/// The history file of a run with a report folder: created, or reopened with its last
/// iteration under `--resume`.
fn open_history(
    paths: Option<&Paths>,
    resume: bool,
    names: &[&str],
) -> Result<(Option<HistoryWriter>, Option<IterationRecord>)> {
    Ok(match paths {
        Some(p) if resume => {
            let (w, last) = HistoryWriter::resume(&p.history, names).kind(ErrorKind::Io)?;
            (Some(w), Some(last))
        }
        Some(p) => (
            Some(HistoryWriter::create(&p.history, names).kind(ErrorKind::Io)?),
            None,
        ),
        None => (None, None),
    })
}

/// What the observer is told at the start of a run (the data and the resumed iteration
/// are the caller's).
fn run_info(
    name: &str,
    law: &Arc<dyn Material>,
    names: &[&'static str],
    id_cfg: &IdentifyConfig,
    opts: &IdentifyOptions,
) -> RunInfo {
    RunInfo {
        config: name.to_string(),
        law: law.name(),
        names: names.to_vec(),
        free: id_cfg.params.iter().map(|p| p.free).collect(),
        held: id_cfg
            .params
            .iter()
            .filter(|p| !p.free)
            .map(|p| format!("{} = {}", p.name, p.value.unwrap_or(f64::NAN)))
            .collect(),
        method: id_cfg.method.name(),
        max_iterations: id_cfg.stop.max_iterations,
        resumed_at: None,
        data: String::new(),
        out: opts.out.clone(),
        cost_unit: "N^2",
    }
}

/// The files of a report directory.
struct Paths {
    dir: PathBuf,
    history: PathBuf,
    result: PathBuf,
    fit: PathBuf,
}

/// Checks the report directory before any solve: writable, and not holding another run's
/// history unless resuming it or forced.
fn check_report_dir(out: &Path, resume: bool, force: bool) -> Result<Paths> {
    // an existing folder must be writable now; a new one is created once every input is
    // known good (crate::run_folder::begin), so a refused run leaves no empty folder
    if out.exists() {
        crate::atomic::ensure_writable_dir(out).kind(ErrorKind::Io)?;
    } else {
        crate::atomic::check_creatable_dir(out).kind(ErrorKind::Io)?;
    }
    let paths = Paths {
        dir: out.to_path_buf(),
        history: out.join("history.csv"),
        result: out.join("result.json"),
        fit: out.join("fit.csv"),
    };
    let occupied = std::fs::metadata(&paths.history).is_ok_and(|m| m.len() > 0);
    if occupied && !resume && !force {
        return Err(Error::msg(
            ErrorKind::Io,
            format!(
                "the report directory `{}` holds another run (history.csv): continue it with \
                 --resume, replace it with --force, or choose another --out",
                out.display()
            ),
        ));
    }
    Ok(paths)
}

/// [`Config::prepare`] with its errors classified: a record that cannot be read or drive
/// a simulation is a data error, anything else a configuration error.
///
/// # Errors
/// As [`Config::prepare`].
pub fn prepare(cfg: &Config, name: &str) -> Result<Prepared> {
    cfg.prepare(name).map_err(|e| {
        let kind = if e.downcast_ref::<crate::config::DataFailure>().is_some() {
            ErrorKind::Data
        } else {
            ErrorKind::Config
        };
        Error::new(kind, e)
    })
}

/// [`Config::prepare_driven`] with its errors classified as [`prepare`]'s: the prepared
/// model and, under load control, the history prescribing the force.
///
/// # Errors
/// As [`Config::prepare_driven`].
pub fn prepare_driven(
    cfg: &Config,
    name: &str,
) -> Result<(Prepared, Option<indentify_contact::LoadHistory>)> {
    cfg.prepare_driven(name).map_err(|e| {
        let kind = if e.downcast_ref::<crate::config::DataFailure>().is_some() {
            ErrorKind::Data
        } else {
            ErrorKind::Config
        };
        Error::new(kind, e)
    })
}

/// The data: the measured record, a curve file, or the configuration's own curve (with
/// `noise`: amplitude, seed).
fn load_data(
    prepared: &Prepared,
    curve: Option<&Path>,
    noise: Option<(f64, u64)>,
    name: &str,
    law: &Arc<dyn Material>,
    law_values: &[f64],
    solver_opts: &SolverOptions,
) -> Result<Data> {
    let schedule = &prepared.schedule;
    match (&prepared.measured, curve) {
        (Some(m), _) => Ok(Data {
            record: ForceRecord::new(m.record.t.clone(), m.record.f.clone())
                .with_context(|| format!("cannot use `{}` as data", m.path.display()))
                .kind(ErrorKind::Data)?,
            describe: describe_measured(m),
            truth: None,
        }),
        (None, Some(path)) => {
            let curve = crate::data::read_curve(path).kind(ErrorKind::Data)?;
            let (t0, t1) = (schedule.t[0], schedule.t[schedule.t.len() - 1]);
            curve.check_covers(t0, t1, name).kind(ErrorKind::Data)?;
            Ok(Data {
                record: curve.record().kind(ErrorKind::Data)?,
                describe: curve.name.clone(),
                truth: None,
            })
        }
        (None, None) => {
            let model = &prepared.model;
            let mut solver = DirectSolver::new(model).kind(ErrorKind::Solver)?;
            let traj = forward(&mut solver, &**law, law_values, schedule, solver_opts, name)
                .kind(ErrorKind::Solver)?;
            let mut forces = traj.forces();
            let names = param_names(&**law);
            let mut describe = format!(
                "synthesized: the curve of `{name}` at {}",
                assignments(&names, law_values)
            );
            if let Some((a, seed)) = noise {
                forces = multiplicative_noise(&forces, a, seed);
                describe.push_str(&format!(
                    ", noise F (1 + {a} xi), xi uniform in [-1, 1], seed {seed}"
                ));
            } else {
                describe.push_str(" (exact)");
            }
            Ok(Data {
                record: ForceRecord::new(schedule.t.clone(), forces)
                    .context("cannot use the simulated curve as data")
                    .kind(ErrorKind::Data)?,
                describe,
                truth: Some(law_values.to_vec()),
            })
        }
    }
}

/// `` `FILE` (anton-paar, test 1), 1000 samples, 60 points after preprocessing (...)``.
pub(crate) fn describe_measured(m: &Measured) -> String {
    format!(
        "{}, {} samples, {} points after preprocessing ({})",
        m.label(),
        m.raw.t.len(),
        m.record.t.len(),
        if m.applied.is_empty() {
            "none applied".to_string()
        } else {
            m.applied
                .iter()
                .map(|a| a.step.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        }
    )
}

/// The optimizer's run, the history written line by line.
fn optimize(
    problem: &Problem,
    id_cfg: &IdentifyConfig,
    resume_from: Option<&IterationRecord>,
    mut history: Option<&mut HistoryWriter>,
    observer: &mut dyn Observer,
) -> Result<IdentifyResult> {
    let mut write_error: Option<anyhow::Error> = None;
    let mut callback = |r: &IterationRecord| {
        if write_error.is_some() {
            return;
        }
        if let Some(h) = history.as_deref_mut() {
            match h.record(r) {
                Ok(false) => return,
                Ok(true) => {}
                Err(e) => {
                    write_error = Some(e);
                    // stop the run: its history can no longer be kept
                    id_cfg.cancel.raise();
                    return;
                }
            }
        }
        observer.iteration(r);
    };
    let outcome = match resume_from {
        Some(last) => resume(problem, id_cfg, last, &mut callback),
        None => indentify_identify::identify(problem, id_cfg, &mut callback),
    };
    if let Some(e) = write_error {
        return Err(Error::new(ErrorKind::Io, e));
    }
    outcome.map_err(|e| Error::new(ErrorKind::Solver, anyhow!(e)))
}

/// One page of a report: report.md, report.json and the figures of one test's curves.
struct Page<'a> {
    dir: PathBuf,
    title: String,
    test: &'a TestSetup,
    fit: &'a FitCurves,
    discretization: Option<indentify_report::DiscretizationSummary>,
    extra_markdown: String,
}

/// Writes result.json, fit.csv and (with `opts.figures`) the report and its figures: for a
/// one-test configuration one page in the report directory (with the multi-start and
/// profiles); for a joint one a page per test in `test-K/` (that test's curves at the
/// shared parameters) and an index report.md in the report directory (the parameters,
/// the tests with links to their pages, the multi-start and profiles). fit.csv of a joint
/// fit has a `test` column and every test's rows.
fn write_report(
    paths: &Paths,
    outcome: &IdentifyOutcome,
    opts: &IdentifyOptions,
    s: &Setup,
) -> Result<ReportFiles> {
    let joint = s.is_joint();
    let fit = if joint {
        // the header of the first test's observable (a mixed joint fit: its own)
        let mut text = match outcome
            .tests
            .iter()
            .map(|t| t.fit.observable)
            .collect::<Vec<_>>()
        {
            o if o.iter().all(|&o| o == Observable::Depth) => {
                String::from("test,t,F,h_data,h_start,h_final\n")
            }
            o if o.iter().all(|&o| o == Observable::Force) => {
                String::from("test,t,h,F_data,F_start,F_final\n")
            }
            // mixed: per test, the prescribed series and the observable's (the force's
            // for a depth-driven test, the depth's for a load-controlled one)
            _ => String::from("test,t,prescribed,data,start,final\n"),
        };
        for (k, t) in outcome.tests.iter().enumerate() {
            for line in fit_csv(&t.fit).lines().skip(1) {
                text.push_str(&format!("{},{line}\n", k + 1));
            }
        }
        text
    } else {
        fit_csv(&outcome.fit)
    };
    crate::atomic::write(&paths.fit, fit).kind(ErrorKind::Io)?;
    // result.json first: a report or figure that cannot be made must not lose the result
    let json = serde_json::to_string_pretty(&result_json(outcome, opts, paths))
        .context("cannot represent the result")
        .kind(ErrorKind::Io)?;
    crate::atomic::write(&paths.result, json + "\n").kind(ErrorKind::Io)?;
    let mut files = ReportFiles {
        result: paths.result.clone(),
        history: paths.history.clone(),
        fit: paths.fit.clone(),
        report: None,
        report_error: None,
    };
    if !opts.figures {
        return Ok(files);
    }
    let history_records = crate::history::read_all(&paths.history, outcome.names.len());
    let (extra_markdown, extra_figures) = explorations(paths, outcome);
    let pages: Vec<Page<'_>> = if joint {
        let n = outcome.tests.len();
        outcome
            .tests
            .iter()
            .zip(&s.tests)
            .enumerate()
            .map(|(k, (t, test))| Page {
                dir: paths.dir.join(format!("test-{}", k + 1)),
                title: format!(
                    "Joint identification of {} parameters: {}, {} of {n}",
                    outcome.law, outcome.config, t.name
                ),
                test,
                fit: &t.fit,
                // the joint shift, with this test's refined discretization and force change
                discretization: outcome.discretization.as_ref().and_then(|d| {
                    let td = d.tests.get(k)?;
                    Some(indentify_report::DiscretizationSummary {
                        refined: format!(
                            "{} with {} (every test refined; the shift is the joint fit's)",
                            td.mesh, td.steps
                        ),
                        rms_rel: td.rms_rel,
                        max_abs: td.max_abs,
                        shift: d.shift.clone(),
                        seconds: d.seconds,
                    })
                }),
                extra_markdown: t
                    .oliver_pharr
                    .as_ref()
                    .map_or(String::new(), crate::op_beside::markdown),
            })
            .collect()
    } else {
        vec![Page {
            dir: paths.dir.clone(),
            title: format!(
                "Identification of {} parameters: {}",
                outcome.law, outcome.config
            ),
            test: &s.tests[0],
            fit: &outcome.fit,
            discretization: outcome.discretization.as_ref().map(|d| {
                indentify_report::DiscretizationSummary {
                    refined: format!("{} with {}", d.mesh, d.steps),
                    rms_rel: d.rms_rel,
                    max_abs: d.max_abs,
                    shift: d.shift.clone(),
                    seconds: d.seconds,
                }
            }),
            extra_markdown: extra_markdown.clone(),
        }]
    };
    let mut figures = Vec::new();
    let mut first = None;
    for page in &pages {
        match write_page(page, outcome, &history_records) {
            Ok(w) => {
                figures.extend(w.figures);
                first.get_or_insert((w.markdown, w.json));
            }
            Err(e) => {
                let which = if joint {
                    format!("no report or figures for {}", page.test.label)
                } else {
                    "no report.md, report.json or figures".to_string()
                };
                tracing::warn!(
                    "warning: {which}: {e:#} (result.json, history.csv and fit.csv are written)"
                );
                files.report_error = Some(format!("{e:#}"));
            }
        }
    }
    figures.extend(extra_figures);
    if joint {
        // the index of the pages: what the console points to
        let index = paths.dir.join("report.md");
        match crate::atomic::write(&index, joint_index(outcome, &extra_markdown)) {
            Ok(()) => {
                if let Some((md, _)) = &mut first {
                    *md = index;
                }
            }
            Err(e) => {
                tracing::warn!("warning: no report.md: {e:#}");
                files.report_error = Some(format!("{e:#}"));
            }
        }
    }
    if let Some((md, json)) = first {
        files.report = Some((md, json, figures));
    }
    Ok(files)
}

/// The multi-start and profiles sections of the report (Markdown) and the profile
/// figures, written into the report directory.
fn explorations(paths: &Paths, outcome: &IdentifyOutcome) -> (String, Vec<PathBuf>) {
    let mut markdown = String::new();
    let mut figures = Vec::new();
    if let Some(c) = &outcome.start {
        markdown.push_str(&format!("## Start\n\n{}\n\n", c.summary()));
    }
    if let Some(c) = &outcome.coarse {
        markdown.push_str(&format!("## Coarse to fine\n\n{}\n\n", c.summary()));
    }
    if let Some(b) = &outcome.oliver_pharr {
        markdown.push_str(&crate::op_beside::markdown(b));
        markdown.push('\n');
    }
    if let Some(m) = &outcome.multistart {
        markdown.push_str(&m.markdown());
    }
    if let Some(p) = &outcome.profiles {
        let (links, written) = match crate::explore::write_profile_figures(&paths.dir, p) {
            Ok(w) => w,
            Err(e) => {
                tracing::warn!("warning: no profile figures: {e:#}");
                (Vec::new(), Vec::new())
            }
        };
        figures = written;
        if !markdown.is_empty() {
            markdown.push('\n');
        }
        markdown.push_str(&crate::explore::profiles_markdown(p, &links));
    }
    (markdown, figures)
}

/// Writes one page ([`figures::write`]) into its folder.
fn write_page(
    page: &Page<'_>,
    outcome: &IdentifyOutcome,
    history: &[IterationRecord],
) -> anyhow::Result<Written> {
    crate::atomic::ensure_writable_dir(&page.dir)?;
    let measured = page.test.measured.as_ref();
    let (file, test) = match measured {
        Some(m) => (
            m.path.display().to_string(),
            m.raw.meta.test_name.clone().unwrap_or_default(),
        ),
        None => (page.test.data.clone(), String::new()),
    };
    figures::write(
        &page.dir,
        &outcome.result,
        &figures::Inputs {
            title: page.title.clone(),
            file,
            test,
            measured,
            observable: page.fit.observable,
            t: &page.fit.t,
            h: &page.fit.h,
            f_data: &page.fit.f_data,
            f_start: &page.fit.f_start,
            f_final: &page.fit.f_final,
            history,
            warnings: &outcome.warnings,
            discretization: page.discretization.clone(),
            extra_markdown: page.extra_markdown.clone(),
        },
    )
}

/// The report.md of a joint fit: the shared parameters, the tests with their weights,
/// shares of `J` and fit qualities, links to their pages, then `extra` (multi-start,
/// profiles).
fn joint_index(o: &IdentifyOutcome, extra: &str) -> String {
    use crate::format::sig;
    let r = &o.result;
    let mut md = format!(
        "# Joint identification of {} parameters: {}\n\n{} tests share the parameters; \
         J = sum_k w_k J_k = {:.4e} ({}, {} iterations). Each test's page shows its curves at \
         the shared parameters, the parameters' identifiability and the convergence.\n\n",
        o.law,
        o.config,
        o.tests.len(),
        r.cost,
        r.stop_reason,
        r.iterations
    );
    md.push_str("| parameter | unit | start | final | std. dev. |\n|---|---|---:|---:|---:|\n");
    for p in &r.params {
        let value = if p.free {
            sig(p.value, 9)
        } else {
            format!("{} (held)", p.value)
        };
        let sd = o.std_dev(p.name).map_or(String::new(), |s| sig(s, 3));
        md.push_str(&format!(
            "| {} | {} | {} | {value} | {sd} |\n",
            p.name, p.unit, p.start
        ));
    }
    md.push_str(
        "\n| test | data | weight | w J | R² | RMS (% of F_max) | page |\n\
         |---|---|---:|---:|---:|---:|---|\n",
    );
    for (k, t) in o.tests.iter().enumerate() {
        let (r2, rms) = t
            .quality
            .as_ref()
            .map_or((String::new(), String::new()), |q| {
                (format!("{:.6}", q.r2), format!("{:.3}", 100.0 * q.rms_rel))
            });
        md.push_str(&format!(
            "| {} | {} | {:.4e} | {:.4e} | {r2} | {rms} | [test-{}/report.md](test-{}/report.md) |\n",
            t.name,
            t.data.replace('|', "\\|"),
            t.weight,
            t.cost,
            k + 1,
            k + 1
        ));
    }
    md.push_str(&crate::op_beside::joint_markdown(&o.tests));
    if !extra.is_empty() {
        md.push('\n');
        md.push_str(extra);
    }
    md
}

/// `t,h,F_data,F_start,F_final` at the schedule times; under load control
/// `t,F,h_data,h_start,h_final` (the force of the run at the result, the depths).
pub fn fit_csv(fit: &FitCurves) -> String {
    let mut text = String::from(match fit.observable {
        Observable::Force => "t,h,F_data,F_start,F_final\n",
        Observable::Depth => "t,F,h_data,h_start,h_final\n",
    });
    for i in 0..fit.t.len() {
        let at = |f: &[f64]| f.get(i).copied().unwrap_or(f64::NAN);
        text.push_str(&format!(
            "{},{},{},{},{}\n",
            fit.t[i],
            fit.h[i],
            at(&fit.f_data),
            at(&fit.f_start),
            at(&fit.f_final)
        ));
    }
    text
}

/// `path` made absolute against the working directory (the configuration's folder does
/// not apply to a path given on the command line).
pub fn absolute(path: &Path) -> String {
    std::env::current_dir()
        .map_or_else(|_| path.to_path_buf(), |d| d.join(path))
        .display()
        .to_string()
}

/// One parameter in result.json.
#[derive(Debug, Serialize)]
struct ParamJson {
    name: &'static str,
    unit: &'static str,
    free: bool,
    start: f64,
    value: f64,
    lower: f64,
    upper: f64,
    bound_hit: Option<&'static str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    truth: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    rel_error: Option<f64>,
}

/// The identifiability summary in result.json.
#[derive(Debug, Serialize)]
struct IdentifiabilityJson {
    names: Vec<&'static str>,
    n_data: usize,
    sigma2: f64,
    std_dev: Named<f64>,
    rel_std_dev: Named<f64>,
    correlation: Vec<Vec<f64>>,
    condition_number: f64,
    /// `condition_number` as text: `singular` beyond 1e16.
    condition: String,
    singular_values: Vec<f64>,
    directions: Vec<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    weakest_direction: Option<String>,
    undetermined: Vec<&'static str>,
    undetermined_reasons: Named<String>,
    /// The older name of `undetermined`.
    unidentifiable: Vec<&'static str>,
    /// What the deviations assume about the noise (absent: one variance for every
    /// weighted residual, `sigma2`).
    #[serde(skip_serializing_if = "Option::is_none")]
    noise: Option<String>,
    /// 2-sigma intervals `[low, high]` that account for the undetermined parameters
    /// (`value ± 2 std. dev.` in the scaled variable when none is).
    intervals: Named<[f64; 2]>,
}

impl IdentifiabilityJson {
    /// The summary of `i` for a fit of `observable` (its noise model named in the fitted
    /// quantity: `% of h` under load control).
    fn of(i: &Identifiability, observable: Observable) -> Self {
        IdentifiabilityJson {
            names: i.names.clone(),
            n_data: i.n_data,
            sigma2: i.sigma2,
            std_dev: Named::new(i.names.iter().copied().zip(i.std_dev.clone())),
            rel_std_dev: Named::new(i.names.iter().copied().zip(i.rel_std_dev.clone())),
            correlation: i.correlation.clone(),
            condition_number: i.condition_number,
            condition: i.condition_text(),
            singular_values: i.singular_values.clone(),
            directions: i.directions.clone(),
            weakest_direction: i.weakest_direction(),
            undetermined: i.undetermined.clone(),
            undetermined_reasons: Named::new(
                i.undetermined
                    .iter()
                    .copied()
                    .zip(i.reasons.iter().cloned()),
            ),
            unidentifiable: i.undetermined.clone(),
            noise: (i.noise != indentify_identify::NoiseModel::Residual).then(
                || match observable {
                    Observable::Force => i.noise.describe(i.noise_level),
                    Observable::Depth => i.noise.describe_observed(i.noise_level, "h", "mm"),
                },
            ),
            intervals: Named::new(
                i.names
                    .iter()
                    .copied()
                    .zip(i.intervals.iter().map(|&(a, b)| [a, b])),
            ),
        }
    }
}

/// result.json.
#[derive(Debug, Serialize)]
struct ResultJson {
    law: &'static str,
    config: String,
    data: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    noise: Option<NoiseJson>,
    method: &'static str,
    /// What is fitted: absent for the force, `"Depth"` under load control (J then in mm^2).
    #[serde(skip_serializing_if = "Observable::is_force")]
    observable: Observable,
    parameters: Vec<ParamJson>,
    #[serde(rename = "J")]
    j: f64,
    #[serde(rename = "J_start")]
    j_start: f64,
    #[serde(rename = "J_ref")]
    j_ref: f64,
    iterations: usize,
    forward_solves: usize,
    adjoint_solves: usize,
    sensitivity_solves: usize,
    stop_reason: String,
    converged: bool,
    /// Free parameters the data do not determine (see `identifiability`).
    undetermined: Vec<&'static str>,
    seconds: f64,
    resumed: bool,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    warnings: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    fit_quality: Option<FitJson>,
    // model adequacy and the headline's caveats (crate::adequacy)
    adequacy: Option<crate::adequacy::FitAdequacy>,
    caveats: Vec<String>,
    identifiability: Option<IdentifiabilityJson>,
    #[serde(skip_serializing_if = "Option::is_none")]
    discretization: Option<DiscretizationJson>,
    #[serde(skip_serializing_if = "Option::is_none")]
    multistart: Option<crate::explore::MultiStartOutcome>,
    #[serde(skip_serializing_if = "Option::is_none")]
    profiles: Option<Vec<crate::explore::ProfileJson>>,
    /// A joint fit's tests, each with its weight, share of J and fit quality.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    tests: Vec<TestJson>,
    /// The closed-form start (`--start closed-form`): the values it set, or why none.
    #[serde(skip_serializing_if = "Option::is_none")]
    start: Option<crate::closed_form_start::ClosedFormStart>,
    /// The Oliver-Pharr numbers of the same test beside the FE result.
    #[serde(skip_serializing_if = "Option::is_none")]
    oliver_pharr: Option<crate::op_beside::OpBeside>,
    history: String,
    fit: String,
}

/// One test of a joint fit in result.json.
#[derive(Debug, Serialize)]
struct TestJson {
    name: String,
    data: String,
    weight: f64,
    default_weight: bool,
    #[serde(rename = "wJ")]
    cost: f64,
    n: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    fit_quality: Option<FitJson>,
    /// Its Oliver-Pharr numbers beside the shared fitted `E`.
    #[serde(skip_serializing_if = "Option::is_none")]
    oliver_pharr: Option<crate::op_beside::OpBeside>,
}

/// The discretization error in result.json.
#[derive(Debug, Serialize)]
struct DiscretizationJson {
    #[serde(flatten)]
    run: RefinedJson,
    /// Per free parameter: `c_refined - c_fit` predicted (null: undetermined).
    shift: Named<Option<f64>>,
    relative_shift: Named<Option<f64>>,
    std_dev: Named<Option<f64>>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    undetermined: Vec<&'static str>,
    seconds: f64,
    /// A joint fit's tests: each one's refined discretization and force change.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    tests: Vec<TestDiscretizationJson>,
}

/// One test's refined discretization in result.json (joint fits).
#[derive(Debug, Serialize)]
struct TestDiscretizationJson {
    name: String,
    #[serde(flatten)]
    run: RefinedJson,
}

/// A refined run against the fit's in result.json: the discretizations (fit, refined) and
/// the force change between them.
#[derive(Debug, Serialize)]
struct RefinedJson {
    mesh: String,
    steps: String,
    elements: [usize; 2],
    n_steps: [usize; 2],
    rms: f64,
    rms_rel: f64,
    max_abs: f64,
}

/// [`RefinedJson`] of anything with the seven fields (the whole fit's discretization error
/// and each test's).
macro_rules! refined_json {
    ($d:expr) => {
        RefinedJson {
            mesh: $d.mesh.clone(),
            steps: $d.steps.clone(),
            elements: [$d.elements.0, $d.elements.1],
            n_steps: [$d.n_steps.0, $d.n_steps.1],
            rms: $d.rms,
            rms_rel: $d.rms_rel,
            max_abs: $d.max_abs,
        }
    };
}

impl DiscretizationJson {
    fn new(o: &IdentifyOutcome, d: &Discretization) -> DiscretizationJson {
        let free: Vec<(usize, &'static str)> = o
            .result
            .params
            .iter()
            .enumerate()
            .filter(|(_, p)| p.free)
            .map(|(k, p)| (k, p.name))
            .collect();
        let named = |v: &[Option<f64>]| Named::new(free.iter().map(|&(k, n)| (n, v[k])));
        DiscretizationJson {
            run: refined_json!(d),
            shift: named(&d.shift),
            relative_shift: named(&d.relative_shift),
            std_dev: Named::new(free.iter().map(|&(_, n)| (n, o.std_dev(n)))),
            undetermined: d.undetermined.clone(),
            seconds: d.seconds,
            tests: if d.tests.len() > 1 {
                d.tests
                    .iter()
                    .map(|t| TestDiscretizationJson {
                        name: t.name.clone(),
                        run: refined_json!(t),
                    })
                    .collect()
            } else {
                Vec::new()
            },
        }
    }
}

/// The quality of the final fit in result.json.
#[derive(Debug, Serialize)]
struct FitJson {
    r2: f64,
    rms: f64,
    rms_rel: f64,
    max_abs: f64,
    n: usize,
}

fn fit_json(q: &indentify_report::FitQuality) -> FitJson {
    FitJson {
        r2: q.r2,
        rms: q.rms,
        rms_rel: q.rms_rel,
        max_abs: q.max_abs,
        n: q.n,
    }
}

/// Noise of synthesized data.
#[derive(Debug, Serialize)]
struct NoiseJson {
    amplitude: f64,
    seed: u64,
}

fn result_json(o: &IdentifyOutcome, opts: &IdentifyOptions, paths: &Paths) -> ResultJson {
    let r = &o.result;
    let parameters = r
        .params
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let truth = o.truth.as_ref().map(|t| t[k]);
            ParamJson {
                name: p.name,
                unit: p.unit,
                free: p.free,
                start: p.start,
                value: p.value,
                lower: p.lower,
                upper: p.upper,
                bound_hit: if p.at_lower {
                    Some("lower")
                } else if p.at_upper {
                    Some("upper")
                } else {
                    None
                },
                truth,
                rel_error: truth.filter(|_| p.free).map(|t| ((p.value - t) / t).abs()),
            }
        })
        .collect();
    ResultJson {
        law: r.law,
        config: o.config.clone(),
        data: o.data.clone(),
        noise: opts
            .noise
            .filter(|_| o.truth.is_some())
            .map(|(amplitude, seed)| NoiseJson { amplitude, seed }),
        method: r.method.name(),
        observable: o.fit.observable,
        parameters,
        j: r.cost,
        j_start: r.initial_cost,
        j_ref: r.reference_cost,
        iterations: r.iterations,
        forward_solves: r.forward_solves,
        adjoint_solves: r.adjoint_solves,
        sensitivity_solves: r.sensitivity_solves,
        stop_reason: r.stop_reason.to_string(),
        converged: r.stop_reason.is_converged(),
        undetermined: r
            .identifiability
            .as_ref()
            .map_or_else(Vec::new, |i| i.undetermined.clone()),
        seconds: r.seconds,
        resumed: o.resumed,
        warnings: o.warnings.clone(),
        fit_quality: o.quality.as_ref().map(fit_json),
        adequacy: o.adequacy(),
        caveats: o.caveats(),
        identifiability: r
            .identifiability
            .as_ref()
            .map(|i| IdentifiabilityJson::of(i, o.fit.observable)),
        discretization: o
            .discretization
            .as_ref()
            .map(|d| DiscretizationJson::new(o, d)),
        multistart: o.multistart.clone(),
        profiles: o
            .profiles
            .as_ref()
            .map(|p| p.iter().map(crate::explore::ProfileJson::from).collect()),
        tests: o
            .tests
            .iter()
            .map(|t| TestJson {
                name: t.name.clone(),
                data: t.data.clone(),
                weight: t.weight,
                default_weight: t.default_weight,
                cost: t.cost,
                n: t.fit.t.len(),
                fit_quality: t.quality.as_ref().map(fit_json),
                oliver_pharr: t.oliver_pharr.clone(),
            })
            .collect(),
        oliver_pharr: o.oliver_pharr.clone(),
        start: o.start.clone(),
        history: paths.history.display().to_string(),
        fit: paths.fit.display().to_string(),
    }
}
