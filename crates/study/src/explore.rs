//! Exploring the cost around a fit: parallel multi-start (`indentify identify --starts N`)
//! and profile-likelihood intervals (`--profiles`), their console tables, Markdown
//! sections, JSON fields and profile figures. The numerics are `indentify_identify`'s
//! ([`indentify_identify::multistart`](mod@indentify_identify::multistart), [`indentify_identify::profile`](mod@indentify_identify::profile)); this module runs
//! them in parallel on rayon's current pool and formats the results.
//!
//! Determinism: every run and every profile chain is computed by its own evaluator from
//! its own start, and the results are gathered in a fixed order (start index; parameter,
//! then side), so the outcome is bit-identical for any number of threads.

use indentify_identify::multistart::{self as ms, Clusters};
use indentify_identify::profile::{
    CHI2_1_95, Limit, Profile, ProfilePoint, ProfileSettings, SideEnd, profile_side,
};
use indentify_identify::{IdentifyConfig, IdentifyResult, Parameterization, Problem};
use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, ErrorKind, Result};
use crate::format::{sig, table};

/// `--starts N --seed S`: how many starts, from which seed, clustered how finely.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StartsOptions {
    /// Number of starts, in `[1, 10000]`.
    pub n: usize,
    /// Seed of the Latin hypercube (SplitMix64).
    pub seed: u64,
    /// Clustering tolerance in the scaled variables (infinity norm).
    pub tol: f64,
}

impl StartsOptions {
    /// Checks the ranges (before any solve).
    ///
    /// # Errors
    /// [`ErrorKind::Config`] naming `--starts` and its range, or the tolerance.
    pub fn check(&self) -> Result<()> {
        if !(1..=ms::MAX_STARTS).contains(&self.n) {
            return Err(Error::msg(
                ErrorKind::Config,
                format!(
                    "--starts {} is not allowed: expected a number of starts in [1, {}]",
                    self.n,
                    ms::MAX_STARTS
                ),
            ));
        }
        if !(self.tol > 0.0 && self.tol.is_finite()) {
            return Err(Error::msg(
                ErrorKind::Config,
                format!(
                    "the clustering tolerance {} is not allowed: expected a finite value > 0",
                    self.tol
                ),
            ));
        }
        Ok(())
    }

    /// `n` starts from `seed`, the default tolerance.
    pub fn new(n: usize, seed: u64) -> StartsOptions {
        StartsOptions {
            n,
            seed,
            tol: ms::DEFAULT_CLUSTER_TOL,
        }
    }
}

/// One run of a multi-start, summarized.
#[derive(Clone, Debug, Serialize)]
pub struct StartRun {
    /// Start index.
    pub index: usize,
    /// The start (free parameters, law order).
    pub start: Vec<f64>,
    /// The end point (free parameters), if the run did not fail.
    pub end: Option<Vec<f64>>,
    /// Final `J` (N^2); NaN for a failed run.
    #[serde(rename = "J")]
    pub cost: f64,
    /// Iterations.
    pub iterations: usize,
    /// Why it stopped, or the error.
    pub stop_reason: String,
    /// Whether it met a convergence criterion.
    pub converged: bool,
    /// The minimum (index into [`MultiStartOutcome::minima`]) it reached.
    pub minimum: Option<usize>,
}

/// A distinct minimum found by a multi-start.
#[derive(Clone, Debug, Serialize)]
pub struct MinimumJson {
    /// Free parameter values at its best point.
    pub values: Vec<f64>,
    /// `J` there (N^2).
    #[serde(rename = "J")]
    pub cost: f64,
    /// `J / J_best`.
    pub cost_ratio: f64,
    /// Starts that reached it.
    pub starts: Vec<usize>,
    /// How many of those converged.
    pub converged: usize,
    /// The start with the lowest cost.
    pub best_start: usize,
    /// Free parameters on a bound there.
    pub at_bound: Vec<&'static str>,
}

/// The outcome of `--starts N`.
#[derive(Clone, Debug, Serialize)]
pub struct MultiStartOutcome {
    /// Number of starts.
    pub n: usize,
    /// Seed.
    pub seed: u64,
    /// How the starts were drawn.
    pub sampling: &'static str,
    /// Clustering tolerance (scaled variables, infinity norm).
    pub tol: f64,
    /// Free parameter names.
    pub names: Vec<&'static str>,
    /// Their units.
    pub units: Vec<&'static str>,
    /// Minima, lowest cost first (the first is the reported fit).
    pub minima: Vec<MinimumJson>,
    /// Every run, in start order.
    pub runs: Vec<StartRun>,
    /// Wall time (s).
    pub seconds: f64,
}

/// Runs `n` Latin-hypercube starts of `config` in parallel (one identification per start,
/// each on one thread), clusters the end points and returns the summary and the best
/// run's full result.
///
/// # Errors
/// [`ErrorKind::Config`] for `n` outside `[1, 10000]`, a non-positive tolerance or
/// non-finite scaled bounds; [`ErrorKind::Solver`] when every run fails.
pub fn multistart(
    problem: &Problem,
    config: &IdentifyConfig,
    opts: &StartsOptions,
) -> Result<(MultiStartOutcome, IdentifyResult)> {
    let wall = std::time::Instant::now();
    let param = Parameterization::new(&*problem.law, &config.params)
        .map_err(|e| Error::new(ErrorKind::Config, anyhow::anyhow!(e)))?;
    opts.check()?;
    let starts = ms::latin_hypercube(&param, opts.n, opts.seed)
        .map_err(|e| Error::new(ErrorKind::Config, anyhow::anyhow!("--starts: {e}")))?;
    // each run computes its own identifiability summary when asked (one sensitivity
    // solve): the best one's is reported
    let cfg = config.clone();
    let n = starts.len();
    let runs: Vec<_> = starts
        .par_iter()
        .enumerate()
        .with_max_len(1)
        .map(|(i, s)| {
            let r = ms::run_start(problem, &cfg, s);
            match &r {
                Ok(r) => tracing::info!(
                    "  start {}/{n} done: J = {:.6e} N^2 after {} iterations ({})",
                    i + 1,
                    r.cost,
                    r.iterations,
                    r.stop_reason
                ),
                Err(e) => tracing::warn!("  start {}/{n} failed: {e}", i + 1),
            }
            r
        })
        .collect();
    let clusters = ms::cluster(&param, &runs, opts.tol);
    let Some(best) = clusters.minima.first().map(|m| m.best_start) else {
        let why = clusters
            .failed
            .first()
            .map_or(String::new(), |(i, e)| format!(": start {i}: {e}"));
        return Err(Error::msg(
            ErrorKind::Solver,
            format!("every one of the {n} starts failed{why}"),
        ));
    };
    let free_of = |c: &[f64]| -> Vec<f64> { param.free.iter().map(|f| c[f.index]).collect() };
    let summary = MultiStartOutcome {
        n,
        seed: opts.seed,
        sampling: "Latin hypercube in the scaled variables (SplitMix64)",
        tol: opts.tol,
        names: param.free.iter().map(|f| f.name).collect(),
        units: param.free.iter().map(|f| f.unit).collect(),
        minima: minima_json(&clusters, &free_of),
        runs: runs
            .iter()
            .enumerate()
            .map(|(i, r)| StartRun {
                index: i,
                start: starts[i].clone(),
                end: r.as_ref().ok().map(|r| free_of(&r.c)),
                cost: r.as_ref().map_or(f64::NAN, |r| r.cost),
                iterations: r.as_ref().map_or(0, |r| r.iterations),
                stop_reason: match r {
                    Ok(r) => r.stop_reason.to_string(),
                    Err(e) => format!("failed: {e}"),
                },
                converged: r.as_ref().is_ok_and(|r| r.stop_reason.is_converged()),
                minimum: clusters.minima.iter().position(|m| m.starts.contains(&i)),
            })
            .collect(),
        seconds: wall.elapsed().as_secs_f64(),
    };
    let mut runs = runs;
    let best_result = match runs.swap_remove(best) {
        Ok(r) => r,
        Err(e) => return Err(Error::new(ErrorKind::Solver, anyhow::anyhow!(e))),
    };
    Ok((summary, best_result))
}

fn minima_json(c: &Clusters, free_of: &dyn Fn(&[f64]) -> Vec<f64>) -> Vec<MinimumJson> {
    let best = c.minima.first().map_or(f64::NAN, |m| m.cost);
    c.minima
        .iter()
        .map(|m| MinimumJson {
            values: free_of(&m.c),
            cost: m.cost,
            cost_ratio: m.cost / best,
            starts: m.starts.clone(),
            converged: m.converged,
            best_start: m.best_start,
            at_bound: m.at_bound.clone(),
        })
        .collect()
}

impl MultiStartOutcome {
    /// The console table of the minima.
    pub fn table(&self) -> String {
        let mut rows = vec![
            ["minimum", "J (N^2)", "J / J_best", "starts", "converged"]
                .map(String::from)
                .to_vec(),
        ];
        for (n, u) in self.names.iter().zip(&self.units) {
            rows[0].push(format!("{n} ({u})"));
        }
        for (k, m) in self.minima.iter().enumerate() {
            let mut row = vec![
                format!("{}{}", k + 1, if k == 0 { " (best)" } else { "" }),
                format!("{:.4e}", m.cost),
                sig(m.cost_ratio, 4),
                m.starts.len().to_string(),
                m.converged.to_string(),
            ];
            for (name, v) in self.names.iter().zip(&m.values) {
                let b = if m.at_bound.contains(name) {
                    " (bound)"
                } else {
                    ""
                };
                row.push(format!("{}{b}", sig(*v, 6)));
            }
            rows.push(row);
        }
        let failed = self.runs.iter().filter(|r| r.end.is_none()).count();
        format!(
            "multi-start: {} starts ({}, seed {}), {} distinct minima (end points within {} in \
             every scaled variable are one minimum){}; {:.1} s\n{}",
            self.n,
            self.sampling,
            self.seed,
            self.minima.len(),
            self.tol,
            if failed > 0 {
                format!(", {failed} runs failed")
            } else {
                String::new()
            },
            self.seconds,
            table(&rows, "  ")
        )
    }

    /// The Markdown section.
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "## Multi-start\n\n{} starts drawn by {} with seed {}, run in parallel; end points \
             within {} of each other in every scaled variable (ln c for log-scaled parameters) \
             are one minimum. {} distinct minima:\n\n| minimum | J (N²) | J / J_best | starts | \
             converged |",
            self.n,
            self.sampling,
            self.seed,
            self.tol,
            self.minima.len()
        );
        for (n, u) in self.names.iter().zip(&self.units) {
            s.push_str(&format!(" {n} ({u}) |"));
        }
        s.push_str("\n|---|---|---|---|---|");
        s.push_str(&"---|".repeat(self.names.len()));
        s.push('\n');
        for (k, m) in self.minima.iter().enumerate() {
            s.push_str(&format!(
                "| {} | {:.4e} | {} | {} | {} |",
                k + 1,
                m.cost,
                sig(m.cost_ratio, 4),
                m.starts.len(),
                m.converged
            ));
            for (name, v) in self.names.iter().zip(&m.values) {
                let b = if m.at_bound.contains(name) {
                    " (bound)"
                } else {
                    ""
                };
                s.push_str(&format!(" {}{b} |", sig(*v, 6)));
            }
            s.push('\n');
        }
        let failed: Vec<String> = self
            .runs
            .iter()
            .filter(|r| r.end.is_none())
            .map(|r| format!("start {}: {}", r.index, r.stop_reason))
            .collect();
        if !failed.is_empty() {
            s.push_str(&format!("\nFailed runs: {}.\n", failed.join("; ")));
        }
        s
    }
}

/// The profiles of every free parameter at the fit `result` (whose identifiability summary
/// gives `s^2` and the steps): the chains of every parameter and side in parallel.
///
/// # Errors
/// [`ErrorKind::Config`] for bad settings or a result without identifiability summary (or
/// with `n <= p`); [`ErrorKind::Solver`] for a configuration that cannot be resolved.
pub fn profiles(
    problem: &Problem,
    config: &IdentifyConfig,
    result: &IdentifyResult,
    settings: &ProfileSettings,
) -> Result<Vec<Profile>> {
    settings
        .validate()
        .map_err(|e| Error::new(ErrorKind::Config, anyhow::anyhow!(e)))?;
    let id = result.identifiability.as_ref().ok_or_else(|| {
        Error::msg(
            ErrorKind::Config,
            "profiles need the identifiability summary (s^2): set identify.identifiability: true",
        )
    })?;
    if !id.profile_variance.iter().all(|v| v.is_finite()) {
        return Err(Error::msg(
            ErrorKind::Config,
            format!(
                "profiles need more weighted data ({}) than free parameters ({}) to estimate s^2",
                id.n_data,
                id.names.len()
            ),
        ));
    }
    let param = Parameterization::new(&*problem.law, &config.params)
        .map_err(|e| Error::new(ErrorKind::Config, anyhow::anyhow!(e)))?;
    // the threshold chi2_1(0.95) s_k^2 / 2, s_k^2 on the scale of the noise model the
    // deviations use (s^2 = 2 J* / (n - p) under `Residual`)
    let thresholds: Vec<f64> = param
        .free
        .iter()
        .map(|f| {
            let k = id.names.iter().position(|n| *n == f.name);
            let s2 = k.map_or(id.sigma2, |k| id.profile_variance[k]);
            CHI2_1_95 * s2 / 2.0
        })
        .collect();
    let steps: Vec<f64> = param
        .free
        .iter()
        .map(|f| {
            let value = result.c[f.index];
            let sd = id
                .names
                .iter()
                .position(|n| *n == f.name)
                .map_or(f64::INFINITY, |k| id.std_dev[k]);
            settings.step_for(sd / f.dc_dy(value).abs())
        })
        .collect();
    let tasks: Vec<(usize, f64)> = (0..param.free.len())
        .flat_map(|k| [(k, -steps[k]), (k, steps[k])])
        .collect();
    let sides: Vec<Result<(Vec<ProfilePoint>, SideEnd)>> = tasks
        .par_iter()
        .with_max_len(1)
        .map(|&(k, step)| {
            profile_side(
                problem,
                config,
                &result.c,
                result.cost,
                k,
                step,
                settings.points_per_side,
                settings.stop_factor * thresholds[k],
            )
            .map_err(|e| Error::new(ErrorKind::Solver, anyhow::anyhow!(e)))
        })
        .collect();
    let mut sides = sides.into_iter();
    let mut out = Vec::new();
    for (f, &threshold) in param.free.iter().zip(&thresholds) {
        let (Some(below), Some(above)) = (sides.next(), sides.next()) else {
            break;
        };
        let p = Profile::assemble(
            f.name,
            f.unit,
            f.index,
            &result.c,
            f.to_scaled(result.c[f.index]),
            result.cost,
            threshold,
            below?,
            above?,
            |y| f.to_physical(y).clamp(f.lower, f.upper),
        );
        out.push(p);
    }
    Ok(out)
}

fn limit_text(l: &Limit, side: &str) -> String {
    match l {
        Limit::At(v) => sig(*v, 5),
        Limit::Unbounded(v) => format!("unbounded {side} within the bounds ({})", sig(*v, 5)),
        Limit::NotReached(v) => format!("beyond {} (not reached)", sig(*v, 5)),
    }
}

/// The console table of profile intervals.
pub fn profiles_table(profiles: &[Profile]) -> String {
    let mut rows = vec![
        [
            "parameter",
            "unit",
            "value",
            "95% lower",
            "95% upper",
            "points",
            "re-fits not converged",
            "rise allowed (N^2)",
        ]
        .map(String::from)
        .to_vec(),
    ];
    for p in profiles {
        rows.push(vec![
            p.name.to_string(),
            p.unit.to_string(),
            sig(p.optimum, 6),
            limit_text(&p.lower, "below"),
            limit_text(&p.upper, "above"),
            p.points.len().to_string(),
            p.points.iter().filter(|q| !q.converged).count().to_string(),
            format!("{:.4e}", p.threshold),
        ]);
    }
    let mut s = format!(
        "profile likelihood: 95% intervals where 2 (J_profile - J*) / s_k^2 <= {CHI2_1_95:.3}, \
         s_k^2 on the scale of the std. dev.'s noise model (2 J* / (n - p) under the residual \
         model){}\n{}",
        profiles
            .first()
            .map_or(String::new(), |p| format!(" (J* = {:.4e} N^2)", p.cost)),
        table(&rows, "  ")
    );
    for p in profiles {
        if let Some(j) = p.lower_cost_found {
            s.push_str(&format!(
                "  warning: the profile of {} found J = {j:.6e} N^2 < J* = {:.6e} N^2: the fit \
                 is not the minimum (try --starts)\n",
                p.name, p.cost
            ));
        }
        for (end, side) in [(&p.ends.0, "lower"), (&p.ends.1, "upper")] {
            if let SideEnd::Failed(why) = end {
                s.push_str(&format!(
                    "  warning: the {side} side of {}'s profile stopped: {why}\n",
                    p.name
                ));
            }
        }
    }
    s
}

/// The Markdown section of the profiles, linking `figures` (file names per parameter).
pub fn profiles_markdown(profiles: &[Profile], figures: &[String]) -> String {
    let mut s = format!(
        "## Profile likelihood\n\nEach profile point holds one parameter and re-fits the others \
         (started from the neighbouring point's optimum). The 95% interval is where \
         2 (J_profile - J*) / s_k² ≤ χ²₁(0.95) = {CHI2_1_95:.3}, with s_k² on the scale of the \
         standard deviations' noise model (the residual variance 2 J* / (n - p) under the \
         residual model; under a stated model the ratio of the parameter's variance under that \
         model to its unit-variance Gauss-Newton one), so that the interval of a linear model is \
         the value ± 1.96 std. dev.; ends are interpolated linearly between profile points.\n\n\
         | parameter | unit | value | 95% lower | 95% upper | points |\n|---|---|---|---|---|---|\n"
    );
    for p in profiles {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} |\n",
            p.name,
            p.unit,
            sig(p.optimum, 6),
            limit_text(&p.lower, "below"),
            limit_text(&p.upper, "above"),
            p.points.len()
        ));
    }
    if !figures.is_empty() {
        s.push('\n');
        for f in figures {
            s.push_str(&format!("![profile]({f})\n"));
        }
    }
    s
}

/// One profile in result.json.
#[derive(Debug, Serialize)]
pub struct ProfileJson {
    name: &'static str,
    unit: &'static str,
    value: f64,
    #[serde(rename = "J")]
    cost: f64,
    threshold: f64,
    lower: LimitJson,
    upper: LimitJson,
    /// `(value, J, converged)` per point, increasing in value.
    points: Vec<(f64, f64, bool)>,
    #[serde(skip_serializing_if = "Option::is_none")]
    lower_cost_found: Option<f64>,
}

/// One end of an interval in result.json: `kind` is `crossed`, `unbounded` (within the
/// bounds) or `not_reached`.
#[derive(Debug, Serialize)]
struct LimitJson {
    kind: &'static str,
    value: f64,
}

impl From<&Limit> for LimitJson {
    fn from(l: &Limit) -> Self {
        let kind = match l {
            Limit::At(_) => "crossed",
            Limit::Unbounded(_) => "unbounded",
            Limit::NotReached(_) => "not_reached",
        };
        LimitJson {
            kind,
            value: l.value(),
        }
    }
}

impl From<&Profile> for ProfileJson {
    fn from(p: &Profile) -> Self {
        ProfileJson {
            name: p.name,
            unit: p.unit,
            value: p.optimum,
            cost: p.cost,
            threshold: p.threshold,
            lower: (&p.lower).into(),
            upper: (&p.upper).into(),
            points: p
                .points
                .iter()
                .map(|q| (q.value, q.cost, q.converged))
                .collect(),
            lower_cost_found: p.lower_cost_found,
        }
    }
}

/// Draws each profile as `profile_<name>.svg` and `.png` in `dir`: the statistic
/// `2 (J - J*) / s^2` against the value, the chi-square level and the interval's ends.
/// Returns the SVG file names (for the Markdown) and every path written.
///
/// # Errors
/// A figure that cannot be drawn or written.
pub fn write_profile_figures(
    dir: &std::path::Path,
    profiles: &[Profile],
) -> anyhow::Result<(Vec<String>, Vec<std::path::PathBuf>)> {
    use anyhow::Context as _;
    let mut names = Vec::new();
    let mut paths = Vec::new();
    for p in profiles {
        let s2 = 2.0 * p.threshold / CHI2_1_95;
        let fig = indentify_report::ProfileFigure {
            name: p.name.to_string(),
            unit: p.unit.to_string(),
            values: p.points.iter().map(|q| q.value).collect(),
            statistic: p
                .points
                .iter()
                .map(|q| 2.0 * (q.cost - p.cost) / s2)
                .collect(),
            level: CHI2_1_95,
            optimum: p.optimum,
            interval: (p.lower.value(), p.upper.value()),
            log_x: p.optimum > 0.0 && p.points.iter().all(|q| q.value > 0.0),
        };
        let stem = format!("profile_{}", p.name);
        let size = indentify_report::FigureSize::default();
        let svg = fig
            .svg(size)
            .with_context(|| format!("cannot draw {stem}"))?;
        let png = fig
            .png(size)
            .with_context(|| format!("cannot draw {stem}"))?;
        for (ext, bytes) in [("svg", svg.into_bytes()), ("png", png)] {
            let path = dir.join(format!("{stem}.{ext}"));
            crate::atomic::write(&path, bytes)?;
            paths.push(path);
        }
        names.push(format!("{stem}.svg"));
    }
    Ok((names, paths))
}
