//! The gradient pipeline: the least-squares misfit `J` between a configuration's simulated
//! force and a measured curve, and its exact gradient `dJ/dc` by the discrete adjoint, with
//! the wall times of the forward run and of the adjoint sweep.
//!
//! `J = 1/2 sum_i (F_i - F_i^exp)^2` over the schedule times `t_i` of the configuration
//! (index 0, the stress-free start, included; every weight 1), `F^exp` being the data
//! interpolated linearly at `t_i` (the cost of `indentify_identify::Problem`).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context as _;
use indentify_adjoint::{Adjoint, Gradient, Replay};
use indentify_contact::DirectSolver;
use indentify_identify::Problem;
use serde::Serialize;

use crate::data::Curve;
use crate::error::{Classify, Error, ErrorKind, Result};
use crate::format::assignments;
use crate::identify::{absolute, prepare};
use crate::solve::{ensure_differentiable, forward, param_names};
use crate::source::ConfigSource;

/// What to differentiate.
#[derive(Clone, Debug)]
pub struct GradientOptions {
    /// The configuration (its `law` values are the point).
    pub config: ConfigSource,
    /// `dotted.path=value` overrides.
    pub sets: Vec<String>,
    /// The measured curve (CSV `t`, `F`) or the record replacing `data.file`.
    pub data: Option<PathBuf>,
    /// Record no fields, save the state every N schedule steps and replay (bounded memory).
    pub checkpoint: Option<usize>,
    /// The test (from 1) of a joint configuration (`tests: [...]`) to work on; required
    /// for one, refused for a one-test configuration.
    pub test: Option<usize>,
}

impl GradientOptions {
    /// The gradient of `config` against `data`.
    pub fn new(config: ConfigSource, data: Option<PathBuf>) -> GradientOptions {
        GradientOptions {
            config,
            sets: Vec::new(),
            data,
            checkpoint: None,
            test: None,
        }
    }
}

/// `J` and `dJ/dc` with what they cost.
#[derive(Clone, Debug, Serialize)]
pub struct GradientOutcome {
    /// The law's name.
    pub law: &'static str,
    /// The configuration's name.
    pub config: String,
    /// The data's name.
    pub data: String,
    /// Parameter names, law order.
    pub names: Vec<&'static str>,
    /// Their units.
    pub units: Vec<&'static str>,
    /// The point (the configuration's law values).
    pub params: Vec<f64>,
    /// The misfit (N^2).
    #[serde(rename = "J")]
    pub j: f64,
    /// `dJ/dc`, law order.
    pub gradient: Vec<f64>,
    /// Wall time of the forward run (s).
    pub forward_seconds: f64,
    /// Wall time of the adjoint sweep (s; replays included with checkpoints).
    pub adjoint_seconds: f64,
    /// Converged steps (sub-steps from cuts included).
    pub steps: usize,
    /// Schedule times.
    pub schedule_times: usize,
    /// The steps of the schedule with their own sub-steps (`data.substeps`; without cuts).
    pub solver_steps: usize,
    /// Factorizations of the adjoint sweep.
    pub factorizations: usize,
    /// Factorizations of the forward run.
    pub forward_factorizations: usize,
    /// Bytes the trajectory recorded.
    pub recorded_bytes: usize,
    /// Bytes recording every step's fields would take.
    pub full_bytes: usize,
    /// The checkpoint interval, if any.
    pub checkpoint_every: Option<usize>,
    /// Rows of the data and their time span (s).
    pub data_rows: usize,
    /// First and last data time (s).
    pub data_span: (f64, f64),
}

/// Computes `J` and `dJ/dc`.
///
/// # Errors
/// An invalid configuration or data, data that do not cover the simulated history, a law
/// not differentiable at the configured parameters, a failing forward run or adjoint, or a
/// non-finite gradient.
pub fn run(opts: &GradientOptions) -> Result<GradientOutcome> {
    let name = opts.config.name();
    let mut cfg = opts
        .config
        .load(&opts.sets)?
        .one_test(opts.test, "gradient", &name)
        .kind(ErrorKind::Config)?;
    let (law, params) = cfg.law.build().kind(ErrorKind::Config)?;
    let law = &law;
    ensure_differentiable(&**law, &params, &format!("no gradient for `{name}`"))
        .kind(ErrorKind::Config)?;
    if let (Some(d), Some(path)) = (&mut cfg.data, &opts.data) {
        d.file = absolute(path);
    }
    let load_controlled = match &cfg.data {
        Some(d) => d.drive == crate::config::Drive::Force,
        None => cfg.load_history().is_ok_and(|h| h.is_load_controlled()),
    };
    if load_controlled {
        // the force drives, the depth is the observable (docs/theory.md §13)
        let (prepared, history) = cfg.prepare_driven(&name).map_err(|e| {
            let kind = if e.downcast_ref::<crate::config::DataFailure>().is_some() {
                ErrorKind::Data
            } else {
                ErrorKind::Config
            };
            Error::new(kind, e)
        })?;
        let Some(history) = history else {
            return Err(Error::msg(
                ErrorKind::Config,
                format!("`{name}` prescribes no force"),
            ));
        };
        let curve = curve_of(&prepared, opts, &name)?;
        return crate::gradient_load::run(
            opts,
            &cfg,
            &name,
            (&**law, params.clone()),
            (prepared, history),
            curve,
        );
    }
    let prepared = prepare(&cfg, &name)?;
    let curve = curve_of(&prepared, opts, &name)?;
    let schedule = prepared.schedule;
    let (t0, t1) = (schedule.t[0], schedule.t[schedule.t.len() - 1]);
    curve.check_covers(t0, t1, &name).kind(ErrorKind::Data)?;
    let mut solver_opts = cfg.solver.options(true);
    if let Some(n) = opts.checkpoint {
        solver_opts.record_fields = false;
        solver_opts.checkpoint_every = n;
    }
    let problem = Problem::new(
        prepared.model,
        law.clone(),
        schedule,
        &curve.record().kind(ErrorKind::Data)?,
        None,
        solver_opts.clone(),
    )
    .with_context(|| format!("cannot compare `{}` with `{name}`", curve.name))
    .kind(ErrorKind::Data)?;
    let model = &problem.model();

    let mut solver = DirectSolver::new(model).kind(ErrorKind::Solver)?;
    let start = Instant::now();
    let traj = forward(
        &mut solver,
        &**law,
        &params,
        problem.schedule(),
        &solver_opts,
        &name,
    )
    .kind(ErrorKind::Solver)?;
    let forward_seconds = start.elapsed().as_secs_f64();
    let j = problem.cost_of(&traj.forces());
    let rho = problem.dj_df(&traj);
    let mut adjoint = Adjoint::new(model).kind(ErrorKind::Solver)?;
    // the forward's factorization serves the sweep (docs/validation-load-control.md §6)
    adjoint.take_factor(&mut solver);
    let grad: Gradient = if opts.checkpoint.is_some() {
        adjoint.gradient_replayed(
            &**law,
            &params,
            &traj,
            &rho,
            Replay {
                solver: &mut solver,
                schedule: problem.schedule(),
                opts: &solver_opts,
            },
        )
    } else {
        adjoint.gradient(&**law, &params, &traj, &rho)
    }
    .with_context(|| format!("the adjoint sweep of `{name}` failed"))
    .kind(ErrorKind::Solver)?;
    let names = param_names(&**law);
    if let Some(k) = grad.dj_dc.iter().position(|g| !g.is_finite()) {
        return Err(Error::msg(
            ErrorKind::Solver,
            format!(
                "the adjoint gave dJ/d{} = {} at {}: no finite gradient there",
                names[k],
                grad.dj_dc[k],
                assignments(&names, &params)
            ),
        ));
    }
    Ok(GradientOutcome {
        law: law.name(),
        config: name,
        data: curve.name.clone(),
        units: law.params().iter().map(|i| i.unit).collect(),
        names,
        params,
        j,
        gradient: grad.dj_dc,
        forward_seconds,
        adjoint_seconds: grad.seconds,
        steps: traj.steps.len(),
        schedule_times: problem.schedule().t.len(),
        solver_steps: problem.schedule().n_solver_steps(),
        factorizations: grad.factorizations,
        forward_factorizations: traj.timing.factorizations,
        recorded_bytes: traj.recorded_bytes(),
        full_bytes: (traj.steps.len() + 1) * (8 * model.disc.n_dofs() + 32 * model.disc.n_qp()),
        checkpoint_every: opts.checkpoint,
        data_rows: curve.t.len(),
        data_span: curve.span(),
    })
}

/// The data of `gradient`: the measured record (its preprocessed curve at its own times),
/// or the curve file of `--data`.
fn curve_of(
    prepared: &crate::config::Prepared,
    opts: &GradientOptions,
    name: &str,
) -> Result<Curve> {
    let curve = match (&prepared.measured, &opts.data) {
        // the measured record: its preprocessed force at its own times (the schedule's)
        (Some(m), _) => Curve {
            name: m.path.display().to_string(),
            t: m.record.t.clone(),
            h: Some(m.record.h.clone()),
            f: m.record.f.clone(),
        },
        (None, Some(path)) => crate::data::read_curve(path).kind(ErrorKind::Data)?,
        (None, None) => {
            return Err(Error::msg(
                ErrorKind::Data,
                format!(
                    "no data for `{name}`: give --data CURVE.csv, or a `data` section in the \
                     configuration"
                ),
            ));
        }
    };
    Ok(curve)
}
