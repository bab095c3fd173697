//! `identify` under load control (a `history` with `force` segments, or `data.drive:
//! Force`): the prescribed force drives the run and the depth is the observable
//! (docs/theory.md §13). The data of a load-controlled test are depths (the measured
//! record's `h`, a curve file's `h` column, or the depths of a run at the configuration's
//! law values, with multiplicative noise on the depth), and its curves in the report are
//! depths beside the force ([`indentify_report::Observable::Depth`]).

use std::path::Path;
use std::sync::Arc;

use anyhow::Context as _;
use indentify_contact::{DirectSolver, LoadHistory, SolverOptions, Trajectory};
use indentify_identify::{ForceRecord, multiplicative_noise};
use indentify_laws::Material;

use crate::config::Prepared;
use crate::error::{Classify, Error, ErrorKind, Result};
use crate::format::assignments;
use crate::identify::Data;
use crate::solve::param_names;

/// The depths of a trajectory at the schedule times (index 0: the stress-free start, 0).
pub(crate) fn depths(traj: &Trajectory) -> Vec<f64> {
    std::iter::once(0.0)
        .chain(traj.schedule_steps().map(|s| s.depth))
        .collect()
}

/// The forward run of a load-controlled test at `c`.
///
/// # Errors
/// A run that fails (the reason from the solver), as [`ErrorKind::Solver`].
pub(crate) fn run(
    solver: &mut DirectSolver,
    law: &dyn Material,
    c: &[f64],
    history: &LoadHistory,
    opts: &SolverOptions,
    name: &str,
) -> Result<Trajectory> {
    solver.run_history(law, c, history, opts).map_err(|e| {
        Error::new(
            ErrorKind::Solver,
            anyhow::anyhow!(e).context(format!("cannot simulate `{name}`")),
        )
    })
}

/// The observed depths of a load-controlled test: the measured record's depth (its force
/// prescribes the run), a curve file's `h` column, or the depths of a run at the
/// configuration's law values (with `noise`: `h (1 + a xi)`, the seed as `simulate
/// --noise` draws it, so that a simulated curve and a synthesized fit see the same data).
///
/// # Errors
/// A record or curve without depths, a curve that does not cover the history
/// ([`ErrorKind::Data`]); a run that fails ([`ErrorKind::Solver`]).
pub(crate) fn load_depths(
    prepared: &Prepared,
    history: &LoadHistory,
    curve: Option<&Path>,
    noise: Option<(f64, u64)>,
    name: &str,
    (law, law_values): (&Arc<dyn Material>, &[f64]),
    solver_opts: &SolverOptions,
) -> Result<Data> {
    let schedule = &prepared.schedule;
    match (&prepared.measured, curve) {
        (Some(m), _) => Ok(Data {
            record: ForceRecord::new(m.record.t.clone(), m.record.h.clone())
                .with_context(|| {
                    format!(
                        "cannot use the depth of `{}` as data (load control: the depth is \
                         the observable)",
                        m.path.display()
                    )
                })
                .kind(ErrorKind::Data)?,
            describe: format!(
                "{} (load control: its force prescribed, its depth fitted)",
                crate::identify::describe_measured(m)
            ),
            truth: None,
        }),
        (None, Some(path)) => {
            let curve = crate::data::read_curve(path).kind(ErrorKind::Data)?;
            let (t0, t1) = (schedule.t[0], schedule.t[schedule.t.len() - 1]);
            curve.check_covers(t0, t1, name).kind(ErrorKind::Data)?;
            let Some(h) = curve.h.clone() else {
                return Err(Error::msg(
                    ErrorKind::Data,
                    format!(
                        "the data `{}` have no depth column `h`: under load control the \
                         depth is the observable of `{name}`",
                        curve.name
                    ),
                ));
            };
            Ok(Data {
                record: ForceRecord::new(curve.t.clone(), h)
                    .with_context(|| format!("invalid depths in `{}`", curve.name))
                    .kind(ErrorKind::Data)?,
                describe: format!("{} (load control: its depth fitted)", curve.name),
                truth: None,
            })
        }
        (None, None) => {
            let mut solver = DirectSolver::new(&prepared.model).kind(ErrorKind::Solver)?;
            let quiet = SolverOptions {
                record_fields: false,
                checkpoint_every: 0,
                ..solver_opts.clone()
            };
            let traj = run(&mut solver, &**law, law_values, history, &quiet, name)?;
            let mut h = depths(&traj);
            if h.len() != schedule.t.len() {
                return Err(Error::msg(
                    ErrorKind::Solver,
                    format!(
                        "the load-controlled run of `{name}` reached {} of its {} schedule \
                         times",
                        h.len(),
                        schedule.t.len()
                    ),
                ));
            }
            let names = param_names(&**law);
            let mut describe = format!(
                "synthesized under load control: the depths of `{name}` at {}",
                assignments(&names, law_values)
            );
            if let Some((a, seed)) = noise {
                h = multiplicative_noise(&h, a, seed);
                describe.push_str(&format!(
                    ", noise h (1 + {a} xi), xi uniform in [-1, 1], seed {seed}"
                ));
            } else {
                describe.push_str(" (exact)");
            }
            Ok(Data {
                record: ForceRecord::new(schedule.t.clone(), h)
                    .context("cannot use the simulated depths as data")
                    .kind(ErrorKind::Data)?,
                describe,
                truth: Some(law_values.to_vec()),
            })
        }
    }
}
