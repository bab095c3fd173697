//! The `gradient` pipeline under load control (a `history` with `force` segments, or
//! `data.drive: Force`): the prescribed force drives the run and the depth is the
//! observable, `J = 1/2 sum_i (h_i - h_i^exp)^2` over the schedule times (every weight 1,
//! the stress-free start included), `h^exp` the data's depth interpolated linearly at
//! `t_i`; `dJ/dc` by the adjoint of the bordered system (docs/theory.md §13,
//! `Adjoint::gradient_load`).

use std::time::Instant;

use indentify_adjoint::{Adjoint, LoadReplay};
use indentify_contact::{DirectSolver, LoadHistory, SolverOptions};
use indentify_laws::Material;

use crate::config::{Config, Prepared};
use crate::data::Curve;
use crate::error::{Classify, Error, ErrorKind, Result};
use crate::gradient::{GradientOptions, GradientOutcome};
use crate::solve::param_names;

/// The depth of `curve` linearly interpolated at `t` (s), or why not.
fn depth_at(curve: &Curve, h: &[f64], t: f64) -> Result<f64> {
    let i = curve.t.partition_point(|&x| x < t);
    let out = || {
        Error::msg(
            ErrorKind::Data,
            format!(
                "the data `{}` do not cover t = {t} s of the load-controlled history",
                curve.name
            ),
        )
    };
    if i == curve.t.len() {
        return Err(out());
    }
    if curve.t[i] == t || i == 0 {
        return if curve.t[i] == t {
            Ok(h[i])
        } else {
            Err(out())
        };
    }
    let (t0, t1) = (curve.t[i - 1], curve.t[i]);
    let w = (t - t0) / (t1 - t0);
    Ok(h[i - 1] + w * (h[i] - h[i - 1]))
}

/// `J` and `dJ/dc` of a load-controlled configuration (`history` its load history).
///
/// # Errors
/// Data without a depth column or not covering the history, a failing forward run or
/// adjoint, `--checkpoint 0`.
pub(crate) fn run(
    opts: &GradientOptions,
    cfg: &Config,
    name: &str,
    (law, params): (&dyn Material, Vec<f64>),
    (prepared, history): (Prepared, LoadHistory),
    curve: Curve,
) -> Result<GradientOutcome> {
    let Some(h_exp) = curve.h.clone() else {
        return Err(Error::msg(
            ErrorKind::Data,
            format!(
                "the data `{}` have no depth column `h`: under load control the depth is \
                 the observable of `{name}`",
                curve.name
            ),
        ));
    };
    let schedule = &history.schedule;
    let target: Vec<f64> = schedule
        .t
        .iter()
        .map(|&t| depth_at(&curve, &h_exp, t))
        .collect::<Result<_>>()?;
    let model = &prepared.model;
    // with --checkpoint the states are saved every n steps and the adjoint replays the
    // stretches between them with the history's drive
    let solver_opts = match opts.checkpoint {
        Some(0) => {
            return Err(Error::msg(
                ErrorKind::Config,
                "--checkpoint 0 is not allowed: expected a number of schedule steps >= 1",
            ));
        }
        Some(n) => SolverOptions {
            record_fields: false,
            checkpoint_every: n,
            ..cfg.solver.options(false)
        },
        None => cfg.solver.options(true),
    };
    let mut solver = DirectSolver::new(model).kind(ErrorKind::Solver)?;
    let start = Instant::now();
    let traj = solver
        .run_history(law, &params, &history, &solver_opts)
        .map_err(|e| {
            Error::new(
                ErrorKind::Solver,
                anyhow::anyhow!(e).context(format!("cannot simulate `{name}`")),
            )
        })?;
    let forward_seconds = start.elapsed().as_secs_f64();
    // J over the schedule times (index 0: the stress-free start, depth 0)
    let mut j = 0.5 * target[0] * target[0];
    let mut dj_dh = vec![0.0; traj.steps.len()];
    for (s, d) in traj.steps.iter().zip(dj_dh.iter_mut()) {
        if s.on_schedule {
            let r = s.depth - target[s.schedule_index];
            j += 0.5 * r * r;
            *d = r;
        }
    }
    let zero = vec![0.0; traj.steps.len()];
    let mut adjoint = Adjoint::new(model).kind(ErrorKind::Solver)?;
    // the forward's factorization serves the sweep (docs/validation-load-control.md §6)
    adjoint.take_factor(&mut solver);
    let grad = adjoint
        .gradient_load_replayed(
            law,
            &params,
            &traj,
            &history,
            &dj_dh,
            &zero,
            LoadReplay {
                solver: &mut solver,
                opts: &solver_opts,
            },
        )
        .map_err(|e| {
            Error::new(
                ErrorKind::Solver,
                anyhow::anyhow!(e).context(format!("the adjoint sweep of `{name}` failed")),
            )
        })?;
    let names = param_names(law);
    if let Some(k) = grad.dj_dc.iter().position(|g| !g.is_finite()) {
        return Err(Error::msg(
            ErrorKind::Solver,
            format!(
                "the adjoint gave dJ/d{} = {}: no finite gradient",
                names[k], grad.dj_dc[k]
            ),
        ));
    }
    Ok(GradientOutcome {
        law: law.name(),
        config: name.to_string(),
        data: curve.name.clone(),
        units: law.params().iter().map(|i| i.unit).collect(),
        names,
        params,
        j,
        gradient: grad.dj_dc,
        forward_seconds,
        adjoint_seconds: grad.seconds,
        steps: traj.steps.len(),
        schedule_times: schedule.t.len(),
        solver_steps: schedule.n_solver_steps(),
        factorizations: grad.factorizations,
        forward_factorizations: traj.timing.factorizations,
        recorded_bytes: traj.recorded_bytes(),
        full_bytes: (traj.steps.len() + 1) * (8 * model.disc.n_dofs() + 32 * model.disc.n_qp()),
        checkpoint_every: None,
        data_rows: curve.t.len(),
        data_span: curve.span(),
    })
}
