//! `indentify map`: the cost `J` over a 2D slice of the parameter space, on a grid in the
//! scaled variables of two free parameters, the others held at the slice's centre (the fit,
//! the `law` values or the start), every grid point one forward solve, the points in
//! parallel; written as CSV, JSON and a contour figure of `log10 J` (SVG and PNG) like the
//! paper's Figs. 4 and 11.
//!
//! Grid: for each of the two parameters, `n` values evenly spaced in its scaled variable
//! (`ln c` for a log-scaled parameter) over `[y0 - span, y0 + span]` clipped to its bounds,
//! `y0` the centre's. The grid points are independent forward solves (a run does not depend
//! on what the solver computed before), so the map is bit-identical for any thread count.

use std::path::{Path, PathBuf};
use std::time::Instant;

use indentify_identify::{Evaluator, Parameterization, identify};
use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Classify, Error, ErrorKind, Result};
use crate::format::sig;
use crate::identify::{IdentifyOptions, Resolved, Setup, resolve, setup};

/// Where the slice passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Through {
    /// The optimum of an identification run first (the configuration's method and start).
    Fit,
    /// The configuration's `law` values (the truth for synthesized data).
    Law,
    /// The identification's start.
    Start,
}

impl Through {
    /// Parses `fit`, `law` or `start`.
    ///
    /// # Errors
    /// Any other text, naming the allowed values.
    pub fn parse(text: &str) -> std::result::Result<Through, String> {
        match text {
            "fit" => Ok(Through::Fit),
            "law" => Ok(Through::Law),
            "start" => Ok(Through::Start),
            _ => Err(format!(
                "`{text}` is not a slice centre: expected fit, law or start"
            )),
        }
    }

    fn describe(self) -> &'static str {
        match self {
            Through::Fit => "the fit",
            Through::Law => "the configuration's law values",
            Through::Start => "the identification's start",
        }
    }
}

/// Largest grid accepted (points per side).
pub const MAX_GRID: usize = 401;

/// What to map.
#[derive(Clone, Debug)]
pub struct MapOptions {
    /// The configuration, data, overrides and noise, as for `identify` (its `out` is not used).
    pub identify: IdentifyOptions,
    /// The two parameters (horizontal, vertical).
    pub pair: Vec<String>,
    /// Points per side, in `[3, MAX_GRID]`.
    pub grid: usize,
    /// Half-width of the grid in the scaled variables: one value for both, or one per
    /// parameter; empty: 0.5 (a factor e^0.5 = 1.65 each way on a log-scaled parameter).
    pub span: Vec<f64>,
    /// The slice's centre.
    pub through: Through,
    /// Output folder (map.csv, map.json, map.svg, map.png).
    pub out: Option<PathBuf>,
    /// Threads for the grid; `None`: rayon's current pool (all cores by default).
    pub jobs: Option<usize>,
}

/// The computed map.
#[derive(Clone, Debug, Serialize)]
pub struct CostMap {
    /// Configuration name.
    pub config: String,
    /// The two parameters.
    pub names: [&'static str; 2],
    /// Their units.
    pub units: [&'static str; 2],
    /// Grid values of the first (horizontal) parameter.
    pub x: Vec<f64>,
    /// Grid values of the second (vertical) parameter.
    pub y: Vec<f64>,
    /// `J` at `(x[i], y[j])` as `cost[j * x.len() + i]` (N^2; NaN where the solve failed).
    #[serde(rename = "J")]
    pub cost: Vec<f64>,
    /// Where the slice passes.
    pub through: Through,
    /// The centre (full law vector).
    pub centre: Vec<f64>,
    /// The centre's values of the two parameters.
    pub centre_pair: [f64; 2],
    /// `J` at the centre (N^2).
    #[serde(rename = "J_centre")]
    pub centre_cost: f64,
    /// The lowest grid point `(x, y, J)`.
    pub grid_min: (f64, f64, f64),
    /// Grid points whose solve failed.
    pub failed: usize,
    /// Threads used.
    pub threads: usize,
    /// Wall time of the grid evaluation (s).
    pub seconds: f64,
    /// Files written.
    pub files: Vec<PathBuf>,
}

/// Computes the map of `opts` (and writes it with an output folder).
///
/// # Errors
/// [`ErrorKind::Config`] for a grid outside `[3, 401]`, a non-positive span, a pair that
/// is not two different free parameters, or a centre outside the bounds; the errors of
/// [`setup`]; [`ErrorKind::Solver`] when the fit or the centre cannot be solved;
/// [`ErrorKind::Io`] for an unwritable folder.
pub fn run(opts: &MapOptions) -> Result<CostMap> {
    match opts.jobs {
        Some(0) => Err(Error::msg(
            ErrorKind::Config,
            "--jobs 0 is not allowed: expected a number of threads >= 1",
        )),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| Error::new(ErrorKind::Io, anyhow::anyhow!("cannot start threads: {e}")))?
            .install(|| run_here(opts)),
        None => run_here(opts),
    }
}

fn run_here(opts: &MapOptions) -> Result<CostMap> {
    let cfg_err = |msg: String| Error::msg(ErrorKind::Config, msg);
    check_grid(opts)?;
    let resolved = resolve(&opts.identify)?;
    let [a, b] = check_pair(opts, &resolved)?;
    if let Some(out) = &opts.out {
        crate::atomic::ensure_writable_dir(out).kind(ErrorKind::Io)?;
    }
    let through = opts.through;
    // a joint configuration's slice is through its joint cost sum_k w_k J_k
    let s = setup(resolved, &opts.identify)?;
    let param = Parameterization::new(&*s.law, &s.id_cfg.params)
        .map_err(|e| Error::new(ErrorKind::Config, anyhow::anyhow!(e)))?;
    let centre = centre(&s, &param, through)?;
    let k_of = |n: &str| param.free.iter().position(|f| f.name == n);
    let (Some(ka), Some(kb)) = (k_of(a), k_of(b)) else {
        return Err(cfg_err(format!("--pair {a},{b}: not free parameters")));
    };
    let axes: Vec<(Vec<f64>, &indentify_identify::params::FreeParam)> = [ka, kb]
        .iter()
        .enumerate()
        .map(|(axis, &k)| {
            let f = &param.free[k];
            let span = opts
                .span
                .get(axis)
                .or(opts.span.first())
                .copied()
                .unwrap_or(0.5);
            let (lo, hi) = f.scaled_bounds();
            let c0 = centre[f.index];
            if !(c0 >= f.lower && c0 <= f.upper) {
                return Err(cfg_err(format!(
                    "the slice's centre {} = {c0} ({}) lies outside its bounds [{}, {}]",
                    f.name,
                    through.describe(),
                    f.lower,
                    f.upper
                )));
            }
            let y0 = f.to_scaled(c0);
            let (y_lo, y_hi) = ((y0 - span).max(lo), (y0 + span).min(hi));
            let n = opts.grid;
            let values = (0..n)
                .map(|i| {
                    let y = y_lo + (y_hi - y_lo) * i as f64 / (n - 1) as f64;
                    if (y - y0).abs() <= 1e-12 * (1.0 + y0.abs()) {
                        // the centre itself, not its round trip through the scaling
                        c0
                    } else {
                        f.to_physical(y).clamp(f.lower, f.upper)
                    }
                })
                .collect();
            Ok((values, f))
        })
        .collect::<Result<_>>()?;
    let (x, fx) = (&axes[0].0, axes[0].1);
    let (y, fy) = (&axes[1].0, axes[1].1);
    let n = opts.grid;
    let problem = &s.problem;
    let cancel = &opts.identify.cancel;
    let interrupted = || {
        Error::msg(
            ErrorKind::Solver,
            format!(
                "interrupted: the map of `{}` was stopped before its grid was complete (nothing \
                 written)",
                s.name
            ),
        )
    };
    if cancel.is_raised() {
        return Err(interrupted());
    }
    let wall = Instant::now();
    let cost: Vec<f64> = (0..n * n)
        .into_par_iter()
        .map_init(
            || Evaluator::new(problem).ok(),
            |ev, p| {
                if cancel.is_raised() {
                    // a stop request: the points not yet started are skipped
                    return f64::NAN;
                }
                let mut c = centre.clone();
                c[fx.index] = x[p % n];
                c[fy.index] = y[p / n];
                ev.as_mut()
                    .and_then(|e| e.cost(&c).ok())
                    .filter(|j| j.is_finite())
                    .unwrap_or(f64::NAN)
            },
        )
        .collect();
    let seconds = wall.elapsed().as_secs_f64();
    if cancel.is_raised() {
        return Err(interrupted());
    }
    let centre_cost = Evaluator::new(problem)
        .and_then(|mut e| e.cost(&centre))
        .map_err(|e| Error::new(ErrorKind::Solver, anyhow::anyhow!(e)))?;
    let failed = cost.iter().filter(|v| !v.is_finite()).count();
    let grid_min = (0..n * n)
        .filter(|&p| cost[p].is_finite())
        .min_by(|&p, &q| cost[p].total_cmp(&cost[q]))
        .map_or((f64::NAN, f64::NAN, f64::NAN), |p| {
            (x[p % n], y[p / n], cost[p])
        });
    let mut map = CostMap {
        config: s.name.clone(),
        names: [fx.name, fy.name],
        units: [fx.unit, fy.unit],
        x: x.clone(),
        y: y.clone(),
        cost,
        through,
        centre_pair: [centre[fx.index], centre[fy.index]],
        centre,
        centre_cost,
        grid_min,
        failed,
        threads: rayon::current_num_threads(),
        seconds,
        files: Vec::new(),
    };
    if let Some(out) = &opts.out {
        map.files = write(out, &map, [fx.scaling, fy.scaling])?;
    }
    Ok(map)
}

/// Checks `--grid` and `--span`.
fn check_grid(opts: &MapOptions) -> Result<()> {
    let cfg_err = |msg: String| Error::msg(ErrorKind::Config, msg);
    if !(3..=MAX_GRID).contains(&opts.grid) {
        return Err(cfg_err(format!(
            "--grid {} is not allowed: expected a number of points per side in [3, {MAX_GRID}]",
            opts.grid
        )));
    }
    if opts.span.len() > 2 || opts.span.iter().any(|s| !(*s > 0.0 && s.is_finite())) {
        return Err(cfg_err(format!(
            "--span {:?} is not allowed: expected one or two finite values > 0 (half-widths in \
             the scaled variables, e.g. 0.5 = a factor e^0.5 on a log-scaled parameter)",
            opts.span
        )));
    }
    Ok(())
}

/// Checks `--pair` (two different free parameters of the law) before any solve; the
/// pair's names.
fn check_pair<'a>(opts: &'a MapOptions, resolved: &Resolved) -> Result<[&'a str; 2]> {
    let cfg_err = |msg: String| Error::msg(ErrorKind::Config, msg);
    let law_names = &resolved.names;
    let [a, b] = match opts.pair.as_slice() {
        [a, b] => [a.trim(), b.trim()],
        _ => {
            return Err(cfg_err(format!(
                "--pair needs exactly two parameter names (e.g. --pair E,eta), got {:?}",
                opts.pair
            )));
        }
    };
    for n in [a, b] {
        let Some(spec) = resolved.id_cfg.params.iter().find(|p| p.name == n) else {
            return Err(cfg_err(format!(
                "--pair: law `{}` has no parameter `{n}`; its parameters are {}",
                resolved.law.name(),
                law_names.join(", ")
            )));
        };
        if !spec.free {
            return Err(cfg_err(format!(
                "--pair: `{n}` is held (fixed) in this identification: free it (--free, or \
                 identify.params.{n}: Free(...)) or map another parameter"
            )));
        }
    }
    if a == b {
        return Err(cfg_err(format!(
            "--pair names `{a}` twice: expected two different free parameters"
        )));
    }
    Ok([a, b])
}

/// The slice's centre: the law values, the start, or the optimum of a fit.
fn centre(s: &Setup, param: &Parameterization, through: Through) -> Result<Vec<f64>> {
    Ok(match through {
        Through::Law => s.law_values.clone(),
        Through::Start => param.base.clone(),
        Through::Fit => {
            let mut cfg = s.id_cfg.clone();
            cfg.identifiability = false;
            let r = identify(&s.problem, &cfg, &mut |_| {})
                .map_err(|e| Error::new(ErrorKind::Solver, anyhow::anyhow!(e)))?;
            tracing::info!(
                "  fit for the slice: J = {:.6e} N^2 after {} iterations ({})",
                r.cost,
                r.iterations,
                r.stop_reason
            );
            r.c
        }
    })
}

/// `x,y,J` lines (named after the parameters), x fastest.
pub fn csv(map: &CostMap) -> String {
    let mut text = format!("{},{},J\n", map.names[0], map.names[1]);
    let n = map.x.len();
    for (p, j) in map.cost.iter().enumerate() {
        text.push_str(&format!("{},{},{}\n", map.x[p % n], map.y[p / n], j));
    }
    text
}

fn write(
    out: &Path,
    map: &CostMap,
    scaling: [indentify_identify::Scaling; 2],
) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let mut put = |name: &str, bytes: Vec<u8>| -> Result<()> {
        let path = out.join(name);
        crate::atomic::write(&path, bytes).kind(ErrorKind::Io)?;
        files.push(path);
        Ok(())
    };
    put("map.csv", csv(map).into_bytes())?;
    let json = serde_json::to_string_pretty(map)
        .map_err(|e| Error::new(ErrorKind::Io, anyhow::anyhow!(e)))?;
    put("map.json", (json + "\n").into_bytes())?;
    let unit = |u: &str| {
        if u == "-" {
            String::new()
        } else {
            format!(" ({u})")
        }
    };
    let [ca, cb] = map.centre_pair;
    let fig = indentify_report::CostMapFigure {
        title: format!(
            "log10 J({}, {}) through {}: {}",
            map.names[0],
            map.names[1],
            map.through.describe(),
            map.config.rsplit('/').next().unwrap_or(map.config.as_str())
        ),
        x_label: format!("{}{}", map.names[0], unit(map.units[0])),
        y_label: format!("{}{}", map.names[1], unit(map.units[1])),
        x: map.x.clone(),
        y: map.y.clone(),
        cost: map.cost.clone(),
        log_x: scaling[0] == indentify_identify::Scaling::Log,
        log_y: scaling[1] == indentify_identify::Scaling::Log,
        cost_unit: "N^2".into(),
        marks: vec![(
            ca,
            cb,
            match map.through {
                Through::Fit => "optimum".to_string(),
                Through::Law => "law".to_string(),
                Through::Start => "start".to_string(),
            },
        )],
        levels: Vec::new(),
    };
    let size = indentify_report::FigureSize::default();
    let svg = fig
        .svg(size)
        .map_err(|e| Error::new(ErrorKind::Io, anyhow::anyhow!("cannot draw the map: {e}")))?;
    let png = fig
        .png(size)
        .map_err(|e| Error::new(ErrorKind::Io, anyhow::anyhow!("cannot draw the map: {e}")))?;
    put("map.svg", svg.into_bytes())?;
    put("map.png", png)?;
    Ok(files)
}

impl CostMap {
    /// A summary for the console.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "cost map of `{}`: J({}, {}) on {} x {} points through {} ({} = {}, {} = {}, J = \
             {:.4e} N^2), {} threads, {:.1} s\n  lowest grid point: {} = {}, {} = {}, J = {:.4e} \
             N^2",
            self.config,
            self.names[0],
            self.names[1],
            self.x.len(),
            self.y.len(),
            self.through.describe(),
            self.names[0],
            sig(self.centre_pair[0], 6),
            self.names[1],
            sig(self.centre_pair[1], 6),
            self.centre_cost,
            self.threads,
            self.seconds,
            self.names[0],
            sig(self.grid_min.0, 6),
            self.names[1],
            sig(self.grid_min.1, 6),
            self.grid_min.2
        );
        if self.failed > 0 {
            s.push_str(&format!(
                "\n  {} grid points failed to solve (blank in the figure)",
                self.failed
            ));
        }
        if !self.files.is_empty() {
            let f: Vec<String> = self.files.iter().map(|p| p.display().to_string()).collect();
            s.push_str(&format!("\n  written: {}", f.join(", ")));
        }
        s.push('\n');
        s
    }
}
