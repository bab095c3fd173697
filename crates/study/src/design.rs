//! `indentify design`: ranks candidate test protocols before going to the instrument, by
//! the standard deviations they would give at nominal parameters.
//!
//! A configuration's `design: (noise: Relative(0.01), candidates: [(name: "...", tests:
//! [...]), ...])` section lists candidates; each is one test or a set of tests fitted
//! jointly (the `tests` entries of a joint fit: history, punch, specimen, contact, weight;
//! what a test omits is the top level's). For each candidate, at the `law` values (the
//! nominal parameters) and for the free parameters of the `identify` section (their
//! scalings):
//!
//! 1. the forces `F_i` and the forward sensitivities `dF_i/dc` of every test
//!    (`indentify_identify::Evaluator::jacobian`, the tests in parallel);
//! 2. the covariance of the least-squares fit the configuration would make (the joint
//!    fit's weights) under the stated noise: `Relative(f)`, standard deviation `f |F_i|`
//!    (multiplicative noise), or `Absolute(s)`, `s` N; the sandwich covariance of
//!    `indentify_identify::identifiability` (the same as an identification with
//!    `identify.noise` set to that model, at that point);
//! 3. the criteria: **D-optimal**, `ln det` of the information matrix (the inverse
//!    covariance) of the scaled variables (`ln c` for log-scaled parameters), larger is
//!    better, `-inf` when a parameter is undetermined; **worst parameter**, the largest
//!    relative standard deviation, smaller is better; and the undetermined parameters
//!    (the identifiability rules: no effect, a numerically null direction, a deviation
//!    as large as the value or a 2-sigma interval as wide as the bounds).
//!
//! A candidate's tests may be load-controlled (a `history` with `force` segments, e.g. a
//! ramp to a hold load, the hold, an unload; docs/theory.md §13): the prescribed force
//! drives the run and the depth is the observable, with the stated `depth_noise`
//! (`Relative(f)`: `f h_i`; `Absolute(s)`: `s` mm; default: a `Relative` `noise`). Depth-
//! and load-controlled tests may be mixed within a candidate and across candidates: the
//! covariance takes every row's own stated deviation (force rows `noise`, depth rows
//! `depth_noise`), `Var = w_i s_i^2`.
//!
//! The candidates are evaluated in parallel (rayon; `jobs` threads), each with its own
//! solvers; a forward run does not depend on what ran before it, and the results are
//! gathered in the candidates' order, so the table is bit-identical for any thread count.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::anyhow;
use indentify_identify::identifiability::{Column, Forces};
use indentify_identify::{Cancel, Evaluator, Identifiability, NoiseModel, Parameterization};
use rayon::prelude::*;
use serde::Serialize;

pub use crate::config::{Candidate, DesignSection};
use crate::config::{Config, Drive, Overrides, TestSpec};
use crate::error::{Classify, Error, ErrorKind, Result};
use crate::format::sig;
use crate::identify::{IdentifyOptions, resolve, set_up_tests};
use crate::source::ConfigSource;

/// What to design.
#[derive(Clone, Debug)]
pub struct DesignOptions {
    /// The configuration (with a `design` section).
    pub config: ConfigSource,
    /// `dotted.path=value` overrides.
    pub sets: Vec<String>,
    /// `--free` / `--fixed`: which parameters count.
    pub overrides: Overrides,
    /// Output folder (design.json, design.md); `None` writes nothing.
    pub out: Option<PathBuf>,
    /// Threads (`None`: rayon's current pool, all cores by default).
    pub jobs: Option<usize>,
}

impl DesignOptions {
    /// The design of `config`, no output folder, all cores.
    pub fn new(config: ConfigSource) -> DesignOptions {
        DesignOptions {
            config,
            sets: Vec::new(),
            overrides: Overrides::default(),
            out: None,
            jobs: None,
        }
    }
}

/// One free parameter of a candidate.
#[derive(Clone, Debug, Serialize)]
pub struct ParamSigma {
    /// Name.
    pub name: &'static str,
    /// Nominal value.
    pub value: f64,
    /// Standard deviation (parameter units; infinite if undetermined).
    pub std_dev: f64,
    /// Relative standard deviation.
    pub rel_std_dev: f64,
}

/// The evaluation of one candidate.
#[derive(Clone, Debug, Serialize)]
pub struct CandidateResult {
    /// Its name.
    pub name: String,
    /// Its tests' names.
    pub tests: Vec<String>,
    /// Which of its tests are load-controlled (their observable the depth).
    pub load_controlled: Vec<bool>,
    /// Data points (schedule times with a non-zero weight, all tests).
    pub n_data: usize,
    /// The free parameters' deviations.
    pub params: Vec<ParamSigma>,
    /// `ln det` of the information matrix of the scaled variables (`-inf`: singular or a
    /// parameter undetermined).
    pub log_det: f64,
    /// The parameter with the largest relative deviation and that deviation (infinite
    /// when undetermined).
    pub worst: (&'static str, f64),
    /// Undetermined parameters, with the reasons.
    pub undetermined: Vec<(&'static str, String)>,
    /// Condition number of the Fisher matrix `S^T S` of the weighted scaled sensitivities.
    pub condition_number: f64,
    /// Its weakest direction in words.
    pub weakest_direction: Option<String>,
    /// Correlations (free parameters x free parameters; NaN for undetermined ones).
    pub correlation: Vec<Vec<f64>>,
}

/// The ranked table.
#[derive(Clone, Debug, Serialize)]
pub struct Design {
    /// Configuration name.
    pub config: String,
    /// The noise model in words (of the force, the observable of depth-controlled tests).
    pub noise: String,
    /// The noise of the depth in words, when a candidate has a load-controlled test.
    pub depth_noise: Option<String>,
    /// Free parameter names.
    pub names: Vec<&'static str>,
    /// The nominal parameters (law order) and their names.
    pub nominal: Vec<(&'static str, f64)>,
    /// The candidates, in the configuration's order.
    pub candidates: Vec<CandidateResult>,
    /// Candidate indices by decreasing `ln det` (D-optimal; ties by index).
    pub rank_d: Vec<usize>,
    /// Candidate indices by increasing worst relative deviation (ties by index).
    pub rank_worst: Vec<usize>,
    /// Threads used.
    pub threads: usize,
    /// Wall time (s).
    pub seconds: f64,
    /// Files written.
    pub files: Vec<PathBuf>,
}

/// Evaluates and ranks the candidates of `opts` (and writes design.json and design.md
/// with an output folder).
///
/// # Errors
/// [`ErrorKind::Config`] for a configuration without `design`, a bad section (no
/// candidate, a noise level <= 0 or not stated, an empty candidate) or bad tests;
/// [`ErrorKind::Solver`] when a candidate's forward or sensitivity solve fails;
/// [`ErrorKind::Io`] for an unwritable folder.
pub fn run(opts: &DesignOptions) -> Result<Design> {
    run_cancellable(opts, &Cancel::default())
}

/// [`run`] that stops when `cancel` is raised: candidates not yet started are skipped (the
/// ones in progress finish their forward and sensitivity solves) and the design ends with
/// an error saying it was interrupted; nothing is written.
///
/// # Errors
/// Those of [`run`]; [`ErrorKind::Solver`] (`interrupted: ...`) after a stop request.
pub fn run_cancellable(opts: &DesignOptions, cancel: &Cancel) -> Result<Design> {
    match opts.jobs {
        Some(0) => Err(Error::msg(
            ErrorKind::Config,
            "--jobs 0 is not allowed: expected a number of threads >= 1",
        )),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| Error::new(ErrorKind::Io, anyhow!("cannot start threads: {e}")))?
            .install(|| run_here(opts, cancel)),
        None => run_here(opts, cancel),
    }
}

fn run_here(opts: &DesignOptions, cancel: &Cancel) -> Result<Design> {
    let wall = Instant::now();
    let mut id_opts = IdentifyOptions::new(opts.config.clone());
    id_opts.sets = opts.sets.clone();
    id_opts.overrides = opts.overrides.clone();
    id_opts.refine = false;
    id_opts.figures = false;
    let resolved = resolve(&id_opts)?;
    let name = resolved.name.clone();
    let section = resolved.cfg.design.clone().ok_or_else(|| {
        Error::msg(
            ErrorKind::Config,
            format!(
                "`{name}` has no `design` section: expected design: (noise: Relative(0.01), \
                 candidates: [(name: \"...\", tests: [(history: (segments: [...]))]), ...]) \
                 (docs/design.md)"
            ),
        )
    })?;
    section.validate().kind(ErrorKind::Config)?;
    let noise = section.noise.model();
    let depth_noise = depth_noise_of(&section)?;
    if let Some(out) = &opts.out {
        crate::atomic::ensure_writable_dir(out).kind(ErrorKind::Io)?;
    }
    let param = Parameterization::new(&*resolved.law, &resolved.id_cfg.params)
        .map_err(|e| Error::new(ErrorKind::Config, anyhow!(e)))?;
    let nominal = resolved.law_values.clone();
    // every candidate's configuration, checked before any solve
    let configs: Vec<Config> = section
        .candidates
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let cfg = Config {
                history: None,
                data: None,
                tests: Some(c.tests.clone()),
                design: None,
                ..resolved.cfg.clone()
            };
            cfg.validate()
                .map_err(|e| e.context(format!("in design.candidates[{k}] (`{}`)", c.name)))
                .kind(ErrorKind::Config)?;
            Ok(cfg)
        })
        .collect::<Result<_>>()?;
    let law = &resolved.law;
    let names: Vec<&'static str> = param.free.iter().map(|f| f.name).collect();
    let candidates: Vec<CandidateResult> = section
        .candidates
        .par_iter()
        .zip(configs.par_iter())
        .map(|(cand, cfg)| {
            if cancel.is_raised() {
                return Err(Error::msg(
                    ErrorKind::Solver,
                    format!(
                        "interrupted: the design of `{name}` was stopped before candidate `{}` \
                         (nothing written)",
                        cand.name
                    ),
                ));
            }
            evaluate(
                cand,
                cfg,
                &id_opts,
                &name,
                (law, &nominal, &param),
                (noise, depth_noise.unwrap_or(noise)),
            )
        })
        .collect::<Vec<Result<CandidateResult>>>()
        .into_iter()
        .collect::<Result<_>>()?;
    let mut rank_d: Vec<usize> = (0..candidates.len()).collect();
    rank_d.sort_by(|&a, &b| {
        let (x, y) = (candidates[a].log_det, candidates[b].log_det);
        y.total_cmp(&x).then(a.cmp(&b))
    });
    let mut rank_worst: Vec<usize> = (0..candidates.len()).collect();
    rank_worst.sort_by(|&a, &b| {
        let (x, y) = (candidates[a].worst.1, candidates[b].worst.1);
        x.total_cmp(&y).then(a.cmp(&b))
    });
    let infos = law.params();
    let mut design = Design {
        config: name,
        noise: noise.describe(f64::NAN),
        depth_noise: depth_noise.map(|d| d.describe_observed(f64::NAN, "h", "mm")),
        names,
        nominal: infos.iter().map(|i| i.name).zip(nominal).collect(),
        candidates,
        rank_d,
        rank_worst,
        threads: rayon::current_num_threads(),
        seconds: wall.elapsed().as_secs_f64(),
        files: Vec::new(),
    };
    if let Some(out) = &opts.out {
        design.files = write(out, &design)?;
    }
    Ok(design)
}

/// Whether a test of a candidate is load-controlled: a history with a `force` segment, or
/// a record that prescribes the force (`data.drive: Force`).
fn is_load_controlled(t: &TestSpec) -> bool {
    t.history
        .iter()
        .flat_map(|h| &h.segments)
        .any(|s| s.force.is_some())
        || t.data.as_ref().is_some_and(|d| d.drive == Drive::Force)
}

/// The noise of the depth (the observable of load-controlled tests): `design.depth_noise`,
/// or a `Relative` `design.noise`; `None` without load-controlled tests.
///
/// # Errors
/// [`ErrorKind::Config`] for a load-controlled test under an `Absolute` `noise` (N) and no
/// `depth_noise`, naming the candidate and the field.
fn depth_noise_of(section: &DesignSection) -> Result<Option<NoiseModel>> {
    let load = section.candidates.iter().enumerate().find_map(|(k, c)| {
        c.tests
            .iter()
            .position(is_load_controlled)
            .map(|j| (k, j, &c.name))
    });
    let Some((k, j, cand)) = load else {
        return Ok(None);
    };
    match (section.depth_noise, section.noise.model()) {
        (Some(d), _) => Ok(Some(d.model())),
        (None, NoiseModel::Relative(f)) => Ok(Some(NoiseModel::Relative(f))),
        (None, n) => Err(Error::msg(
            ErrorKind::Config,
            format!(
                "design.depth_noise is missing: design.candidates[{k}].tests[{j}] (`{cand}`) is \
                 load-controlled (its depth is the observable) and design.noise = {n:?} is a \
                 force in N; state the depth's noise, e.g. depth_noise: Absolute(1e-5) (mm) or \
                 Relative(0.01)"
            ),
        )),
    }
}

/// The stated standard deviation of every row (the tests' observables end to end): the
/// force noise on the rows of depth-controlled tests, the depth noise on those of
/// load-controlled tests; `Relative(f)` gives `f |y_i|`, `Absolute(s)` gives `s`.
fn row_deviations(
    problem: &indentify_identify::Problem,
    observed: &[f64],
    (force, depth): (NoiseModel, NoiseModel),
) -> Vec<f64> {
    let mut sd = vec![f64::NAN; observed.len()];
    for (k, t) in problem.tests.iter().enumerate() {
        let model = if t.load.is_some() { depth } else { force };
        for i in problem.rows_of(k) {
            sd[i] = match model {
                NoiseModel::Relative(f) => f * observed[i].abs(),
                NoiseModel::Absolute(s) => s,
                NoiseModel::Residual | NoiseModel::RelativeEstimated => f64::NAN,
            };
        }
    }
    sd
}

/// One candidate: its joint problem at the nominal parameters (exact synthesized data),
/// observables and sensitivities, the covariance under the stated noise of the force
/// (depth-controlled tests) and of the depth (load-controlled tests).
fn evaluate(
    cand: &Candidate,
    cfg: &Config,
    id_opts: &IdentifyOptions,
    name: &str,
    (law, nominal, param): (
        &std::sync::Arc<dyn indentify_laws::Material>,
        &[f64],
        &Parameterization,
    ),
    noise: (NoiseModel, NoiseModel),
) -> Result<CandidateResult> {
    let label = format!("{name} [{}]", cand.name);
    let (problem, tests, _warnings) = set_up_tests(cfg, &label, law, nominal, id_opts)
        .map_err(|e| e.context(format!("candidate `{}`", cand.name)))?;
    let solver_err = |e: indentify_identify::IdentifyError| {
        Error::new(
            ErrorKind::Solver,
            anyhow!(e).context(format!("candidate `{}`", cand.name)),
        )
    };
    let mut ev = Evaluator::new(&problem).map_err(solver_err)?;
    let forces = ev.forces(nominal).map_err(solver_err)?;
    let jac = ev.jacobian(nominal).map_err(solver_err)?;
    let columns: Vec<Column> = param
        .free
        .iter()
        .map(|f| Column::of(f, nominal[f.index]))
        .collect();
    // every row's own stated deviation s_i: `Relative(1)` on `s_i` in place of the fitted
    // observable is the row variance `w_i s_i^2` (the sandwich of `Identifiability`)
    let sd = row_deviations(&problem, &forces, noise);
    let id = Identifiability::with_noise_observed(
        &jac,
        &problem.weights,
        problem.cost_of(&forces),
        nominal,
        &columns,
        NoiseModel::Relative(1.0),
        Some(Forces {
            fitted: &sd,
            measured: &problem.target,
        }),
        problem.observed(),
    );
    let params: Vec<ParamSigma> = id
        .names
        .iter()
        .enumerate()
        .map(|(k, &n)| ParamSigma {
            name: n,
            value: id.values[k],
            std_dev: id.std_dev[k],
            rel_std_dev: id.rel_std_dev[k],
        })
        .collect();
    let worst = params
        .iter()
        .map(|p| {
            (
                p.name,
                if p.rel_std_dev.is_finite() {
                    p.rel_std_dev
                } else {
                    f64::INFINITY
                },
            )
        })
        .fold(
            ("", f64::NEG_INFINITY),
            |a, b| if b.1 > a.1 { b } else { a },
        );
    Ok(CandidateResult {
        name: cand.name.clone(),
        tests: tests.iter().map(|t| t.label.clone()).collect(),
        load_controlled: problem.tests.iter().map(|t| t.load.is_some()).collect(),
        n_data: id.n_data,
        log_det: id.log_det_information(),
        worst,
        undetermined: id
            .undetermined
            .iter()
            .copied()
            .zip(id.reasons.iter().cloned())
            .collect(),
        condition_number: id.condition_number,
        weakest_direction: id.weakest_direction(),
        correlation: id.correlation.clone(),
        params,
    })
}

impl Design {
    /// The table (Markdown): one row per candidate in D-optimal order.
    pub fn table(&self) -> String {
        let mut s = format!(
            "| rank (D) | rank (worst) | candidate | tests | ln det I | worst (rel. σ) | {} | \
             undetermined |\n|---|---|---|---|---|---|{}---|\n",
            self.names
                .iter()
                .map(|n| format!("σ({n})/{n}"))
                .collect::<Vec<_>>()
                .join(" | "),
            "---|".repeat(self.names.len())
        );
        for (r, &k) in self.rank_d.iter().enumerate() {
            let c = &self.candidates[k];
            let rw = self.rank_worst.iter().position(|&j| j == k).unwrap_or(0);
            let sd: Vec<String> = c
                .params
                .iter()
                .map(|p| {
                    if p.rel_std_dev.is_finite() {
                        percent(p.rel_std_dev)
                    } else {
                        "undetermined".into()
                    }
                })
                .collect();
            let und: Vec<&str> = c.undetermined.iter().map(|u| u.0).collect();
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} {} | {} | {} |\n",
                r + 1,
                rw + 1,
                c.name,
                c.tests.len(),
                if c.log_det.is_finite() {
                    format!("{:.2}", c.log_det)
                } else {
                    "-inf".into()
                },
                c.worst.0,
                if c.worst.1.is_finite() {
                    percent(c.worst.1)
                } else {
                    "undetermined".into()
                },
                sd.join(" | "),
                if und.is_empty() {
                    "none".into()
                } else {
                    und.join(", ")
                }
            ));
        }
        s
    }

    /// The noise in words: of the force, and of the depth when a candidate has a
    /// load-controlled test.
    fn noise_text(&self) -> String {
        match &self.depth_noise {
            None => self.noise.clone(),
            Some(d) => format!(
                "{} on the force (depth-controlled tests), {d} on the depth (load-controlled \
                 tests)",
                self.noise
            ),
        }
    }

    /// The console summary: the setting, the table, the best candidates.
    pub fn summary(&self) -> String {
        let nominal: Vec<String> = self
            .nominal
            .iter()
            .map(|(n, v)| format!("{n} = {}", sig(*v, 6)))
            .collect();
        let mut s = format!(
            "test design of `{}`: {} candidates at {} ({} free: {}); noise: {}; {} threads, \
             {:.1} s\n\n",
            self.config,
            self.candidates.len(),
            nominal.join(", "),
            self.names.len(),
            self.names.join(", "),
            self.noise_text(),
            self.threads,
            self.seconds
        );
        s.push_str(&self.table());
        let best = |k: usize| &self.candidates[k];
        if let Some(&k) = self.rank_d.first() {
            s.push_str(&format!(
                "\nD-optimal (largest ln det of the information): `{}`",
                best(k).name
            ));
        }
        if let Some(&k) = self.rank_worst.first() {
            s.push_str(&format!(
                "; best worst-parameter deviation: `{}` ({} {})",
                best(k).name,
                best(k).worst.0,
                if best(k).worst.1.is_finite() {
                    percent(best(k).worst.1)
                } else {
                    "undetermined".into()
                }
            ));
        }
        let none: Vec<&str> = self
            .candidates
            .iter()
            .filter(|c| c.undetermined.is_empty())
            .map(|c| c.name.as_str())
            .collect();
        s.push_str(&format!(
            "\ndetermine every free parameter: {}\n",
            if none.is_empty() {
                "none of the candidates".to_string()
            } else {
                none.join(", ")
            }
        ));
        if !self.files.is_empty() {
            let f: Vec<String> = self.files.iter().map(|p| p.display().to_string()).collect();
            s.push_str(&format!("written: {}\n", f.join(", ")));
        }
        s
    }

    /// design.md: the summary and, per candidate, the undetermined parameters' reasons and
    /// the weakest direction.
    pub fn markdown(&self) -> String {
        let mut s = format!("# Test design: `{}`\n\n", self.config);
        s.push_str(&format!(
            "Standard deviations at the nominal parameters ({}) of the least-squares fit of each \
             candidate's tests (their joint-fit weights), noise: {}. ln det I: the \
             information matrix (inverse covariance) of the scaled variables (ln c for \
             log-scaled parameters); larger is better (D-optimal). Worst: the largest relative \
             standard deviation; smaller is better.\n\n",
            self.nominal
                .iter()
                .map(|(n, v)| format!("{n} = {}", sig(*v, 6)))
                .collect::<Vec<_>>()
                .join(", "),
            self.noise_text()
        ));
        s.push_str(&self.table());
        s.push_str("\n## Candidates\n\n");
        for c in &self.candidates {
            s.push_str(&format!(
                "- **{}** ({} tests: {}; {} data points): condition number of S^T S {}",
                c.name,
                c.tests.len(),
                c.tests
                    .iter()
                    .zip(&c.load_controlled)
                    .map(|(t, &l)| if l {
                        format!("{t} (load control: the depth observed)")
                    } else {
                        t.clone()
                    })
                    .collect::<Vec<_>>()
                    .join(", "),
                c.n_data,
                indentify_identify::identifiability::condition_text(c.condition_number)
            ));
            if let Some(w) = &c.weakest_direction {
                s.push_str(&format!("; weakest direction: {w}"));
            }
            for (n, why) in &c.undetermined {
                s.push_str(&format!("; {n} undetermined: {why}"));
            }
            s.push('\n');
        }
        s
    }
}

/// A relative deviation as a percentage with 3 significant digits.
fn percent(v: f64) -> String {
    format!("{}%", sig(100.0 * v, 3))
}

fn write(out: &Path, design: &Design) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let json = serde_json::to_string_pretty(&JsonDesign(design))
        .map_err(|e| Error::new(ErrorKind::Io, anyhow!(e)))?;
    for (file, text) in [
        ("design.json", json + "\n"),
        ("design.md", design.markdown()),
    ] {
        let path = out.join(file);
        crate::atomic::write(&path, text).kind(ErrorKind::Io)?;
        files.push(path);
    }
    Ok(files)
}

/// design.json: the [`Design`] with non-finite numbers as `null` (serde_json's own rule)
/// and `-inf` log-determinants written as the text `"-inf"`.
struct JsonDesign<'a>(&'a Design);

impl Serialize for JsonDesign<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut v = serde_json::to_value(self.0).map_err(serde::ser::Error::custom)?;
        if let Some(cands) = v.get_mut("candidates").and_then(|c| c.as_array_mut()) {
            for (c, r) in cands.iter_mut().zip(&self.0.candidates) {
                if !r.log_det.is_finite() {
                    c["log_det"] = serde_json::Value::String(format!("{}", r.log_det));
                }
            }
        }
        v.serialize(s)
    }
}
